//! `gough mu bench`: the estimators against simulated truth, in two groups of cases: the
//! vehicle suite on one tyre (below), then the wheel cases on every tyre of a folder, on the
//! tyre of the file and on tyres that are not their file, at several log rates
//! ([`wheel`](mod@wheel): the product's estimator alone). `--quick` runs a subset of both,
//! `--seeds` each seed of a list ([`run_seeds`]), `--warm` every case a second time on the same
//! estimator.
//!
//! The vehicle suite's plant is the host vehicle simulation (`crate::sim`) on the bundled tyre;
//! each case of the suite ([`cases`]) is a manoeuvre on a road. Its per-wheel Fy, Mz, Fz, Fx
//! pass through a sensor model ([`sensors`]) — additive Gaussian noise (Mz 2 N·m rms, Fy, Fx
//! and Fz 1 % of Fz rms, seeded) and a 10 ms pure delay — before any estimator sees them; κ
//! comes with the noise of a wheel-speed estimate. The peers additionally get the (delayed, exact) slip angle and slip
//! ratio of a slip sensor, which the bank never reads. Every estimator ([`Method::ALL`]) runs
//! through [`crate::mu::Estimator`] on the four wheels, sample by sample as a car measures them.
//!
//! Metrics per estimator and case, over the four wheels ([`metrics`](mod@metrics)):
//! - μ error |μ̂ − μ| (mean and 95th percentile) over the samples the estimator calls
//!   identifiable, and the share of them within twice the σ reported (whether σ is honest);
//! - the utilisation |F|/(μ·Fz) (docs/architecture.md) reached when the reported estimate first stays
//!   within ±0.1 of the truth until the end of its surface (median over wheels);
//! - latency: time from the utilisation first reaching 0.5 on a surface to the estimate staying
//!   within ±0.1 (median over wheels);
//! - for surfaces that change: the time from the wheel entering the new surface to the estimate
//!   staying within ±0.1 of it;
//! - change flags, and the false ones among them ([`false_change_flags`]: no change of road
//!   since the identification they change from, or a wrong new value).
//!
//! The wheel cases add the time to read each step of the surface ([`step_reads`]).
//!
//! The tables ([`tables`], [`wheel::tables`]) and, for the vehicle suite's cases whose surface
//! changes, a plot of the front-left wheel's estimates (`plots`, feature `plot`).

pub mod cases;
pub mod metrics;
#[cfg(feature = "plot")]
pub mod plots;
pub mod sensors;
pub mod tables;
pub mod wheel;

pub use cases::{
    model_with_error, sim_wheelbase, simulate_case, suite, suite_shifted, Case, Group,
};
pub use metrics::{
    common, false_change_flags, metrics, segment_latency, step_reads, warm_false_change_flags,
    wheel_surfaces, Common, Metrics, StepRead, Totals, WheelSurface, GROSS, TARGET_LATENCY,
    TARGET_STEP,
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
    /// Only one group of cases (`None`: the vehicle suite, then the wheel cases).
    pub only: Option<Only>,
    /// The folder of tyre files the wheel cases run on ([`wheel::tyres`]).
    pub tyres: PathBuf,
    /// The quick subset: the wheel cases of [`wheel::plan`]'s `quick`, and the vehicle suite's
    /// first three cases unless [`Config::cases`] says otherwise.
    pub quick: bool,
    /// Every wheel case twice in a row on one estimator: cold, then warm ([`wheel::run_case`]).
    pub warm: bool,
    /// Threads running the wheel cases (the results do not depend on it).
    pub jobs: usize,
    /// The estimators are given this tyre file instead of the simulated tyre's: the vehicle
    /// suite's (with [`Config::model_error`] on top), and in the wheel cases every tyre's, which
    /// then run on the exact level only (the simulated tyre is the file of `tyres`: the car's
    /// tyre; this the file the estimator has of it). `None`: each tyre's own file.
    pub estimator_tir: Option<PathBuf>,
}

