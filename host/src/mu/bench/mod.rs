//! `gough mu bench` and `gough mu demo`: the estimators against simulated truth.
//!
//! The plant is the host vehicle simulation (`crate::sim`) on the bundled tyre; its per-wheel
//! Fy, Mz, Fz, Fx pass through a sensor model — additive Gaussian noise (Mz 2 N·m rms, Fy, Fx and
//! Fz 1 % of Fz rms, seeded) and a 10 ms pure delay — before any estimator sees them. The
//! peers additionally get the (delayed, exact) slip angle and slip ratio, which the Gough method
//! never reads.
//!
//! Metrics per estimator and case, over the four wheels:
//! - μ error |μ̂ − μ| (mean and 95th percentile) over the samples the estimator calls
//!   identifiable, and the share of them within twice the σ reported (whether σ is honest);
//! - the utilisation |F|/(μ·Fz) (architecture.md) reached when the reported estimate first stays
//!   within ±0.1 of the truth until the end of its surface (median over wheels);
//! - latency: time from the utilisation first reaching 0.5 on a surface to the estimate staying
//!   within ±0.1 (median over wheels);
//! - for surfaces that change: the time from the wheel entering the new surface to the estimate
//!   staying within ±0.1 of it;
//! - change flags, and the false ones among them ([`false_change_flags`]: no change of road
//!   since the identification they change from, or a wrong new value).

pub mod cases;
pub mod metrics;
pub mod plots;
pub mod sensors;
pub mod tables;

pub use cases::{
    model_with_error, sim_wheelbase, simulate_case, straight_stop, suite, suite_shifted, Case,
};
pub use metrics::{
    common, false_change_flags, hold_tally, metrics, segment_latency, wheel_surfaces, Common,
    HoldTally, Metrics, WheelSurface, GROSS, TARGET_LATENCY,
};
pub(crate) use metrics::{median, segments};
pub use sensors::{measure, Sensors, WheelTrace};
pub(crate) use tables::csv_field;

use super::peers::{HsuGerdes, SlipSlope};
use super::table_estimator::{Config, Estimate, GoughTable, MuEstimator};
use clap::Args;
use gough::math::Libm;
use gough::mf::Params;
use plots::plot_mu;
use std::fmt::Write as _;
use std::path::PathBuf;
use tables::{against_the_others, fmt, hold_tables, misses_table, WHEELS};

/// Arguments of `gough mu bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// Tyre property file (.tir).
    #[arg(
        long,
        default_value = "host-tests/data/tyres/MagicFormula61_Parameters.tir"
    )]
    pub tir: PathBuf,
    /// Output directory for the table (table.md, table.csv) and the plots.
    #[arg(long, default_value = "out/mu_bench")]
    pub out: PathBuf,
    /// Noise seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Only the first N cases (for a quick look).
    #[arg(long)]
    pub cases: Option<usize>,
    /// A setting of the Gough estimator's `Config` other than its default, as NAME=VALUE
    /// (the field's name, e.g. `trail_drop_min=0.1`); repeatable, or comma-separated.
    #[arg(long = "set", value_name = "NAME=VALUE", value_delimiter = ',')]
    pub set: Vec<String>,
    /// Aligning-torque sensor noise, rms \[N·m\], added to every row the estimators see. The
    /// sensors, not the estimator: what the estimator assumes is its own `sigma_mz` (`--set`).
    #[arg(long, value_name = "NM", allow_negative_numbers = true, default_value_t = Sensors::default().sigma_mz)]
    pub noise_mz: f64,
    /// Force sensor noise (Fy, Fx, Fz), rms, as a fraction of Fz \[-\]; the estimator's own
    /// assumption is `sigma_fy_rel` (`--set`).
    #[arg(long, value_name = "FRACTION", allow_negative_numbers = true, default_value_t = Sensors::default().sigma_rel)]
    pub noise_f: f64,
    /// Pure delay of every measured channel \[s\] (rounded to the simulation's step, 1 ms).
    #[arg(long, value_name = "S", allow_negative_numbers = true, default_value_t = Sensors::default().delay)]
    pub delay: f64,
    /// Weight of the bank's front-to-rear preview (`gough::mu::preview`: what a front wheel
    /// read, handed to the rear wheel on its side a wheelbase later), inside (0, 1); 0: every
    /// wheel alone.
    #[arg(long, value_name = "W", default_value_t = 0.9)]
    pub preview: f64,
    /// Shift every surface's μ in the suite by D (0.025: midway between two of the bank's
    /// hypotheses, which the suite's own surfaces coincide with); |D| ≤ 0.05.
    #[arg(
        long,
        value_name = "D",
        allow_negative_numbers = true,
        default_value_t = 0.0
    )]
    pub mu_shift: f64,
    /// A tyre model that is not the tyre: NAME=DELTA adds DELTA to the `.tir` parameter NAME
    /// of the estimators' copy of the file only (e.g. `PHY1=0.002`: its horizontal shift 2 mrad
    /// off), the simulation keeps the file; repeatable, or comma-separated. How the estimators
    /// fare when the file they are given is wrong.
    #[arg(
        long = "model-error",
        value_name = "NAME=DELTA",
        value_delimiter = ',',
        allow_hyphen_values = true
    )]
    pub model_error: Vec<String>,
}

