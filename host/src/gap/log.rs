//! The measurement log of a gap diagnosis: a CSV with a header, SI units, ISO-W axes.
//!
//! Required columns `t,vx,alpha,kappa,gamma,fz,fx,fy,mz`; optional `p` (inflation pressure
//! \[Pa\]; absent means INFLPRES), `phit` (turn slip \[1/m\]) and `mu` (reference road friction,
//! on the tyre file's scale, see `docs/architecture.md`); other columns are ignored.
//! Every error is one line naming the file, the line and the column.

use crate::csvio;
use std::path::Path;

/// The required columns, in the order [`Log`] keeps them.
pub const REQUIRED: [&str; 9] = ["t", "vx", "alpha", "kappa", "gamma", "fz", "fx", "fy", "mz"];

/// The fewest data rows a log may have: five cross-validation blocks of 20 rows.
pub const MIN_ROWS: usize = 100;

/// A log, column by column. SI units, ISO-W axes at the contact point.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Log {
    /// Time \[s\], strictly increasing.
    pub t: Vec<f64>,
    /// Forward speed of the wheel centre Vx \[m/s\].
    pub vx: Vec<f64>,
    /// Slip angle α \[rad\] (α > 0 gives Fy < 0).
    pub alpha: Vec<f64>,
    /// Longitudinal slip κ \[-\].
    pub kappa: Vec<f64>,
    /// Inclination γ \[rad\].
    pub gamma: Vec<f64>,
    /// Vertical load Fz \[N\].
    pub fz: Vec<f64>,
    /// Measured Fx, Fy \[N\] and Mz \[N·m\], as `[fx, fy, mz]` per row.
    pub meas: Vec<[f64; 3]>,
    /// Inflation pressure \[Pa\], when logged.
    pub p: Option<Vec<f64>>,
    /// Turn slip φt \[1/m\], when logged.
    pub phit: Option<Vec<f64>>,
    /// Reference road friction μ \[-\], when logged.
    pub mu: Option<Vec<f64>>,
    /// 1-based file line of each row (for error messages); empty for generated logs.
    pub lines: Vec<usize>,
}

/// The longest step between two rows that the sim bridges, in median steps: one dropped row
/// with the timestamps jittered by up to ±20 % of the step (2 × 1.2 = 2.4).
pub const BRIDGED_STEPS: f64 = 2.5;

