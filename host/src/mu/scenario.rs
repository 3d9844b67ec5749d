//! Wheel-level scenarios for the friction estimator's bench: one tyre, one wheel, driven by a
//! manoeuvre stated in the tyre's own scales (utilisation of whatever surface is under it, its
//! slip at a utilisation), on a surface that may step, with the tyre on the car differing from
//! its file by a [`Perturbation`], logged at any rate with sensor noise scaled to the tyre.
//!
//! Unlike the vehicle simulation ([`crate::sim`]), whose car is sized for one tyre, this runs
//! every tyre at its own nominal load: the estimator's bench uses it for the tyres of
//! `host-tests/data/tyres` and for the tyre-that-is-not-its-file envelope (docs/estimator.md).
//!
//! The truth is the core's transient tyre ([`gough::relax::TransientTyre`]: eq. 20, then the
//! Magic Formula at α′, κ′) stepped at [`STEP`] with the *perturbed* parameters on a surface μ
//! (λμx = λμy = μ/μy0 of the perturbed file, docs/architecture.md); the log takes every
//! `1/rate` of it, with white noise on Fz, Fy, Fx (a share of Fz), Mz (a share of FNOMIN·R0)
//! and κ.
use crate::rng::Rng;
use gough::math::Libm;
use gough::mf::{self, Input, Options, Params};
use gough::relax::{Kinematics, Operating, TransientTyre};

/// Internal step of the truth \[s\].
pub const STEP: f64 = 1e-3;
/// Forward speed of every scenario \[m/s\].
pub const VX: f64 = 20.0;

/// How the tyre on the car differs from its file. Scales multiply, shifts add.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Perturbation {
    /// Cornering stiffness scale (λKy).
    pub ky: f64,
    /// Longitudinal slip stiffness scale (λKx).
    pub kx: f64,
    /// Peak trail scale (λt).
    pub trail: f64,
    /// Trail shape: the scale of Bt (QBZ1–QBZ3).
    pub trail_shape: f64,
    /// Horizontal shift of Fy, added to PHY1 \[rad\].
    pub shy: f64,
    /// Horizontal shift of the trail, added to QHZ1 \[rad\].
    pub sht: f64,
    /// Inflation pressure scale (INFLPRES), where the file has pressure terms.
    pub pressure: f64,
}

impl Default for Perturbation {
    fn default() -> Self {
        Perturbation {
            ky: 1.0,
            kx: 1.0,
            trail: 1.0,
            trail_shape: 1.0,
            shy: 0.0,
            sht: 0.0,
            pressure: 1.0,
        }
    }
}

/// The envelope of issue 55: a real tyre differs from its file by up to ±10 % in cornering and
/// longitudinal stiffness and in peak trail, ±2 mrad in the Fy and trail shifts and ±15 % in
/// pressure (where the file has pressure terms); `scale` 2 doubles every bound.
pub fn draw(rng: &mut Rng, scale: f64, has_pressure: bool) -> Perturbation {
    let mut u = |a: f64| rng.range(-a * scale, a * scale);
    Perturbation {
        ky: 1.0 + u(0.10),
        kx: 1.0 + u(0.10),
        trail: 1.0 + u(0.10),
        trail_shape: 1.0,
        shy: u(0.002),
        sht: u(0.002),
        pressure: if has_pressure { 1.0 + u(0.15) } else { 1.0 },
    }
}

impl Perturbation {
    /// The file's parameters with the perturbation put in.
    pub fn apply(&self, p: &Params<f64>) -> Params<f64> {
        let mut q = p.clone();
        q.lky *= self.ky;
        q.lkx *= self.kx;
        q.ltr *= self.trail;
        q.qbz1 *= self.trail_shape;
        q.qbz2 *= self.trail_shape;
        q.qbz3 *= self.trail_shape;
        q.phy1 += self.shy;
        q.qhz1 += self.sht;
        if q.inflpres > 0.0 {
            q.inflpres *= self.pressure;
        }
        q
    }
}