impl BenchArgs {
    /// The preview these arguments ask for over the simulated vehicle's wheelbase (`None`:
    /// `--preview 0`).
    pub fn preview(&self) -> Result<Option<gough::mu::preview::Config<f64>>, String> {
        if self.preview == 0.0 {
            return Ok(None);
        }
        if !(self.preview > 0.0 && self.preview < 1.0) {
            return Err(format!(
                "--preview {}: a weight inside (0, 1), or 0 for none",
                self.preview
            ));
        }
        Ok(Some(gough::mu::preview::Config {
            wheelbase: sim_wheelbase(),
            weight: self.preview,
        }))
    }

    /// The sensor model these arguments ask for: each value finite and ≥ 0, the delay at most
    /// 1 s.
    pub fn sensors(&self) -> Result<Sensors, String> {
        for (name, v, max) in [
            ("--noise-mz", self.noise_mz, f64::MAX),
            ("--noise-f", self.noise_f, f64::MAX),
            ("--delay", self.delay, 1.0),
        ] {
            if !(v.is_finite() && (0.0..=max).contains(&v)) {
                return Err(format!(
                    "{name} {v}: expected a finite value from 0 to {}",
                    if max < f64::MAX { "1 s" } else { "any size" }
                ));
            }
        }
        Ok(Sensors {
            sigma_mz: self.noise_mz,
            sigma_rel: self.noise_f,
            delay: self.delay,
            ..Sensors::default()
        })
    }
}

