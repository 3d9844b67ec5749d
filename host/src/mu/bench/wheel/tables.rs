//! The wheel cases' tables: "By tyre", "A tyre that is not its file", "Sample rates" and (with
//! `--warm`) "Warm start" sections of `table.md`, their closing lines, and `wheel_cases.csv`.
//!
//! Every table adds up cases into a [`Tally`]: wheel-surfaces within ±0.1 within 150 ms of
//! utilisation 0.5, the worst case's p95 error while identifiable and its share of samples
//! identifiable and off by more than 0.2, change flags and the false ones, the steps of the
//! surface and how soon each was read, the share of samples identifiable.

use super::{CaseResult, Level, Outcome, Tyre, WheelCase, WheelScenario, RATE, RATES, RATE_SUBSET};
use crate::mu::bench::metrics::{GROSS, TARGET_LATENCY, TARGET_STEP};
use crate::mu::bench::tables::{csv_field, fmt};
use std::fmt::Write as _;
use std::path::Path;

/// Issue 55's limits a case is held to: p95 while identifiable, the share of samples off by
/// more than [`GROSS`], and the share of wheel-surfaces within 150 ms (of a tyre's or a level's).
pub const TARGET_P95: f64 = 0.08;
/// See [`TARGET_P95`].
pub const TARGET_GROSS: f64 = 0.005;
/// See [`TARGET_P95`].
pub const TARGET_WS: f64 = 0.90;

/// Cases added up.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Tally {
    /// Cases run.
    pub cases: usize,
    /// Wheel-surfaces within ±0.1 within [`TARGET_LATENCY`] of utilisation 0.5, of those
    /// reaching it.
    pub ws: (usize, usize),
    /// The worst case's p95 error while identifiable (none: never identifiable).
    pub worst_p95: Option<f64>,
    /// The worst case's share of samples identifiable and off by more than [`GROSS`].
    pub worst_gross: f64,
    /// The worst case's share of those without the model-mismatch indication.
    pub worst_gross_unflagged: f64,
    /// Samples with the model-mismatch indication set (summed over the cases).
    pub mismatch: f64,
    /// False change flags, and all change flags.
    pub flags: (usize, usize),
    /// Each step's read time \[s\] (none: never read).
    pub steps: Vec<Option<f64>>,
    /// Samples identifiable, all samples; the same at utilisation ≥ 0.5.
    pub ident: (usize, usize, usize, usize),
    /// Cases over [`TARGET_P95`], over [`TARGET_GROSS`], with a false change flag, with a step
    /// not read within [`TARGET_STEP`].
    pub outside: [usize; 4],
}

