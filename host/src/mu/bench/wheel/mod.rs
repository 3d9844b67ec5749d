//! The bench's wheel cases: every tyre of a folder (`host-tests/data/tyres`) that the estimator
//! accepts, one wheel at the tyre's own FNOMIN, driven by the scenarios of [`scenarios`] (the
//! wheel-level generator [`crate::mu::scenario`]: manoeuvres in the tyre's own scales, surface
//! steps, sensor noise scaled to the tyre), on the tyre of the file and on a tyre that is not its
//! file (the issue-55 envelope, [`Level`]), at several log rates ([`plan`]).
//!
//! A case is (tyre, scenario, [`Level`], rate) under the bench's seed: the simulated tyre is the
//! file moved by a [`Perturbation`] drawn for (tyre, scenario, seed) — exact: none; 1×: the
//! envelope; 2×: the same draw doubled, so that the two levels are the same tyre error at twice
//! the size — while the estimator is always given the file ([`run_case`]). Each case's traces
//! become the bench's [`WheelTrace`]s, so that the vehicle suite's metrics apply
//! ([`metrics`](mod@super::metrics)), and the step reads ([`step_reads`]).
//!
//! The estimator is reached through [`crate::mu::Estimator`] only (the bench runs
//! [`Method::Bank`], every wheel as the file describes its tyre, no preview): whatever is behind
//! that trait is what the cases measure. A warm start ([`run_case`] with `warm`) is the same
//! estimator driven through the case twice in a row, its clock continued; the second run's
//! figures are the warm ones. Cases run on threads ([`run_all`]); every case's randomness comes
//! from its own key and the bench's seed, so the results do not depend on the scheduling.

pub mod tables;

use super::metrics::{metrics, step_reads, warm_false_change_flags, Metrics, StepRead};
use super::{drive, WheelTrace};
use crate::mu::scenario::{self, has_pressure, Manoeuvre, Noise, Perturbation, Scenario};
use crate::mu::{Estimate, Estimator, Method, Sample, Setup};
use crate::rng::Rng;
use gough::mf::{Params, Version};
use std::path::Path;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// The folder of tyre files the standard run reads.
pub const TYRES: &str = "host-tests/data/tyres";

/// The standard log rate of the wheel cases \[Hz\].
pub const RATE: f64 = 200.0;

/// The other log rates, on [`RATE_SUBSET`] \[Hz\].
pub const RATES: [f64; 2] = [100.0, 1000.0];

/// The scenarios also run at [`RATES`] (every tyre, [`Level::Exact`] and [`Level::Envelope`]):
/// those with a step of the surface, whose read the rate bounds, and the ABS's μ-split, whose
/// slip cycles at 4 Hz.
pub const RATE_SUBSET: [&str; 6] = [
    "cornering 1.0→0.3",
    "cornering 0.3→1.0",
    "cornering 0.6→0.1",
    "braking 1.0→0.3",
    "slalom 1.0→0.1",
    "μ-split 0.9/0.2",
];

/// `--quick`: these tyres (a car's, the small racing tyre, a truck's) …
pub const QUICK_TYRES: [&str; 3] = [
    "MagicFormula61_Parameters.tir",
    "FSAE_Defaults.tir",
    "MagicFormula52_Parameters.tir",
];

/// … on these scenarios, exact and at 1×, at [`RATE`]; and the first of them exact at each of
/// [`RATES`].
pub const QUICK_SCENARIOS: [&str; 4] = [
    "cornering 1.0→0.3",
    "braking 1.0→0.3",
    "slalom 1.0→0.1",
    "μ-split 0.9/0.2",
];

/// A tyre file the estimator accepts.
#[derive(Debug, Clone, PartialEq)]
pub struct Tyre {
    /// File name (in the folder read).
    pub file: String,
    /// Its parameters: the estimator's model, and the simulated tyre before any perturbation.
    pub params: Params<f64>,
    /// μy0 of the file (the scale of μ, as the estimator reports it) \[-\].
    pub mu_y0: f64,
    /// Whether the file has inflation-pressure terms (the envelope then moves the pressure).
    pub pressure: bool,
}

