//! `gough mu bench`: the estimators against simulated truth.
//!
//! The plant is the host vehicle simulation (`crate::sim`) on the bundled tyre; each case of the
//! suite ([`cases`]) is a manoeuvre on a road. Its per-wheel Fy, Mz, Fz, Fx pass through a sensor
//! model ([`sensors`]) — additive Gaussian noise (Mz 2 N·m rms, Fy, Fx and Fz 1 % of Fz rms,
//! seeded) and a 10 ms pure delay — before any estimator sees them; κ comes with the noise of a
//! wheel-speed estimate. The peers additionally get the (delayed, exact) slip angle and slip
//! ratio of a slip sensor, which the bank never reads. Every estimator ([`Method::ALL`]) runs
//! through [`crate::mu::Estimator`] on the four wheels, sample by sample as a car measures them.
//!
//! Metrics per estimator and case, over the four wheels ([`metrics`](mod@metrics)):
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
//!
//! The tables ([`tables`]) and, for the cases whose surface changes, a plot of the front-left
//! wheel's estimates ([`plots`]).

pub mod cases;
pub mod metrics;
pub mod plots;
pub mod sensors;
pub mod tables;

pub use cases::{
    model_with_error, sim_wheelbase, simulate_case, straight_stop, suite, suite_shifted, Case,
};
pub use metrics::{
    common, false_change_flags, metrics, segment_latency, wheel_surfaces, Common, Metrics, Totals,
    WheelSurface, GROSS, TARGET_LATENCY,
};
pub(crate) use metrics::{median, segments};
pub use sensors::{measure, Sensors, WheelTrace};
pub(crate) use tables::csv_field;
pub use tables::MethodResult;

use crate::mu::{Estimate, Method, Setup};
use clap::Args;
use gough::mf::Params;
use gough::proto::Wheel;
use plots::plot_mu;
use std::fmt::Write as _;
use std::path::PathBuf;

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
    /// Aligning-torque sensor noise, rms \[N·m\], added to every row the estimators see. The
    /// sensors, not the estimators: what the bank assumes is its own configuration's.
    #[arg(long, value_name = "NM", allow_negative_numbers = true, default_value_t = Sensors::default().sigma_mz)]
    pub noise_mz: f64,
    /// Force sensor noise (Fy, Fx, Fz), rms, as a fraction of Fz \[-\] (the sensors, not the
    /// estimators' assumption).
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

/// Runs `method` (set up as `setup`) over a case's wheel traces (fl, fr, rl, rr), sample by
/// sample as a car measures them: every wheel's sample `i`, then every wheel's `i + 1`; each
/// wheel's samples as the method sees them ([`WheelTrace::sample`]). An estimate per row per
/// wheel; an error when the estimator cannot be built or there are more than four traces.
pub fn run_method(
    method: Method,
    p: &Params<f64>,
    setup: &Setup,
    traces: &[WheelTrace],
) -> Result<Vec<Vec<Estimate>>, String> {
    let wheels: Vec<Wheel> = (0..traces.len())
        .map(|w| Wheel::from_index(w).ok_or(format!("{} wheel traces: at most 4", traces.len())))
        .collect::<Result<_, _>>()?;
    let mut e = method.estimator(p, setup)?;
    let n = traces.iter().map(|t| t.rows.len()).max().unwrap_or(0);
    let mut out: Vec<Vec<Estimate>> = traces
        .iter()
        .map(|t| Vec::with_capacity(t.rows.len()))
        .collect();
    for i in 0..n {
        for ((tr, o), &w) in traces.iter().zip(&mut out).zip(&wheels) {
            if i < tr.rows.len() {
                o.push(e.update(w, &tr.sample(i, method.slip_sensor())));
            }
        }
    }
    Ok(out)
}