/// One group of the bench's cases: the vehicle suite ([`suite`]) or the wheel cases
/// ([`wheel`](mod@wheel)). (The variants' docs are `gough mu bench --help`'s.)
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Only {
    /// The vehicle simulation's suite on the one tyre of `--tir`.
    Vehicle,
    /// The wheel cases on every tyre of `--tyres`.
    Wheel,
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
            only: None,
            tyres: wheel::TYRES.into(),
            quick: false,
            warm: false,
            jobs: 2,
            estimator_tir: None,
        }
    }
}

/// What one run of the bench found, for [`run_seeds`]' summary.
#[derive(Debug, Clone, Default)]
pub struct Report {
    /// `table.md`.
    pub md: String,
    /// The bank's totals over the vehicle suite, with the suite's cases and the issue's among
    /// them (none: the suite did not run).
    pub vehicle: Option<(Totals, usize, usize)>,
    /// Per level, the wheel cases at the standard rate added up.
    pub wheel: Vec<(wheel::Level, wheel::tables::Tally)>,
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
    if traces.len() > 4 {
        return Err(format!("{} wheel traces: at most 4", traces.len()));
    }
    let mut e = method.estimator(p, setup)?;
    drive(&mut *e, traces, method.slip_sensor(), 0.0)
}

/// Runs estimator `e` over wheel traces (fl, fr, rl, rr) as [`run_method`] does, each row's time
/// moved by `t_offset` \[s\] (a second run on the same estimator continues its clock:
/// [`wheel`](mod@wheel)'s warm start); `slip_sensor`: give it the slip sensor's α and κ
/// ([`WheelTrace::sample`]). An error when there are more than four traces.
pub fn drive(
    e: &mut dyn crate::mu::Estimator,
    traces: &[WheelTrace],
    slip_sensor: bool,
    t_offset: f64,
) -> Result<Vec<Vec<Estimate>>, String> {
    let wheels: Vec<Wheel> = (0..traces.len())
        .map(|w| Wheel::from_index(w).ok_or(format!("{} wheel traces: at most 4", traces.len())))
        .collect::<Result<_, _>>()?;
    let n = traces.iter().map(|t| t.rows.len()).max().unwrap_or(0);
    let mut out: Vec<Vec<Estimate>> = traces
        .iter()
        .map(|t| Vec::with_capacity(t.rows.len()))
        .collect();
    for i in 0..n {
        for ((tr, o), &w) in traces.iter().zip(&mut out).zip(&wheels) {
            if i < tr.rows.len() {
                let mut s = tr.sample(i, slip_sensor);
                if t_offset != 0.0 {
                    s.t += t_offset;
                }
                o.push(e.update(w, &s));
            }
        }
    }
    Ok(out)
}

/// Runs the benchmark: writes `table.md` and its CSVs into `cfg.out` ([`report`]), and prints
/// `table.md`.
pub fn run(cfg: &Config) -> Result<(), String> {
    let r = report(cfg)?;
    print!("{}", r.md);
    let mut files = vec!["table.md"];
    if cfg.only != Some(Only::Wheel) {
        files.extend(["table.csv", "wheels.csv"]);
        if cfg!(feature = "plot") {
            files.push("mu_*.png");
        }
    }
    if cfg.only != Some(Only::Vehicle) {
        files.push("wheel_cases.csv");
    }
    eprintln!("-> {}/{}", cfg.out.display(), files.join(", "));
    Ok(())
}

