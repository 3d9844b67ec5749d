//! Issue 40, items 3 and 4: thermal and speed-dependent friction told apart where the programme
//! lets them and reported indistinguishable where it does not; two effects at once by forward
//! selection (a pair gets both, one effect exactly one, none none). Small generated logs with
//! few fit rows; `gough gap bench` is the heavy check.
use gough_host::gap::bench::{self, GenConfig};
use gough_host::gap::effects::Effect;
use gough_host::gap::log::Log;
use gough_host::gap::{self as gap};
use gough_host::rng::Rng;
use std::path::Path;

fn tyre(name: &str) -> gough::mf::Params<f64> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data/tyres")
        .join(name);
    gough_host::tyre::load(&p).unwrap().params
}

fn diagnose(p: gough::mf::Params<f64>, lg: &Log, fit_rows: usize) -> gap::Diagnosis {
    gap::diagnose(
        p,
        lg,
        "SIM.tir",
        "generated",
        &gap::Options {
            fit_rows: Some(fit_rows),
            ..gap::Options::default()
        },
    )
    .unwrap()
}

/// The truth `effects` on `lg`'s inputs at magnitude 1, with 1 % white noise (seeded).
fn with_truth(p: &gough::mf::Params<f64>, lg: Log, effects: &[Effect], seed: u64) -> Log {
    with_truth_at(p, lg, effects, seed, 1.0, 0.01)
}

/// The truth `effects` on `lg`'s inputs at magnitude `m`, white noise `noise` × each channel's
/// RMS (seeded).
fn with_truth_at(
    p: &gough::mf::Params<f64>,
    mut lg: Log,
    effects: &[Effect],
    seed: u64,
    m: f64,
    noise: f64,
) -> Log {
    let clean = bench::truth(p, &lg, effects, m, seed).unwrap();
    let mut rng = Rng::new(seed);
    let sd: Vec<f64> = (0..3)
        .map(|c| noise * gap::stats::rms(clean.iter().map(|o| o[c])))
        .collect();
    lg.meas = clean
        .iter()
        .map(|o| {
            [
                o[0] + sd[0] * rng.normal(),
                o[1] + sd[1] * rng.normal(),
                o[2] + sd[2] * rng.normal(),
            ]
        })
        .collect();
    lg
}

fn cfg(rows: usize, seed: u64) -> GenConfig {
    GenConfig {
        rows,
        rate: 100.0,
        seed,
        noise: 0.01,
        load_oscillation: true,
        ..GenConfig::default()
    }
}

const THERMAL: Effect = Effect::Thermal;
const SPEED: Effect = Effect::SpeedDependentFriction;

#[test]
fn thermal_and_speed_friction_are_told_apart_where_the_programme_varies_them_independently() {
    // The test-trailer programme: Vx, α, κ, Fz each their own multisine, so the slip speed and
    // the (low-passed) slip power move independently of each other. The four diagnoses in
    // parallel (the CI machine's cores).
    let cases = [
        ("MagicFormula61_Parameters.tir", 2, THERMAL, SPEED),
        ("MagicFormula61_Parameters.tir", 2, SPEED, THERMAL),
        ("reference_tire_tvd3.tir", 3, THERMAL, SPEED),
        ("reference_tire_tvd3.tir", 3, SPEED, THERMAL),
    ];
    std::thread::scope(|s| {
        let handles: Vec<_> = cases
            .iter()
            .map(|&(file, seed, truth, other)| {
                s.spawn(move || {
                    let p = tyre(file);
                    let lg = with_truth(&p, bench::inputs(&p, &cfg(1500, seed)), &[truth], seed);
                    (file, truth, other, diagnose(p, &lg, 300))
                })
            })
            .collect();
        for h in handles {
            let (file, truth, other, d) = h.join().unwrap();
            assert_eq!(
                d.verdict,
                Some(truth),
                "{file}, truth {truth:?}: {:?}",
                d.report.verdict
            );
            assert!(
                !d.indistinguishable.contains(&other),
                "{file}, truth {truth:?}: {other:?} reported indistinguishable: {:?}",
                d.report.verdict
            );
        }
    });
}

