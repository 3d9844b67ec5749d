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
//! wheel's estimates (`plots`, feature `plot`).

pub mod cases;
pub mod metrics;
#[cfg(feature = "plot")]
pub mod plots;
pub mod sensors;
pub mod tables;

pub use cases::{
    model_with_error, sim_wheelbase, simulate_case, suite, suite_shifted, Case, Group,
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
use gough::mf::Params;
use gough::proto::Wheel;
use std::fmt::Write as _;
use std::path::PathBuf;

/// What `gough mu bench` runs, and where it writes.
#[derive(Debug, Clone, PartialEq)]
pub struct Config {
    /// Tyre property file (.tir): the simulated tyre, and the estimators' model of it.
    pub tir: PathBuf,
    /// Output directory: table.md, table.csv, wheels.csv and the plots.
    pub out: PathBuf,
    /// Noise seed.
    pub seed: u64,
    /// Only the first N cases of the suite.
    pub cases: Option<usize>,
    /// The sensor model.
    pub sensors: Sensors,
    /// The bank's front-to-rear preview (`None`: every wheel alone).
    pub preview: Option<gough::mu::preview::Config<f64>>,
    /// Every surface of the suite shifted by this \[-\] ([`suite_shifted`]), |D| ≤ 0.05.
    pub mu_shift: f64,
    /// The estimators' tyre is the file with these parameters moved by these amounts
    /// ([`model_with_error`]); the simulation keeps the file.
    pub model_error: Vec<(gough::mf::Key, f64)>,
}

impl Default for Config {
    /// The bench as documented: the bundled MF 6.1 tyre, seed 1, the whole suite, the default
    /// sensors, the preview at weight 0.9 over the simulated vehicle's wheelbase, no shift, no
    /// model error.
    fn default() -> Self {
        Config {
            tir: "host-tests/data/tyres/MagicFormula61_Parameters.tir".into(),
            out: "out/mu_bench".into(),
            seed: 1,
            cases: None,
            sensors: Sensors::default(),
            preview: Some(gough::mu::preview::Config::with_wheelbase(sim_wheelbase())),
            mu_shift: 0.0,
            model_error: Vec::new(),
        }
    }
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

/// Runs the benchmark: writes `table.md`, `table.csv`, `wheels.csv` and the plots of the cases
/// whose surface changes into `cfg.out`, and prints `table.md`.
pub fn run(cfg: &Config) -> Result<(), String> {
    let sensors = cfg.sensors;
    let setup = Setup::car(cfg.preview);
    let t = crate::tyre::load(&cfg.tir)?;
    // `sim`: the tyre the simulation runs; `p`: the estimators' model of it (the same file
    // unless `--model-error`).
    let sim = t.params;
    let p = model_with_error(&sim, &cfg.model_error)?;
    if !(cfg.mu_shift.is_finite() && cfg.mu_shift.abs() <= 0.05) {
        return Err(format!(
            "--mu-shift {}: expected a value from -0.05 to 0.05",
            cfg.mu_shift
        ));
    }
    let mut cases = suite_shifted(cfg.mu_shift);
    if let Some(n) = cfg.cases {
        cases.truncate(n);
    }
    std::fs::create_dir_all(&cfg.out).map_err(|e| format!("{}: {e}", cfg.out.display()))?;
    let mut md = String::new();
    if !cfg.model_error.is_empty() {
        let errors: Vec<String> = cfg
            .model_error
            .iter()
            .map(|(k, d)| format!("{}={d}", k.name()))
            .collect();
        let _ = writeln!(
            md,
            "Model error (`--model-error`): the estimators' tyre is {} with {}; the simulation's is the file.\n",
            cfg.tir.display(),
            errors.join(", ")
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
    let issue_cases = cases.iter().filter(|c| c.group.issue_case()).count();
    let mut per_case: Vec<(&Case, Vec<MethodResult>)> = Vec::new();
    for c in &cases {
        bar.set_message(format!("{} on {}", c.manoeuvre, c.road));
        let log = simulate_case(&sim, c)?;
        let traces: Vec<WheelTrace> = (0..4)
            .map(|w| measure(&log, w, &sensors, cfg.seed))
            .collect();
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
            total.add(&mt, c.group.issue_case());
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
        // The front-left wheel's estimates of the bank, on a case whose surface changes.
        #[cfg(feature = "plot")]
        if c.road.contains("patch") || c.road.contains("step") {
            let name = format!(
                "{}_{}",
                c.manoeuvre,
                c.road.replace(['=', '+', '@', '.', ',', '/'], "_")
            );
            if let Some(fl) = bank.first() {
                plots::plot_mu(
                    &traces[0],
                    &[("bank", fl)],
                    &cfg.out.join(format!("mu_{name}.png")),
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
    if cfg.mu_shift != 0.0 {
        let _ = writeln!(
            md,
            "\nEvery surface of the suite shifted by {:+} (the road specs above are the shifted ones).",
            cfg.mu_shift
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
    std::fs::write(cfg.out.join("table.md"), &md).map_err(|e| e.to_string())?;
    std::fs::write(cfg.out.join("table.csv"), &csv).map_err(|e| e.to_string())?;
    std::fs::write(cfg.out.join("wheels.csv"), &wheels_csv).map_err(|e| e.to_string())?;
    print!("{md}");
    eprintln!(
        "-> {}/table.md, table.csv, wheels.csv{}",
        cfg.out.display(),
        if cfg!(feature = "plot") {
            ", mu_*.png"
        } else {
            ""
        }
    );
    Ok(())
}
