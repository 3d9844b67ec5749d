//! The estimate read from the likelihoods: μ, its σ, the lower bound μ_min, the state it rests
//! on, the value held while the evidence is thin, its ageing, and the change flag.
//!
//! ## Estimate
//! The surface of the cell at the minimum of ℓ (centre plus offset); σ from ℓ's curvature and
//! the spread of the posterior exp(−ℓ) over the cells' surfaces, with a floor (`sigma_floor`).
//!
//! ## States ([`State`])
//! - `Identifiable`: 1.96·σ ≤ 0.1 by the estimator's own account (`sigma_identifiable`),
//!   every surface more than 0.1 away is excluded (ℓ more than `exclude_nll` above the best),
//!   the reported surface explains the latest batch (χ² ≤ `chi2_identifiable`), and the
//!   identification is fresh: σ aged (`age_q_time`, `age_q_distance`) over the time and distance
//!   since the last batch whose horizontal force used `inform_util` of the reported surface
//!   (|F| ≥ `inform_util`·μ·Fz) is still within `sigma_identifiable`.
//! - `NotIdentifiable`: some surfaces are excluded (`mu_min` says which μ is still possible), but
//!   not enough for the above. The last identifiable μ is reported while the evidence does not
//!   turn against it (ℓ ≤ `hold_nll` at it), its σ growing with time and distance
//!   (`age_q_time`, `age_q_distance`); once that σ reaches the prior's it is still reported
//!   while some surface stays excluded. Otherwise the minimum of ℓ.
//! - `Fallback`: no surface can be excluded (no excitation yet, or the evidence aged out): the
//!   prior `mu_prior` is reported.
//!
//! Below `inform_util` of the reported surface a batch says little of μ near it (the curve is
//! linear there, and every surface above the force explains it alike — a wheel that has just
//! run onto ice at a zero crossing of the force is explained by the old grip as well), so an
//! identification ages from the last batch that reached it: with the defaults (σ² growing by
//! 0.01 per second and 0.0005 per metre, 0.02/s at 20 m/s) an estimate of σ 0.015–0.03 stays
//! identifiable for 0.08–0.12 s of such running, then is held as `NotIdentifiable` (above),
//! and is identifiable again on the first batch that uses the surface once more.
//!
//! ## A force the estimate cannot produce
//! On every sample, the running mean of the batch being collected is checked against the
//! reported μ (`Report::check_force`): a horizontal force it cannot produce at this load
//! (|F|/Fz less 3σ of the noise and the model error above hypot(|Dx| + |SVx|, |Dy| + |SVy|)/Fz,
//! the pure-slip peaks with their vertical shifts — a bound, not the combined-slip maximum)
//! ends the identification at once (a change to a grippier surface is not reported as the old
//! one for a batch and its fit), drops the held value, and bounds μ from below (`mu_min` and
//! the reported μ) for the next two batches.
//!
//! ## Change of surface
//! An identifiable μ that moved by more than `change_min` + 2σ from the last identifiable value
//! (also when the held value was dropped on the way) is flagged ([`Estimate::change`]) on that
//! one estimate.

use super::batch::{Batch, Sums};
use super::config::{Config, CELLS};
use super::fit::Fit;
use super::likelihood::Likelihood;
use crate::math::{Backend, Float};
use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

/// What an estimate rests on (see the module's "States"). The protocol carries it in its
/// `Estimate` message as one byte: 0, 1, 2 in this order.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum State {
    /// μ is within ±0.1 at 95 % by the estimator's own account: usable now. A value may be
    /// held through a zero crossing of the force; without excitation it ages with time and
    /// distance rolled and falls back to `NotIdentifiable`.
    Identifiable,
    /// Some surfaces are excluded but not enough for the above: [`Estimate::mu_min`] bounds μ
    /// from below; μ is the last identifiable value while the evidence has not turned against
    /// it, else the most likely surface — not to be relied on.
    NotIdentifiable,
    /// No surface can be excluded (no excitation yet, or the evidence aged out): μ is the prior
    /// (`Config::mu_prior`).
    Fallback,
}

impl State {
    /// Name as in logs: `identifiable`, `not_identifiable`, `fallback`.
    pub const fn name(self) -> &'static str {
        match self {
            State::Identifiable => "identifiable",
            State::NotIdentifiable => "not_identifiable",
            State::Fallback => "fallback",
        }
    }
}

