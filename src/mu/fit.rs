//! The fit of each surface hypothesis to a batch: its transient slips by damped Gauss–Newton in
//! a trust region, its surface within its interval by recursive least squares, and the seeds a
//! poorly fitting cell tries.
//!
//! - **Slips are nuisances, fitted per hypothesis**: the transient slips α′, κ′ (eqs. 19–21) are
//!   not measured (α never is; κ′ lags the measured κ by the relaxation length σκ). Each cell
//!   keeps its own α′, κ′ and moves them by one damped Gauss–Newton step per batch, from where
//!   the last batch left them, towards the values that explain (Fx, Fy, Mz) on its surface
//!   (`Fit::fit_cell`); where κ is measured, the κ′ that the relaxation filter (eq. 20) makes
//!   of it is one more residual. A step is kept when a trial evaluation finds that it lowers the
//!   batch's χ² (the trust region then grows; otherwise it shrinks), except a small one (at most
//!   [`TRUST_STEP`] in α′ and κ′, its linear model predicting a fall of χ² below
//!   [`TRUST_GAIN`]): that one is taken untried, and the batch's χ² is the one its linear model
//!   predicts — as is the step of a cell held at the cap (out of reach of the best) whose
//!   predicted χ² leaves it unable to explain the batch (above `chi2_explain`), but on a batch
//!   the likeliest cell does not explain (the road may have changed to that cell's). From batch
//!   to batch every cell's κ′ moves with the measured κ′
//!   ([`crate::mu::batch`]).
//! - **Seeds**: a cell that fits the batch badly tries a seed: the best cell's slips, the brush
//!   model's slip angle for the batch's |Fy| on its own surface, or a point of a scan (at most
//!   [`RESEEDS`] per batch in turn); a cell still in contention (ℓ within `exclude_nll` of the
//!   best) always tries the brush seed, so that a cell that lost its slips (a fast reversal out
//!   of the saturated range) is not excluded for it.
//! - **The surface within the cell**: after the slip step, the cell's surface offset (within
//!   ±`mu_step`/2) takes one recursive-least-squares step on the residuals the slip step leaves:
//!   their slope in μ comes with the slip slopes from one evaluation in dual numbers of three
//!   directions (`Prepared::eval_d_scale`; cells held at `switch_nll`, out of reach, take the
//!   two-direction one and keep their offset), the earlier batches' information is kept and
//!   forgotten as ℓ is, and a weak prior (σ 0.25) about the centre bounds the step while the
//!   batches say nothing of μ. So a road between two centres has a cell that is that road: with
//!   fixed points, near the limit both neighbours misfit every batch a little and a far surface
//!   that explains the same forces at another slip angle won (`gough mu bench --mu-shift
//!   0.025`: 57 % of a case's samples identifiable and off by more than 0.2). Intervals cost
//!   some discrimination: a cell more than 0.1 away can come 0.025 nearer, and is excluded only
//!   when that nearer surface is.
//!
//! A cell's surface is the wheel's Magic Formula at the batch's load ([`Prepared`], its load
//! stage evaluated once per batch) with the friction stage of λμx = λμy = μ/μy0 times the file's
//! (docs/architecture.md): no table, load, camber and combined slip enter through the model.

use super::batch::Batch;
use super::calibration::{NUISANCES, PROPERTIES};
use super::config::{Config, Grid, CELLS};
use crate::math::{Backend, Float};
use crate::mf::prepared::{Adjust, Mu, Operating, Prepared, Slopes};
use crate::mf::{self, Options, Params, Side};