impl Tyre {
    /// The Magic Formula version of the file, as the tables name it.
    pub fn model(&self) -> &'static str {
        match self.params.version {
            Version::Delft96 => "MF-Tyre 5.0",
            Version::Mf52 => "MF 5.2",
            Version::Mf61 => "MF 6.1",
            Version::Mf62 => "MF 6.2",
        }
    }

    /// Sensor noise of the wheel cases on this tyre, rms: Fx, Fy, Fz \[share of Fz\], Mz
    /// \[N·m\], κ \[-\].
    pub fn noise(&self) -> (f64, f64, f64) {
        let n = Noise::default();
        (n.f_rel, n.mz_sigma(&self.params), n.kappa)
    }
}

/// What builds a case's estimator from the tyre file's parameters ([`estimator`] in the
/// bench; the tests watch what it is given).
pub type MakeEstimator<'a> = dyn Fn(&Params<f64>) -> Result<Box<dyn Estimator>, String> + Sync + 'a;

/// The estimator the wheel cases run, on tyre file `p`: the bank, every wheel as the file
/// describes its tyre (the scenarios simulate it so), no preview.
pub fn estimator(p: &Params<f64>) -> Result<Box<dyn Estimator>, String> {
    Method::Bank.estimator(p, &Setup::one_wheel(None))
}

/// The `.tir` files of `dir` in the order of their names: the tyres the estimator accepts, and
/// the others with why each is skipped (the reader refuses it, it has no friction at FNOMIN, the
/// estimator refuses it).
#[allow(clippy::type_complexity)]
pub fn tyres(dir: &Path) -> Result<(Vec<Tyre>, Vec<(String, String)>), String> {
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .map_err(|e| format!("{}: {e}", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x.eq_ignore_ascii_case("tir")))
        .collect();
    files.sort();
    let (mut ok, mut skipped) = (Vec::new(), Vec::new());
    for f in files {
        let file = f
            .file_name()
            .map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        let t = match crate::tyre::load(&f) {
            Ok(t) => t,
            Err(e) => {
                let why = e
                    .strip_prefix(&format!("{}: ", f.display()))
                    .unwrap_or(&e)
                    .to_string();
                skipped.push((file, format!("the reader refuses it ({why})")));
                continue;
            }
        };
        let mu_y0 = match scenario::mu_y0(&t.params) {
            Ok(m) => m,
            Err(e) => {
                skipped.push((file, e));
                continue;
            }
        };
        if let Err(e) = estimator(&t.params) {
            skipped.push((file, format!("the estimator refuses it ({e})")));
            continue;
        }
        let pressure = has_pressure(&t.params);
        ok.push(Tyre {
            file,
            params: t.params,
            mu_y0,
            pressure,
        });
    }
    Ok((ok, skipped))
}

/// A scenario of the wheel cases: one wheel, or (the μ-split) two wheels of one car, each its
/// own [`Scenario`] on the same tyre.
#[derive(Debug, Clone, PartialEq)]
pub struct WheelScenario {
    /// Its name in the tables.
    pub name: &'static str,
    /// What each wheel does (FL, then FR).
    pub wheels: Vec<Scenario>,
}