/// Whether a file has inflation-pressure terms (MF 6.x with a nonzero PPY/PPX/PPZ).
pub fn has_pressure(p: &Params<f64>) -> bool {
    p.inflpres > 0.0
        && [p.ppy1, p.ppy3, p.ppx1, p.ppx3, p.ppz1]
            .iter()
            .any(|x| *x != 0.0)
}

/// A manoeuvre of one wheel, in the tyre's own scales. Utilisation is |F|/(μ·Fz) of the surface
/// under the wheel at the time.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Manoeuvre {
    /// Steady cornering: the driver holds pure-lateral utilisation `util` of whatever surface is
    /// under the car (the slip angle follows a step of the surface at once).
    SteadyCornering {
        /// Utilisation held \[-\].
        util: f64,
    },
    /// Steady straight braking (an ABS holding `util` of whatever surface).
    SteadyBraking {
        /// Utilisation held \[-\].
        util: f64,
    },
    /// Braking in a turn: the slip angle of pure-lateral utilisation `lat_util` on the first
    /// surface, held; κ ramped from 0 to `kappa` over 3 s from t = 2 s, held 2 s, released
    /// over 1 s.
    BrakeInTurn {
        /// Pure-lateral utilisation of the slip angle held \[-\].
        lat_util: f64,
        /// Deepest κ (negative: braking) \[-\].
        kappa: f64,
    },
    /// Braking under an ABS, straight: κ ramped over 0.5 s to κ95, the slip ratio of utilisation
    /// 0.95 on the first surface at FNOMIN, then cycling at `freq` between 0.6 and 1.4 times
    /// it (past the peak and back, as a slip-threshold ABS cycles). Two wheels of it on two
    /// surfaces are the wheel level's μ-split stop.
    AbsBraking {
        /// Cycles per second \[Hz\].
        freq: f64,
    },
    /// A slalom: α = `amplitude`·α(util 0.95 on the first surface)·sin(2π·`freq`·t).
    Slalom {
        /// Amplitude in units of the first surface's slip angle at utilisation 0.95 \[-\].
        amplitude: f64,
        /// \[Hz\]
        freq: f64,
    },
}

/// A scenario: a manoeuvre on a surface that steps from `mu[0]` to `mu[1]` at `step` s (none:
/// `mu[0]` throughout), lasting `duration` s, with the load FNOMIN·(1 + 0.15 sin(2π·0.2t) +
/// 0.02 sin(2π·10t)): slow weight transfer and wheel hop.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scenario {
    /// The manoeuvre.
    pub manoeuvre: Manoeuvre,
    /// The surfaces, before and after the step \[-\].
    pub mu: [f64; 2],
    /// Time of the step \[s\] (`None`: no step).
    pub step: Option<f64>,
    /// Length \[s\].
    pub duration: f64,
}

/// Sensor noise, rms, scaled to the tyre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Noise {
    /// Fx, Fy, Fz as a share of Fz \[-\].
    pub f_rel: f64,
    /// Mz as a share of FNOMIN·R0 \[-\] (7.5e-4: 2 N·m on the bench's MF 6.1 car tyre).
    pub mz_rel: f64,
    /// κ \[-\].
    pub kappa: f64,
}

impl Noise {
    /// The Mz noise on tyre `p`, rms \[N·m\]: `mz_rel`·FNOMIN·R0.
    pub fn mz_sigma(&self, p: &Params<f64>) -> f64 {
        self.mz_rel * p.fnomin * p.unloaded_radius
    }

    /// These sensors on tyre `p` as the bench's [`Sensors`](super::bench::Sensors) (no delay;
    /// κ with its noise): what `mu::bound` takes for a scenario's trace.
    pub fn sensors(&self, p: &Params<f64>) -> super::bench::Sensors {
        super::bench::Sensors {
            sigma_mz: self.mz_sigma(p),
            sigma_rel: self.f_rel,
            delay: 0.0,
            sigma_kappa: self.kappa,
        }
    }
}