impl Tally {
    /// Adds one case's outcome.
    pub fn add(&mut self, o: &Outcome) {
        let m = &o.metrics;
        self.cases += 1;
        self.ws.0 += m.ws_within;
        self.ws.1 += m.ws_total;
        self.worst_p95 = match (self.worst_p95, m.err_p95) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (a, b) => a.or(b),
        };
        self.worst_gross = self.worst_gross.max(m.gross);
        self.worst_gross_unflagged = self.worst_gross_unflagged.max(m.gross_unflagged);
        self.mismatch += m.mismatch * m.n_samples as f64;
        self.flags.0 += m.false_alarms;
        self.flags.1 += m.change_flags;
        self.steps.extend(o.steps.iter().map(|s| s.read));
        self.ident.0 += m.n_identifiable;
        self.ident.1 += m.n_samples;
        self.ident.2 += m.n_identifiable_util_hi;
        self.ident.3 += m.n_util_hi;
        self.outside[0] += usize::from(m.err_p95.is_some_and(|p| p > TARGET_P95));
        self.outside[1] += usize::from(m.gross > TARGET_GROSS);
        self.outside[2] += usize::from(m.false_alarms > 0);
        self.outside[3] += usize::from(o.steps.iter().any(|s| !s.in_time()));
    }

    /// Steps read later than [`TARGET_STEP`] or never.
    pub fn steps_late(&self) -> usize {
        self.steps
            .iter()
            .filter(|r| !r.is_some_and(|x| x <= TARGET_STEP + 1e-9))
            .count()
    }

    /// The median step read time (a step never read counts as the longest), "never" when that
    /// is one; "–" without steps.
    pub fn step_median(&self) -> String {
        let mut v: Vec<f64> = self
            .steps
            .iter()
            .map(|r| r.unwrap_or(f64::INFINITY))
            .collect();
        v.sort_by(f64::total_cmp);
        match v.get(v.len() / 2) {
            None => "–".into(),
            Some(x) if x.is_finite() => format!("{x:.3}"),
            Some(_) => "never".into(),
        }
    }

    /// The worst step read time, "never" when a step was never read; "–" without steps.
    pub fn step_worst(&self) -> String {
        if self.steps.is_empty() {
            "–".into()
        } else if self.steps.iter().any(Option::is_none) {
            "never".into()
        } else {
            let w = self.steps.iter().flatten().copied().fold(0.0, f64::max);
            format!("{w:.3}")
        }
    }

    /// Wheel-surfaces within 150 ms: "n of N (x %)".
    pub fn ws_cell(&self) -> String {
        format!(
            "{} of {} ({})",
            self.ws.0,
            self.ws.1,
            pct(self.ws.0, self.ws.1)
        )
    }

    /// The columns of [`HEAD`] from "wheel-surfaces" on.
    fn cells(&self) -> String {
        format!(
            "{} | {} | {:.2} % | {} of {} | {} | {} | {} of {} | {} | {}",
            self.ws_cell(),
            fmt(self.worst_p95, 3),
            100.0 * self.worst_gross,
            self.flags.0,
            self.flags.1,
            self.step_median(),
            self.step_worst(),
            self.steps_late(),
            self.steps.len(),
            pct(self.ident.0, self.ident.1),
            pct(self.ident.2, self.ident.3),
        )
    }
}

fn pct(a: usize, b: usize) -> String {
    if b == 0 {
        "–".into()
    } else {
        format!("{:.1} %", 100.0 * a as f64 / b as f64)
    }
}

/// The tally columns' header (after the row's own columns).
const HEAD: &str = "wheel-surfaces within 150 ms | worst p95 | worst off by > 0.2 | false change flags (of flags) | step read, median [s] | worst [s] | steps later than 0.2 s | identifiable | identifiable at util ≥ 0.5 |";
const HEAD_N: usize = 9;

fn header(first: &[&str]) -> String {
    let mut s = format!("| {} | {HEAD}\n|", first.join(" | "));
    for _ in 0..first.len() + HEAD_N {
        s.push_str("---|");
    }
    s.push('\n');
    s
}