/// Cells out of contention per batch that may try a seed when their own fit is poor (cells in
/// contention always may).
pub const RESEEDS: usize = 6;
/// A Gauss–Newton step no longer than this in α′ and κ′, in the cell's slip scales (`Fit`:
/// μ·Fz/|Kyα| and μ·Fz/Kxκ, the slips at which its surface leaves the linear range) …
pub const TRUST_STEP: f64 = 0.04;
/// … whose linear model predicts a fall of χ² below this is taken without a trial evaluation
/// (its χ² is the model's prediction).
pub const TRUST_GAIN: f64 = 1.0;
/// Prior σ of a cell's surface offset about its centre, in widths of the cell (5: σ 0.25 for a
/// cell 0.05 wide): weak beside one informative batch; it bounds the step while the batches say
/// nothing of μ.
const OFFSET_PRIOR_WIDTHS: f64 = 5.0;
/// Slip angles a poorly fitting cell tries in turn (on the side of the lateral force), in its
/// slip scale μ·Fz/|Kyα|.
const SCAN: [f64; 8] = [0.2, 0.4, 0.7, 1.0, 1.6, 2.5, 4.0, 7.0];
/// The trust region's radius in the cell's slip scales: at a (re)start, the largest, the
/// smallest.
const DAMP_START: f64 = 0.4;
const DAMP_MAX: f64 = 4.0;
const DAMP_MIN: f64 = 0.002;
/// The seeds' cycle: the three kinds of seed, the scan's points in turn on every third.
const SCAN_PERIOD: u8 = 3 * SCAN.len() as u8;

/// A surface hypothesis's fitted state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Cell<F> {
    /// Transient slip angle α′ \[rad\].
    pub(crate) alpha: F,
    /// Transient longitudinal slip κ′ \[-\].
    pub(crate) kappa: F,
    /// Trust-region radius of the next step, in the cell's slip scales.
    damp: F,
    /// The surface's offset from the cell's centre \[-\], fitted within its interval.
    dmu: F,
    /// Information on `dmu` from the batches fitted so far \[1/μ²\], forgotten as ℓ is.
    info: F,
}

/// The cells' fits: the tyre's friction scale, the load stage of the batch being fitted, each
/// cell's slips and surface, the χ² each found on its last batch, and the seeds.
#[derive(Debug, Clone)]
pub(crate) struct Fit<F> {
    /// The file's λμx, λμy and μy0, and the grid of hypotheses.
    lmux: F,
    lmuy: F,
    mu_y0: F,
    grid: Grid<F>,
    opts: Options,
    /// The pending batch's slip scales at μ = 1: Fz/|Kyα| \[rad\], Fz/Kxκ \[-\].
    slip: (F, F),
    /// The Magic Formula's load stage at the pending batch's Fz, γ, Vx.
    prep: Option<Prepared<F>>,
    cells: [Cell<F>; CELLS],
    /// Each cell's χ² on the last batch it was fitted on.
    chi2: [F; CELLS],
    /// Seeds taken by cells out of contention in the pending batch (at most [`RESEEDS`]).
    reseeds: u8,
    /// Slips of the best cell of the last batch (a seed for poorly fitting cells).
    best: (F, F),
    /// Seeds tried so far, modulo [`SCAN_PERIOD`] (all that `scan % 3` and `(scan / 3) % 8`
    /// read).
    scan: u8,
}

impl<F: Float> Fit<F> {
    /// Cells at zero slip on their centres, for tyre `params` mounted on `side` (mirrored as
    /// `mf::eval` mirrors with `Options::mounted`), μy0 `mu_y0`.
    pub(crate) fn new(cfg: &Config<F>, params: &Params<F>, side: Option<Side>, mu_y0: F) -> Self {
        let cell = Cell {
            alpha: F::ZERO,
            kappa: F::ZERO,
            damp: F::from_f64(DAMP_START),
            dmu: F::ZERO,
            info: F::ZERO,
        };
        Fit {
            lmux: params.lmux,
            lmuy: params.lmuy,
            mu_y0,
            grid: Grid::new(cfg, mu_y0),
            slip: (F::from_f64(0.05), F::from_f64(0.05)),
            opts: Options {
                transient: true,
                mounted: side,
                moments: false,
                ..Options::default()
            },
            prep: None,
            cells: [cell; CELLS],
            chi2: [F::ZERO; CELLS],
            reseeds: 0,
            best: (F::ZERO, F::ZERO),
            scan: 0,
        }
    }

    /// μy0 of the tyre.
    pub(crate) fn mu_y0(&self) -> F {
        self.mu_y0
    }

    /// The grid of hypotheses.
    pub(crate) fn grid(&self) -> &Grid<F> {
        &self.grid
    }