impl Default for Noise {
    fn default() -> Self {
        Noise {
            f_rel: 0.01,
            mz_rel: 7.5e-4,
            kappa: 0.005,
        }
    }
}

/// One wheel's log: what the sensors measure (no slip angle is given to an estimator) and the
/// truth, per logged row.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Trace {
    /// Time \[s\].
    pub t: Vec<f64>,
    /// Measured Fz, Fy, Fx \[N\], Mz \[N·m\], κ \[-\], Vx \[m/s\], γ \[rad\].
    pub fz: Vec<f64>,
    pub fy: Vec<f64>,
    pub fx: Vec<f64>,
    pub mz: Vec<f64>,
    pub kappa: Vec<f64>,
    pub vx: Vec<f64>,
    pub gamma: Vec<f64>,
    /// True μ under the wheel.
    pub mu: Vec<f64>,
    /// True utilisation |F|/(μ·Fz).
    pub util: Vec<f64>,
    /// True slip angle α and κ (the input, before relaxation).
    pub alpha: Vec<f64>,
    pub kappa_true: Vec<f64>,
    /// The transient slips α′, κ′ the forces were evaluated at (`gough::relax`).
    pub alpha_t: Vec<f64>,
    pub kappa_t: Vec<f64>,
    /// The true load \[N\].
    pub fz_true: Vec<f64>,
}

/// μy0 of a parameter set (the bank's definition: μy at FNOMIN, zero slip and camber, nominal
/// pressure, docs/architecture.md).
pub fn mu_y0(p: &Params<f64>) -> Result<f64, String> {
    gough::mu::mu_y0::<f64, Libm>(p).ok_or_else(|| "the tyre has no friction at FNOMIN".into())
}

/// The parameters on surface μ: λμx, λμy scaled by μ/μy0.
fn on_surface(p: &Params<f64>, mu: f64, mu0: f64) -> Params<f64> {
    let mut q = p.clone();
    q.lmux *= mu / mu0;
    q.lmuy *= mu / mu0;
    q
}

fn steady(q: &Params<f64>, fz: f64, alpha: f64, kappa: f64) -> Result<(f64, f64), String> {
    let o = mf::eval::<f64, Libm>(
        q,
        &Input {
            fz,
            alpha,
            kappa,
            vx: VX,
            ..Input::default()
        },
        &Options {
            moments: false,
            ..Options::default()
        },
    )
    .map_err(|e| format!("{e:?}"))?;
    Ok((o.fx, o.fy))
}

/// The smallest slip x ≥ 0 in steps of `dx` up to `max` at which `force(x)` reaches `target`,
/// refined on that step ([`refine`]: the rising side of the curve); when the force never
/// reaches it (a utilisation beyond the tyre's peak at this load: a tyre whose peak |F| is
/// below μ·Fz, or a perturbed pressure), the slip of the largest force on the steps, the peak's.
fn solve(
    target: f64,
    dx: f64,
    max: f64,
    force: impl Fn(f64) -> Result<f64, String>,
) -> Result<f64, String> {
    let mut x = 0.0;
    let mut fx = force(0.0)?;
    if fx >= target {
        return Ok(0.0);
    }
    let mut peak = (fx, 0.0);
    while x < max {
        let nx = x + dx;
        let fn_ = force(nx)?;
        if fn_ >= target {
            return refine(target, (x, fx), (nx, fn_), &force);
        }
        if fn_ > peak.0 {
            peak = (fn_, nx);
        }
        (x, fx) = (nx, fn_);
    }
    Ok(peak.1)
}