/// An estimate of the road friction. The protocol's `Estimate` message carries it in `f32`,
/// its fields in this order.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Estimate<F> {
    /// Peak friction μ \[-\] on the tyre file's scale (docs/architecture.md); the prior in `Fallback`.
    pub mu: F,
    /// Standard deviation of μ \[-\] by the estimator's own account (the confidence).
    pub sigma: F,
    /// What it rests on: how to read μ.
    pub state: State,
    /// The lowest μ \[-\] the evidence has not excluded: a lower bound on the road's friction a
    /// controller may rely on in any state (`mu_lo`, the lowest hypothesis, when nothing is
    /// excluded).
    pub mu_min: F,
    /// Change of surface: set on the one estimate at which the estimator declared it (an
    /// identifiable μ that moved by more than `change_min` + 2σ from the last identifiable
    /// value); clear on every other. It is not repeated: a receiver that misses that one
    /// estimate sees the new μ only.
    pub change: bool,
    /// The calibrated model does not explain the data: the likeliest surface's χ² over the
    /// recent excited batches (`mismatch_time`) is above `mismatch_chi2`, or a calibrated
    /// property is at its bound — the tyre is not what its file and the calibration can
    /// describe, and μ is to be taken with care whatever its state.
    pub mismatch: bool,
}

/// What a bank reports, and what its report rests on between batches: the held value, its
/// ages, the change flag's reference, the bound from a force the estimate cannot produce.
#[derive(Debug, Clone)]
pub(crate) struct Report<F> {
    /// The last identifiable μ and its σ, held while not identifiable (dropped when the
    /// evidence turns against it), and the time \[s\] and distance \[m\] since.
    held: Option<(F, F)>,
    /// The last identifiable μ, never dropped: the change flag's reference.
    last_mu: Option<F>,
    age_s: F,
    age_m: F,
    /// Distance \[m\] rolled between the last two identifiable estimates, taken at the later.
    gap_m: F,
    /// Time \[s\] and distance \[m\] since the last batch that used `inform_util` of the
    /// reported surface.
    quiet_s: F,
    quiet_m: F,
    est: Estimate<F>,
    /// A bound of |F|/Fz on the reported μ's surface at the last batch's load, over μ
    /// ([`Fit::peak_ratio`]).
    peak_ratio: F,
    /// A lower bound of μ from a measured force the reported μ cannot produce, and the batches
    /// it stays in force (until the likelihoods have taken that force in).
    floor: F,
    floor_batches: u8,
}

impl<F: Float> Report<F> {
    /// The fallback, nothing held.
    pub(crate) fn new(c: &Config<F>) -> Self {
        Report {
            held: None,
            last_mu: None,
            age_s: F::ZERO,
            age_m: F::ZERO,
            gap_m: F::ZERO,
            quiet_s: F::ZERO,
            quiet_m: F::ZERO,
            est: Estimate {
                mu: c.mu_prior,
                sigma: c.sigma_prior,
                state: State::Fallback,
                mu_min: c.mu_lo,
                change: false,
                mismatch: false,
            },
            peak_ratio: F::ONE,
            floor: F::ZERO,
            floor_batches: 0,
        }
    }

    /// The estimate reported now.
    pub(crate) fn current(&self) -> Estimate<F> {
        self.est
    }

    /// Distance \[m\] rolled between the last two identifiable estimates.
    pub(crate) fn identification_gap(&self) -> F {
        self.gap_m
    }

    /// A new sample: the change flag is set on one estimate only.
    pub(crate) fn begin_sample(&mut self) {
        self.est.change = false;
    }

    /// The likeliest cell no longer explains the batch: an identifiable estimate is withdrawn
    /// (its value held).
    pub(crate) fn withdraw(&mut self) {
        if self.est.state == State::Identifiable {
            self.est.state = State::NotIdentifiable;
            self.est.change = false;
        }
    }

    /// Drops the held value if `against` holds for it (a reading from ahead excludes it).
    pub(crate) fn drop_held_if(&mut self, against: impl FnOnce(F) -> bool) {
        if let Some((h, _)) = self.held {
            if against(h) {
                self.held = None;
            }
        }
    }

