//! Baseline friction estimators from the literature, implemented from their papers (host only),
//! to compare the product's estimator (the bank) against. Both read the slip a slip sensor
//! gives ([`Method::slip_sensor`](super::Method::slip_sensor)); each runs per wheel
//! ([`EachWheel`]).
//!
//! - [`HsuGerdes`]: Y.-H. J. Hsu, S. M. Laws, J. C. Gerdes, "Estimation of tire slip angle and
//!   friction limits using steering torque", IEEE Trans. Control Systems Technology 18(4), 2010.
//!   Brush model with a pneumatic trail falling linearly with slip,
//!   `tp = tp0 − sgn(α)·tp0·Cα/(3·μ·Fz)·tan α`, solved for μ given the measured trail
//!   tp = −Mz/Fy and the slip angle; used only when |α| > 2°, tp < tp0 and Vx > 3 m/s (the
//!   paper's gates), clamped to 0.05…1.5 ([`MU_RANGE`]), and smoothed by a first-order filter. Cα and tp0 are taken from the same
//!   `.tir` file at the current load (the paper fits them from data): a fair comparison.
//! - [`SlipSlope`]: F. Gustafsson, "Slip-based tire-road friction estimation", Automatica 33(6),
//!   1997. The normalised traction force μn = Fx/Fz is regressed on the longitudinal slip κ at
//!   low slip (μn = k·κ, recursive least squares with forgetting), and the slope k is mapped to
//!   μ through a calibration curve — here computed from the same tyre model: the secant slope
//!   at κ = 0.03 for friction levels 0.05…1.5 (every 0.05; [`MU_RANGE`]).

use super::estimator::{Estimate, Estimator, Sample};
use gough::math::Libm;
use gough::mf::{self, Input, Options, Params};
use gough::mu::State;
use gough::proto::Wheel;

/// The range of μ both peers report (a reading outside it saturates): Hsu–Gerdes' clamp, the
/// slip-slope calibration's span. Wider than every benchmark surface (μ 0.1…1.0), so that no
/// peer reads a test surface exactly merely by saturating at its end (with the slip-slope
/// calibration starting at μ 0.1, as it did, its saturated readings on μ 0.1 had error 0).
/// A saturated reading is still reported identifiable, and on μ 0.1 its error, 0.05, is within
/// the bench's ±0.1: the bench counts slip-slope's saturated readings on μ 0.1 as reads
/// (docs/estimator.md, "better than … on every case").
pub const MU_RANGE: (f64, f64) = (0.05, 1.5);

fn prior() -> Estimate {
    Estimate {
        mu: 0.8,
        sigma: 0.4,
        state: State::Fallback,
        change: false,
        mismatch: false,
    }
}

/// μ of a surface λμ on the file's scale, and the MF at pure slip with that λμ (speed: the
/// file's LONGVL; limits off; γ = 0).
pub(super) fn eval_at(
    p: &Params<f64>,
    lambda: f64,
    fz: f64,
    alpha: f64,
    kappa: f64,
) -> Option<mf::Output<f64>> {
    eval_cambered(p, lambda, fz, alpha, kappa, 0.0)
}

/// [`eval_at`] at inclination `gamma` \[rad\].
pub(super) fn eval_cambered(
    p: &Params<f64>,
    lambda: f64,
    fz: f64,
    alpha: f64,
    kappa: f64,
    gamma: f64,
) -> Option<mf::Output<f64>> {
    let mut q = p.clone();
    q.lmux = lambda;
    q.lmuy = lambda;
    let opts = Options {
        limits: false,
        ..Options::default()
    };
    mf::eval::<f64, Libm>(
        &q,
        &Input {
            fz,
            alpha,
            kappa,
            gamma,
            vx: q.longvl,
            ..Input::default()
        },
        &opts,
    )
    .ok()
}

/// The Hsu–Laws–Gerdes pneumatic-trail estimator.
#[derive(Debug, Clone)]
pub struct HsuGerdes {
    p: Params<f64>,
    mu0: f64,
    est: Option<f64>,
    last_t: Option<f64>,
    /// Smoothing time constant \[s\].
    pub tau: f64,
}

impl HsuGerdes {
    /// On a tyre file.
    pub fn new(p: &Params<f64>) -> Option<Self> {
        let mu0 = eval_at(p, 1.0, p.fnomin, 0.0, 0.0)?.mu_y;
        Some(HsuGerdes {
            p: p.clone(),
            mu0,
            est: None,
            last_t: None,
            tau: 0.05,
        })
    }