/// The root of `force(x) = target` in the bracket `lo` (below the target) .. `hi` (at or above
/// it), each `(x, force(x))`, by the Illinois variant of regula falsi: to 1e-12 of the slip or
/// 1e-9 of the target (a utilisation to 1e-9), at most 100 evaluations.
fn refine(
    target: f64,
    lo: (f64, f64),
    hi: (f64, f64),
    force: &impl Fn(f64) -> Result<f64, String>,
) -> Result<f64, String> {
    let ((mut a, mut fa), (mut b, mut fb)) = ((lo.0, lo.1 - target), (hi.0, hi.1 - target));
    let tol_f = 1e-9 * target.abs().max(f64::MIN_POSITIVE);
    let mut side = 0i8;
    for _ in 0..100 {
        if b - a <= 1e-12 || fb <= tol_f {
            break;
        }
        let x = (a * fb - b * fa) / (fb - fa);
        let x = if x > a && x < b { x } else { 0.5 * (a + b) };
        let f = force(x)? - target;
        if f >= 0.0 {
            (b, fb) = (x, f);
            if side == 1 {
                fa *= 0.5;
            }
            side = 1;
        } else {
            (a, fa) = (x, f);
            if side == -1 {
                fb *= 0.5;
            }
            side = -1;
        }
    }
    Ok(b)
}

/// [`solve`] started from the previous root `prev` of the same surface (the steady manoeuvres
/// solve at every step of the truth, and the load moves little in a step): the bracket walked
/// from it in steps of 1 % of it, doubling, then [`refine`]d; the full [`solve`] on a new
/// surface, or when the walk leaves `0..max`. `prev` is updated.
fn track(
    prev: &mut Option<(usize, f64)>,
    surface: usize,
    target: f64,
    dx: f64,
    max: f64,
    force: impl Fn(f64) -> Result<f64, String>,
) -> Result<f64, String> {
    let warm = match *prev {
        Some((s, x0)) if s == surface && x0 > 0.0 => {
            let f0 = force(x0)?;
            let mut d = (0.01 * x0).max(1e-7);
            let (mut lo, mut hi) = ((x0, f0), (x0, f0));
            let mut found = false;
            for _ in 0..60 {
                if f0 < target {
                    let x = hi.0 + d;
                    if x > max {
                        break;
                    }
                    lo = hi;
                    hi = (x, force(x)?);
                    if hi.1 >= target {
                        found = true;
                        break;
                    }
                } else {
                    let x = lo.0 - d;
                    if x <= 0.0 {
                        break;
                    }
                    hi = lo;
                    lo = (x, force(x)?);
                    if lo.1 < target {
                        found = true;
                        break;
                    }
                }
                d *= 2.0;
            }
            if found {
                Some(refine(target, lo, hi, &force)?)
            } else {
                None
            }
        }
        _ => None,
    };
    let x = match warm {
        Some(x) => x,
        None => solve(target, dx, max, &force)?,
    };
    *prev = Some((surface, x));
    Ok(x)
}

/// α > 0 at which pure side slip gives |Fy| = `util`·μ·Fz on surface parameters `q` \[rad\]
/// (the rising side; beyond the tyre's peak at this load, the peak's slip angle).
pub fn alpha_at(q: &Params<f64>, fz: f64, mu: f64, util: f64) -> Result<f64, String> {
    solve(util * mu * fz, 5e-4, 0.6, |a| Ok(-steady(q, fz, a, 0.0)?.1))
}

/// κ < 0 at which straight braking gives |Fx| = `util`·μ·Fz on surface parameters `q` (the
/// rising side; beyond the tyre's peak at this load, the peak's slip ratio).
pub fn kappa_at(q: &Params<f64>, fz: f64, mu: f64, util: f64) -> Result<f64, String> {
    solve(
        util * mu * fz,
        5e-4,
        0.6,
        |k| Ok(-steady(q, fz, 0.0, -k)?.0),
    )
    .map(|k| -k)
}