/// Sets one field of the estimator's configuration from `NAME=VALUE` (the field's name as in
/// [`Config`]; SI units as documented there).
pub fn set_config(c: &mut Config<f64>, kv: &str) -> Result<(), String> {
    let (k, v) = kv
        .split_once('=')
        .ok_or_else(|| format!("--set {kv}: expected NAME=VALUE"))?;
    let (k, v) = (k.trim(), v.trim());
    let num = || -> Result<f64, String> {
        v.parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("--set {k}: '{v}' is not a finite number"))
    };
    let count = || -> Result<u16, String> {
        v.parse::<u16>()
            .map_err(|_| format!("--set {k}: '{v}' is not a count (0..=65535)"))
    };
    let f = match k {
        "change_count" => {
            c.change_count = count()?;
            return Ok(());
        }
        "init_count" => {
            c.init_count = count()?;
            return Ok(());
        }
        "gamma" => &mut c.gamma,
        "sigma_mz" => &mut c.sigma_mz,
        "sigma_fy_rel" => &mut c.sigma_fy_rel,
        "vx_min" => &mut c.vx_min,
        "fz_min_rel" => &mut c.fz_min_rel,
        "fy_min_rel" => &mut c.fy_min_rel,
        "fy_share_min" => &mut c.fy_share_min,
        "trail_drop_min" => &mut c.trail_drop_min,
        "trail_drop_abs_min" => &mut c.trail_drop_abs_min,
        "sigma_max" => &mut c.sigma_max,
        "trail_model_rel" => &mut c.trail_model_rel,
        "arm_model_rel" => &mut c.arm_model_rel,
        "combined_model_rel" => &mut c.combined_model_rel,
        "combined_force_rel" => &mut c.combined_force_rel,
        "mzr_model_rel" => &mut c.mzr_model_rel,
        "q" => &mut c.q,
        "gate" => &mut c.gate,
        "gate_sigma_max" => &mut c.gate_sigma_max,
        "change_min" => &mut c.change_min,
        "run_gap" => &mut c.run_gap,
        "mu_prior" => &mut c.mu_prior,
        "sigma_prior" => &mut c.sigma_prior,
        "lowpass_tau" => &mut c.lowpass_tau,
        "settle" => &mut c.settle,
        "settle_distance" => &mut c.settle_distance,
        "ambiguity_sigmas" => &mut c.ambiguity_sigmas,
        "ambiguity_margin" => &mut c.ambiguity_margin,
        _ => {
            return Err(format!(
                "--set {k}: no such setting of the estimator's Config"
            ))
        }
    };
    *f = num()?;
    Ok(())
}

/// Arguments of `gough mu demo`.
#[derive(Args)]
pub struct DemoArgs {
    /// Tyre property file (.tir).
    #[arg(
        long,
        default_value = "host-tests/data/tyres/MagicFormula61_Parameters.tir"
    )]
    pub tir: PathBuf,
    /// Manoeuvre (one of the simulation's).
    #[arg(long, default_value = "sine-dwell")]
    pub manoeuvre: String,
    /// Road (the simulation's spec grammar).
    #[arg(long, default_value = "mu=1.0+patch=0.4@45..300")]
    pub road: String,
    /// Output directory (estimates.csv, mu.png, gough.png).
    #[arg(long, default_value = "out/demo")]
    pub out: PathBuf,
    /// Noise seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// The estimators compared.
pub const METHODS: [&str; 4] = ["gough", "hsu-gerdes", "slip-slope", "bank"];

/// Index of the bank (the product's estimator) in [`METHODS`].
pub(super) const BANK: usize = 3;

/// The Gough tables of the left and right wheels: the simulation mounts the tyre on both sides
/// (mirrored where the side differs from the file's TYRESIDE), so does the estimator.
pub struct Tables {
    left: Box<GoughTable<f64>>,
    right: Box<GoughTable<f64>>,
}

impl Tables {
    /// For both sides of the vehicle.
    pub fn new(p: &Params<f64>) -> Result<Tables, String> {
        use gough::mf::Side;
        Ok(Tables {
            left: super::table::<f64, Libm>(p, Some(Side::Left))?,
            right: super::table::<f64, Libm>(p, Some(Side::Right))?,
        })
    }
    /// Table of wheel `w` (fl, fr, rl, rr).
    pub fn wheel(&self, w: usize) -> &GoughTable<f64> {
        if w.is_multiple_of(2) {
            &self.left
        } else {
            &self.right
        }
    }
}

/// Runs estimator `m` (index into [`METHODS`]) over wheel `w`'s trace.
pub fn run_method(
    m: usize,
    p: &Params<f64>,
    tables: &Tables,
    w: usize,
    tr: &WheelTrace,
) -> Vec<Estimate<f64>> {
    match m {
        0 => run_gough(p, tables, w, tr, &Config::default()).0,
        3 => run_bank(p, w, tr),
        1 => match HsuGerdes::new(p) {
            Some(mut e) => tr.rows.iter().map(|r| e.update(r)).collect(),
            None => Vec::new(),
        },
        _ => match SlipSlope::new(p) {
            Some(mut e) => tr.rows.iter().map(|r| e.update(r)).collect(),
            None => Vec::new(),
        },
    }
}

