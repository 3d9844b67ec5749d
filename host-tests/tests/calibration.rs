//! The online calibration converges from ordinary driving (issue 55, item 5's last target):
//! after 60 s of a slalom up to utilisation 0.5 on a surface the estimator is not told, each
//! calibrated property is within a quarter of its initial error, or its σ says why not.
//!
//! Each tyre is simulated off its file (peak trail +8 %, the trail's shift +1 mrad, Kxκ −8 %)
//! while the bank is given the file; the table printed (`-- --nocapture`) holds, per property,
//! the truth, the calibration at the end and its σ, the prior's σ — with the default
//! calibration (its steps gated on an identification held over a sweep) and with the road a
//! state of the calibration's own (`Config::cal_joint`).

use gough::math::Libm;
use gough::mu::calibration::{Property, PROPERTIES};
use gough::mu::{Bank, Config, Sample};
use gough_host::mu::scenario::{self, Manoeuvre, Noise, Perturbation, Scenario};
use std::path::Path;

fn params(name: &str) -> gough::mf::Params<f64> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data/tyres")
        .join(name);
    gough::tir::parse(&std::fs::read_to_string(p).unwrap())
        .unwrap()
        .params
}

/// The calibration after `sc` on the tyre `truth` (the bank given `file`), logged at 200 Hz.
fn run(
    file: &gough::mf::Params<f64>,
    truth: &gough::mf::Params<f64>,
    sc: &Scenario,
    cfg: Config<f64>,
) -> Bank<f64> {
    let tr = scenario::simulate(truth, sc, 200.0, &Noise::default(), 1).unwrap();
    let mut bank = Bank::new::<Libm>(file, None, cfg).unwrap();
    for i in 0..tr.t.len() {
        let s = Sample {
            t_us: (tr.t[i] * 1e6).round() as u32,
            fz: tr.fz[i],
            fy: tr.fy[i],
            mz: tr.mz[i],
            fx: Some(tr.fx[i]),
            kappa: Some(tr.kappa[i]),
            vx: Some(tr.vx[i]),
            gamma: Some(tr.gamma[i]),
        };
        bank.update::<Libm>(file, &s);
    }
    bank
}