/// The wheel part of `seeds.md`: per seed and level the tally at [`RATE`], then per level the
/// worst over the seeds (the fewest wheel-surfaces within 150 ms by share, the largest p95 and
/// share off by > 0.2, the most false flags and late steps, the longest step reads, the lowest
/// share identifiable); nothing without wheel cases.
pub fn seeds(per_seed: &[(u64, &[(Level, Tally)])]) -> String {
    if per_seed.is_empty() {
        return String::new();
    }
    let mut md = format!("\n## Wheel cases at {RATE} Hz\n\n");
    md.push_str(&header(&["seed", "tyre on the car"]));
    for (seed, ts) in per_seed {
        for (level, t) in *ts {
            let _ = writeln!(md, "| {seed} | {} | {} |", level.name(), t.cells());
        }
    }
    let share = |a: usize, b: usize| if b == 0 { 1.0 } else { a as f64 / b as f64 };
    for level in Level::ALL {
        let ts: Vec<&Tally> = per_seed
            .iter()
            .flat_map(|(_, ts)| ts.iter().filter(|(l, _)| *l == level).map(|(_, t)| t))
            .collect();
        let Some(first) = ts.first() else { continue };
        let ws = ts
            .iter()
            .min_by(|a, b| share(a.ws.0, a.ws.1).total_cmp(&share(b.ws.0, b.ws.1)))
            .map_or(first.ws_cell(), |t| t.ws_cell());
        let p95 = ts
            .iter()
            .filter_map(|t| t.worst_p95)
            .fold(None, |a: Option<f64>, b| Some(a.map_or(b, |a| a.max(b))));
        let gross = ts.iter().map(|t| t.worst_gross).fold(0.0, f64::max);
        let flags = ts.iter().map(|t| t.flags.0).max().unwrap_or(0);
        // Step reads as text: "never" is the longest.
        let longest = |f: &dyn Fn(&Tally) -> String| {
            ts.iter()
                .map(|t| f(t))
                .max_by(|a, b| {
                    let v = |s: &str| match s {
                        "never" => f64::INFINITY,
                        "–" => f64::NEG_INFINITY,
                        x => x.parse().unwrap_or(f64::NEG_INFINITY),
                    };
                    v(a).total_cmp(&v(b))
                })
                .unwrap_or_else(|| "–".into())
        };
        let late = ts.iter().map(|t| t.steps_late()).max().unwrap_or(0);
        let ident = ts
            .iter()
            .map(|t| share(t.ident.0, t.ident.1))
            .fold(1.0, f64::min);
        let ident_hi = ts
            .iter()
            .map(|t| share(t.ident.2, t.ident.3))
            .fold(1.0, f64::min);
        let _ = writeln!(
            md,
            "| worst | {} | {ws} | {} | {:.2} % | {flags} | {} | {} | {late} of {} | {:.1} % | {:.1} % |",
            level.name(),
            fmt(p95, 3),
            100.0 * gross,
            longest(&|t| t.step_median()),
            longest(&|t| t.step_worst()),
            first.steps.len(),
            100.0 * ident,
            100.0 * ident_hi,
        );
    }
    md
}

/// The results of a run of the wheel cases, as the tables read them.
pub struct Run<'a> {
    /// The folder the tyres were read from, as given.
    pub dir: &'a Path,
    /// The tyres the cases ran on.
    pub tyres: &'a [Tyre],
    /// Files skipped, and why.
    pub skipped: &'a [(String, String)],
    /// The scenarios.
    pub scenarios: &'a [WheelScenario],
    /// The cases, and each one's result.
    pub cases: &'a [(WheelCase, Result<CaseResult, String>)],
    /// The noise seed.
    pub seed: u64,
    /// Whether the cases ran warm too.
    pub warm: bool,
}

impl Run<'_> {
    /// The tally of the cases that ran and `keep` keeps; `warm`: of their warm runs.
    pub fn tally(&self, keep: impl Fn(&WheelCase) -> bool, warm: bool) -> Tally {
        let mut t = Tally::default();
        for (c, r) in self.cases {
            if let Ok(r) = r {
                if keep(c) {
                    match (warm, &r.warm) {
                        (false, _) => t.add(&r.cold),
                        (true, Some(w)) => t.add(w),
                        (true, None) => {}
                    }
                }
            }
        }
        t
    }

    fn levels(&self, rate: f64) -> Vec<Level> {
        Level::ALL
            .into_iter()
            .filter(|l| {
                self.cases
                    .iter()
                    .any(|(c, _)| c.level == *l && c.rate == rate)
            })
            .collect()
    }

    fn tyres_run(&self) -> Vec<usize> {
        (0..self.tyres.len())
            .filter(|t| self.cases.iter().any(|(c, _)| c.tyre == *t))
            .collect()
    }
}