/// The bank estimator over wheel `w`'s trace (mounted on the wheel's side, measured κ), alone.
pub fn run_bank(p: &Params<f64>, w: usize, tr: &WheelTrace) -> Vec<Estimate<f64>> {
    let Some(mut e) = new_bank(p, w) else {
        return Vec::new();
    };
    (0..tr.rows.len())
        .map(|i| super::bank_estimate(e.update::<Libm>(p, &bank_row(tr, i))))
        .collect()
}

fn new_bank(p: &Params<f64>, w: usize) -> Option<gough::mu::bank::Bank<f64>> {
    let side = gough::proto::Wheel::from_index(w).map(|x| x.side());
    gough::mu::bank::Bank::new::<Libm>(p, side, gough::mu::bank::Config::default()).ok()
}

/// Row `i` of a trace as the bank's sample (Fx, measured κ, Vx, camber).
fn bank_row(tr: &WheelTrace, i: usize) -> gough::mu::bank::Sample<f64> {
    let mut r = tr.rows[i];
    r.kappa = tr.kappa_meas.get(i).copied().unwrap_or(f64::NAN);
    super::bank_sample(&r, true, true, tr.gamma.get(i).copied())
}

/// The bank over a vehicle's four wheels (fl, fr, rl, rr, sampled together), sample by sample
/// as the firmware runs them: each front wheel, then each rear wheel with what its front wheel
/// read handed on a wheelbase later ([`gough::mu::preview`], `preview`; `None`: every wheel
/// alone). Traces of other lengths than four, or not of one length, run wheel by wheel alone.
pub fn run_banks(
    p: &Params<f64>,
    traces: &[WheelTrace],
    preview: Option<gough::mu::preview::Config<f64>>,
) -> Vec<Vec<Estimate<f64>>> {
    use gough::mu::preview::Preview;
    let n = traces.first().map_or(0, |t| t.rows.len());
    let together = traces.len() == 4 && traces.iter().all(|t| t.rows.len() == n);
    let (Some(cfg), true) = (preview, together) else {
        return traces
            .iter()
            .enumerate()
            .map(|(w, tr)| run_bank(p, w, tr))
            .collect();
    };
    let banks: Option<Vec<_>> = (0..4).map(|w| new_bank(p, w)).collect();
    let (Some(mut banks), Ok(pv)) = (banks, Preview::new(cfg)) else {
        return vec![Vec::new(); traces.len()];
    };
    let mut pvs = [pv.clone(), pv];
    let mut out: Vec<Vec<_>> = (0..4).map(|_| Vec::with_capacity(n)).collect();
    for i in 0..n {
        for (w, (bank, o)) in banks.iter_mut().zip(out.iter_mut()).enumerate() {
            let s = bank_row(&traces[w], i);
            let e = gough::mu::preview::update::<f64, Libm>(Some(&mut pvs), w, bank, p, &s);
            o.push(super::bank_estimate(e));
        }
    }
    out
}

/// The Gough estimator (settings `cfg`) over wheel `w`'s trace: its estimates and, per sample,
/// why each held estimate was held ([`MuEstimator::last_hold`]).
pub fn run_gough(
    p: &Params<f64>,
    tables: &Tables,
    w: usize,
    tr: &WheelTrace,
    cfg: &Config<f64>,
) -> super::Run {
    let mut e = MuEstimator::for_tyre(tables.wheel(w), p, *cfg);
    (0..tr.rows.len())
        .map(|i| (e.update::<Libm>(&tr.sample(i)), e.last_hold()))
        .unzip()
}