/// Runs `sc` on the tyre `truth` (the perturbed file), logged at `rate` Hz with `noise`.
pub fn simulate(
    truth: &Params<f64>,
    sc: &Scenario,
    rate: f64,
    noise: &Noise,
    seed: u64,
) -> Result<Trace, String> {
    if !(rate > 0.0 && rate <= 1.0 / STEP + 1e-9) {
        return Err(format!("log rate {rate} Hz: not in (0, {}]", 1.0 / STEP));
    }
    let mu0 = mu_y0(truth)?;
    let fz0 = truth.fnomin;
    let sigma_mz = noise.mz_sigma(truth);
    let every = ((1.0 / rate) / STEP).round().max(1.0) as usize;
    let n = (sc.duration / STEP).round() as usize;
    let surfaces = [
        on_surface(truth, sc.mu[0], mu0),
        on_surface(truth, sc.mu[1], mu0),
    ];
    let load = |t: f64| {
        use std::f64::consts::PI;
        fz0 * (1.0 + 0.15 * (2.0 * PI * 0.2 * t).sin() + 0.02 * (2.0 * PI * 10.0 * t).sin())
    };
    // Slips held in the first surface's terms, at FNOMIN.
    let alpha0 = match sc.manoeuvre {
        Manoeuvre::BrakeInTurn { lat_util, .. } => alpha_at(&surfaces[0], fz0, sc.mu[0], lat_util)?,
        Manoeuvre::Slalom { amplitude, .. } => {
            amplitude * alpha_at(&surfaces[0], fz0, sc.mu[0], 0.95)?
        }
        _ => 0.0,
    };
    let kappa95 = match sc.manoeuvre {
        Manoeuvre::AbsBraking { .. } => kappa_at(&surfaces[0], fz0, sc.mu[0], 0.95)?,
        _ => 0.0,
    };
    // The steady manoeuvres' slip, tracked from step to step (surface index, slip magnitude).
    let mut prev: Option<(usize, f64)> = None;
    let mut tyre = TransientTyre::new(truth);
    let opts = Options {
        transient: true,
        moments: false,
        ..Options::default()
    };
    let mut rng = Rng::new(seed);
    let mut tr = Trace::default();
    for i in 0..n {
        let t = i as f64 * STEP;
        let k = usize::from(sc.step.is_some_and(|s| t >= s));
        let (mu, q) = (sc.mu[k], &surfaces[k]);
        let fz = load(t);
        let (alpha, kappa) = match sc.manoeuvre {
            Manoeuvre::SteadyCornering { util } => {
                let a = track(&mut prev, k, util * mu * fz, 5e-4, 0.6, |a| {
                    Ok(-steady(q, fz, a, 0.0)?.1)
                })?;
                (a, 0.0)
            }
            Manoeuvre::SteadyBraking { util } => {
                let b = track(&mut prev, k, util * mu * fz, 5e-4, 0.6, |k| {
                    Ok(-steady(q, fz, 0.0, -k)?.0)
                })?;
                (0.0, -b)
            }
            Manoeuvre::AbsBraking { freq } => {
                let f = if t < 0.5 {
                    t / 0.5
                } else {
                    1.0 + 0.4 * (2.0 * std::f64::consts::PI * freq * (t - 0.5)).sin()
                };
                (0.0, kappa95 * f)
            }
            Manoeuvre::BrakeInTurn { kappa, .. } => {
                let f = if t < 2.0 {
                    0.0
                } else if t < 5.0 {
                    (t - 2.0) / 3.0
                } else if t < 7.0 {
                    1.0
                } else if t < 8.0 {
                    8.0 - t
                } else {
                    0.0
                };
                (alpha0, kappa * f)
            }
            Manoeuvre::Slalom { freq, .. } => {
                (alpha0 * (2.0 * std::f64::consts::PI * freq * t).sin(), 0.0)
            }
        };
        let kin = Kinematics {
            vx: VX,
            vsx: -kappa * VX,
            vsy: VX * alpha.tan(),
        };
        let (o, slips) = tyre
            .step::<Libm>(
                q,
                &opts,
                STEP,
                &Operating {
                    kin,
                    fz,
                    gamma: 0.0,
                    phit: 0.0,
                    p: None,
                },
            )
            .map_err(|e| format!("t = {t:.3} s: {e:?}"))?;
        if i % every == 0 {
            let sf = noise.f_rel * fz;
            tr.t.push(t);
            tr.fz.push(fz + sf * rng.normal());
            tr.fy.push(o.fy + sf * rng.normal());
            tr.fx.push(o.fx + sf * rng.normal());
            tr.mz.push(o.mz + sigma_mz * rng.normal());
            tr.kappa.push(kappa + noise.kappa * rng.normal());
            tr.vx.push(VX);
            tr.gamma.push(0.0);
            tr.mu.push(mu);
            tr.util.push(o.fx.hypot(o.fy) / (mu * fz));
            tr.alpha.push(alpha);
            tr.kappa_true.push(kappa);
            tr.alpha_t.push(slips.alpha);
            tr.kappa_t.push(slips.kappa);
            tr.fz_true.push(fz);
        }
    }
    Ok(tr)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tyre() -> Params<f64> {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../host-tests/data/tyres/MagicFormula61_Parameters.tir"
        ))
        .unwrap();
        gough::tir::parse(&text).unwrap().params
    }

    #[test]
    fn steady_cornering_holds_the_utilisation_of_whatever_surface() {
        let p = tyre();
        let sc = Scenario {
            manoeuvre: Manoeuvre::SteadyCornering { util: 0.65 },
            mu: [1.0, 0.3],
            step: Some(1.0),
            duration: 2.0,
        };
        let quiet = Noise {
            f_rel: 0.0,
            mz_rel: 0.0,
            kappa: 0.0,
        };
        let tr = simulate(&p, &sc, 100.0, &quiet, 1).unwrap();
        assert_eq!(tr.t.len(), 200);
        // Settled (a few relaxation lengths after the start and after the step).
        for (i, &t) in tr.t.iter().enumerate() {
            if (0.3..1.0).contains(&t) || t >= 1.3 {
                assert!(
                    (tr.util[i] - 0.65).abs() < 0.02,
                    "t {t}: util {}",
                    tr.util[i]
                );
            }
        }
        assert_eq!(tr.mu[50], 1.0);
        assert_eq!(tr.mu[150], 0.3);
    }

    #[test]
    fn the_same_seed_gives_the_same_log_and_the_rate_thins_it() {
        let p = tyre();
        let sc = Scenario {
            manoeuvre: Manoeuvre::Slalom {
                amplitude: 1.3,
                freq: 0.5,
            },
            mu: [0.5, 0.5],
            step: None,
            duration: 1.0,
        };
        let a = simulate(&p, &sc, 1000.0, &Noise::default(), 7).unwrap();
        let b = simulate(&p, &sc, 1000.0, &Noise::default(), 7).unwrap();
        assert_eq!(a, b);
        let c = simulate(&p, &sc, 200.0, &Noise::default(), 7).unwrap();
        assert_eq!(c.t.len(), 200);
        assert!(simulate(&p, &sc, 2000.0, &Noise::default(), 7).is_err());
    }

    #[test]
    fn the_envelope_stays_inside_its_bounds_and_a_perturbation_moves_the_named_keys() {
        let p = tyre();
        let mut rng = Rng::new(3);
        for _ in 0..200 {
            let d = draw(&mut rng, 2.0, true);
            assert!((d.ky - 1.0).abs() <= 0.2 && (d.trail - 1.0).abs() <= 0.2);
            assert!(d.shy.abs() <= 0.004 && (d.pressure - 1.0).abs() <= 0.3);
        }
        let d = Perturbation {
            trail: 1.1,
            sht: 0.002,
            ..Perturbation::default()
        };
        let q = d.apply(&p);
        assert_eq!(q.ltr, p.ltr * 1.1);
        assert_eq!(q.qhz1, p.qhz1 + 0.002);
        assert_eq!(q.lky, p.lky);
        assert!(has_pressure(&p));
    }

    /// The slip tracked from step to step is the one solved afresh, on either side of the
    /// previous one and across a change of surface; a utilisation beyond the peak gives the
    /// peak's slip.
    #[test]
    fn the_tracked_slip_is_the_solved_one_and_beyond_the_peak_the_peak() {
        let p = tyre();
        let mu0 = mu_y0(&p).unwrap();
        let mut prev = None;
        for (i, (mu, fz)) in [(1.0, 6000.0), (1.0, 6100.0), (1.0, 5500.0), (0.3, 5500.0)]
            .into_iter()
            .enumerate()
        {
            let q = on_surface(&p, mu, mu0);
            let cold = alpha_at(&q, fz, mu, 0.65).unwrap();
            let warm = track(
                &mut prev,
                usize::from(i == 3),
                0.65 * mu * fz,
                5e-4,
                0.6,
                |a| Ok(-steady(&q, fz, a, 0.0)?.1),
            )
            .unwrap();
            assert!((cold - warm).abs() < 1e-9, "{i}: {cold} {warm}");
            let (_, fy) = steady(&q, fz, warm, 0.0).unwrap();
            assert!((-fy / (mu * fz) - 0.65).abs() < 1e-8, "{i}: {fy}");
        }
        // Beyond the peak: the largest force's slip angle, to the scan's step.
        let q = on_surface(&p, 1.0, mu0);
        let a = alpha_at(&q, p.fnomin, 1.0, 2.0).unwrap();
        let f = |a: f64| -steady(&q, p.fnomin, a, 0.0).unwrap().1;
        assert!(a > 0.0 && a < 0.6, "{a}");
        assert!(f(a) >= f(a - 5e-4) && f(a) >= f(a + 5e-4), "{a}");
    }

    /// The ABS cycles the slip ratio between 0.6 and 1.4 times that of utilisation 0.95 on its
    /// surface, after a ramp of 0.5 s; the Mz noise is 7.5e-4·FNOMIN·R0 (2 N·m on this tyre).
    #[test]
    fn the_abs_cycles_about_the_slip_of_utilisation_095() {
        let p = tyre();
        let sc = Scenario {
            manoeuvre: Manoeuvre::AbsBraking { freq: 4.0 },
            mu: [0.2, 0.2],
            step: None,
            duration: 2.0,
        };
        let tr = simulate(&p, &sc, 1000.0, &Noise::default(), 1).unwrap();
        let q = on_surface(&p, 0.2, mu_y0(&p).unwrap());
        let k95 = kappa_at(&q, p.fnomin, 0.2, 0.95).unwrap();
        let (lo, hi) = tr.kappa_true[500..]
            .iter()
            .fold((0.0f64, f64::MIN), |(a, b), &k| (a.min(k), b.max(k)));
        assert!(((lo / k95) - 1.4).abs() < 1e-3 && ((hi / k95) - 0.6).abs() < 1e-3);
        assert!((Noise::default().mz_sigma(&p) - 2.0).abs() < 0.01);
    }

    #[test]
    fn braking_holds_its_utilisation() {
        let p = tyre();
        let q = on_surface(&p, 0.7, mu_y0(&p).unwrap());
        let k = kappa_at(&q, p.fnomin, 0.7, 0.65).unwrap();
        let (fx, _) = steady(&q, p.fnomin, 0.0, k).unwrap();
        assert!(
            k < 0.0 && ((-fx) / (0.7 * p.fnomin) - 0.65).abs() < 1e-6,
            "{k} {fx}"
        );
    }
}