/// Runs the benchmark.
pub fn run(a: BenchArgs) -> Result<(), String> {
    let sensors = a.sensors()?;
    let setup = Setup::car(a.preview()?);
    let t = crate::tyre::load(&a.tir)?;
    // `sim`: the tyre the simulation runs; `p`: the estimators' model of it (the same file
    // unless `--model-error`).
    let sim = t.params;
    let p = model_with_error(&sim, &a.model_error)?;
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
    md.push_str(tables::MD_HEADER);
    let mut csv = String::from(tables::CSV_HEADER);
    let mut wheels_csv =
        String::from("manoeuvre,road,wheel,mu,t_start_s,t_end_s,t_util05_s,latency_s,within\n");
    let mut misses: Vec<(&Case, WheelSurface)> = Vec::new();
    let mut not_run: Vec<(Method, String)> = Vec::new();
    let bar = indicatif::ProgressBar::new(cases.len() as u64);
    let mut totals: Vec<(Method, Totals)> = Method::ALL
        .iter()
        .map(|&m| (m, Totals::default()))
        .collect();
    let issue_cases = cases.iter().filter(|c| !straight_stop(c)).count();
    let mut per_case: Vec<(&Case, Vec<MethodResult>)> = Vec::new();
    for c in &cases {
        bar.set_message(format!("{} on {}", c.manoeuvre, c.road));
        let log = simulate_case(&sim, c)?;
        let traces: Vec<WheelTrace> = (0..4).map(|w| measure(&log, w, &sensors, a.seed)).collect();
        let mut runs: Vec<(Method, Vec<Vec<Estimate>>, Metrics)> = Vec::new();
        for (m, total) in &mut totals {
            let ests = match run_method(*m, &p, &setup, &traces) {
                Ok(e) => e,
                Err(why) => {
                    // Not run on this tyre: its rows say nothing was identifiable, and a line
                    // below the table says why.
                    if !not_run.iter().any(|(x, _)| x == m) {
                        not_run.push((*m, why));
                    }
                    vec![Vec::new(); traces.len()]
                }
            };
            let mt = metrics(&traces, &ests);
            if *m == Method::Bank {
                for x in wheel_surfaces(&traces, &ests) {
                    wheels_csv.push_str(&tables::wheel_row(c, &x));
                    if !x.within() {
                        misses.push((c, x));
                    }
                }
            }
            md.push_str(&tables::md_row(c, *m, &mt));
            csv.push_str(&tables::csv_row(c, *m, &mt));
            total.add(&mt, !straight_stop(c));
            runs.push((*m, ests, mt));
        }
        // Each other estimator against the bank on the samples both call identifiable (the
        // bank's own entry left empty).
        let bank = runs
            .iter()
            .find(|(m, ..)| *m == Method::Bank)
            .map(|(_, e, _)| e.clone())
            .unwrap_or_default();
        let results = runs
            .into_iter()
            .map(|(m, e, metrics)| MethodResult {
                method: m,
                metrics,
                common: if m == Method::Bank {
                    Common::default()
                } else {
                    common(&traces, &bank, &e)
                },
            })
            .collect();
        if c.road.contains("patch") || c.road.contains("step") {
            let name = format!(
                "{}_{}",
                c.manoeuvre,
                c.road.replace(['=', '+', '@', '.', ',', '/'], "_")
            );
            // The front-left wheel's estimates of the bank.
            if let Some(fl) = bank.first() {
                plot_mu(
                    &traces[0],
                    &[("bank", fl)],
                    &a.out.join(format!("mu_{name}.png")),
                    &format!("{} on {} (front left)", c.manoeuvre, c.road),
                )?;
            }
        }
        per_case.push((c, results));
        bar.inc(1);
    }
    bar.finish_and_clear();
    md.push('\n');
    md.push_str(&tables::summary(&totals, cases.len(), issue_cases));
    md.push_str(&tables::against_the_others(&per_case));
    md.push_str(&tables::misses_table(&misses));
    for (m, why) in &not_run {
        let _ = writeln!(md, "\n{} did not run on this tyre: {why}.", m.name());
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
    std::fs::write(a.out.join("table.md"), &md).map_err(|e| e.to_string())?;
    std::fs::write(a.out.join("table.csv"), &csv).map_err(|e| e.to_string())?;
    std::fs::write(a.out.join("wheels.csv"), &wheels_csv).map_err(|e| e.to_string())?;
    print!("{md}");
    eprintln!(
        "-> {}/table.md, table.csv, wheels.csv, mu_*.png",
        a.out.display()
    );
    Ok(())
}