    /// The slip scales of surface `mu` at the pending batch's load: μ·Fz/|Kyα| \[rad\],
    /// μ·Fz/Kxκ \[-\].
    fn slip_units(&self, mu: F) -> (F, F) {
        let lo = F::from_f64(1e-6);
        ((mu * self.slip.0).max(lo), (mu * self.slip.1).max(lo))
    }

    /// [`Fit::slip_units`] of cell `k`'s surface.
    pub(crate) fn slip_units_of(&self, k: usize) -> (F, F) {
        self.slip_units(self.mu_c(k))
    }

    /// κ′'s σ about free rolling when neither κ nor Fx is measured: half the slip at which the
    /// file's surface leaves its linear range.
    fn pin(&self) -> F {
        F::HALF * self.kappa_scale()
    }

    /// The longitudinal slip at which the file's surface leaves its linear range at the
    /// pending batch's load, μy0·Fz/Kxκ.
    pub(crate) fn kappa_scale(&self) -> F {
        self.mu_y0 * self.slip.1
    }

    /// The cells' fitted states.
    pub(crate) fn cells(&self) -> &[Cell<F>; CELLS] {
        &self.cells
    }

    /// Each cell's χ² on the last batch it was fitted on.
    pub(crate) fn chi2(&self) -> &[F; CELLS] {
        &self.chi2
    }

    /// Cell `k`'s surface: its centre plus its fitted offset.
    pub(crate) fn mu_c(&self, k: usize) -> F {
        self.grid.mu_of(k) + self.cells.get(k).map_or(F::ZERO, |c| c.dmu)
    }

    /// Moves every cell's κ′ by `d` (within ±1): the measured κ′'s change between batches.
    pub(crate) fn follow_kappa(&mut self, d: F) {
        for c in self.cells.iter_mut() {
            c.kappa = clamp(c.kappa + d, F::ONE);
        }
    }

    /// Forgets the offsets' information by the factor `d` (as the likelihoods are forgotten).
    pub(crate) fn forget(&mut self, d: F) {
        for c in self.cells.iter_mut() {
            c.info *= d;
        }
    }

    /// Evaluates the load stage of batch `b` for tyre `params` as the calibration `adjust`
    /// has it ([`Prepared::adjusted`]; `None` when it cannot be: non-finite or no contact), takes
    /// the batch's slip scales from it, and starts the batch's count of seeds. Returns σκ \[m\]
    /// at that load (the κ′ lag's relaxation length), when evaluated.
    pub(crate) fn prepare<M: Backend<F>>(
        &mut self,
        params: &Params<F>,
        adjust: &Adjust<F>,
        b: Option<&Batch<F>>,
    ) -> Option<F> {
        self.prep = b.and_then(|b| {
            let op = Operating {
                fz: b.fz,
                gamma: b.gamma,
                phit: F::ZERO,
                vx: b.vx,
                p: None,
            };
            Prepared::new::<M>(params, &op, &self.opts)
                .ok()
                .map(|p| p.adjusted(adjust))
        });
        self.reseeds = 0;
        let pr = self.prep.as_ref()?;
        let (kya, kxk, fz) = (pr.k_ya().abs(), pr.k_xk().abs(), pr.fz());
        if kya > F::ZERO && kxk > F::ZERO && fz > F::ZERO && (fz / kya).is_finite() {
            self.slip = (fz / kya, fz / kxk);
        }
        let (sx, _) = mf::sigma::sigma::<F, M>(params, pr.conditioned(), pr.k_xk(), pr.k_ya());
        Some(sx)
    }

    /// Whether a batch's load stage is ready to fit on.
    pub(crate) fn prepared(&self) -> bool {
        self.prep.is_some()
    }

    /// The best cell of the last batch: its χ², and its slips kept as a seed.
    pub(crate) fn best_of_batch(&mut self) -> F {
        let mut best = F::from_f64(f64::MAX);
        let mut kb = 0;
        for (k, c) in self.chi2.iter().enumerate() {
            if *c < best {
                best = *c;
                kb = k;
            }
        }
        if let Some(c) = self.cells.get(kb) {
            self.best = (c.alpha, c.kappa);
        }
        best
    }