/// The scenarios, on every tyre (issue 55's list, in the tyre's own scales):
/// - steady cornering at utilisation 0.65 of whatever surface, which steps at 4 s from 1.0 to
///   0.3, from 0.3 to 1.0, and from 0.6 to 0.1 (ice), 8 s;
/// - steady straight braking at utilisation 0.65, 1.0 → 0.3 at 4 s, 8 s;
/// - braking in a turn on 0.7 (the slip angle of pure-lateral utilisation 0.4, κ ramped to −0.1
///   from 2 s to 5 s, held to 7 s, released by 8 s), 9 s;
/// - slaloms at 0.5 Hz, amplitude 1.3 × the slip angle of utilisation 0.95, on 1.0, 0.6 and
///   0.25, 10 s; and one whose surface steps from 1.0 to 0.1 (ice) at 6.25 s (a quarter period
///   past a zero crossing of the steer: mid-swing), 12 s;
/// - the μ-split stop: two wheels of one car (one estimator), on 0.9 and on 0.2, each braking
///   under an ABS cycling about its own surface's slip of utilisation 0.95 at 4 Hz, 6 s.
///
/// Every one runs at the load FNOMIN·(1 + 0.15 sin(2π·0.2t) + 0.02 sin(2π·10t)) at 20 m/s.
pub fn scenarios() -> Vec<WheelScenario> {
    let one = |name, manoeuvre, mu: [f64; 2], step, duration| WheelScenario {
        name,
        wheels: vec![Scenario {
            manoeuvre,
            mu,
            step,
            duration,
        }],
    };
    let corner = Manoeuvre::SteadyCornering { util: 0.65 };
    let brake = Manoeuvre::SteadyBraking { util: 0.65 };
    let slalom = Manoeuvre::Slalom {
        amplitude: 1.3,
        freq: 0.5,
    };
    let abs = |mu| Scenario {
        manoeuvre: Manoeuvre::AbsBraking { freq: 4.0 },
        mu: [mu, mu],
        step: None,
        duration: 6.0,
    };
    vec![
        one("cornering 1.0→0.3", corner, [1.0, 0.3], Some(4.0), 8.0),
        one("cornering 0.3→1.0", corner, [0.3, 1.0], Some(4.0), 8.0),
        one("cornering 0.6→0.1", corner, [0.6, 0.1], Some(4.0), 8.0),
        one("braking 1.0→0.3", brake, [1.0, 0.3], Some(4.0), 8.0),
        one(
            "brake in turn 0.7",
            Manoeuvre::BrakeInTurn {
                lat_util: 0.4,
                kappa: -0.1,
            },
            [0.7, 0.7],
            None,
            9.0,
        ),
        one("slalom 1.0", slalom, [1.0, 1.0], None, 10.0),
        one("slalom 0.6", slalom, [0.6, 0.6], None, 10.0),
        one("slalom 0.25", slalom, [0.25, 0.25], None, 10.0),
        one("slalom 1.0→0.1", slalom, [1.0, 0.1], Some(6.25), 12.0),
        WheelScenario {
            name: "μ-split 0.9/0.2",
            wheels: vec![abs(0.9), abs(0.2)],
        },
    ]
}

/// How the simulated tyre differs from the file the estimator is given.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Level {
    /// The tyre is its file.
    Exact,
    /// Drawn from issue 55's envelope ([`scenario::draw`] at scale 1).
    Envelope,
    /// The same draw at twice the size (scale 2).
    Twice,
}

impl Level {
    /// The three, in the tables' order.
    pub const ALL: [Level; 3] = [Level::Exact, Level::Envelope, Level::Twice];

    /// The envelope's scale.
    pub const fn scale(self) -> f64 {
        match self {
            Level::Exact => 0.0,
            Level::Envelope => 1.0,
            Level::Twice => 2.0,
        }
    }

    /// Its name in the tables and CSVs.
    pub const fn name(self) -> &'static str {
        match self {
            Level::Exact => "exact",
            Level::Envelope => "1×",
            Level::Twice => "2×",
        }
    }
}

/// One wheel case: indices into the tyres and the scenarios it was planned on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WheelCase {
    /// Index into the tyres.
    pub tyre: usize,
    /// Index into the scenarios.
    pub scenario: usize,
    /// The simulated tyre's difference from its file.
    pub level: Level,
    /// Log rate \[Hz\].
    pub rate: f64,
}

