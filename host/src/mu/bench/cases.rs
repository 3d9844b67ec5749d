//! The bench's cases as data: a manoeuvre of the vehicle simulation on a road, the suite of
//! them, and how a case is simulated (the tyre the estimators are given may differ from the
//! simulated one: `--model-error`).

use crate::sim::{self, Log, Manoeuvre, Overrides, SimConfig};
use gough::mf::Params;

/// A benchmark case: a manoeuvre on a road.
#[derive(Debug, Clone)]
pub struct Case {
    /// Manoeuvre name.
    pub manoeuvre: &'static str,
    /// Road spec.
    pub road: String,
}

/// The suite: every manoeuvre on μ = 1.0, 0.7, 0.5, 0.3, 0.1, plus surface changes, plus the
/// straight ABS stop (the `abs-split` manoeuvre on one surface) on each μ.
pub fn suite() -> Vec<Case> {
    suite_shifted(0.0)
}

/// [`suite`] with every surface's μ shifted by `d` (`gough mu bench --mu-shift`): with
/// `d` = 0.025 each lies midway between two of the bank's hypotheses (0.10, 0.15, …), which the
/// suite's own surfaces all coincide with. `d` = 0 gives the suite's road specs unchanged.
pub fn suite_shifted(d: f64) -> Vec<Case> {
    let m = |mu: f64| -> String {
        let v = ((mu + d) * 1e6).round() / 1e6;
        format!("{v:?}")
    };
    let mut v = Vec::new();
    for man in [
        "step-steer",
        "sine-dwell",
        "brake-in-turn",
        "constant-radius",
        "slalom",
    ] {
        for mu in [1.0, 0.7, 0.5, 0.3, 0.1] {
            v.push(Case {
                manoeuvre: man,
                road: format!("mu={}", m(mu)),
            });
        }
    }
    v.push(Case {
        manoeuvre: "abs-split",
        road: format!("split={}/{}", m(0.9), m(0.2)),
    });
    v.push(Case {
        manoeuvre: "sine-dwell",
        road: format!("mu={}+patch={}@45..300", m(1.0), m(0.4)),
    });
    v.push(Case {
        manoeuvre: "slalom",
        road: format!("step={}@0,{}@90", m(1.0), m(0.3)),
    });
    v.push(Case {
        manoeuvre: "constant-radius",
        road: format!("mu={}+patch={}@-5..5", m(0.9), m(0.3)),
    });
    // Straight ABS stops (the μ-split stop's braking on one surface): μ from Fx against κ.
    for mu in [1.0, 0.7, 0.5, 0.3, 0.1] {
        v.push(Case {
            manoeuvre: "abs-split",
            road: format!("mu={}", m(mu)),
        });
    }
    v
}

/// A straight ABS stop: the `abs-split` manoeuvre on one surface (not among issue 39's cases;
/// the suite adds them after those).
pub fn straight_stop(c: &Case) -> bool {
    c.manoeuvre == "abs-split" && c.road.starts_with("mu=")
}

/// Simulates a case.
pub fn simulate_case(p: &Params<f64>, c: &Case) -> Result<Log, String> {
    let m = Manoeuvre::by_name(c.manoeuvre, &Overrides::default())?;
    let mut cfg = SimConfig::new(m);
    cfg.road = sim::Road::parse(&c.road)?;
    sim::simulate(&cfg, p, false)
}

/// The estimators' tyre model under `--model-error`: `p` with each NAME=DELTA added to the
/// parameter NAME (a `.tir` key, any case). Refuses an unknown name, a DELTA that is not a
/// finite number, and a result the `.tir` checks refuse.
pub fn model_with_error(p: &Params<f64>, errors: &[String]) -> Result<Params<f64>, String> {
    let mut q = p.clone();
    for kv in errors {
        let (name, v) = kv
            .split_once('=')
            .ok_or_else(|| format!("--model-error {kv}: expected NAME=DELTA"))?;
        let key = gough::mf::Key::from_name(name.trim())
            .ok_or_else(|| format!("--model-error {kv}: no .tir parameter '{}'", name.trim()))?;
        let d: f64 = v
            .trim()
            .parse()
            .ok()
            .filter(|d: &f64| d.is_finite())
            .ok_or_else(|| format!("--model-error {kv}: '{}' is not a finite number", v.trim()))?;
        q.set(key, q.get(key) + d);
    }
    gough::tir::validate(&q).map_err(|(k, why)| {
        format!(
            "--model-error: the estimators' tyre is not a valid one ({}: {why:?})",
            k.name()
        )
    })?;
    Ok(q)
}