/// Runs the benchmark.
pub fn run(a: BenchArgs) -> Result<(), String> {
    let mut cfg = Config::default();
    for kv in &a.set {
        set_config(&mut cfg, kv)?;
    }
    let sensors = a.sensors()?;
    let t = crate::tyre::load(&a.tir)?;
    // `sim`: the tyre the simulation runs; `p`: the estimators' model of it (the same file
    // unless `--model-error`).
    let sim = t.params;
    let p = model_with_error(&sim, &a.model_error)?;
    let tables = Tables::new(&p)?;
    if !(a.mu_shift.is_finite() && a.mu_shift.abs() <= 0.05) {
        return Err(format!(
            "--mu-shift {}: expected a value from -0.05 to 0.05",
            a.mu_shift
        ));
    }
    let mut cases = suite_shifted(a.mu_shift);
    if let Some(n) = a.cases {
        cases.truncate(n);
    }
    std::fs::create_dir_all(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let mut md = String::new();
    if !a.model_error.is_empty() {
        let _ = writeln!(
            md,
            "Model error (`--model-error`): the estimators' tyre is {} with {}; the simulation's is the file.\n",
            a.tir.display(),
            a.model_error.join(", ")
        );
    }
    let _ = writeln!(md, "| manoeuvre | road | estimator | identifiable samples | mean err | p95 err | within 2σ | off by > 0.2 | util when within ±0.1 | latency from util 0.5 [s] | detect change [s] | false alarms |");
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|---|---|---|");
    let mut csv = String::from("manoeuvre,road,estimator,n_identifiable,err_mean,err_p95,within_2sigma,gross,util_within,latency_s,detect_s,false_alarms,ws_within,ws_total\n");
    let mut wheels_csv =
        String::from("manoeuvre,road,wheel,mu,t_start_s,t_end_s,t_util05_s,latency_s,within\n");
    let mut misses: Vec<(&Case, WheelSurface)> = Vec::new();
    let bar = indicatif::ProgressBar::new(cases.len() as u64);
    let mut tallies: Vec<(&Case, HoldTally)> = Vec::new();
    let mut gough_wins = 0;
    let mut comparable = 0;
    let mut within = [0usize; METHODS.len()];
    let mut ws = [(0usize, 0usize); METHODS.len()];
    // The same over the issue's cases: the suite without the straight ABS stops.
    let mut within_issue = [0usize; METHODS.len()];
    let mut ws_issue = [(0usize, 0usize); METHODS.len()];
    let issue_cases = cases.iter().filter(|c| !straight_stop(c)).count();
    let mut alarms = [0usize; METHODS.len()];
    let mut flags = [0usize; METHODS.len()];
    let mut worst: [Option<f64>; METHODS.len()] = [None; METHODS.len()];
    let mut worst_gross = [0.0f64; METHODS.len()];
    // Identifiable samples over the suite: (identifiable, all, identifiable at utilisation
    // ≥ 0.5, all at ≥ 0.5).
    let mut shares = [(0usize, 0usize, 0usize, 0usize); METHODS.len()];
    let mut per_case: Vec<(&Case, Vec<Metrics>, Vec<Common>)> = Vec::new();
    for c in &cases {
        bar.set_message(format!("{} on {}", c.manoeuvre, c.road));
        let log = simulate_case(&sim, c)?;
        let traces: Vec<WheelTrace> = (0..4).map(|w| measure(&log, w, &sensors, a.seed)).collect();
        let mut ms = Vec::new();
        let mut all_ests: Vec<Vec<Vec<Estimate<f64>>>> = Vec::new();
        for (m, method) in METHODS.iter().enumerate() {
            let ests: Vec<Vec<Estimate<f64>>> = if m == 0 {
                let (ests, holds): (Vec<_>, Vec<_>) = traces
                    .iter()
                    .enumerate()
                    .map(|(w, tr)| run_gough(&p, &tables, w, tr, &cfg))
                    .unzip();
                tallies.push((c, hold_tally(&traces, &ests, &holds)));
                ests
            } else if m == BANK {
                run_banks(&p, &traces, a.preview()?)
            } else {
                traces
                    .iter()
                    .enumerate()
                    .map(|(w, tr)| run_method(m, &p, &tables, w, tr))
                    .collect()
            };
            let mt = metrics(&traces, &ests);
            if m == BANK {
                for x in wheel_surfaces(&traces, &ests) {
                    let _ = writeln!(
                        wheels_csv,
                        "{},{},{},{},{:.3},{:.3},{:.3},{},{}",
                        csv_field(c.manoeuvre),
                        csv_field(&c.road),
                        WHEELS.get(x.wheel).copied().unwrap_or("?"),
                        x.mu,
                        x.t_start,
                        x.t_end,
                        x.t_util05,
                        fmt(x.latency, 3),
                        x.within()
                    );
                    if !x.within() {
                        misses.push((c, x));
                    }
                }
            }
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {} | {} | {:.2} % | {} | {} | {} | {} |",
                c.manoeuvre,
                c.road,
                method,
                mt.n_identifiable,
                fmt(mt.err_mean, 3),
                fmt(mt.err_p95, 3),
                mt.within_2sigma
                    .map_or("–".into(), |x| format!("{:.1} %", 100.0 * x)),
                100.0 * mt.gross,
                fmt(mt.util_within, 2),
                fmt(mt.latency, 3),
                fmt(mt.detect, 3),
                if m == 0 {
                    mt.false_alarms.to_string()
                } else {
                    "n/a".into()
                }
            );
            let _ = writeln!(
                csv,
                "{},{},{},{},{},{},{},{:.5},{},{},{},{},{},{}",
                csv_field(c.manoeuvre),
                csv_field(&c.road),
                method,
                mt.n_identifiable,
                fmt(mt.err_mean, 4),
                fmt(mt.err_p95, 4),
                fmt(mt.within_2sigma, 4),
                mt.gross,
                fmt(mt.util_within, 3),
                fmt(mt.latency, 4),
                fmt(mt.detect, 4),
                mt.false_alarms,
                mt.ws_within,
                mt.ws_total
            );
            let in_time = mt.latency.is_some_and(|l| l <= TARGET_LATENCY + 1e-9);
            within[m] += usize::from(in_time);
            ws[m].0 += mt.ws_within;
            ws[m].1 += mt.ws_total;
            if !straight_stop(c) {
                within_issue[m] += usize::from(in_time);
                ws_issue[m].0 += mt.ws_within;
                ws_issue[m].1 += mt.ws_total;
            }
            alarms[m] += mt.false_alarms;
            flags[m] += mt.change_flags;
            shares[m].0 += mt.n_identifiable;
            shares[m].1 += mt.n_samples;
            shares[m].2 += mt.n_identifiable_util_hi;
            shares[m].3 += mt.n_util_hi;
            worst_gross[m] = worst_gross[m].max(mt.gross);
            worst[m] = match (worst[m], mt.err_p95) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            };
            ms.push(mt);
            all_ests.push(ests);
        }
        // Each other estimator against the bank on the samples both call identifiable (the
        // bank's own entry left empty).
        let commons: Vec<Common> = all_ests
            .iter()
            .enumerate()
            .map(|(m, e)| {
                if m == BANK {
                    Common::default()
                } else {
                    common(&traces, &all_ests[BANK], e)
                }
            })
            .collect();
        // "Better than both peers where they produce an estimate": compare p95 error.
        for peer in &ms[1..3] {
            if let (Some(g), Some(q)) = (ms[0].err_p95, peer.err_p95) {
                comparable += 1;
                if g <= q {
                    gough_wins += 1;
                }
            }
        }
        if c.road.contains("patch") || c.road.contains("step") {
            let name = format!(
                "{}_{}",
                c.manoeuvre,
                c.road.replace(['=', '+', '@', '.', ',', '/'], "_")
            );
            // The front-left wheel's estimates, the bank's and the table estimator's.
            plot_mu(
                &traces[0],
                &[
                    ("bank", &all_ests[BANK][0]),
                    ("gough (table)", &all_ests[0][0]),
                ],
                &a.out.join(format!("mu_{name}.png")),
                &format!("{} on {} (front left)", c.manoeuvre, c.road),
            )?;
        }
        per_case.push((c, ms, commons));
        bar.inc(1);
    }
    bar.finish_and_clear();
    let mut summary = format!("\nThe table estimator (`gough`) at or below both peers' p95 error in {gough_wins} of {comparable} comparisons where a peer produced an estimate.\n");
    for (m, name) in METHODS.iter().enumerate() {
        let _ = writeln!(
            summary,
            "{name}: within ±0.1 within {TARGET_LATENCY} s of utilisation 0.5 on {} of {} cases and {} of {} wheel-surfaces; {} false change alarms of {} change flags; worst p95 error {}; worst share of samples identifiable and off by > {GROSS}: {:.2} %.",
            within[m],
            cases.len(),
            ws[m].0,
            ws[m].1,
            alarms[m],
            flags[m],
            fmt(worst[m], 3),
            100.0 * worst_gross[m],
        );
    }
    for (m, name) in METHODS.iter().enumerate() {
        let _ = writeln!(
            summary,
            "{name}, without the straight ABS stops: within ±0.1 within {TARGET_LATENCY} s of utilisation 0.5 on {} of {issue_cases} cases and {} of {} wheel-surfaces.",
            within_issue[m], ws_issue[m].0, ws_issue[m].1,
        );
    }
    for (m, name) in METHODS.iter().enumerate() {
        let (i, n, ih, nh) = shares[m];
        let pct = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
        let _ = writeln!(
            summary,
            "{name}: identifiable on {:.1} % of the suite's samples ({i} of {n}), {:.1} % of those at utilisation 0.5 or more ({ih} of {nh}).",
            pct(i, n),
            pct(ih, nh),
        );
    }
    md.push_str(&summary);
    md.push_str(&against_the_others(&per_case));
    md.push_str(&misses_table(&misses));
    if !a.set.is_empty() {
        let _ = writeln!(
            md,
            "\nThe Gough estimator ran with these settings changed from their defaults: {}.",
            a.set.join(", ")
        );
    }
    if a.mu_shift != 0.0 {
        let _ = writeln!(
            md,
            "\nEvery surface of the suite shifted by {:+} (the road specs above are the shifted ones).",
            a.mu_shift
        );
    }
    if sensors != Sensors::default() {
        let _ = writeln!(
            md,
            "\nSensor model changed from the default: Mz {} N·m rms, F {:.2} % Fz rms, {:.1} ms delay.",
            sensors.sigma_mz,
            100.0 * sensors.sigma_rel,
            1000.0 * sensors.delay
        );
    }
    let (holds_md, holds_csv) = hold_tables(&tallies);
    md.push_str(&holds_md);
    std::fs::write(a.out.join("table.md"), &md).map_err(|e| e.to_string())?;
    std::fs::write(a.out.join("table.csv"), &csv).map_err(|e| e.to_string())?;
    std::fs::write(a.out.join("holds.csv"), &holds_csv).map_err(|e| e.to_string())?;
    std::fs::write(a.out.join("wheels.csv"), &wheels_csv).map_err(|e| e.to_string())?;
    print!("{md}");
    eprintln!(
        "-> {}/table.md, table.csv, wheels.csv, holds.csv, mu_*.png",
        a.out.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::table_estimator::State;
    use super::*;
    use crate::tyre::bundled;

    /// Every field of the estimator's `Config` can be set by name (and only it), to the value
    /// given; a bad value or name is an error naming it.
    #[test]
    fn set_config_reaches_every_field() {
        let names = [
            "gamma",
            "sigma_mz",
            "sigma_fy_rel",
            "vx_min",
            "fz_min_rel",
            "fy_min_rel",
            "fy_share_min",
            "trail_drop_min",
            "trail_drop_abs_min",
            "sigma_max",
            "trail_model_rel",
            "arm_model_rel",
            "combined_model_rel",
            "combined_force_rel",
            "mzr_model_rel",
            "q",
            "gate",
            "gate_sigma_max",
            "change_min",
            "change_count",
            "run_gap",
            "init_count",
            "mu_prior",
            "sigma_prior",
            "lowpass_tau",
            "settle",
            "settle_distance",
            "ambiguity_sigmas",
            "ambiguity_margin",
        ];
        let mut all = Config::default();
        for n in names {
            let mut c = Config::default();
            set_config(&mut c, &format!("{n}=7")).unwrap();
            assert_ne!(c, Config::default(), "{n}");
            set_config(&mut all, &format!(" {n} = 7 ")).unwrap();
        }
        // Every field set: the Debug form holds no default value any more but 7s.
        let dbg = format!("{all:?}");
        let values: Vec<&str> = dbg
            .split(", ")
            .map(|kv| kv.rsplit(": ").next().unwrap().trim_end_matches(" }"))
            .collect();
        assert_eq!(values.len(), names.len(), "{dbg}");
        assert!(values.iter().all(|v| *v == "7.0" || *v == "7"), "{dbg}");
        for bad in [
            "q",
            "q=",
            "q=nan",
            "q=inf",
            "init_count=-1",
            "init_count=0.5",
            "nope=1",
        ] {
            let e = set_config(&mut Config::default(), bad).unwrap_err();
            assert!(e.contains(bad.split('=').next().unwrap()), "{bad}: {e}");
        }
    }

    /// Straight running with a static camber makes points that read like ice at full sliding:
    /// the camber thrust alone passes `fy_min_rel` (|Fy|/Fz ≈ 0.05 at 0.85·Fz0) and the
    /// residual torque leaves a trail of a few mm (Fy ≈ 300 N, Mz ≈ −2 N·m), so the trail looks
    /// collapsed and the reading says μ ≈ 0.05. Every per-reading check passes many of them
    /// ([`MuEstimator::raw`] returns a reading: 320 here). They come in runs; it is
    /// `init_count` that keeps them from becoming an estimate: with it at 1 this test counts
    /// 22 wrong estimates below a utilisation of 0.2 (and over the whole bench suite, 36; a
    /// scratch run). At 6 none, but then a burst at higher utilisation in the slalom on μ 1.0
    /// becomes a wrong estimate (p95 error 0.68 there): 13 stays.
    #[test]
    fn straight_running_with_camber_never_reads_ice() {
        let p = bundled();
        let tables = Tables::new(&p).unwrap();
        let (mut hazards, mut wrong, mut right) = (0, 0, 0);
        for manoeuvre in ["sine-dwell", "slalom"] {
            let case = Case {
                manoeuvre,
                road: "mu=1.0".into(),
            };
            let log = simulate_case(&p, &case).unwrap();
            for w in 0..4 {
                let tr = measure(&log, w, &Sensors::default(), 1);
                let est = run_method(0, &p, &tables, w, &tr);
                let probe = MuEstimator::for_tyre(tables.wheel(w), &p, Config::default());
                for (i, e) in est.iter().enumerate() {
                    let low = tr.util[i] < 0.2;
                    // What one reading of the sample (unfiltered) says.
                    let raw = probe.raw::<Libm>(&tr.sample(i));
                    if low && raw.is_some_and(|x| (x.lambda * probe.mu0() - 1.0).abs() > 0.5) {
                        hazards += 1;
                    }
                    if e.state == State::Identifiable {
                        if (e.mu - tr.mu_true[i]).abs() > 0.1 && low {
                            wrong += 1;
                        } else {
                            right += 1;
                        }
                    }
                }
            }
        }
        println!("ice-like readings below utilisation 0.2: {hazards}; wrong estimates there: {wrong}; other identifiable: {right}");
        assert!(
            hazards > 50,
            "the hazard this test guards is gone ({hazards}): revisit it"
        );
        assert_eq!(wrong, 0);
        assert!(right > 1000);
    }
}
