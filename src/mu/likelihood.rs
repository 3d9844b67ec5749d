//! The likelihood with memory: each surface hypothesis's negative log-likelihood ℓ over the
//! recent batches.
//!
//! - A cell's ℓ is the sum of its batches' χ²/2 in excess of the best cell's, each through a
//!   soft dead zone (d ↦ d²/(d + `deadzone`): differences a model error could make in one batch
//!   add little, so that evidence accumulates from batches that discriminate, not from many
//!   that barely do) and capped at `chi2_cap` (so that one batch the model cannot represent — a
//!   transient faster than the batch — never decides). A batch that no cell explains
//!   (`chi2_explain`) or that is not excited is not used (`Likelihood::fold`).
//! - **A model that does not fit says less**: while the likeliest cell's χ², averaged, is above
//!   `mismatch_chi2` (the mismatch indication), each batch's excesses are divided by the ratio
//!   (a Birge ratio: the errors are that much larger than the model assumes).
//! - **Forgetting**: ℓ is forgotten at the rate exp(−Δt/`memory` − Δs/`memory_distance`), time
//!   and distance rolled (`Likelihood::age`).
//! - **Switching cap**: the best cell is at 0 and no cell is more than `switch_nll` above it
//!   (`Likelihood::normalise`): a surface once excluded can return within a few batches when
//!   the road changes (a switching hypothesis, as in an interacting-multiple-model filter over a
//!   discrete grid).
//!
//! A reading from ahead is mixed into ℓ by the front-to-rear preview ([`crate::mu::preview`]).
//! The profile of ℓ over the cells is what the estimate is read from ([`crate::mu::estimate`]).

use super::config::{Config, CELLS};
use crate::math::{Backend, Float};

/// The cells' negative log-likelihoods, relative to the best cell's, and whether any evidence
/// has been taken in.
#[derive(Debug, Clone)]
pub(crate) struct Likelihood<F> {
    pub(crate) nll: [F; CELLS],
    /// Whether any batch (or reading from ahead) has been used.
    pub(crate) evidence: bool,
    /// The share of ℓ that came from ahead (a reading's weight when mixed in, forgotten as ℓ
    /// is): evidence that this wheel's own tyre errors do not touch.
    pub(crate) external: F,
}

impl<F: Float> Likelihood<F> {
    /// No evidence: every cell at 0.
    pub(crate) fn new() -> Self {
        Likelihood {
            nll: [F::ZERO; CELLS],
            evidence: false,
            external: F::ZERO,
        }
    }

    /// ℓ of cell `k`.
    pub(crate) fn get(&self, k: usize) -> Option<F> {
        self.nll.get(k).copied()
    }

    /// The likeliest cell (the first at the minimum of ℓ).
    pub(crate) fn best(&self) -> usize {
        let mut best = 0;
        let mut lo = F::from_f64(f64::MAX);
        for (k, l) in self.nll.iter().enumerate() {
            if *l < lo {
                lo = *l;
                best = k;
            }
        }
        best
    }

    /// The smallest ℓ.
    pub(crate) fn min(&self) -> F {
        let mut lo = F::from_f64(f64::MAX);
        for l in self.nll.iter() {
            lo = lo.min(*l);
        }
        lo
    }

    /// Forgets evidence over `dt` seconds and `dist` metres; returns the factor ℓ was
    /// multiplied by (the fitted offsets' information is forgotten alike).
    pub(crate) fn age<M: Backend<F>>(&mut self, c: &Config<F>, dt: F, dist: F) -> F {
        let x =
            dt / c.memory.max(F::from_f64(1e-3)) + dist / c.memory_distance.max(F::from_f64(1e-3));
        let d = M::exp(-x);
        for l in self.nll.iter_mut() {
            *l *= d;
        }
        self.external *= d;
        d
    }

    /// Adds a batch's χ² per cell `chi2`, the best of them `best`: each cell's excess over the
    /// best, divided by `scale` when it is above 1 (a model that fits that much worse than it
    /// should says that much less), through the soft dead zone, capped.
    pub(crate) fn fold(&mut self, c: &Config<F>, chi2: &[F; CELLS], best: F, scale: F) {
        let inv = F::ONE / scale.max(F::ONE);
        let cap = c.chi2_cap;
        // Each batch's excess χ² over the best, through a soft dead zone: differences a
        // model error could make in one batch (≲ `deadzone`) add little, so that evidence
        // accumulates from batches that discriminate, not from many that barely do.
        let dz = c.deadzone;
        for (l, x) in self.nll.iter_mut().zip(chi2.iter()) {
            let d = ((*x - best) * inv).min(cap).max(F::ZERO);
            *l += F::HALF * d * d / (d + dz);
        }
        self.evidence = true;
    }

    /// The best cell at 0, none more than `switch_nll` above it.
    pub(crate) fn normalise(&mut self, c: &Config<F>) {
        let lo = self.min();
        for l in self.nll.iter_mut() {
            *l = (*l - lo).min(c.switch_nll);
        }
    }
}