/// The closing lines over all tyres, one per level at [`RATE`] (what docs/estimator.md quotes).
pub fn summary(run: &Run) -> String {
    let mut s = String::new();
    let n_tyres = run.tyres_run().len();
    for level in run.levels(RATE) {
        let t = run.tally(|c| c.level == level && c.rate == RATE, false);
        let _ = writeln!(
            s,
            "wheel cases, {} ({n_tyres} tyres, {} cases at {RATE} Hz): within ±0.1 within {TARGET_LATENCY} s of utilisation 0.5 on {}; {} false change alarms of {} change flags; worst p95 error {}; worst share of samples identifiable and off by > {GROSS}: {:.2} % ({:.2} % without the model-mismatch indication, which is set on {:.1} % of the samples); surface steps read within {TARGET_STEP} s: {} of {} (median {}, worst {}); identifiable on {} of the samples, {} of those at utilisation 0.5 or more.",
            level.name(),
            t.cases,
            t.ws_cell(),
            t.flags.0,
            t.flags.1,
            fmt(t.worst_p95, 3),
            100.0 * t.worst_gross,
            100.0 * t.worst_gross_unflagged,
            100.0 * t.mismatch / t.ident.1.max(1) as f64,
            t.steps.len() - t.steps_late(),
            t.steps.len(),
            seconds(t.step_median()),
            seconds(t.step_worst()),
            pct(t.ident.0, t.ident.1),
            pct(t.ident.2, t.ident.3),
        );
    }
    s
}

/// A time of [`Tally::step_median`] or [`Tally::step_worst`] with its unit (a number: "0.425 s").
fn seconds(x: String) -> String {
    if x.parse::<f64>().is_ok() {
        format!("{x} s")
    } else {
        x
    }
}

/// "By tyre": the tyres (and the files skipped), then per tyre and level the tally of its cases
/// at [`RATE`], and the closing lines.
pub fn by_tyre(run: &Run) -> String {
    let mut md = format!(
        "\n## By tyre\n\n\
         Wheel cases (host/src/mu/bench/wheel): one wheel of every tyre file of {} that the \
         estimator accepts, at the tyre's own FNOMIN (load FNOMIN·(1 + 0.15 sin 2π·0.2t + 0.02 sin \
         2π·10t), 20 m/s), the estimator (bank, through `mu::Estimator`, every wheel as the file \
         describes its tyre, no preview) given the file; sensor noise scaled to each tyre, rms: Fx, \
         Fy, Fz 1 % of Fz, Mz 7.5e-4·FNOMIN·R0, κ 0.005; no delay; logged at {RATE} Hz; noise seed {}. \
         Each tyre on each scenario exact, and drawn from the envelope at 1× and 2× (next section). \
         Scenarios: {}. Step read: from the first row on the new surface to the estimate identifiable \
         within ±0.1 of the new μ and staying within ±0.1 from then (target {TARGET_STEP} s). Every case: \
         wheel_cases.csv.\n\n\
         | tyre | model | FNOMIN [N] | R0 [m] | μy0 | Mz noise [N·m] | pressure terms |\n\
         |---|---|---|---|---|---|---|\n",
        run.dir.display(),
        run.seed,
        run.scenarios
            .iter()
            .map(|s| s.name)
            .collect::<Vec<_>>()
            .join(", "),
    );
    for t in run.tyre_list() {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {:.3} | {:.3} | {} |",
            t.file,
            t.model(),
            t.params.fnomin,
            t.params.unloaded_radius,
            t.mu_y0,
            t.noise().1,
            if t.pressure { "yes" } else { "no" },
        );
    }
    if !run.skipped.is_empty() {
        md.push('\n');
        for (f, why) in run.skipped {
            let _ = writeln!(md, "Skipped: {f}: {why}.");
        }
    }
    md.push('\n');
    md.push_str(&header(&["tyre", "tyre on the car"]));
    for t in run.tyres_run() {
        for level in run.levels(RATE) {
            let tl = run.tally(|c| c.tyre == t && c.level == level && c.rate == RATE, false);
            if tl.cases > 0 {
                let _ = writeln!(
                    md,
                    "| {} | {} | {} |",
                    run.tyres[t].file,
                    level.name(),
                    tl.cells()
                );
            }
        }
    }
    md.push('\n');
    md.push_str(&summary(run));
    md
}

