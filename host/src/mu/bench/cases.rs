//! The bench's cases as data: a manoeuvre of the vehicle simulation on a road, the suite of
//! them, and how a case is simulated (the tyre the estimators are given may differ from the
//! simulated one: `--model-error`).

use crate::sim::{self, Log, Manoeuvre, Overrides, SimConfig};
use gough::mf::{Key, Params};

/// A benchmark case: a manoeuvre of the simulation on a road, and the group it counts in.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// Manoeuvre name (one of [`sim::MANOEUVRES`]).
    pub manoeuvre: &'static str,
    /// Road spec (the simulation's grammar, `gough sim --road`).
    pub road: String,
    /// Which group of the suite it belongs to.
    pub group: Group,
}

impl Case {
    /// Manoeuvre `name` (one of [`sim::MANOEUVRES`]) on `road` (the simulation's spec), in the
    /// group its road makes it: a change of surface where the road has a split, a step or a
    /// patch; else a straight ABS stop for the [`STRAIGHT_STOP`] manoeuvre, one surface for
    /// the others. An error names an unknown manoeuvre or a bad road.
    pub fn new(name: &str, road: &str) -> Result<Case, String> {
        let manoeuvre = sim::MANOEUVRES
            .iter()
            .copied()
            .find(|m| *m == name)
            .ok_or_else(|| {
                format!(
                    "unknown manoeuvre '{name}' (one of {})",
                    sim::MANOEUVRES.join(", ")
                )
            })?;
        let r = sim::Road::parse(road)?;
        let group = if r.split.is_some() || !r.steps.is_empty() || !r.patches.is_empty() {
            Group::Change
        } else if manoeuvre == STRAIGHT_STOP {
            Group::StraightStop
        } else {
            Group::Surface
        };
        Ok(Case {
            manoeuvre,
            road: road.to_string(),
            group,
        })
    }
}

/// The groups of the suite. The bench's closing lines count the issue's cases (issue 39's
/// targets: [`Group::Surface`] and [`Group::Change`]) apart from the whole suite.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Group {
    /// A manoeuvre on one surface.
    Surface,
    /// A manoeuvre over a change of surface (a patch, a step, a μ-split).
    Change,
    /// A straight ABS stop on one surface (the μ-split stop's braking: μ from Fx against κ).
    StraightStop,
}

impl Group {
    /// Among issue 39's cases (the suite without the straight ABS stops).
    pub const fn issue_case(self) -> bool {
        !matches!(self, Group::StraightStop)
    }
}

/// The surfaces (μ) of the suite's one-surface cases.
pub const SURFACES: [f64; 5] = [1.0, 0.7, 0.5, 0.3, 0.1];

/// The manoeuvres run on each of [`SURFACES`].
pub const ON_EACH_SURFACE: [&str; 5] = [
    "step-steer",
    "sine-dwell",
    "brake-in-turn",
    "constant-radius",
    "slalom",
];

/// The changes of surface: a manoeuvre, its road with `{0}`, `{1}` for the surfaces, and those
/// surfaces (μ).
pub const CHANGES: [(&str, &str, [f64; 2]); 4] = [
    ("abs-split", "split={0}/{1}", [0.9, 0.2]),
    ("sine-dwell", "mu={0}+patch={1}@45..300", [1.0, 0.4]),
    ("slalom", "step={0}@0,{1}@90", [1.0, 0.3]),
    ("constant-radius", "mu={0}+patch={1}@-5..5", [0.9, 0.3]),
];

/// The manoeuvre of the straight ABS stops (on each of [`SURFACES`]: the μ-split stop's braking
/// on one surface).
pub const STRAIGHT_STOP: &str = "abs-split";

/// The suite: every manoeuvre of [`ON_EACH_SURFACE`] on each of [`SURFACES`], the [`CHANGES`],
/// and the straight ABS stop on each of [`SURFACES`] (34 cases).
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
    let surface = |manoeuvre, mu, group| Case {
        manoeuvre,
        road: format!("mu={}", m(mu)),
        group,
    };
    let mut v = Vec::new();
    for man in ON_EACH_SURFACE {
        for mu in SURFACES {
            v.push(surface(man, mu, Group::Surface));
        }
    }
    for (manoeuvre, road, [a, b]) in CHANGES {
        v.push(Case {
            manoeuvre,
            road: road.replace("{0}", &m(a)).replace("{1}", &m(b)),
            group: Group::Change,
        });
    }
    for mu in SURFACES {
        v.push(surface(STRAIGHT_STOP, mu, Group::StraightStop));
    }
    v
}

/// Simulates a case.
pub fn simulate_case(p: &Params<f64>, c: &Case) -> Result<Log, String> {
    let m = Manoeuvre::by_name(c.manoeuvre, &Overrides::default())?;
    let mut cfg = SimConfig::new(m);
    cfg.road = sim::Road::parse(&c.road)?;
    sim::simulate(&cfg, p, false)
}

/// The estimators' tyre model under `--model-error`: `p` with each `(key, delta)` added to its
/// parameter. Refuses a result the `.tir` checks refuse.
pub fn model_with_error(p: &Params<f64>, errors: &[(Key, f64)]) -> Result<Params<f64>, String> {
    let mut q = p.clone();
    for &(key, d) in errors {
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
        // The groups: 25 cases on one surface, 4 changes, 5 straight stops after them.
        let groups: Vec<Group> = suite().into_iter().map(|c| c.group).collect();
        let count = |g| groups.iter().filter(|&&x| x == g).count();
        assert_eq!(
            (
                count(Group::Surface),
                count(Group::Change),
                count(Group::StraightStop)
            ),
            (25, 4, 5)
        );
        assert!(groups[29..].iter().all(|&g| g == Group::StraightStop));
        // Each as its road makes it.
        for c in suite_shifted(0.025).into_iter().chain(suite()) {
            assert_eq!(Case::new(c.manoeuvre, &c.road), Ok(c.clone()));
        }
        assert!(Case::new("moonwalk", "mu=0.5").is_err());
        assert!(Case::new("slalom", "mu=").is_err());
        assert!(suite()
            .iter()
            .all(|c| sim::MANOEUVRES.contains(&c.manoeuvre)));
    }

    /// `--model-error` adds each delta to its parameter and to nothing else; a tyre the `.tir`
    /// checks refuse is an error.
    #[test]
    fn a_model_error_changes_its_parameters_only() {
        let p = bundled();
        let q = model_with_error(&p, &[(Key::PHY1, 0.002), (Key::PVY1, -0.01)]).unwrap();
        assert!((q.phy1 - p.phy1 - 0.002).abs() < 1e-15);
        assert!((q.pvy1 - p.pvy1 + 0.01).abs() < 1e-15);
        let mut back = q.clone();
        back.phy1 = p.phy1;
        back.pvy1 = p.pvy1;
        assert_eq!(back, p);
        assert_eq!(model_with_error(&p, &[]).unwrap(), p);
        let e = model_with_error(&p, &[(Key::FNOMIN, -1e9)]).unwrap_err();
        assert!(e.contains("FNOMIN"), "{e}");
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
        let log = simulate_case(&p, &suite()[0]).unwrap();
        assert_eq!(suite()[0].road, "mu=1.0");
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