/// The cases of a run, in the tables' order (rate, then tyre, scenario, level). The standard
/// run: every tyre × every scenario × every [`Level`] at [`RATE`]; then [`RATE_SUBSET`] on every
/// tyre, exact and at 1×, at each of [`RATES`]. `quick`: [`QUICK_TYRES`] (those present) ×
/// [`QUICK_SCENARIOS`], exact and at 1×, at [`RATE`]; and the first of them, exact, at each of
/// [`RATES`].
pub fn plan(tyres: &[Tyre], scenarios: &[WheelScenario], quick: bool) -> Vec<WheelCase> {
    let sc = |name: &str| scenarios.iter().position(|s| s.name == name);
    let mut v = Vec::new();
    let mut add = |tyre, names: &[usize], levels: &[Level], rate| {
        for &scenario in names {
            for &level in levels {
                v.push(WheelCase {
                    tyre,
                    scenario,
                    level,
                    rate,
                });
            }
        }
    };
    let picked: Vec<usize> = if quick {
        (0..tyres.len())
            .filter(|&t| QUICK_TYRES.contains(&tyres[t].file.as_str()))
            .collect()
    } else {
        (0..tyres.len()).collect()
    };
    let (standard, subset, levels): (Vec<usize>, Vec<usize>, &[Level]) = if quick {
        (
            QUICK_SCENARIOS.iter().filter_map(|n| sc(n)).collect(),
            QUICK_SCENARIOS
                .iter()
                .take(1)
                .filter_map(|n| sc(n))
                .collect(),
            &[Level::Exact],
        )
    } else {
        (
            (0..scenarios.len()).collect(),
            RATE_SUBSET.iter().filter_map(|n| sc(n)).collect(),
            &[Level::Exact, Level::Envelope],
        )
    };
    let standard_levels: &[Level] = if quick {
        &[Level::Exact, Level::Envelope]
    } else {
        &Level::ALL
    };
    for &t in &picked {
        add(t, &standard, standard_levels, RATE);
    }
    for rate in RATES {
        for &t in &picked {
            add(t, &subset, levels, rate);
        }
    }
    v
}