impl Run<'_> {
    fn tyre_list(&self) -> Vec<&Tyre> {
        self.tyres_run()
            .into_iter()
            .map(|t| &self.tyres[t])
            .collect()
    }
}

/// "A tyre that is not its file": the envelope, per level and per scenario and level over every
/// tyre at [`RATE`], the cases outside the limits per level, and the worst ones.
pub fn not_its_file(run: &Run) -> String {
    let mut md = String::from(
        "\n## A tyre that is not its file\n\n\
         The simulated tyre of every case is drawn from issue 55's envelope while the estimator is \
         given the file: cornering stiffness (λKy) ±10 %, longitudinal stiffness (λKx) ±10 %, peak \
         trail (λt) ±10 %, Fy and trail horizontal shifts (PHY1, QHZ1) ±2 mrad each, inflation \
         pressure (INFLPRES) ±15 % where the file has pressure terms; uniform, one draw per tyre, \
         scenario and seed. At 2× the same draw doubled. The draws are in wheel_cases.csv.\n\n",
    );
    md.push_str(&header(&["tyre on the car"]));
    for level in run.levels(RATE) {
        let t = run.tally(|c| c.level == level && c.rate == RATE, false);
        let _ = writeln!(md, "| {} | {} |", level.name(), t.cells());
    }
    md.push('\n');
    md.push_str(&header(&["scenario", "tyre on the car"]));
    for (i, s) in run.scenarios.iter().enumerate() {
        for level in run.levels(RATE) {
            let t = run.tally(
                |c| c.scenario == i && c.level == level && c.rate == RATE,
                false,
            );
            if t.cases > 0 {
                let _ = writeln!(md, "| {} | {} | {} |", s.name, level.name(), t.cells());
            }
        }
    }
    let _ = write!(
        md,
        "\nCases outside issue 55's limits (p95 > {TARGET_P95}, share off by > {GROSS} above {:.1} %, a false change flag, a step read later than {TARGET_STEP} s or never), and tyres under {:.0} % of their wheel-surfaces within 150 ms:\n\n\
         | tyre on the car | cases | p95 > {TARGET_P95} | off by > {GROSS} | false change flag | step late | tyres under {:.0} % |\n|---|---|---|---|---|---|---|\n",
        100.0 * TARGET_GROSS,
        100.0 * TARGET_WS,
        100.0 * TARGET_WS,
    );
    for level in run.levels(RATE) {
        let t = run.tally(|c| c.level == level && c.rate == RATE, false);
        let under = run
            .tyres_run()
            .into_iter()
            .filter(|&ty| {
                let x = run.tally(
                    |c| c.tyre == ty && c.level == level && c.rate == RATE,
                    false,
                );
                x.ws.1 > 0 && (x.ws.0 as f64) < TARGET_WS * x.ws.1 as f64
            })
            .count();
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {under} of {} |",
            level.name(),
            t.cases,
            t.outside[0],
            t.outside[1],
            t.outside[2],
            t.outside[3],
            run.tyres_run().len(),
        );
    }
    // The worst cases off the file: by share off by > 0.2, then p95.
    let mut worst: Vec<&(WheelCase, Result<CaseResult, String>)> = run
        .cases
        .iter()
        .filter(|(c, r)| c.level != Level::Exact && c.rate == RATE && r.is_ok())
        .collect();
    let key = |x: &&(WheelCase, Result<CaseResult, String>)| {
        x.1.as_ref()
            .map(|r| (r.cold.metrics.gross, r.cold.metrics.err_p95.unwrap_or(0.0)))
            .unwrap_or_default()
    };
    worst.sort_by(|a, b| {
        let (ka, kb) = (key(a), key(b));
        kb.0.total_cmp(&ka.0).then(kb.1.total_cmp(&ka.1))
    });
    worst.truncate(10);
    worst.retain(|x| key(x).0 > 0.0);
    if !worst.is_empty() {
        md.push_str(
            "\nThe worst cases off the file (share of samples identifiable and off by > 0.2, then p95):\n\n\
             | tyre | scenario | tyre on the car | λKy | λKx | λt | ΔPHY1 [mrad] | ΔQHZ1 [mrad] | pressure | p95 | off by > 0.2 | wheel-surfaces within 150 ms | steps read [s] |\n\
             |---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        );
        for (c, r) in worst {
            let Ok(r) = r else { continue };
            let d = &r.perturbation;
            let m = &r.cold.metrics;
            let steps: Vec<String> = r
                .cold
                .steps
                .iter()
                .map(|s| s.read.map_or("never".into(), |x| format!("{x:.3}")))
                .collect();
            let _ = writeln!(
                md,
                "| {} | {} | {} | {:.3} | {:.3} | {:.3} | {:+.2} | {:+.2} | {:.3} | {} | {:.2} % | {} of {} | {} |",
                run.tyres[c.tyre].file,
                run.scenarios[c.scenario].name,
                c.level.name(),
                d.ky,
                d.kx,
                d.trail,
                1000.0 * d.shy,
                1000.0 * d.sht,
                d.pressure,
                fmt(m.err_p95, 3),
                100.0 * m.gross,
                m.ws_within,
                m.ws_total,
                if steps.is_empty() { "–".into() } else { steps.join(", ") },
            );
        }
    }
    md
}