    /// A bound of |F|/Fz on surface `mu` at the pending batch's load, over `mu`:
    /// hypot(|Dx| + |SVx|, |Dy| + |SVy|)/(Fz·μ) ([`Mu::f_peak`]; the shifts scale with λμ′, so
    /// on ice the resultant exceeds μx·Fz and μy·Fz). `None` without a load stage or when it is
    /// not a positive number.
    pub(crate) fn peak_ratio<M: Backend<F>>(&self, mu: F) -> Option<F> {
        let pr = self.prep.as_ref()?;
        let lambda = mu / self.mu_y0;
        let (px, py) = pr.with_mu(self.lmux * lambda, self.lmuy * lambda).f_peak();
        let r = M::sqrt(px * px + py * py) / (pr.fz() * mu);
        (r.is_finite() && r > F::ZERO).then_some(r)
    }

    /// One Gauss–Newton step of cell `k`, whose ℓ is `nll`, on batch `b`; keeps the batch's χ²
    /// after it as the cell's, and returns it.
    pub(crate) fn fit_cell<M: Backend<F>>(
        &mut self,
        cfg: &Config<F>,
        k: usize,
        nll: F,
        b: &Batch<F>,
    ) -> F {
        let chi2 = self.step::<M>(cfg, k, nll, b);
        if let Some(slot) = self.chi2.get_mut(k) {
            *slot = chi2;
        }
        chi2
    }