impl Log {
    /// The log of rows `rows` (indices into this one, in order).
    pub fn select(&self, rows: &[usize]) -> Log {
        let pick = |v: &[f64]| rows.iter().map(|&i| v[i]).collect::<Vec<f64>>();
        Log {
            t: pick(&self.t),
            vx: pick(&self.vx),
            alpha: pick(&self.alpha),
            kappa: pick(&self.kappa),
            gamma: pick(&self.gamma),
            fz: pick(&self.fz),
            meas: rows.iter().map(|&i| self.meas[i]).collect(),
            p: self.p.as_deref().map(pick),
            phit: self.phit.as_deref().map(pick),
            mu: self.mu.as_deref().map(pick),
            lines: if self.lines.is_empty() {
                Vec::new()
            } else {
                rows.iter().map(|&i| self.lines[i]).collect()
            },
        }
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// No rows.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// File line of row `i` (or `i + 2` for a generated log: header on line 1).
    pub fn line(&self, i: usize) -> usize {
        self.lines.get(i).copied().unwrap_or(i + 2)
    }

    /// Pressure of row `i` \[Pa\], `None` when the log has no `p` column.
    pub fn p_at(&self, i: usize) -> Option<f64> {
        self.p.as_ref().and_then(|p| p.get(i).copied())
    }

    /// Turn slip of row `i` \[1/m\] (0 when not logged).
    pub fn phit_at(&self, i: usize) -> f64 {
        self.phit
            .as_ref()
            .and_then(|p| p.get(i).copied())
            .unwrap_or(0.0)
    }

    /// Kinematic slip speeds of row `i` from the logged slips: (Vsx, Vsy) \[m/s\] with
    /// κ = −Vsx/|Vx| and tan α = Vsy/|Vx| (the sign conventions of `gough::relax`).
    pub fn slip_velocity(&self, i: usize) -> (f64, f64) {
        let v = self.vx[i].abs();
        (-self.kappa[i] * v, self.alpha[i].tan() * v)
    }

    /// Slip speed |Vs| = √(Vsx² + Vsy²) of row `i` \[m/s\].
    pub fn slip_speed(&self, i: usize) -> f64 {
        let (a, b) = self.slip_velocity(i);
        a.hypot(b)
    }

    /// Median step between rows \[s\] (0 with fewer than two rows).
    pub fn median_step(&self) -> f64 {
        let mut d: Vec<f64> = self.t.windows(2).map(|w| w[1] - w[0]).collect();
        if d.is_empty() {
            return 0.0;
        }
        d.sort_by(f64::total_cmp);
        d[d.len() / 2]
    }

    /// Rows where the relaxation filters (re)start: row 0, and every row after a gap in time —
    /// a step longer than [`BRIDGED_STEPS`] × the median step (two rows or more dropped in a
    /// row; one dropped row, jittered, is bridged by the sim's interpolant) or than
    /// `gough::relax::MAX_DT`.
    pub fn restarts(&self) -> Vec<bool> {
        let gap = BRIDGED_STEPS * self.median_step();
        let mut r = Vec::with_capacity(self.len());
        for i in 0..self.len() {
            r.push(
                i == 0 || {
                    let h = self.t[i] - self.t[i - 1];
                    h > gap || h > gough::relax::MAX_DT
                },
            );
        }
        r
    }

    /// Number of gaps in time (restarts after row 0).
    pub fn gaps(&self) -> usize {
        self.restarts().iter().skip(1).filter(|&&g| g).count()
    }

    /// Checks what the diagnosis relies on: equal column lengths, strictly increasing time,
    /// positive pressure, enough rows. `name` is the file for messages.
    pub fn validate(&self, name: &str) -> Result<(), String> {
        let n = self.len();
        let lens = [
            self.vx.len(),
            self.alpha.len(),
            self.kappa.len(),
            self.gamma.len(),
            self.fz.len(),
            self.meas.len(),
        ];
        if lens.iter().any(|&l| l != n)
            || [&self.p, &self.phit, &self.mu]
                .iter()
                .any(|c| c.as_ref().is_some_and(|c| c.len() != n))
        {
            return Err(format!("{name}: columns of unequal length"));
        }
        for i in 1..n {
            if self.t[i] <= self.t[i - 1] {
                return Err(format!(
                    "{name}: line {}, column t: time is not increasing ({} after {})",
                    self.line(i),
                    self.t[i],
                    self.t[i - 1]
                ));
            }
        }
        if let Some(p) = &self.p {
            if let Some(i) = p.iter().position(|&x| x <= 0.0) {
                return Err(format!(
                    "{name}: line {}, column p: inflation pressure must be > 0 Pa, got {}",
                    self.line(i),
                    p[i]
                ));
            }
        }
        if n < MIN_ROWS {
            return Err(format!(
                "{name}: {n} data rows; the diagnosis needs at least {MIN_ROWS} \
                 (5 cross-validation blocks of 20)"
            ));
        }
        Ok(())
    }
}

/// One row of a log file.
#[derive(Debug, Clone, Copy, serde::Deserialize)]
struct Row {
    t: f64,
    vx: f64,
    alpha: f64,
    kappa: f64,
    gamma: f64,
    fz: f64,
    fx: f64,
    fy: f64,
    mz: f64,
    #[serde(default)]
    p: Option<f64>,
    #[serde(default)]
    phit: Option<f64>,
    #[serde(default)]
    mu: Option<f64>,
}

/// Reads and validates a log. The error is one line: `FILE: line N, column C: what`.
pub fn read(path: &Path) -> Result<Log, String> {
    let rows = csvio::read::<Row>(path).map_err(|e| e.to_string())?;
    let log = from_rows(&rows);
    log.validate(&path.display().to_string())?;
    Ok(log)
}

/// Parses log text already in memory (as [`read`]; `name` names it in errors).
pub fn parse(text: &str, name: &str) -> Result<Log, String> {
    let rows = csvio::parse::<Row>(text, Path::new(name)).map_err(|e| e.to_string())?;
    let log = from_rows(&rows);
    log.validate(name)?;
    Ok(log)
}

fn from_rows(t: &csvio::Rows<Row>) -> Log {
    let col = |f: fn(&Row) -> f64| -> Vec<f64> { t.rows.iter().map(f).collect() };
    let opt = |name: &str, f: fn(&Row) -> Option<f64>| -> Option<Vec<f64>> {
        t.has(name)
            .then(|| t.rows.iter().map(|r| f(r).unwrap_or(0.0)).collect())
    };
    Log {
        t: col(|r| r.t),
        vx: col(|r| r.vx),
        alpha: col(|r| r.alpha),
        kappa: col(|r| r.kappa),
        gamma: col(|r| r.gamma),
        fz: col(|r| r.fz),
        meas: t.rows.iter().map(|r| [r.fx, r.fy, r.mz]).collect(),
        p: opt("p", |r| r.p),
        phit: opt("phit", |r| r.phit),
        mu: opt("mu", |r| r.mu),
        lines: t.lines.clone(),
    }
}

/// Writes a log as CSV (atomically: to `PATH.tmp`, then renamed), with the optional columns it
/// has; 8 significant digits (far below any sensor's resolution).
pub fn write(path: &Path, log: &Log) -> std::io::Result<()> {
    use std::io::Write;
    let mut header: Vec<&str> = REQUIRED.to_vec();
    let opts: [(&str, &Option<Vec<f64>>); 3] =
        [("p", &log.p), ("phit", &log.phit), ("mu", &log.mu)];
    for (name, c) in &opts {
        if c.is_some() {
            header.push(name);
        }
    }
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let tmp = path.with_extension("csv.tmp");
    {
        let mut w = std::io::BufWriter::new(std::fs::File::create(&tmp)?);
        writeln!(w, "{}", header.join(","))?;
        for i in 0..log.len() {
            let mut r = vec![
                log.t[i],
                log.vx[i],
                log.alpha[i],
                log.kappa[i],
                log.gamma[i],
                log.fz[i],
                log.meas[i][0],
                log.meas[i][1],
                log.meas[i][2],
            ];
            for (_, c) in &opts {
                if let Some(c) = c {
                    r.push(c[i]);
                }
            }
            let cells: Vec<String> = r
                .iter()
                .map(|v| {
                    let s = format!("{v:.7e}");
                    // 1.2345000e3 -> 1.2345e3: shorter, same value.
                    match s.split_once('e') {
                        Some((m, e)) if m.contains('.') => {
                            let m = m.trim_end_matches('0').trim_end_matches('.');
                            format!("{m}e{e}")
                        }
                        _ => s,
                    }
                })
                .collect();
            writeln!(w, "{}", cells.join(","))?;
        }
        w.flush()?;
    }
    std::fs::rename(&tmp, path)
}