/// "Sample rates": the rate subset at each rate and level (the standard cases of the same
/// scenarios and levels at [`RATE`]); nothing when the run has no other rate.
pub fn sample_rates(run: &Run) -> String {
    let rates: Vec<f64> = RATES
        .into_iter()
        .filter(|r| run.cases.iter().any(|(c, _)| c.rate == *r))
        .collect();
    if rates.is_empty() {
        return String::new();
    }
    // The scenarios and levels run at another rate.
    let other = |c: &WheelCase| {
        run.cases.iter().any(|(o, _)| {
            o.rate != RATE && o.scenario == c.scenario && o.level == c.level && o.tyre == c.tyre
        })
    };
    let names: Vec<&str> = run
        .scenarios
        .iter()
        .enumerate()
        .filter(|(i, _)| {
            run.cases
                .iter()
                .any(|(c, _)| c.rate != RATE && c.scenario == *i)
        })
        .map(|(_, s)| s.name)
        .collect();
    let levels: Vec<&str> = Level::ALL
        .into_iter()
        .filter(|l| {
            run.cases
                .iter()
                .any(|(c, _)| c.rate != RATE && c.level == *l)
        })
        .map(Level::name)
        .collect();
    let n_tyres = (0..run.tyres.len())
        .filter(|t| {
            run.cases
                .iter()
                .any(|(c, _)| c.rate != RATE && c.tyre == *t)
        })
        .count();
    let mut md = format!(
        "\n## Sample rates\n\n\
         At {} Hz too: {} on {n_tyres} tyres, {}{}; beside them the same cases at {RATE} Hz.\n\n",
        rates
            .iter()
            .map(|r| r.to_string())
            .collect::<Vec<_>>()
            .join(" and "),
        names.join(", "),
        levels.join(" and "),
        if names.len() == RATE_SUBSET.len() {
            " (the scenarios with a step of the surface, whose read the rate bounds, and the μ-split, whose ABS cycles at 4 Hz)"
        } else {
            ""
        },
    );
    md.push_str(&header(&["rate [Hz]", "tyre on the car"]));
    let mut all = rates.clone();
    all.push(RATE);
    all.sort_by(f64::total_cmp);
    for rate in all {
        for level in Level::ALL {
            let t = run.tally(
                |c| c.rate == rate && c.level == level && (rate != RATE || other(c)),
                false,
            );
            if t.cases > 0 {
                let _ = writeln!(md, "| {rate} | {} | {} |", level.name(), t.cells());
            }
        }
    }
    md
}