    /// [`Fit::fit_cell`]'s step; returns the batch's χ² after it.
    fn step<M: Backend<F>>(&mut self, cfg: &Config<F>, k: usize, nll: F, b: &Batch<F>) -> F {
        let Some(cell) = self.cells.get(k).copied() else {
            return F::ZERO;
        };
        let mu_c = self.mu_c(k);
        let lambda = mu_c / self.mu_y0;
        let Some(prep) = self.prep.as_ref() else {
            return F::ZERO;
        };
        // The friction stage of this surface: λμx = λμy = μ/μy0 times the file's (docs/architecture.md).
        let (lx, ly) = (self.lmux * lambda, self.lmuy * lambda);
        let mu = prep.with_mu(lx, ly);
        // The residuals, their slopes in (α′, κ′) and — but for a cell held at the cap, out of
        // reach of the best, which keeps its offset — in the cell's surface μ: the friction
        // stage in dual numbers too (∂/∂μ = ∂/∂s / μ with both scalings times s).
        let fitted = if nll < cfg.switch_nll && mu_c > F::from_f64(1e-3) {
            self.residuals_mu::<M>(lx, ly, mu_c, b, cell.alpha, cell.kappa)
                .map(|(r, j, jm)| (r, j, Some(jm)))
        } else {
            self.residuals::<M>(&mu, b, cell.alpha, cell.kappa, true)
                .map(|(r, j)| (r, j, None))
        };
        let Some((r0, jac, jmu)) = fitted else {
            return cfg.chi2_cap;
        };
        let chi0 = norm2(&r0);
        // Normal equations of the 2 unknowns (α′, κ′): (JᵀJ + damping·diag) Δ = Jᵀr.
        let (mut h00, mut h01, mut h11, mut g0, mut g1) =
            (F::ZERO, F::ZERO, F::ZERO, F::ZERO, F::ZERO);
        for (r, j) in r0.iter().zip(jac.iter()) {
            h00 += j[0] * j[0];
            h01 += j[0] * j[1];
            h11 += j[1] * j[1];
            g0 += j[0] * *r;
            g1 += j[1] * *r;
        }
        // A trust region of radius `cell.damp` in the cell's slip scales around a barely damped
        // Gauss–Newton step: it grows while steps succeed and shrinks when one fails. κ′'s
        // scale is at least the measured κ′'s σ (a step within its noise is no leap).
        let eps = F::from_f64(1e-9);
        let reg = F::from_f64(1e-6);
        h00 = h00 * (F::ONE + reg) + eps;
        h11 = h11 * (F::ONE + reg) + eps;
        // Scaled by a power of two that brings the largest entry to at most 1 (at most 32
        // halvings by 16): exact in floating point, so the step is the same to the bit, and it
        // keeps the determinant and the numerators (up to ~1e14 unscaled at 100 Hz) inside
        // Q31.32's range (2³¹), where they would saturate.
        let sixteenth = F::from_f64(0.0625);
        let (mut m, mut s) = (h00.max(h11), F::ONE);
        for _ in 0..32 {
            if m <= F::ONE {
                break;
            }
            m *= sixteenth;
            s *= sixteenth;
        }
        let (h00, h01, h11, g0, g1) = (h00 * s, h01 * s, h11 * s, g0 * s, g1 * s);
        let det = h00 * h11 - h01 * h01;
        let mut next = cell;
        let mut chi = chi0;
        if det > F::ZERO && det.is_finite() {
            let mut da = (h11 * g0 - h01 * g1) / det;
            let mut dk = (h00 * g1 - h01 * g0) / det;
            let (ua, uk) = self.slip_units(mu_c);
            let uk = b.kappa.map_or(uk, |(_, s)| uk.max(s));
            let len = (da / ua).abs().max((dk / uk).abs());
            if len > cell.damp {
                let s = cell.damp / len;
                da *= s;
                dk *= s;
            }
            let na = clamp(cell.alpha + da, F::from_f64(1.4));
            let nk = clamp(cell.kappa + dk, F::ONE);
            // The χ² the linear model predicts after the step.
            let (sa, sk) = (na - cell.alpha, nk - cell.kappa);
            let mut pred = F::ZERO;
            for (r, j) in r0.iter().zip(jac.iter()) {
                pred += (*r - j[0] * sa - j[1] * sk).sq();
            }
            let small = (sa / ua).abs().max((sk / uk).abs()) <= F::from_f64(TRUST_STEP)
                && chi0 - pred < F::from_f64(TRUST_GAIN);
            if small {
                // A small step that changes little: the linear model is trusted, and the step
                // taken without a trial evaluation (its χ² is the model's).
                next.alpha = na;
                next.kappa = nk;
                chi = pred.max(F::ZERO).min(chi0);
            } else {
                match self.residuals::<M>(&mu, b, na, nk, false) {
                    Some((r1, _)) if norm2(&r1) < chi0 => {
                        chi = norm2(&r1);
                        next.alpha = na;
                        next.kappa = nk;
                        next.damp = (cell.damp * F::TWO).min(F::from_f64(DAMP_MAX));
                    }
                    _ => {
                        next.damp =
                            (len.min(cell.damp) * F::from_f64(0.25)).max(F::from_f64(DAMP_MIN));
                    }
                }
            }
        }
        // Then the surface within the cell: a step of its offset on the residuals the slip step
        // leaves (predicted by the slopes), within its interval.
        if let Some(jm) = jmu {
            let (sa, sk) = (next.alpha - cell.alpha, next.kappa - cell.kappa);
            let (mut jj, mut jr, mut rr) = (F::ZERO, F::ZERO, F::ZERO);
            let mut rp = [F::ZERO; 4];
            for (((o, r), j), m) in rp.iter_mut().zip(r0.iter()).zip(jac.iter()).zip(jm.iter()) {
                *o = *r - j[0] * sa - j[1] * sk;
                jj += *m * *m;
                jr += *m * *o;
                rr += *o * *o;
            }
            // Recursive least squares over the batches (the information of the earlier ones,
            // forgotten as ℓ is, in `info`) with a weak prior about the cell's centre: the
            // offset follows what the recent batches together say, not the latest batch's noise.
            let (down, up) = self.grid.half(k);
            let width = F::from_f64(OFFSET_PRIOR_WIDTHS) * (down + up);
            let p0 = F::ONE / (width * width).max(F::from_f64(1e-12));
            let nd = (cell.dmu + (jr - p0 * cell.dmu) / (cell.info + jj + p0))
                .max(-down)
                .min(up);
            let d = nd - cell.dmu;
            let mut pred = F::ZERO;
            for (o, m) in rp.iter().zip(jm.iter()) {
                pred += (*o - *m * d).sq();
            }
            next.dmu = nd;
            next.info = cell.info + jj;
            chi = (chi + (pred - rr)).max(F::ZERO);
        }
        // A cell still in contention (ℓ within `exclude_nll` of the best) that fits poorly has
        // most likely lost its slips (a fast reversal out of the saturated range, where the
        // force says little of α′): it always tries the brush model's slip angle for the
        // batch's |Fy| on its own surface, beyond the [`RESEEDS`] budget, so that a tracking
        // failure is not counted as evidence against the surface. Other cells take turns.
        let contending = nll <= cfg.exclude_nll;
        if chi > cfg.reseed_chi2 && (usize::from(self.reseeds) < RESEEDS || contending) {
            if !contending {
                self.reseeds += 1;
            }
            // Alternately the best cell's slips, the brush model's slip angle and a point of a
            // scan of α′ on the side the lateral force gives (α′ > 0 gives Fy < 0, ISO-W), κ′ at
            // the measured value.
            let (sa, sk) = self.best;
            let sk = b.kappa.map_or(sk, |(k, _)| k);
            self.scan = (self.scan + 1) % SCAN_PERIOD;
            let side = |a: F| if b.fy.0 > F::ZERO { -a } else { a };
            let pick = if contending { 1 } else { self.scan % 3 };
            let sa = match pick {
                0 => sa,
                1 => side(self.brush_alpha::<M>(k, b)),
                _ => {
                    let i = usize::from(self.scan / 3) % SCAN.len();
                    let (ua, _) = self.slip_units(mu_c);
                    side(F::from_f64(SCAN.get(i).copied().unwrap_or(0.0)) * ua)
                }
            };
            if let Some((r2, _)) = self.residuals::<M>(&mu, b, sa, sk, false) {
                if norm2(&r2) < chi {
                    chi = norm2(&r2);
                    next.alpha = sa;
                    next.kappa = sk;
                    next.damp = F::from_f64(DAMP_START);
                }
            }
        }
        if let Some(c) = self.cells.get_mut(k) {
            *c = next;
        }
        if chi.is_finite() {
            chi
        } else {
            cfg.chi2_cap
        }
    }