    /// A force the reported μ cannot produce: checked on every sample against the running mean
    /// of the batch being collected (`a`, from its 3rd sample), so that a change to a grippier
    /// surface ends a stale identification within a few samples instead of after the batch and
    /// its fit. The mean |F|/Fz, less 3σ of its noise and the model error, above the bound of
    /// what the reported μ gives at this load (`peak_ratio`) makes the estimate
    /// not identifiable, drops the held value, and sets a lower bound of μ (`mu_min`, and the
    /// reported μ at least) for the next two batches.
    pub(crate) fn check_force<M: Backend<F>>(&mut self, c: &Config<F>, a: &Sums<F>, f_rel: F) {
        if a.n < 3 || self.est.state == State::Fallback {
            return;
        }
        let n = F::from_index(a.n);
        let fz = a.fz / n;
        let fx = if a.n_fx == a.n { a.fx / n } else { F::ZERO };
        let fy = a.fy / n;
        if fz <= F::ZERO {
            return;
        }
        let f = M::sqrt(fx * fx + fy * fy) / fz;
        let noise = M::sqrt(F::TWO * f_rel.sq() / n + c.model_f_abs.sq());
        let bound = (f * (F::ONE - c.model_f_rel) - F::from_f64(3.0) * noise) / self.peak_ratio;
        if bound > self.est.mu && bound.is_finite() {
            self.floor = self.floor.max(bound);
            self.floor_batches = 2;
            self.held = None;
            self.est.state = State::NotIdentifiable;
            self.est.change = false;
            self.est.mu = bound;
            self.est.mu_min = self.est.mu_min.max(bound);
        }
    }

    /// A batch `b` has been fitted: the held value and the identification age by its time and
    /// distance, unless (for the identification) its force used `inform_util` of the reported
    /// surface.
    pub(crate) fn roll(&mut self, c: &Config<F>, b: &Batch<F>) {
        self.age_s += b.dt;
        self.age_m += b.dist;
        if b.excited(c) && b.force() >= c.inform_util * self.est.mu * b.fz {
            self.quiet_s = F::ZERO;
            self.quiet_m = F::ZERO;
        } else {
            self.quiet_s += b.dt;
            self.quiet_m += b.dist;
        }
    }

    /// The ratio of [`Fit::peak_ratio`] at the reported μ, when there is one.
    pub(crate) fn set_peak_ratio(&mut self, r: Option<F>) {
        if let Some(r) = r {
            self.peak_ratio = r;
        }
    }

    /// σ of an estimate `sigma` aged over `s` seconds and `m` metres without informative force
    /// (σ² grows by `age_q_time` per second and `age_q_distance` per metre).
    fn aged<M: Backend<F>>(c: &Config<F>, sigma: F, s: F, m: F) -> F {
        M::sqrt(sigma * sigma + c.age_q_time * s + c.age_q_distance * m)
    }

    /// The estimate from the cells' likelihoods `l` and surfaces (`fit`), after a batch, with
    /// the model-mismatch indication `mismatch`; the bound from a force the estimate could not
    /// produce counts down and holds.
    pub(crate) fn update<M: Backend<F>>(
        &mut self,
        c: &Config<F>,
        l: &Likelihood<F>,
        fit: &Fit<F>,
        mismatch: bool,
        sys_var: F,
    ) {
        if self.floor_batches > 0 {
            self.floor_batches -= 1;
        } else {
            self.floor = F::ZERO;
        }
        self.estimate::<M>(c, l, fit, sys_var);
        self.est.mismatch = mismatch;
        // A change of surface is asserted only by a model that explains the data: under the
        // mismatch indication the estimate still follows the evidence, but a jump between
        // surfaces is as likely the tyre's own error.
        if mismatch {
            self.est.change = false;
        }
        if self.floor > F::ZERO && self.est.state != State::Fallback {
            self.est.mu = self.est.mu.max(self.floor);
            self.est.mu_min = self.est.mu_min.max(self.floor);
        }
    }