/// "Warm start": per tyre and level at [`RATE`], and per level over all tyres, the cold run
/// and the warm one (each cell "cold / warm"); nothing when the run was not warm.
pub fn warm_start(run: &Run) -> String {
    if !run.warm {
        return String::new();
    }
    let mut md = String::from(
        "\n## Warm start\n\n\
         Every case run twice in a row on one estimator (its clock continued): cold is the first \
         run, warm the second, from the state the first left. Each cell: cold / warm.\n\n\
         | tyre | tyre on the car | wheel-surfaces within 150 ms | worst p95 | worst off by > 0.2 | false change flags | step read, median [s] | worst [s] | steps later than 0.2 s | identifiable |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    let row = |md: &mut String, name: &str, level: Level, keep: &dyn Fn(&WheelCase) -> bool| {
        let (c, w) = (run.tally(keep, false), run.tally(keep, true));
        if c.cases == 0 {
            return;
        }
        let _ = writeln!(
            md,
            "| {name} | {} | {} / {} | {} / {} | {:.2} % / {:.2} % | {} / {} | {} / {} | {} / {} | {} / {} | {} / {} |",
            level.name(),
            c.ws_cell(),
            w.ws_cell(),
            fmt(c.worst_p95, 3),
            fmt(w.worst_p95, 3),
            100.0 * c.worst_gross,
            100.0 * w.worst_gross,
            c.flags.0,
            w.flags.0,
            c.step_median(),
            w.step_median(),
            c.step_worst(),
            w.step_worst(),
            c.steps_late(),
            w.steps_late(),
            pct(c.ident.0, c.ident.1),
            pct(w.ident.0, w.ident.1),
        );
    };
    for level in run.levels(RATE) {
        row(&mut md, "all", level, &|c| {
            c.level == level && c.rate == RATE
        });
    }
    for t in run.tyres_run() {
        for level in run.levels(RATE) {
            row(&mut md, &run.tyres[t].file, level, &|c| {
                c.tyre == t && c.level == level && c.rate == RATE
            });
        }
    }
    md
}

/// "Wheel cases that did not run", with why; nothing when all ran.
pub fn failures(run: &Run) -> String {
    let failed: Vec<_> = run
        .cases
        .iter()
        .filter_map(|(c, r)| r.as_ref().err().map(|e| (c, e)))
        .collect();
    if failed.is_empty() {
        return String::new();
    }
    let mut md = String::from("\n## Wheel cases that did not run\n\n");
    for (c, e) in failed {
        let _ = writeln!(
            md,
            "- {} | {} | {} | {} Hz: {e}",
            run.tyres[c.tyre].file,
            run.scenarios[c.scenario].name,
            c.level.name(),
            c.rate
        );
    }
    md
}

/// Every section of the wheel cases, in `table.md`'s order.
pub fn markdown(run: &Run) -> String {
    [
        by_tyre(run),
        not_its_file(run),
        sample_rates(run),
        warm_start(run),
        failures(run),
    ]
    .concat()
}

/// The header of `wheel_cases.csv`.
pub const CSV_HEADER: &str = "tyre,scenario,level,rate_hz,seed,ky,kx,trail,shy_rad,sht_rad,pressure,samples,identifiable,samples_util05,identifiable_util05,err_mean,err_p95,within_2sigma,gross,gross_unflagged,mismatch,ws_within,ws_total,change_flags,false_change_flags,steps,step_reads_s,steps_late,warm_identifiable,warm_err_p95,warm_gross,warm_ws_within,warm_change_flags,warm_false_change_flags,warm_step_reads_s,warm_steps_late,error\n";

fn outcome_cells(o: &Outcome) -> String {
    let m = &o.metrics;
    format!(
        "{},{},{},{},{},{},{},{:.5},{:.5},{:.5},{},{},{},{},{},{},{}",
        m.n_samples,
        m.n_identifiable,
        m.n_util_hi,
        m.n_identifiable_util_hi,
        fmt(m.err_mean, 4),
        fmt(m.err_p95, 4),
        fmt(m.within_2sigma, 4),
        m.gross,
        m.gross_unflagged,
        m.mismatch,
        m.ws_within,
        m.ws_total,
        m.change_flags,
        m.false_alarms,
        o.steps.len(),
        reads(o),
        o.steps.iter().filter(|s| !s.in_time()).count(),
    )
}