#[test]
fn sixty_seconds_of_slalom_calibrate_the_tyre_or_say_why_not() {
    let d = Perturbation {
        trail: 1.08,
        sht: 0.001,
        kx: 0.92,
        ..Perturbation::default()
    };
    // What each property should read: ln of the scales, the shift SHt − SHy.
    let truth = [d.trail.ln(), 0.0, d.sht - d.shy, d.kx.ln()];
    let prior = Config::<f64>::default().cal_sigma;
    let sc = Scenario {
        manoeuvre: Manoeuvre::Slalom {
            amplitude: 0.5,
            freq: 0.5,
        },
        mu: [0.8, 0.8],
        step: None,
        duration: 60.0,
    };
    println!("| calibration | tyre | property | truth | at 60 s | σ | prior σ | verdict |");
    println!("|---|---|---|---|---|---|---|---|");
    let mut failures = Vec::new();
    for joint in [false, true] {
        let cfg = Config {
            cal_joint: joint,
            ..Config::default()
        };
        let how = if joint { "joint road" } else { "default" };
        for name in [
            "MagicFormula61_Parameters.tir",
            "FSAE_Defaults.tir",
            "CityBus_Pac02Tire.tir",
        ] {
            let file = params(name);
            let bank = run(&file, &d.apply(&file), &sc, cfg);
            let cal = bank.calibration();
            for k in 0..PROPERTIES {
                let p = Property::ALL[k];
                let (t, x) = (truth[k], cal.theta[k]);
                let s = cal.sigma::<Libm>(p);
                // Within a quarter of the initial error (the file's: |truth|), or not and its σ
                // says so (the truth within 2σ).
                let converged = (x - t).abs() <= 0.25 * t.abs() + 1e-12;
                let honest = (x - t).abs() <= 2.0 * s + 1e-12;
                let verdict = match (converged, honest) {
                    (true, _) => "converged",
                    (false, true) => "not yet: σ says so",
                    _ => "WRONG, σ too small",
                };
                println!(
                    "| {how} | {name} | {} | {t:+.4} | {x:+.4} | {s:.4} | {:.4} | {verdict} |",
                    p.name(),
                    prior[k]
                );
                if !(converged || honest) {
                    failures.push(format!(
                        "{how} {name} {}: {x:+.4} against {t:+.4}, σ {s:.4}",
                        p.name()
                    ));
                }
                // The slalom excites the trail: with the road a state of its own, it is learnt.
                if joint && p == Property::Trail && !converged {
                    failures.push(format!(
                        "{how} {name} trail not learnt: {x:+.4} against {t:+.4}"
                    ));
                }
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The log of `parts` (scenarios run one after the other on `truth`, 200 Hz, noise seed 1) as
/// one wheel's samples.
fn log_of(
    truth: &gough::mf::Params<f64>,
    parts: &[Scenario],
) -> Vec<(gough::proto::Wheel, gough_host::mu::Sample)> {
    let mut out = Vec::new();
    let mut t0 = 0.0;
    for sc in parts {
        let tr = scenario::simulate(truth, sc, 200.0, &Noise::default(), 1).unwrap();
        // The wheel cases' samples of the trace (no slip angle), on one clock.
        for mut r in gough_host::mu::bench::wheel::wheel_trace(&tr).rows {
            r.t += t0;
            out.push((gough::proto::Wheel::FrontLeft, r));
        }
        t0 += sc.duration + 0.005;
    }
    out
}

/// `gough mu calibrate`'s machinery (the online calibration on a road of known μ): a tyre off
/// its file in every calibrated property, a 40 s slalom to utilisation 0.8 and 10 s of steady
/// braking at utilisation 0.4 on μ 0.8. The trail, its shape and its shift are learnt on every
/// tyre (within a quarter of the initial error); Kxκ moves towards the truth but falls short
/// (a known limitation, docs/estimator.md: its σ can be too small), so for it the test asks
/// only that it moves the right way and does not overshoot.
#[test]
fn a_known_road_calibrates_every_property() {
    use gough_host::mu::calibrate;
    let d = Perturbation {
        trail: 1.08,
        trail_shape: 0.93,
        sht: 0.001,
        kx: 0.92,
        ..Perturbation::default()
    };
    let truth = [d.trail.ln(), d.trail_shape.ln(), d.sht - d.shy, d.kx.ln()];
    let parts = [
        Scenario {
            manoeuvre: Manoeuvre::Slalom {
                amplitude: 0.8,
                freq: 0.5,
            },
            mu: [0.8, 0.8],
            step: None,
            duration: 40.0,
        },
        Scenario {
            manoeuvre: Manoeuvre::SteadyBraking { util: 0.4 },
            mu: [0.8, 0.8],
            step: None,
            duration: 10.0,
        },
    ];
    println!("| tyre | property | truth | calibrated | σ | verdict |");
    println!("|---|---|---|---|---|---|");
    let mut failures = Vec::new();
    for name in [
        "MagicFormula61_Parameters.tir",
        "FSAE_Defaults.tir",
        "CityBus_Pac02Tire.tir",
    ] {
        let file = params(name);
        let tr = d.apply(&file);
        let log = log_of(&tr, &parts);
        let cals = calibrate::calibrate(&file, 0.8, &log, [None; 4]).unwrap();
        let c = cals[0].cal;
        assert!(
            cals[0].explained as f64 >= 0.99 * cals[0].excited as f64,
            "{:?}",
            cals[0]
        );
        for (k, p) in Property::ALL.iter().enumerate() {
            let v = f64::from(c.value[k]);
            let x = if p.is_scale() { v.ln() } else { v };
            let s = f64::from(c.sigma[k]);
            let t = truth[k];
            let converged = (x - t).abs() <= 0.25 * t.abs() + 1e-12;
            let honest = (x - t).abs() <= 2.0 * s + 1e-12;
            println!(
                "| {name} | {} | {t:+.4} | {x:+.4} | {s:.4} | {} |",
                p.name(),
                if converged {
                    "converged"
                } else if honest {
                    "σ says why not"
                } else {
                    "WRONG"
                }
            );
            let towards = x * t > 0.0 && (x - t).abs() < t.abs();
            let ok = match p {
                Property::Kx => towards,
                _ => converged,
            };
            if !ok {
                failures.push(format!(
                    "{name} {}: {x:+.4} against {t:+.4}, σ {s:.4}",
                    p.name()
                ));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