    /// The estimate from the cells' likelihoods.
    fn estimate<M: Backend<F>>(
        &mut self,
        c: &Config<F>,
        l: &Likelihood<F>,
        fit: &Fit<F>,
        sys_var: F,
    ) {
        let m = l.best();
        let nll = |k: usize| l.get(k);
        // The grid's local spacing at the best cell.
        let (down, up) = fit.grid().half(m);
        let h = down + up;
        // The best cell's own surface (its centre and fitted offset).
        let mu = fit.mu_c(m);
        let mut var_curv = F::from_f64(f64::MAX);
        if let (Some(l0), Some(l1), Some(l2)) = (m.checked_sub(1).and_then(nll), nll(m), nll(m + 1))
        {
            let curv = l0 - l1 - l1 + l2;
            if curv > F::ZERO {
                var_curv = h * h / curv;
            }
        } else if let (Some(l1), Some(ln)) = (
            nll(m),
            if m == 0 {
                nll(1)
            } else {
                nll(m.wrapping_sub(1))
            },
        ) {
            // At an edge of the grid: a one-sided curvature.
            let d = ln - l1;
            if d > F::ZERO {
                var_curv = h * h / (F::TWO * d);
            }
        }
        // Posterior spread over the grid (weights exp(−ℓ)).
        let (mut sw, mut s1, mut s2) = (F::ZERO, F::ZERO, F::ZERO);
        let mut mu_min = F::from_f64(f64::MAX);
        let mut far_open = false;
        let mut excluded = 0usize;
        for (k, lk) in l.nll.iter().enumerate() {
            let mk = fit.mu_c(k);
            let w = M::exp(-*lk);
            sw += w;
            s1 += w * mk;
            s2 += w * mk * mk;
            if *lk <= c.exclude_nll {
                mu_min = mu_min.min(mk);
                if (mk - mu).abs() > F::from_f64(0.1) {
                    far_open = true;
                }
            } else {
                excluded += 1;
            }
        }
        let mean = s1 / sw;
        let var_post = (s2 / sw - mean * mean).max(F::ZERO);
        let var = var_post.max(var_curv.min(var_post.max(h * h)));
        // The likelihoods' spread, the floor, and what the calibration's σ of the tyre leaves
        // unknown of μ at the latest batch's operating point (`sys_var`).
        let sigma = M::sqrt(var + c.sigma_floor.sq() + sys_var.max(F::ZERO));
        // The reported surface must explain the latest batch (a cell that wins only because
        // the true one lost its slips is no identification).
        let fits = fit.chi2().get(m).is_some_and(|x| *x <= c.chi2_identifiable);
        // Aged since the last batch that used enough of the reported surface to say something
        // of it.
        let aged_now = Self::aged::<M>(c, sigma, self.quiet_s, self.quiet_m);
        // The highest hypothesis is not an identification: the surfaces above the grid are not
        // there to be excluded, and what makes it likeliest is mostly a force every surface
        // above it explains alike (the linear range; camber thrust).
        let at_top = m + 1 >= CELLS;
        let identifiable = l.evidence
            && excluded > 0
            && aged_now <= c.sigma_identifiable
            && !far_open
            && fits
            && !at_top
            && mu >= self.floor;
        let mu_min = if mu_min < F::from_f64(f64::MAX) {
            mu_min
        } else {
            c.mu_lo
        };
        if identifiable {
            // Against the last identifiable value, also when the held one was dropped on the
            // way (the evidence turned against it: what a change of surface does).
            let change = self
                .last_mu
                .is_some_and(|prev| (mu - prev).abs() > c.change_min + F::TWO * sigma);
            self.held = Some((mu, sigma));
            self.last_mu = Some(mu);
            self.gap_m = self.age_m;
            self.age_s = F::ZERO;
            self.age_m = F::ZERO;
            self.est = Estimate {
                mu,
                sigma,
                state: State::Identifiable,
                mu_min,
                change,
                mismatch: false,
            };
            return;
        }
        // Not identifiable now. The last identifiable value is held — through a zero crossing
        // of the force, a stretch of straight running — while the evidence does not turn
        // against it (`hold_nll`), its σ growing with time and distance (`age_q_time`,
        // `age_q_distance`) until it reaches the prior's.
        if let Some((h, hs)) = self.held {
            let against = l
                .get(fit.grid().cell_of(h))
                .is_some_and(|lh| lh > c.hold_nll);
            let aged = Self::aged::<M>(c, hs, self.age_s, self.age_m);
            // Aged to the prior's σ, it is still kept while the evidence excludes some surface
            // (the data say something, and not that the held value is wrong): a steady
            // state that two surfaces explain alike does not make the estimate jump between them.
            if !against && (aged < c.sigma_prior || excluded > 0) {
                self.est = Estimate {
                    mu: h,
                    sigma: aged.min(c.sigma_prior).max(sigma.min(c.sigma_prior)),
                    state: State::NotIdentifiable,
                    mu_min,
                    change: false,
                    mismatch: false,
                };
                return;
            }
            self.held = None;
        }
        self.est = if l.evidence && excluded > 0 {
            Estimate {
                mu,
                sigma,
                state: State::NotIdentifiable,
                mu_min,
                change: false,
                mismatch: false,
            }
        } else {
            Estimate {
                mu: c.mu_prior,
                sigma: c.sigma_prior,
                state: State::Fallback,
                mu_min: c.mu_lo,
                change: false,
                mismatch: false,
            }
        };
    }
}