/// The step reads of an outcome, `;`-separated \[s\] ("never": not read).
fn reads(o: &Outcome) -> String {
    o.steps
        .iter()
        .map(|s| s.read.map_or("never".into(), |x| format!("{x:.3}")))
        .collect::<Vec<_>>()
        .join(";")
}

/// `wheel_cases.csv`: one row per case, its perturbation and every metric (cold, and warm with
/// `--warm`; a case that did not run has its error and empty figures).
pub fn csv(run: &Run) -> String {
    let mut s = String::from(CSV_HEADER);
    for (c, r) in run.cases {
        let _ = write!(
            s,
            "{},{},{},{},{},",
            csv_field(&run.tyres[c.tyre].file),
            csv_field(run.scenarios[c.scenario].name),
            c.level.name(),
            c.rate,
            run.seed,
        );
        match r {
            Ok(r) => {
                let d = &r.perturbation;
                let _ = write!(
                    s,
                    "{:.6},{:.6},{:.6},{:.7},{:.7},{:.6},{},",
                    d.ky,
                    d.kx,
                    d.trail,
                    d.shy,
                    d.sht,
                    d.pressure,
                    outcome_cells(&r.cold)
                );
                match &r.warm {
                    Some(w) => {
                        let m = &w.metrics;
                        let _ = writeln!(
                            s,
                            "{},{},{:.5},{},{},{},{},{},",
                            m.n_identifiable,
                            fmt(m.err_p95, 4),
                            m.gross,
                            m.ws_within,
                            m.change_flags,
                            m.false_alarms,
                            reads(w),
                            w.steps.iter().filter(|s| !s.in_time()).count(),
                        );
                    }
                    None => s.push_str(",,,,,,,,\n"),
                }
            }
            Err(e) => {
                let _ = writeln!(s, "{}{}", ",".repeat(31), csv_field(e));
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mu::bench::metrics::{Metrics, StepRead};

    /// A tally adds wheel-surfaces, flags, samples and steps, keeps the worst p95 and gross,
    /// and counts a step never read as the longest and as late.
    #[test]
    fn a_tally_adds_up_and_keeps_the_worst() {
        let step = |read| StepRead {
            wheel: 0,
            from: 1.0,
            to: 0.3,
            t_step: 4.0,
            read,
        };
        let o = |p95, gross, steps: Vec<StepRead>| Outcome {
            metrics: Metrics {
                err_p95: p95,
                gross,
                ws_within: 1,
                ws_total: 2,
                false_alarms: 1,
                change_flags: 3,
                n_identifiable: 10,
                n_samples: 40,
                ..Metrics::default()
            },
            steps,
        };
        let mut t = Tally::default();
        t.add(&o(Some(0.05), 0.001, vec![step(Some(0.1))]));
        t.add(&o(Some(0.09), 0.0, vec![step(Some(0.3)), step(Some(0.15))]));
        t.add(&o(None, 0.01, vec![]));
        assert_eq!((t.cases, t.ws, t.flags), (3, (3, 6), (3, 9)));
        assert_eq!((t.worst_p95, t.worst_gross), (Some(0.09), 0.01));
        assert_eq!(
            (t.step_median(), t.step_worst(), t.steps_late()),
            ("0.150".into(), "0.300".into(), 1)
        );
        assert_eq!(t.outside, [1, 1, 3, 1]);
        assert_eq!(t.ws_cell(), "3 of 6 (50.0 %)");
        t.add(&o(None, 0.0, vec![step(None), step(None)]));
        // Never read: the longest (the median of five is now the third, 0.3 s), and late.
        assert_eq!(
            (t.step_median(), t.step_worst(), t.steps_late()),
            ("0.300".into(), "never".into(), 3)
        );
        assert_eq!(Tally::default().step_median(), "–");
    }
}