/// Runs the benchmark and writes into `cfg.out`: the vehicle suite (unless `--only wheel`):
/// its tables, `table.csv`, `wheels.csv` and the plots of the cases whose surface changes; then
/// the wheel cases (unless `--only vehicle`): their sections after it, `wheel_cases.csv`;
/// `table.md`, which it returns with the figures [`run_seeds`] sums up.
pub fn report(cfg: &Config) -> Result<Report, String> {
    std::fs::create_dir_all(&cfg.out).map_err(|e| format!("{}: {e}", cfg.out.display()))?;
    let mut r = Report::default();
    if cfg.only != Some(Only::Wheel) {
        let (md, v) = vehicle(cfg)?;
        r.md.push_str(&md);
        r.vehicle = Some(v);
    }
    if cfg.only != Some(Only::Vehicle) {
        let (md, csv, tallies) = wheel_cases(cfg)?;
        r.md.push_str(&md);
        r.wheel = tallies;
        std::fs::write(cfg.out.join("wheel_cases.csv"), &csv).map_err(|e| e.to_string())?;
    }
    std::fs::write(cfg.out.join("table.md"), &r.md).map_err(|e| e.to_string())?;
    Ok(r)
}

/// The wheel cases of `cfg`: their sections of `table.md`, `wheel_cases.csv`, and per level
/// the cases at the standard rate added up.
#[allow(clippy::type_complexity)]
fn wheel_cases(
    cfg: &Config,
) -> Result<(String, String, Vec<(wheel::Level, wheel::tables::Tally)>), String> {
    let (tyres, skipped) = wheel::tyres(&cfg.tyres)?;
    if tyres.is_empty() {
        return Err(format!(
            "{}: no tyre file the estimator accepts",
            cfg.tyres.display()
        ));
    }
    let scenarios = wheel::scenarios();
    let mut cases = wheel::plan(&tyres, &scenarios, cfg.quick);
    let given = match &cfg.estimator_tir {
        Some(f) => {
            cases.retain(|c| c.level == wheel::Level::Exact);
            Some(crate::tyre::load(f)?.params)
        }
        None => None,
    };
    let make = |p: &gough::mf::Params<f64>| wheel::estimator(given.as_ref().unwrap_or(p));
    let bar = indicatif::ProgressBar::new(cases.len() as u64);
    bar.set_message("wheel cases");
    let results = wheel::run_all(
        &cases,
        &tyres,
        &scenarios,
        cfg.seed,
        cfg.warm,
        cfg.jobs,
        &make,
        &|| bar.inc(1),
    );
    bar.finish_and_clear();
    let cases: Vec<_> = cases.into_iter().zip(results).collect();
    let run = wheel::tables::Run {
        dir: &cfg.tyres,
        tyres: &tyres,
        skipped: &skipped,
        scenarios: &scenarios,
        cases: &cases,
        seed: cfg.seed,
        warm: cfg.warm,
    };
    let tallies = wheel::Level::ALL
        .into_iter()
        .map(|l| {
            (
                l,
                run.tally(|c| c.level == l && c.rate == wheel::RATE, false),
            )
        })
        .filter(|(_, t)| t.cases > 0)
        .collect();
    Ok((
        wheel::tables::markdown(&run),
        wheel::tables::csv(&run),
        tallies,
    ))
}