#[test]
fn thermal_and_speed_friction_are_indistinguishable_where_slip_power_follows_slip_speed() {
    // One operating point throughout: constant Vx, Fz, α = 0.1 rad, no κ, no camber. Slip
    // speed and slip power never move, so a friction that falls with slip speed and one that
    // falls with a tread temperature (at its equilibrium from the log's start: t0 is fitted)
    // predict the same forces; the held-out difference is neither relevant nor significant.
    // The truth is the speed-dependent one (a thermal truth starts cold and shows its warm-up,
    // which tells them apart). The diagnosis must not pick one of the two.
    let p = tyre("MagicFormula61_Parameters.tir");
    let mut lg = bench::inputs(
        &p,
        &GenConfig {
            load_oscillation: false,
            ..cfg(1500, 4)
        },
    );
    for i in 0..lg.len() {
        lg.vx[i] = 16.0;
        lg.fz[i] = p.fnomin;
        lg.kappa[i] = 0.0;
        lg.gamma[i] = 0.0;
        lg.alpha[i] = 0.1;
    }
    lg.p = None;
    lg.phit = None;
    for (m, noise) in [(1.0, 0.01), (0.5, 0.03)] {
        let lg = with_truth_at(&p, lg.clone(), &[SPEED], 5, m, noise);
        let d = diagnose(p.clone(), &lg, 300);
        let sh = |e: Effect| d.shrinks.iter().find(|s| s.0 == e).map(|s| s.1);
        eprintln!(
            "m {m}, noise {noise}: named {:?}, indistinguishable {:?}; shrink thermal {:?}, speed {:?}",
            d.named,
            d.indistinguishable,
            sh(THERMAL),
            sh(SPEED)
        );
        let named: Vec<Effect> = d
            .named
            .iter()
            .chain(&d.indistinguishable)
            .copied()
            .collect();
        assert!(
            named.contains(&THERMAL) && named.contains(&SPEED),
            "m {m}: {:?}",
            d.report.verdict
        );
        if d.verdict == Some(SPEED) || d.verdict == Some(THERMAL) {
            // Reported against each other, in the report too.
            let other = if d.verdict == Some(SPEED) {
                THERMAL
            } else {
                SPEED
            };
            assert!(d
                .report
                .verdict
                .indistinguishable_from
                .contains(&other.name().to_string()));
        }
    }
}

#[test]
fn a_pair_gets_both_a_single_effect_one_and_none_none() {
    let p = tyre("MagicFormula61_Parameters.tir");
    let cases: [(&[Effect], u64); 4] = [
        (&[Effect::Thermal, Effect::SensorLag], 11),
        (&[Effect::CombinedSlip, Effect::ConicityPlysteer], 12),
        (&[Effect::Thermal], 13),
        (&[], 14),
    ];
    std::thread::scope(|s| {
        let handles: Vec<_> = cases
            .iter()
            .map(|&(effects, seed)| {
                let p = p.clone();
                s.spawn(move || {
                    let lg = with_truth(&p, bench::inputs(&p, &cfg(1500, seed)), effects, seed);
                    let d = diagnose(p, &lg, 300);
                    (effects, d)
                })
            })
            .collect();
        for h in handles {
            let (effects, d) = h.join().unwrap();
            let mut want = effects.to_vec();
            let mut got = d.named.clone();
            want.sort();
            got.sort();
            assert_eq!(
                got, want,
                "{:?}; second round {:?}",
                d.report.verdict, d.seconds
            );
            let v = &d.report.verdict;
            assert_eq!(v.effects.len(), effects.len());
            if effects.len() == 2 {
                // Each with its own share, and the whole more than either alone.
                let total = v.shrink.unwrap();
                for e in &v.effects {
                    assert!(e.shrink_added > gap::MIN_ADD_SHRINK, "{v:?}");
                    assert!(e.shrink_alone < total, "{v:?}");
                }
                assert!(d.report.pair_params.is_some());
            }
        }
    });
}