    /// What the calibration's step needs of batch `b` at cell `k` ([`crate::mu::calibration`]):
    /// the normalised residuals there, their model part's slopes in the calibrated properties
    /// (by differences of the adjusted load stage: one more adjustment and evaluation each) and
    /// in the nuisances α′, κ′ (the dual numbers) and the cell's surface μ. `None` without a
    /// load stage or when a number is not finite. In pieces, each about a slot of a sample's
    /// work: [`Fit::calibration_base`], then [`Fit::calibration_column`] per property.
    #[allow(clippy::type_complexity)]
    pub(crate) fn calibration_slopes<M: Backend<F>>(
        &self,
        k: usize,
        b: &Batch<F>,
    ) -> Option<([F; 4], [[F; PROPERTIES]; 4], [[F; NUISANCES]; 4])> {
        let (r0, h_nuis) = self.calibration_base::<M>(k, b)?;
        let mut h_cal = [[F::ZERO; PROPERTIES]; 4];
        for j in 0..PROPERTIES {
            let col = self.calibration_column::<M>(k, b, j, &r0)?;
            for (row, x) in h_cal.iter_mut().zip(col.iter()) {
                if let Some(o) = row.get_mut(j) {
                    *o = *x;
                }
            }
        }
        let ok = h_cal.iter().all(|r| F::all_finite(r)) && F::all_finite(&r0);
        ok.then_some((r0, h_cal, h_nuis))
    }

    /// [`Fit::calibration_slopes`]' first piece: the normalised residuals at cell `k` and their
    /// slopes in the nuisances (α′, κ′, μ). `None` without a load stage or when not finite.
    pub(crate) fn calibration_base<M: Backend<F>>(
        &self,
        k: usize,
        b: &Batch<F>,
    ) -> Option<([F; 4], [[F; NUISANCES]; 4])> {
        let cell = self.cells.get(k).copied()?;
        let mu_c = self.mu_c(k);
        let lambda = mu_c / self.mu_y0;
        let (lx, ly) = (self.lmux * lambda, self.lmuy * lambda);
        let (r0, jn, jm) = self.residuals_mu::<M>(lx, ly, mu_c, b, cell.alpha, cell.kappa)?;
        let mut h_nuis = [[F::ZERO; NUISANCES]; 4];
        for (row, (j, m)) in h_nuis.iter_mut().zip(jn.iter().zip(jm.iter())) {
            *row = [j[0], j[1], *m];
        }
        Some((r0, h_nuis))
    }

