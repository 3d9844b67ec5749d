//! The likelihood with memory: each surface hypothesis's negative log-likelihood ℓ over the
//! recent batches.
//!
//! - A cell's ℓ is the sum of its batches' χ²/2 in excess of the best cell's, each through a
//!   soft dead zone (d ↦ d²/(d + `deadzone`): differences a model error could make in one batch
//!   add little, so that evidence accumulates from batches that discriminate, not from many
//!   that barely do) and capped at `chi2_cap` (so that one batch the model cannot represent — a
//!   transient faster than the batch — never decides). A batch that no cell explains
//!   (`chi2_explain`) or that is not excited is not used (`Likelihood::fold`).
//! - **One operating point counts once**: a batch's evidence is weighted by how new its
//!   operating point is — 1/(1 + n/`novelty`), n the batches of the memory (forgotten as ℓ is)
//!   whose force |F|/(μy0·Fz) fell in the same of [`BINS`] bins. A steady operating point
//!   tells the surface from the tyre's own errors (a trail a few per cent off, a shift) no
//!   better over many batches than over a few: without the weight, a steady turn at
//!   utilisation 0.4 on a tyre whose trail is 17 % below its file read μ 0.43 on a road of 0.7,
//!   identifiable, for two seconds (issue 55's envelope). A sweep of the force (a slalom, a
//!   ramp, a step of the surface) meets new bins and counts in full.
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

/// Bins of the operating point |F|/(μy0·Fz) over [0, [`BINS_TOP`]).
pub const BINS: usize = 16;
/// The top of the bins (a force beyond it falls in the last).
pub const BINS_TOP: f64 = 1.28;

/// The cells' negative log-likelihoods, relative to the best cell's, and whether any evidence
/// has been taken in.
#[derive(Debug, Clone)]
pub(crate) struct Likelihood<F> {
    pub(crate) nll: [F; CELLS],
    /// Batches of the memory per bin of |F|/(μy0·Fz) (forgotten as ℓ is).
    visits: [F; BINS],
    /// Whether any batch (or reading from ahead) has been used.
    pub(crate) evidence: bool,
}

impl<F: Float> Likelihood<F> {
    /// No evidence: every cell at 0.
    pub(crate) fn new() -> Self {
        Likelihood {
            nll: [F::ZERO; CELLS],
            visits: [F::ZERO; BINS],
            evidence: false,
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
        for v in self.visits.iter_mut() {
            *v *= d;
        }
        d
    }

    /// Adds a batch's χ² per cell `chi2`, the best of them `best`, at the operating point
    /// `u0` = |F|/(μy0·Fz): each cell's excess over the best through the soft dead zone, capped,
    /// weighted by the point's novelty (see the module's documentation).
    pub(crate) fn fold(&mut self, c: &Config<F>, chi2: &[F; CELLS], best: F, u0: F) {
        let bin = (u0.max(F::ZERO) * F::from_f64(BINS as f64 / BINS_TOP)).floor_index(BINS - 1);
        let seen = self.visits.get(bin).copied().unwrap_or(F::ZERO);
        let w = F::ONE / (F::ONE + seen / c.novelty.max(F::from_f64(1e-3)));
        if let Some(v) = self.visits.get_mut(bin) {
            *v += F::ONE;
        }
        let cap = c.chi2_cap;
        // Each batch's excess χ² over the best, through a soft dead zone: differences a
        // model error could make in one batch (≲ `deadzone`) add little, so that evidence
        // accumulates from batches that discriminate, not from many that barely do.
        let dz = c.deadzone;
        for (l, x) in self.nll.iter_mut().zip(chi2.iter()) {
            let d = (*x - best).min(cap).max(F::ZERO);
            *l += w * F::HALF * d * d / (d + dz);
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