/// The vehicle suite of `cfg`: its part of `table.md` (as it was before the wheel cases), and
/// the bank's totals with the number of cases and of the issue's cases; writes `table.csv`,
/// `wheels.csv` and the plots.
fn vehicle(cfg: &Config) -> Result<(String, (Totals, usize, usize)), String> {
    let sensors = cfg.sensors;
    let setup = Setup::car(cfg.preview);
    let t = crate::tyre::load(&cfg.tir)?;
    // `sim`: the tyre the simulation runs; `p`: the estimators' model of it (the same file
    // unless `--model-error`).
    let sim = t.params;
    let p = match &cfg.estimator_tir {
        Some(f) => model_with_error(&crate::tyre::load(f)?.params, &cfg.model_error)?,
        None => model_with_error(&sim, &cfg.model_error)?,
    };
    if !(cfg.mu_shift.is_finite() && cfg.mu_shift.abs() <= 0.05) {
        return Err(format!(
            "--mu-shift {}: expected a value from -0.05 to 0.05",
            cfg.mu_shift
        ));
    }
    let mut cases = suite_shifted(cfg.mu_shift);
    if let Some(n) = cfg.cases.or(cfg.quick.then_some(3)) {
        cases.truncate(n);
    }
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
    if let Some(f) = &cfg.estimator_tir {
        let _ = writeln!(
            md,
            "The estimators are given {} (`--estimator-tir`); the simulation runs {}.\n",
            f.display(),
            cfg.tir.display()
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
    // `--warm`: the bank on each case from a cold start and warm (its second run in a row).
    let mut warm: Vec<(&Case, Metrics, Metrics)> = Vec::new();
    let mut warm_totals = (Totals::default(), Totals::default());
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
        if cfg.warm {
            if let Ok(mut e) = Method::Bank.estimator(&p, &setup) {
                let cold = drive(&mut *e, &traces, false, 0.0)?;
                let rows = &traces[0].rows;
                let dt = rows.get(1).map_or(1e-3, |r| r.t - rows[0].t);
                let end = rows.last().map_or(0.0, |r| r.t);
                let again = drive(&mut *e, &traces, false, end + dt)?;
                let (mc, mut mw) = (metrics(&traces, &cold), metrics(&traces, &again));
                mw.false_alarms = warm_false_change_flags(&traces, &cold, &again);
                warm_totals.0.add(&mc, c.group.issue_case());
                warm_totals.1.add(&mw, c.group.issue_case());
                warm.push((c, mc, mw));
            }
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
    if cfg.warm {
        md.push_str(&tables::warm_vehicle(
            &warm,
            &warm_totals,
            cases.len(),
            issue_cases,
        ));
    }
    std::fs::write(cfg.out.join("table.csv"), &csv).map_err(|e| e.to_string())?;
    std::fs::write(cfg.out.join("wheels.csv"), &wheels_csv).map_err(|e| e.to_string())?;
    let bank = totals
        .iter()
        .find(|(m, _)| *m == Method::Bank)
        .map(|(_, t)| t.clone())
        .unwrap_or_default();
    Ok((md, (bank, cases.len(), issue_cases)))
}

/// `--seeds A-B` (or a comma-separated list, or one seed): the seeds, each once, in order.
pub fn parse_seeds(s: &str) -> Result<Vec<u64>, String> {
    let bad = || format!("--seeds {s}: expected A-B (A ≤ B), a list A,B,C or one seed");
    let mut v: Vec<u64> = Vec::new();
    for part in s.split(',').map(str::trim) {
        let range = match part.split_once('-') {
            Some((a, b)) => {
                let (a, b) = (
                    a.trim().parse::<u64>().map_err(|_| bad())?,
                    b.trim().parse::<u64>().map_err(|_| bad())?,
                );
                if a > b || b - a >= 1000 {
                    return Err(bad());
                }
                a..=b
            }
            None => {
                let a = part.parse::<u64>().map_err(|_| bad())?;
                a..=a
            }
        };
        for x in range {
            if !v.contains(&x) {
                v.push(x);
            }
        }
    }
    if v.is_empty() {
        return Err(bad());
    }
    Ok(v)
}

/// Runs the bench once per seed, each into `cfg.out/seed-N` ([`report`]), then writes and
/// prints `cfg.out/seeds.md`: per seed and the worst over them, the bank on the vehicle suite
/// and the wheel cases per level ([`tables::seeds`]).
pub fn run_seeds(cfg: &Config, seeds: &[u64]) -> Result<(), String> {
    let mut reports = Vec::new();
    for &seed in seeds {
        let c = Config {
            seed,
            out: cfg.out.join(format!("seed-{seed}")),
            ..cfg.clone()
        };
        eprintln!("seed {seed} -> {}", c.out.display());
        reports.push((seed, report(&c)?));
    }
    let md = tables::seeds(&reports);
    std::fs::create_dir_all(&cfg.out).map_err(|e| format!("{}: {e}", cfg.out.display()))?;
    std::fs::write(cfg.out.join("seeds.md"), &md).map_err(|e| e.to_string())?;
    print!("{md}");
    eprintln!(
        "-> {}/seeds.md, seed-N/ (each a run's table.md and CSVs)",
        cfg.out.display()
    );
    Ok(())
}