/// Wheelbase of the simulated vehicle \[m\] (the front-to-rear preview's distance).
pub fn sim_wheelbase() -> f64 {
    sim::VehicleParams::default().wheelbase()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tyre::bundled;
    use gough::math::Libm;

    /// `--mu-shift`: every surface of the suite moved by the same amount, the specs unchanged
    /// at 0; the shifted ones lie midway between the bank's hypotheses.
    #[test]
    fn the_shifted_suite_moves_every_surface() {
        let roads =
            |d: f64| -> Vec<String> { suite_shifted(d).into_iter().map(|c| c.road).collect() };
        assert_eq!(
            roads(0.0),
            suite().into_iter().map(|c| c.road).collect::<Vec<_>>()
        );
        assert!(roads(0.0).contains(&"step=1.0@0,0.3@90".to_string()));
        let r = roads(0.025);
        assert_eq!(r.len(), suite().len());
        for want in [
            "mu=1.025",
            "mu=0.125",
            "split=0.925/0.225",
            "mu=1.025+patch=0.425@45..300",
            "step=1.025@0,0.325@90",
            "mu=0.925+patch=0.325@-5..5",
        ] {
            assert!(r.contains(&want.to_string()), "{want}: {r:?}");
        }
        for c in suite_shifted(0.025) {
            sim::Road::parse(&c.road).unwrap();
        }
    }

    /// `--model-error` adds each delta to its parameter (any case) and to nothing else.
    #[test]
    fn a_model_error_changes_its_parameters_only() {
        let p = crate::tyre::load(std::path::Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../host-tests/data/tyres/MagicFormula61_Parameters.tir"
        )))
        .unwrap()
        .params;
        let q = model_with_error(&p, &["PHY1=0.002".into(), "pvy1 = -0.01".into()]).unwrap();
        assert!((q.phy1 - p.phy1 - 0.002).abs() < 1e-15);
        assert!((q.pvy1 - p.pvy1 + 0.01).abs() < 1e-15);
        let mut back = q.clone();
        back.phy1 = p.phy1;
        back.pvy1 = p.pvy1;
        assert_eq!(back, p);
        assert_eq!(model_with_error(&p, &[]).unwrap(), p);
        for bad in ["PHY1", "NOPE=1", "PHY1=x", "PHY1=NaN", "FNOMIN=-1e9"] {
            assert!(model_with_error(&p, &[bad.into()]).is_err(), "{bad}");
        }
    }

    /// Why the step steer on μ 1.0 stays ambiguous with perfect sensors: its front-left wheel,
    /// steady at 4 s (Fz ≈ 3,370 N, γ ≈ −0.036 rad, utilisation ≈ 0.56, trail 9.1 mm), makes a
    /// point that the simulation's own Magic Formula puts on two surfaces: the true one, and
    /// one near λμ 0.62 (μ ≈ 0.63) at utilisation ≈ 0.89, where the trail has collapsed to
    /// the grippy curve's value at that force. No single reading can choose between
    /// them; only how the point got there can (README, "Not the sensors: a single point").
    #[test]
    fn one_steady_point_lies_on_two_surfaces() {
        use gough::mf::{self, Input, Options, Side};
        let p = bundled();
        let case = Case {
            manoeuvre: "step-steer",
            road: "mu=1.0".into(),
        };
        let log = simulate_case(&p, &case).unwrap();
        let rec = log.records.iter().find(|r| r.t >= 4.0).unwrap();
        let w = &rec.wheels[0]; // front left
        let tau_m = -w.mz / w.fy;
        let opts = Options {
            transient: true,
            mounted: Some(Side::Left),
            ..Options::default()
        };
        // The trail on surface λμ at the measured |Fy|, on the rising side of the force (small
        // slip first), with the record's load, camber, slip ratio and speed; None when the
        // surface never reaches the force.
        let eval = |q: &Params<f64>, alpha: f64| {
            let inp = Input {
                fz: w.fz,
                kappa: w.kappa_t,
                alpha,
                gamma: w.gamma,
                vx: w.vx,
                ..Input::default()
            };
            mf::eval::<f64, Libm>(q, &inp, &opts).unwrap()
        };
        let trail_at_force = |lam: f64| -> Option<(f64, f64)> {
            let mut q = p.clone();
            q.lmuy = lam;
            q.lmux = lam;
            let sgn = w.alpha_t.signum();
            let (mut lo, mut hi) = (0.0, 0.0);
            for i in 1..=400 {
                let a = sgn * 0.0005 * i as f64;
                if eval(&q, a).fy.abs() >= w.fy.abs() {
                    hi = a;
                    break;
                }
                lo = a;
            }
            if hi == 0.0 {
                return None;
            }
            for _ in 0..50 {
                let mid = 0.5 * (lo + hi);
                if eval(&q, mid).fy.abs() < w.fy.abs() {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let o = eval(&q, hi);
            // Utilisation as the bench counts it: |F|/(μ·Fz), μ = λμ·μy0.
            Some((-o.mz / o.fy, w.fx.hypot(w.fy) / (lam * log.mu_y0 * w.fz)))
        };
        let lam_true = 1.0 / log.mu_y0;
        let grid: Vec<f64> = (40..=130).map(|i| 0.01 * i as f64).collect();
        let d: Vec<Option<(f64, f64)>> = grid
            .iter()
            .map(|&l| trail_at_force(l).map(|(t, u)| (t - tau_m, u)))
            .collect();
        // Surfaces whose curve passes through the measured point: sign changes of d.
        let mut roots = Vec::new();
        for i in 1..grid.len() {
            if let (Some((a, _)), Some((b, u))) = (d[i - 1], d[i]) {
                if a * b <= 0.0 && a != b {
                    let l = grid[i - 1] + (grid[i] - grid[i - 1]) * a / (a - b);
                    roots.push((l, u * grid[i] / l));
                }
            }
        }
        std::println!(
            "trail {:.2} mm at Fy {:.0} N, Fz {:.0} N, γ {:.4}: on λμ {roots:.3?}",
            1000.0 * tau_m,
            w.fy,
            w.fz,
            w.gamma
        );
        assert_eq!(roots.len(), 2, "{roots:?}");
        let (hi, lo) = (roots[1], roots[0]);
        assert!(
            (hi.0 - lam_true).abs() < 0.02,
            "{roots:?} against {lam_true}"
        );
        assert!((0.55..0.7).contains(&lo.0), "{roots:?}");
        assert!(hi.1 < 0.6 && lo.1 > 0.85, "utilisations {roots:?}");
    }
}