    /// One sample.
    pub fn update(&mut self, r: &Sample) -> Estimate {
        let dt = self.last_t.map_or(0.0, |t0| (r.t - t0).clamp(0.0, 1.0));
        self.last_t = Some(r.t);
        let alpha = r.alpha.filter(|a| a.abs() > 2f64.to_radians());
        let gated = r.vx.is_some_and(|v| v.abs() > 3.0) && r.fz > 0.0 && r.fy.abs() > 1e-3 * r.fz;
        let raw = if let (Some(alpha), true) = (alpha, gated) {
            // Cα and tp0 at this load from the tyre file (small-slip values).
            eval_at(&self.p, 1.0, r.fz, 1e-4, 0.0).and_then(|o| {
                let c_alpha = o.k_ya.abs();
                let tp0 = o.t;
                let tp = -r.mz / r.fy; // > 0 for either sign of α in ISO-W
                if tp0 <= 0.0 || tp >= tp0 {
                    return None;
                }
                // tp = tp0·(1 − Cα·|tan α|/(3·μ·Fz))  →  μ = Cα·|tan α|·tp0 / (3·Fz·(tp0 − tp))
                let mu = c_alpha * alpha.tan().abs() * tp0 / (3.0 * r.fz * (tp0 - tp));
                // Physically plausible range only (the linear trail model blows up as tp → tp0).
                let mu = mu.clamp(MU_RANGE.0, MU_RANGE.1);
                (mu.is_finite() && mu > 0.0).then_some(mu)
            })
        } else {
            None
        };
        match raw {
            Some(mu) => {
                let a = if self.tau > 0.0 {
                    dt / (self.tau + dt)
                } else {
                    1.0
                };
                let v = match self.est {
                    None => mu,
                    Some(e) => e + a * (mu - e),
                };
                self.est = Some(v);
                Estimate {
                    mu: v,
                    sigma: 0.1,
                    state: State::Identifiable,
                    change: false,
                    mismatch: false,
                }
            }
            None => match self.est {
                Some(v) => Estimate {
                    mu: v,
                    sigma: 0.2,
                    state: State::NotIdentifiable,
                    change: false,
                    mismatch: false,
                },
                None => prior(),
            },
        }
    }

    /// μy0 of the file (for reference).
    pub fn mu0(&self) -> f64 {
        self.mu0
    }
}

/// Gustafsson's slip-slope estimator (longitudinal).
#[derive(Debug, Clone)]
pub struct SlipSlope {
    /// Calibration: (slope k, μ) pairs, k increasing.
    calib: Vec<(f64, f64)>,
    k: f64,
    p_rls: f64,
    have: bool,
    /// Forgetting factor per sample.
    pub forget: f64,
}

/// Reference slip of the calibration curve.
pub const KAPPA_REF: f64 = 0.03;

impl SlipSlope {
    /// On a tyre file (calibration from its Magic Formula at Fz0).
    pub fn new(p: &Params<f64>) -> Option<Self> {
        let mu0 = eval_at(p, 1.0, p.fnomin, 0.0, 0.0)?.mu_y;
        let mut calib = Vec::new();
        // Every 0.05 over MU_RANGE, both ends included.
        let n = ((MU_RANGE.1 - MU_RANGE.0) / 0.05).round() as usize + 1;
        for i in 0..n {
            let mu = MU_RANGE.0 + 0.05 * i as f64;
            let o = eval_at(p, mu / mu0, p.fnomin, 0.0, -KAPPA_REF)?;
            let k = (o.fx / p.fnomin / -KAPPA_REF).abs();
            calib.push((k, mu));
        }
        calib.sort_by(|a, b| a.0.total_cmp(&b.0));
        Some(SlipSlope {
            calib,
            k: 0.0,
            p_rls: 1e3,
            have: false,
            forget: 0.999,
        })
    }

    fn mu_of(&self, k: f64) -> f64 {
        let c = &self.calib;
        if let (Some(first), Some(last)) = (c.first(), c.last()) {
            if k <= first.0 {
                return first.1;
            }
            if k >= last.0 {
                return last.1;
            }
        }
        for w in c.windows(2) {
            let (a, b) = (w[0], w[1]);
            if k >= a.0 && k <= b.0 && b.0 > a.0 {
                return a.1 + (k - a.0) / (b.0 - a.0) * (b.1 - a.1);
            }
        }
        0.8
    }