    /// [`Fit::calibration_slopes`]' piece for property `j`: the slopes of the residuals' model
    /// part at cell `k` in it, by the difference of the load stage adjusted by a step of it
    /// (1 % of a scale, a tenth of a milliradian of the shift) from `r0`
    /// ([`Fit::calibration_base`]). `None` without a load stage or when the evaluation fails.
    pub(crate) fn calibration_column<M: Backend<F>>(
        &self,
        k: usize,
        b: &Batch<F>,
        j: usize,
        r0: &[F; 4],
    ) -> Option<[F; 4]> {
        let cell = self.cells.get(k).copied()?;
        let prep = self.prep.as_ref()?;
        let mu_c = self.mu_c(k);
        let lambda = mu_c / self.mu_y0;
        let (lx, ly) = (self.lmux * lambda, self.lmuy * lambda);
        let (hs, hh) = (F::from_f64(0.01), F::from_f64(1e-4));
        let es = M::exp(hs);
        let (a, h) = match j {
            0 => (
                Adjust {
                    trail: es,
                    ..Adjust::NONE
                },
                hs,
            ),
            1 => (
                Adjust {
                    trail_shape: es,
                    ..Adjust::NONE
                },
                hs,
            ),
            2 => (
                Adjust {
                    trail_shift: hh,
                    ..Adjust::NONE
                },
                hh,
            ),
            _ => (
                Adjust {
                    kx: es,
                    ..Adjust::NONE
                },
                hs,
            ),
        };
        let p = prep.adjusted(&a);
        let f = p
            .eval_with::<M>(&p.with_mu(lx, ly), cell.kappa, cell.alpha)
            .ok()?;
        let r1 = res_of(b, &[f.fx, f.fy, f.mz], cell.kappa, self.pin());
        let mut col = [F::ZERO; 4];
        for (o, (x1, x0)) in col.iter_mut().zip(r1.iter().zip(r0.iter())) {
            // The model's slope over σ: r = (measured − model)/σ.
            *o = (*x0 - *x1) / h;
        }
        Some(col)
    }

    /// |α′| at which the brush model (parabolic pressure, one friction coefficient) gives the
    /// batch's |Fy| on cell `k`'s surface: Fy = μFz·(1 − (1 − θ|α|)³), θ = Kyα/(3μFz), solved
    /// for |α|; the onset of full sliding (1/θ) when |Fy| ≥ μFz. A seed for a cell that lost
    /// its slips (e.g. deep in the saturated range after a fast reversal on a slippery road).
    fn brush_alpha<M: Backend<F>>(&self, k: usize, b: &Batch<F>) -> F {
        let (ua, _) = self.slip_units(self.mu_c(k));
        let cap = F::from_f64(SCAN.last().copied().unwrap_or(7.0)) * ua;
        let mu_fz = self.mu_c(k) * b.fz;
        let kya = self.prep.as_ref().map_or(F::ZERO, |p| p.k_ya().abs());
        if !(mu_fz > F::ZERO && kya > F::ZERO) {
            return F::from_f64(SCAN.first().copied().unwrap_or(0.2)) * ua;
        }
        let theta = kya / (F::from_f64(3.0) * mu_fz);
        let u = (b.fy.0.abs() / mu_fz).min(F::ONE);
        let rest = F::ONE - u;
        let cbrt = if rest > F::ZERO {
            M::exp(M::ln(rest) / F::from_f64(3.0))
        } else {
            F::ZERO
        };
        ((F::ONE - cbrt) / theta).min(cap)
    }