/// FNV-1a of `s`: a case's key, stable across runs, platforms and the set of tyres.
fn key(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// The generator of key `k` under the bench's seed.
fn rng(seed: u64, k: &str) -> Rng {
    Rng::new(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ key(k))
}

/// The perturbation of `tyre` in `scenario` at `level` under `seed`: none when exact; else the
/// envelope's draw for (tyre, scenario, seed), scaled by the level (the 2× tyre is the 1× one's
/// error doubled); the pressure moves only where the file has pressure terms.
pub fn perturbation(seed: u64, tyre: &Tyre, scenario: &str, level: Level) -> Perturbation {
    if level == Level::Exact {
        return Perturbation::default();
    }
    let mut r = rng(seed, &format!("envelope|{}|{scenario}", tyre.file));
    scenario::draw(&mut r, level.scale(), tyre.pressure)
}

/// The tyre simulated under perturbation `d`: the file when exact, else the file moved by `d`.
pub fn truth(tyre: &Tyre, d: &Perturbation, level: Level) -> Params<f64> {
    match level {
        Level::Exact => tyre.params.clone(),
        _ => d.apply(&tyre.params),
    }
}

/// A scenario's trace as the bench's metrics read it: the sensors' rows (no slip angle; κ
/// noisy as an ABS has it), the true slips as a slip sensor would give them, the truth.
pub fn wheel_trace(tr: &scenario::Trace) -> WheelTrace {
    let rows = (0..tr.t.len())
        .map(|i| Sample {
            t: tr.t[i],
            fz: tr.fz[i],
            fy: tr.fy[i],
            mz: tr.mz[i],
            fx: Some(tr.fx[i]),
            vx: Some(tr.vx[i]),
            kappa: Some(tr.kappa[i]),
            alpha: None,
            gamma: Some(tr.gamma[i]),
        })
        .collect();
    WheelTrace {
        rows,
        slip_sensor: tr
            .alpha
            .iter()
            .copied()
            .zip(tr.kappa_true.iter().copied())
            .collect(),
        mu_true: tr.mu.clone(),
        util: tr.util.clone(),
    }
}

/// The traces of a case: each wheel of the scenario simulated on tyre `truth` at the case's
/// rate, with the noise of [`Noise::default`] under its own key (tyre, scenario, wheel, rate,
/// seed).
pub fn traces(
    truth: &Params<f64>,
    tyre: &Tyre,
    sc: &WheelScenario,
    rate: f64,
    seed: u64,
) -> Result<Vec<WheelTrace>, String> {
    sc.wheels
        .iter()
        .enumerate()
        .map(|(w, s)| {
            let k = key(&format!("noise|{}|{}|{w}|{rate}", tyre.file, sc.name));
            let tr = scenario::simulate(truth, s, rate, &Noise::default(), seed ^ k)?;
            Ok(wheel_trace(&tr))
        })
        .collect()
}

/// What an estimator did on a case's traces.
#[derive(Debug, Clone, Default)]
pub struct Outcome {
    /// The vehicle suite's metrics over the case's wheels.
    pub metrics: Metrics,
    /// Every step of the surface and when it was read.
    pub steps: Vec<StepRead>,
}

/// A wheel case's results.
#[derive(Debug, Clone)]
pub struct CaseResult {
    /// The perturbation the simulated tyre had (the default one when exact).
    pub perturbation: Perturbation,
    /// From a cold start.
    pub cold: Outcome,
    /// With `warm`: the second run in a row on the same estimator.
    pub warm: Option<Outcome>,
}

/// Runs a case: the traces simulated on the perturbed tyre ([`truth`]), the estimator built by
/// `make` from the *file's* parameters, driven over them; with `warm`, driven over them a
/// second time, its clock continued one row past the first run's end, and that run measured
/// too (its false change flags: [`warm_false_change_flags`]).
pub fn run_case(
    case: &WheelCase,
    tyres: &[Tyre],
    scenarios: &[WheelScenario],
    seed: u64,
    warm: bool,
    make: &MakeEstimator<'_>,
) -> Result<CaseResult, String> {
    let tyre = tyres.get(case.tyre).ok_or("no such tyre")?;
    let sc = scenarios.get(case.scenario).ok_or("no such scenario")?;
    let d = perturbation(seed, tyre, sc.name, case.level);
    let traces = traces(&truth(tyre, &d, case.level), tyre, sc, case.rate, seed)?;
    let mut e = make(&tyre.params)?;
    let cold = drive(&mut *e, &traces, false, 0.0)?;
    let outcome = |ests: &[Vec<Estimate>]| Outcome {
        metrics: metrics(&traces, ests),
        steps: step_reads(&traces, ests),
    };
    let warm = if warm {
        let end = traces
            .iter()
            .filter_map(|t| t.rows.last().map(|r| r.t))
            .fold(0.0, f64::max);
        let again = drive(&mut *e, &traces, false, end + 1.0 / case.rate)?;
        let mut o = outcome(&again);
        o.metrics.false_alarms = warm_false_change_flags(&traces, &cold, &again);
        Some(o)
    } else {
        None
    };
    Ok(CaseResult {
        perturbation: d,
        cold: outcome(&cold),
        warm,
    })
}

/// Runs every case on `jobs` threads (at least one); the results in the cases' order, whatever
/// the scheduling. `tick` is called after each case.
#[allow(clippy::too_many_arguments)]
pub fn run_all(
    cases: &[WheelCase],
    tyres: &[Tyre],
    scenarios: &[WheelScenario],
    seed: u64,
    warm: bool,
    jobs: usize,
    make: &MakeEstimator<'_>,
    tick: &(dyn Fn() + Sync),
) -> Vec<Result<CaseResult, String>> {
    let next = AtomicUsize::new(0);
    let out: Mutex<Vec<Option<Result<CaseResult, String>>>> =
        Mutex::new((0..cases.len()).map(|_| None).collect());
    std::thread::scope(|s| {
        for _ in 0..jobs.max(1).min(cases.len().max(1)) {
            s.spawn(|| loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(c) = cases.get(i) else { break };
                let r = run_case(c, tyres, scenarios, seed, warm, make);
                if let Ok(mut o) = out.lock() {
                    o[i] = Some(r);
                }
                tick();
            });
        }
    });
    out.into_inner()
        .unwrap_or_default()
        .into_iter()
        .map(|r| r.unwrap_or_else(|| Err("not run".into())))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all() -> (Vec<Tyre>, Vec<(String, String)>) {
        tyres(&Path::new(env!("CARGO_MANIFEST_DIR")).join("../host-tests/data/tyres")).unwrap()
    }

    /// Every file of the folder but the one the reader refuses (Model_Unstable.tir) is a tyre of
    /// the wheel cases; the standard plan is every tyre × scenario × level at 200 Hz and the
    /// rate subset exact and at 1× at 100 Hz and 1 kHz; the quick plan its three tyres.
    #[test]
    fn the_tyres_and_the_plan() {
        let (ok, skipped) = all();
        let names: Vec<&str> = ok.iter().map(|t| t.file.as_str()).collect();
        for want in [
            "MagicFormula52_Parameters.tir",
            "MagicFormula61_Parameters.tir",
            "MagicFormula62_Parameters.tir",
            "reference_tire_tvd3.tir",
            "PacejkaBook_Defaults.tir",
            "FSAE_Defaults.tir",
            "335_65R22_5_G275MSA_40psi.tir",
        ] {
            assert!(names.contains(&want), "{want}: {names:?}");
        }
        assert_eq!(skipped.len(), 1, "{skipped:?}");
        assert_eq!(skipped[0].0, "Model_Unstable.tir");
        assert!(skipped[0].1.contains("PCX1"), "{skipped:?}");
        let sc = scenarios();
        let n = ok.len();
        let p = plan(&ok, &sc, false);
        assert_eq!(p.len(), n * sc.len() * 3 + 2 * n * RATE_SUBSET.len() * 2);
        assert!(p.iter().take(n * sc.len() * 3).all(|c| c.rate == RATE));
        for r in RATES {
            assert_eq!(
                p.iter().filter(|c| c.rate == r).count(),
                n * RATE_SUBSET.len() * 2
            );
        }
        let q = plan(&ok, &sc, true);
        assert_eq!(q.len(), 3 * QUICK_SCENARIOS.len() * 2 + 2 * 3);
        let mut quick_tyres: Vec<&str> = q.iter().map(|c| ok[c.tyre].file.as_str()).collect();
        quick_tyres.sort();
        quick_tyres.dedup();
        let mut want = QUICK_TYRES;
        want.sort();
        assert_eq!(quick_tyres, want);
        // The FSAE tyre's sensors: Mz 7.5e-4·1000 N·0.26 m.
        let fsae = ok.iter().find(|t| t.file == "FSAE_Defaults.tir").unwrap();
        assert!((fsae.noise().1 - 0.195).abs() < 1e-9, "{:?}", fsae.noise());
    }

    /// A perturbation reaches the simulated tyre and never the estimator's: the estimator is
    /// built from the file at every level, the simulated tyre is the file moved by the
    /// perturbation (exact: the file itself), and the 2× tyre is the 1× one's error doubled.
    /// Every field of the envelope moves every tyre's forces or moments.
    #[test]
    fn a_perturbation_reaches_the_simulated_tyre_not_the_estimators_file() {
        let (ok, _) = all();
        let sc = scenarios();
        let t = ok
            .iter()
            .position(|t| t.file == "MagicFormula61_Parameters.tir")
            .unwrap();
        let short = WheelScenario {
            name: sc[0].name,
            wheels: vec![Scenario {
                duration: 0.5,
                ..sc[0].wheels[0]
            }],
        };
        let given = Mutex::new(Vec::new());
        for level in Level::ALL {
            let case = WheelCase {
                tyre: t,
                scenario: 0,
                level,
                rate: RATE,
            };
            let make = |p: &Params<f64>| {
                given.lock().unwrap().push(p.clone());
                estimator(p)
            };
            let res = run_case(&case, &ok, std::slice::from_ref(&short), 1, false, &make).unwrap();
            let d = res.perturbation;
            assert_eq!(d, perturbation(1, &ok[t], short.name, level));
            let sim = truth(&ok[t], &d, level);
            if level == Level::Exact {
                assert_eq!(d, Perturbation::default());
                assert_eq!(sim, ok[t].params);
            } else {
                assert_ne!(sim, ok[t].params);
                assert_eq!(sim.lky, ok[t].params.lky * d.ky);
                assert_eq!(sim.phy1, ok[t].params.phy1 + d.shy);
                assert_eq!(sim.inflpres, ok[t].params.inflpres * d.pressure);
                assert!(d.pressure != 1.0 && d.ky != 1.0);
            }
        }
        let given = given.into_inner().unwrap();
        assert_eq!(given.len(), 3);
        assert!(given.iter().all(|p| *p == ok[t].params));
        // 2× = the 1× draw doubled.
        let one = perturbation(1, &ok[t], "x", Level::Envelope);
        let two = perturbation(1, &ok[t], "x", Level::Twice);
        assert!(((two.ky - 1.0) - 2.0 * (one.ky - 1.0)).abs() < 1e-12);
        assert!((two.sht - 2.0 * one.sht).abs() < 1e-15);
        assert_ne!(one, perturbation(2, &ok[t], "x", Level::Envelope));
        // The simulated tyre moves the traces: the same noise on the file and on the 2× tyre.
        let d = perturbation(1, &ok[t], short.name, Level::Twice);
        let a = traces(&ok[t].params, &ok[t], &short, RATE, 1).unwrap();
        let b = traces(&truth(&ok[t], &d, Level::Twice), &ok[t], &short, RATE, 1).unwrap();
        assert_ne!(a[0].rows, b[0].rows);
        // Each field of the envelope moves each tyre (Fy, Mz at a small slip angle; Fx at a
        // small slip ratio).
        use gough::math::Libm;
        use gough::mf::{self, Input, Options};
        for ty in &ok {
            let out = |p: &Params<f64>| {
                let o = |alpha, kappa| {
                    mf::eval::<f64, Libm>(
                        p,
                        &Input {
                            fz: p.fnomin,
                            alpha,
                            kappa,
                            vx: 20.0,
                            ..Input::default()
                        },
                        &Options::default(),
                    )
                    .unwrap()
                };
                let (a, k) = (o(0.01, 0.0), o(0.0, -0.01));
                (a.fy, a.mz, k.fx)
            };
            let base = out(&ty.params);
            let fields: [(&str, Perturbation); 6] = [
                (
                    "ky",
                    Perturbation {
                        ky: 1.1,
                        ..Perturbation::default()
                    },
                ),
                (
                    "kx",
                    Perturbation {
                        kx: 1.1,
                        ..Perturbation::default()
                    },
                ),
                (
                    "trail",
                    Perturbation {
                        trail: 1.1,
                        ..Perturbation::default()
                    },
                ),
                (
                    "shy",
                    Perturbation {
                        shy: 0.002,
                        ..Perturbation::default()
                    },
                ),
                (
                    "sht",
                    Perturbation {
                        sht: 0.002,
                        ..Perturbation::default()
                    },
                ),
                (
                    "pressure",
                    Perturbation {
                        pressure: 1.15,
                        ..Perturbation::default()
                    },
                ),
            ];
            for (name, d) in fields {
                if name == "pressure" && !ty.pressure {
                    continue;
                }
                assert_ne!(out(&d.apply(&ty.params)), base, "{}: {name}", ty.file);
            }
        }
    }

    /// Each tyre's sensor noise is scaled to it: on a noise-free and a noisy log of the same
    /// case, Fy and Fz differ by 1 % of Fz rms, Mz by 7.5e-4·FNOMIN·R0 (2 N·m on the MF 6.1 car
    /// tyre, 0.195 N·m on the FSAE tyre, 2.8 N·m on the MF 5.2 truck tyre), κ by 0.005.
    #[test]
    fn each_tyres_noise_is_scaled_to_it() {
        let (ok, _) = all();
        let sc = Scenario {
            manoeuvre: Manoeuvre::SteadyCornering { util: 0.65 },
            mu: [0.8, 0.8],
            step: None,
            duration: 2.0,
        };
        let quiet = Noise {
            f_rel: 0.0,
            mz_rel: 0.0,
            kappa: 0.0,
        };
        for t in &ok {
            let a = scenario::simulate(&t.params, &sc, 1000.0, &quiet, 5).unwrap();
            let b = scenario::simulate(&t.params, &sc, 1000.0, &Noise::default(), 5).unwrap();
            let rms = |d: &dyn Fn(usize) -> f64| {
                ((0..a.t.len()).map(|i| d(i).powi(2)).sum::<f64>() / a.t.len() as f64).sqrt()
            };
            let (f, mz, k) = t.noise();
            let fy = rms(&|i| (b.fy[i] - a.fy[i]) / a.fz[i]);
            let fz = rms(&|i| (b.fz[i] - a.fz[i]) / a.fz[i]);
            let m = rms(&|i| b.mz[i] - a.mz[i]);
            let kk = rms(&|i| b.kappa[i] - a.kappa[i]);
            assert!(
                (fy / f - 1.0).abs() < 0.06 && (fz / f - 1.0).abs() < 0.06,
                "{}",
                t.file
            );
            assert!((m / mz - 1.0).abs() < 0.06, "{}: Mz {m} of {mz}", t.file);
            assert!((kk / k - 1.0).abs() < 0.06, "{}", t.file);
            let want = 7.5e-4 * t.params.fnomin * t.params.unloaded_radius;
            assert!((mz - want).abs() < 1e-12, "{}", t.file);
        }
        let by = |f: &str| ok.iter().find(|t| t.file == f).unwrap().noise().1;
        assert!((by("MagicFormula61_Parameters.tir") - 2.0).abs() < 0.01);
        assert!((by("FSAE_Defaults.tir") - 0.195).abs() < 1e-9);
        assert!((by("MagicFormula52_Parameters.tir") - 2.825).abs() < 0.01);
    }

    /// The results do not depend on the threads: one thread and two give the same figures, and
    /// a warm run is measured on its own rows.
    #[test]
    fn the_threads_change_nothing() {
        let (ok, _) = all();
        let sc: Vec<WheelScenario> = scenarios()
            .into_iter()
            .map(|mut s| {
                for w in &mut s.wheels {
                    w.duration = 1.0;
                    w.step = w.step.map(|_| 0.5);
                }
                s
            })
            .collect();
        let cases: Vec<WheelCase> = plan(&ok, &sc, true);
        let run = |jobs| {
            run_all(&cases, &ok, &sc, 3, true, jobs, &estimator, &|| {})
                .into_iter()
                .map(|r| {
                    let r = r.unwrap();
                    let w = r.warm.unwrap();
                    (
                        r.perturbation,
                        format!("{:?}", r.cold.metrics),
                        r.cold.steps,
                        format!("{:?}", w.metrics),
                        w.steps,
                    )
                })
                .collect::<Vec<_>>()
        };
        let (a, b) = (run(1), run(2));
        assert_eq!(a.len(), cases.len());
        assert_eq!(a, b);
    }
}