    /// One sample.
    pub fn update(&mut self, r: &Sample) -> Estimate {
        let slip = r
            .kappa
            .zip(r.fx)
            .filter(|(k, _)| k.abs() > 0.005 && k.abs() < 0.1);
        let gated = r.fz > 0.0 && r.vx.is_none_or(|v| v.abs() > 3.0);
        if let (Some((kappa, fx)), true) = (slip, gated) {
            // RLS on μn = k·κ (Gustafsson's eq. with the offset omitted: κ is measured
            // relative to free rolling here).
            let x = kappa.abs();
            let y = (fx / r.fz).abs();
            let g = self.p_rls * x / (self.forget + x * self.p_rls * x);
            self.k += g * (y - self.k * x);
            self.p_rls = (self.p_rls - g * x * self.p_rls) / self.forget;
            self.have = true;
            return Estimate {
                mu: self.mu_of(self.k),
                sigma: 0.1,
                state: State::Identifiable,
                change: false,
                mismatch: false,
            };
        }
        if self.have {
            Estimate {
                mu: self.mu_of(self.k),
                sigma: 0.2,
                state: State::NotIdentifiable,
                change: false,
                mismatch: false,
            }
        } else {
            prior()
        }
    }
}

/// A per-wheel estimator: one sample of one wheel in, that wheel's estimate out.
pub trait WheelEstimator {
    /// One sample.
    fn update(&mut self, s: &Sample) -> Estimate;
}

impl WheelEstimator for HsuGerdes {
    fn update(&mut self, s: &Sample) -> Estimate {
        HsuGerdes::update(self, s)
    }
}

impl WheelEstimator for SlipSlope {
    fn update(&mut self, s: &Sample) -> Estimate {
        SlipSlope::update(self, s)
    }
}

/// A per-wheel estimator at each of a car's four wheels, each on its own samples.
#[derive(Debug, Clone)]
pub struct EachWheel<E>([E; 4]);

impl<E: Clone> EachWheel<E> {
    /// `e` (as built, before any sample) at every wheel.
    pub fn new(e: E) -> Self {
        EachWheel([e.clone(), e.clone(), e.clone(), e])
    }
}

impl<E: WheelEstimator> Estimator for EachWheel<E> {
    fn update(&mut self, wheel: Wheel, s: &Sample) -> Estimate {
        self.0[wheel.index()].update(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tyre() -> Params<f64> {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        crate::tyre::load(&dir.join("../host-tests/data/tyres/MagicFormula61_Parameters.tir"))
            .expect("bundled tyre")
            .params
    }

    /// Steady braking at slip `kappa` on surface μ (the file's scale), noise-free, 1 kHz.
    fn braking(p: &Params<f64>, mu: f64, kappa: f64, n: usize) -> Vec<Sample> {
        let mu0 = eval_at(p, 1.0, p.fnomin, 0.0, 0.0).expect("mu0").mu_y;
        let o = eval_at(p, mu / mu0, p.fnomin, 0.0, kappa).expect("eval");
        (0..n)
            .map(|i| Sample {
                t: i as f64 * 1e-3,
                fz: p.fnomin,
                fx: Some(o.fx),
                vx: Some(20.0),
                alpha: Some(0.0),
                kappa: Some(kappa),
                ..Sample::default()
            })
            .collect()
    }

    /// Inside its calibration the slip-slope peer reads the surface (its curve is the same
    /// tyre's); a slope below that of every calibrated surface saturates at `MU_RANGE.0`,
    /// below the lowest benchmark surface, not on it.
    #[test]
    fn slip_slope_reads_its_calibration_and_saturates_off_the_bench_surfaces() {
        let p = tyre();
        for mu in [0.1, 0.3, 0.7, 1.0] {
            let mut s = SlipSlope::new(&p).expect("calibration");
            let e = braking(&p, mu, -KAPPA_REF, 500)
                .iter()
                .map(|r| s.update(r))
                .last()
                .expect("rows");
            assert_eq!(e.state, State::Identifiable);
            assert!((e.mu - mu).abs() < 0.01, "μ {mu}: read {}", e.mu);
        }
        // No force at the slip: the flattest slope there is.
        let mut s = SlipSlope::new(&p).expect("calibration");
        let rows = braking(&p, 0.3, -KAPPA_REF, 50);
        let e = rows
            .iter()
            .map(|r| {
                s.update(&Sample {
                    fx: Some(0.0),
                    ..*r
                })
            })
            .last()
            .expect("rows");
        assert_eq!(e.mu, MU_RANGE.0);
        assert!(MU_RANGE.0 < 0.1 && MU_RANGE.1 > 1.0);
    }
}