    /// The normalised residuals (measured − model)/σ of (Fx, Fy, Mz, κ′) at slips (α′, κ′) on
    /// the friction stage `mu`, and (when `jac`) the derivatives of the model's part in
    /// (α′, κ′), from the slip stage's dual numbers. Rows that are not measured are 0.
    #[allow(clippy::type_complexity)]
    fn residuals<M: Backend<F>>(
        &self,
        mu: &Mu<F>,
        b: &Batch<F>,
        alpha: F,
        kappa: F,
        jac: bool,
    ) -> Option<([F; 4], [[F; 2]; 4])> {
        let prep = self.prep.as_ref()?;
        let mut j = [[F::ZERO; 2]; 4];
        let f = if jac {
            let (f, d) = prep.eval_d::<M>(mu, kappa, alpha).ok()?;
            j = jac_of(b, &d, self.pin());
            f
        } else {
            prep.eval_with::<M>(mu, kappa, alpha).ok()?
        };
        let m = [f.fx, f.fy, f.mz];
        if !F::all_finite(&m)
            || !F::all_finite(&[j[0][0], j[0][1], j[1][0], j[1][1], j[2][0], j[2][1]])
        {
            return None;
        }
        Some((res_of(b, &m, kappa, self.pin()), j))
    }

    /// [`Fit::residuals`] with the slopes, at λμx* = `lx`, λμy* = `ly` (surface `mu_c`), and
    /// the slopes of the model's part in the surface μ (one evaluation in dual numbers of three
    /// directions, [`Prepared::eval_d_scale`]).
    #[allow(clippy::type_complexity)]
    fn residuals_mu<M: Backend<F>>(
        &self,
        lx: F,
        ly: F,
        mu_c: F,
        b: &Batch<F>,
        alpha: F,
        kappa: F,
    ) -> Option<([F; 4], [[F; 2]; 4], [F; 4])> {
        let prep = self.prep.as_ref()?;
        let (f, d) = prep.eval_d_scale::<M>(lx, ly, kappa, alpha).ok()?;
        let j = jac_of(b, &d.slip, self.pin());
        let inv = F::ONE / mu_c;
        let jm = [
            b.fx.map_or(F::ZERO, |(_, s)| d.lmu.fx * inv / s),
            d.lmu.fy * inv / b.fy.1,
            d.lmu.mz * inv / b.mz.1,
            F::ZERO,
        ];
        let m = [f.fx, f.fy, f.mz];
        if !F::all_finite(&m)
            || !F::all_finite(&[j[0][0], j[0][1], j[1][0], j[1][1], j[2][0], j[2][1]])
            || !F::all_finite(&jm)
        {
            return None;
        }
        Some((res_of(b, &m, kappa, self.pin()), j, jm))
    }
}

/// The slopes of the normalised residuals' model part in (α′, κ′), from the slip stage's.
/// Without κ and Fx, κ′ is pinned near free rolling with σ `pin`.
fn jac_of<F: Float>(b: &Batch<F>, d: &Slopes<F>, pin: F) -> [[F; 2]; 4] {
    let sx = b.fx.map_or(F::ZERO, |(_, s)| F::ONE / s);
    [
        [d.alpha.fx * sx, d.kappa.fx * sx],
        [d.alpha.fy / b.fy.1, d.kappa.fy / b.fy.1],
        [d.alpha.mz / b.mz.1, d.kappa.mz / b.mz.1],
        match (b.kappa, b.fx) {
            (Some((_, s)), _) => [F::ZERO, F::ONE / s],
            (None, None) => [F::ZERO, F::ONE / pin],
            (None, Some(_)) => [F::ZERO, F::ZERO],
        },
    ]
}

/// The normalised residuals of (Fx, Fy, Mz, κ′) of the model's forces `f` at κ′ `kappa`.
fn res_of<F: Float>(b: &Batch<F>, f: &[F; 3], kappa: F, pin: F) -> [F; 4] {
    let rx = b.fx.map_or(F::ZERO, |(v, s)| (v - f[0]) / s);
    let ry = (b.fy.0 - f[1]) / b.fy.1;
    let rm = (b.mz.0 - f[2]) / b.mz.1;
    let rk = match (b.kappa, b.fx) {
        (Some((v, s)), _) => (v - kappa) / s,
        // Neither κ nor Fx: κ′ is pinned near free rolling.
        (None, None) => -kappa / pin,
        (None, Some(_)) => F::ZERO,
    };
    [rx, ry, rm, rk]
}

fn norm2<F: Float>(r: &[F; 4]) -> F {
    r.iter().fold(F::ZERO, |s, x| s + *x * *x)
}

fn clamp<F: Float>(x: F, lim: F) -> F {
    x.max(-lim).min(lim)
}
