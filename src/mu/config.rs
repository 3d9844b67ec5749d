//! The bank's settings: the grid of surface hypotheses on the tyre file's scale, the sensors'
//! noise and the model's error, the gates of the likelihood and of the states.
//!
//! ## The grid
//! [`CELLS`] hypotheses ("cells") of road surface μ from `mu_lo` (ice and below) to
//! `mu_hi_rel`·μy0 (above the file's own test surface), each an interval reaching halfway to
//! its neighbours ([`crate::mu::fit`] fits the surface within it), on the tyre file's scale: a
//! surface μ is the wheel's own Magic Formula with λμx = λμy = μ/μy0 times the file's λμ, μy0
//! the file's μy at FNOMIN ([`mu_y0`]; docs/architecture.md). The centres are `mu_step` apart
//! where that reaches `mu_hi_rel`·μy0 with [`CELLS`] cells (a car tyre of μy0 ≈ 1); beyond, each
//! step is at least ρ times its centre, ρ as small as reaches it ([`Grid`]): a racing tyre of
//! μy0 3 gets steps of 0.05 up to μ ≈ 0.4 and of 13 % above.
//!
//! ## Scale-free
//! Every setting is stated in the tyre's own scales or the data's: noise and model error as
//! shares of Fz, FNOMIN·R0, |F|, |Mz| (the noise then tracked from the data,
//! [`crate::mu::noise`]), slips in the slip at which each surface's linear range ends
//! (μ·Fz/|Kyα|, μ·Fz/Kxκ), the grid in μy0, the batch in time.

use super::calibration::PROPERTIES;
use crate::math::{Backend, Float};
use crate::mf::{self, Input, Options, Params};

/// Number of surface hypotheses.
pub const CELLS: usize = 25;

/// Estimator settings. SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Config<F> {
    /// Lowest surface hypothesis μ \[-\] (file's scale).
    pub mu_lo: F,
    /// Smallest spacing of the hypotheses \[-\] (the grid's, where it reaches `mu_hi_rel`·μy0).
    pub mu_step: F,
    /// Highest hypothesis as a multiple of the file's μy0 \[-\].
    pub mu_hi_rel: F,
    /// Duration of a batch \[µs\] (the estimator's update interval, at any sample rate).
    pub batch_us: u32,
    /// Camber \[rad\] used when a sample carries none.
    pub gamma: F,
    /// Aligning-torque sensor noise, rms, as a share of FNOMIN·R0 \[-\] (the start of its
    /// online estimate, [`crate::mu::noise`]; 7.5e-4 is 2 N·m on the bundled MF 6.1 car tyre).
    pub sigma_mz_rel: F,
    /// Force sensor noise (Fx, Fy, Fz), rms, as a fraction of Fz \[-\] (the start of its online
    /// estimate).
    pub sigma_f_rel: F,
    /// Longitudinal slip sensor noise, rms \[-\] (κ from wheel speed and a vehicle-speed
    /// estimate; the start of its online estimate).
    pub sigma_kappa: F,
    /// Model error of the forces, as a fraction of |F| \[-\].
    pub model_f_rel: F,
    /// Model error of the forces, as a fraction of Fz \[-\] (the shifts SHy, SVy, SVx, ply
    /// steer and sensor offsets: what the model says at zero slip is not evidence of μ).
    pub model_f_abs: F,
    /// Model error of the aligning torque, as a fraction of |Mz| \[-\].
    pub model_mz_rel: F,
    /// Model error of the aligning torque, as a share of Fz·R0 \[-\] (residual torque,
    /// conicity; 3.8e-4 is 1 N·m on the bundled MF 6.1 car tyre at FNOMIN).
    pub model_mz_abs: F,
    /// Model error of κ′ from the measured κ, as a share of the slip μy0·Fz/Kxκ at which the
    /// file's surface leaves its linear range \[-\] (the relaxation filter's lag and σκ).
    pub model_kappa: F,
    /// Share of a channel's variance within a batch (beyond its noise) that counts as the
    /// batch mean's error \[-\]: a batch over which the point moves far along the curve says less.
    pub spread: F,
    /// Below this |Vx| \[m/s\] (when measured) a sample is not used.
    pub vx_min: F,
    /// Below this Fz/FNOMIN a sample is not used.
    pub fz_min_rel: F,
    /// Forgetting time \[s\] of the evidence.
    pub memory: F,
    /// Forgetting distance \[m\] of the evidence (distance rolled, |Vx|·Δt).
    pub memory_distance: F,
    /// Smallest horizontal force, as a fraction of Fz, of a batch that counts as evidence \[-\]
    /// (default 0.01: twice `model_f_abs`, which keeps the free-rolling wheel's force out; 0.03
    /// is utilisation 0.3 on μ 0.1 and hid the batches that tell ice, docs/decisions.md).
    pub excitation: F,
    /// Largest χ² one batch adds to a cell.
    pub chi2_cap: F,
    /// Soft dead zone of a batch's χ² excess (d ↦ d²/(d + deadzone)).
    pub deadzone: F,
    /// A batch whose best cell's χ² exceeds this is not used.
    pub chi2_explain: F,
    /// Largest ℓ of a cell above the best (a switching probability of e^−switch_nll per batch).
    pub switch_nll: F,
    /// A cell whose ℓ lies this far above the best is excluded.
    pub exclude_nll: F,
    /// While not identifiable, the last identifiable μ is reported as long as its ℓ lies no
    /// further than this above the best (the evidence has not turned against it).
    pub hold_nll: F,
    /// Floor of the reported σ \[-\] (the grid's interpolation, the model).
    pub sigma_floor: F,
    /// Largest σ \[-\] of an identifiable estimate (0.1/1.96: ±0.1 at 95 %).
    pub sigma_identifiable: F,
    /// Smallest jump of an identifiable μ flagged as a change of surface \[-\].
    pub change_min: F,
    /// Growth of a held estimate's variance with time \[1/s\] (σ² grows by this per second).
    pub age_q_time: F,
    /// Growth of a held estimate's variance with distance rolled \[1/m\].
    pub age_q_distance: F,
    /// μ reported as the fallback.
    pub mu_prior: F,
    /// σ reported with the fallback.
    pub sigma_prior: F,
    /// A cell whose batch χ² exceeds this tries the best cell's slips (at most
    /// [`RESEEDS`](crate::mu::RESEEDS)).
    pub reseed_chi2: F,
    /// Largest χ² of the latest batch at the reported surface for the estimate to be
    /// identifiable (the surface must explain what is measured now).
    pub chi2_identifiable: F,
    /// Smallest utilisation of the reported surface, |F|/(μ·Fz), of a batch that refreshes an
    /// identification \[-\]. Below it a batch says little of μ near the reported value (the
    /// curve is linear there, every surface above the force explains it alike), and the
    /// identification ages as a held value does (`age_q_time`, `age_q_distance`, from the last
    /// batch that reached it): it ends when its aged σ exceeds `sigma_identifiable`. 0: every
    /// excited batch refreshes.
    pub inform_util: F,
    /// Calibrate the tyre online ([`crate::mu::calibration`]).
    pub calibrate: bool,
    /// The calibration's steps share one road, a state of their own across batches
    /// ([`crate::mu::calibration::Calibration::step_joint`]), and step on every excited batch
    /// the likeliest surface explains; off (the default), each step takes the road as a
    /// nuisance of its batch, gated on an identification held `cal_settle` over a sweep.
    /// Experimental: on it converges from a slalom, but misleads the bench's exact cases
    /// (docs/decisions.md, "Friction estimator v3").
    pub cal_joint: bool,
    /// Prior σ of the calibrated properties (trail, trail shape: of their logarithms; trail
    /// shift \[rad\]; Kxκ: of its logarithm) — how far a tyre on a car is taken to differ from its
    /// file before the data say.
    pub cal_sigma: [F; PROPERTIES],
    /// Time over which a calibrated property may drift by its prior σ \[s\].
    pub cal_tau: F,
    /// A calibrated property is kept within this many prior σ.
    pub cal_bound: F,
    /// The calibration takes at most one step per this time \[s\].
    pub cal_period: F,
    /// A batch calibrates away from the linear range only while |F|/Fz has swept at least this
    /// share of its maximum over the last `cal_sweep_time` (a steady operating point tells μ
    /// and the tyre apart no better over many batches than over one).
    pub cal_sweep: F,
    /// \[s\]
    pub cal_sweep_time: F,
    /// ... and while the estimate has been identifiable, without a change, this long \[s\].
    pub cal_settle: F,
    /// A batch whose |F| is below this utilisation of the lowest hypothesis (the linear range
    /// of every surface) calibrates without either.
    pub cal_util: F,
    /// Averaging time of the model-mismatch indication \[s\].
    pub mismatch_time: F,
    /// The likeliest surface's χ², averaged, above which the calibrated model does not explain
    /// the data ([`Estimate::mismatch`](crate::mu::Estimate::mismatch)).
    pub mismatch_chi2: F,
}

impl<F: Float> Default for Config<F> {
    fn default() -> Self {
        let c = F::from_f64;
        Config {
            mu_lo: c(0.05),
            mu_step: c(0.05),
            mu_hi_rel: c(1.25),
            batch_us: 10_000,
            gamma: F::ZERO,
            sigma_mz_rel: c(7.5e-4),
            sigma_f_rel: c(0.01),
            sigma_kappa: c(0.005),
            model_f_rel: c(0.01),
            model_f_abs: c(0.005),
            model_mz_rel: c(0.03),
            model_mz_abs: c(3.8e-4),
            model_kappa: c(0.25),
            spread: c(1.0),
            vx_min: c(3.0),
            fz_min_rel: c(0.1),
            memory: c(2.0),
            memory_distance: c(50.0),
            excitation: c(0.01),
            chi2_cap: c(8.0),
            deadzone: c(1.0),
            chi2_explain: c(30.0),
            switch_nll: c(12.0),
            exclude_nll: c(4.5),
            hold_nll: c(11.5),
            sigma_floor: c(0.01),
            sigma_identifiable: c(0.1 / 1.96),
            change_min: c(0.1),
            age_q_time: c(0.01),
            age_q_distance: c(0.0005),
            mu_prior: c(0.8),
            sigma_prior: c(0.4),
            reseed_chi2: c(25.0),
            chi2_identifiable: c(12.0),
            inform_util: c(0.3),
            calibrate: true,
            cal_joint: false,
            cal_sigma: [c(0.1), c(0.1), c(0.002), c(0.1)],
            cal_tau: c(120.0),
            cal_bound: c(4.0),
            cal_period: c(0.04),
            cal_sweep: c(0.5),
            cal_sweep_time: c(1.0),
            cal_settle: c(0.5),
            cal_util: c(0.4),
            mismatch_time: c(1.0),
            mismatch_chi2: c(4.0),
        }
    }
}

impl<F: Float> Config<F> {
    /// Whether the grid and the batch can be used: `batch_us` > 0, `mu_lo`, `mu_step` and
    /// `mu_hi_rel` positive, the calibration's σ finite and ≥ 0 (0: the property known
    /// exactly), its time and bound positive.
    pub(crate) fn usable(&self) -> bool {
        let pos = |x: F| x.partial_cmp(&F::ZERO) == Some(core::cmp::Ordering::Greater);
        self.batch_us > 0
            && pos(self.mu_lo)
            && pos(self.mu_step)
            && pos(self.mu_hi_rel)
            && self
                .cal_sigma
                .iter()
                .all(|s| s.is_finite() && *s >= F::ZERO)
            && pos(self.cal_tau)
            && pos(self.cal_bound)
    }
}

/// The grid of surface hypotheses of one tyre (see the module's "The grid").
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Grid<F> {
    /// The cells' centres \[-\], increasing.
    centre: [F; CELLS],
    /// Half the configured step (`mu_step`): how far a cell may move with no neighbour.
    step_half: F,
}

impl<F: Float> Grid<F> {
    /// From `mu_lo` in steps of `mu_step` to at least `mu_hi_rel`·`mu_y0`, each step at least ρ
    /// times its centre with ρ ≥ 0 as small as reaches it.
    pub fn new(c: &Config<F>, mu_y0: F) -> Self {
        let hi = c.mu_hi_rel * mu_y0;
        let build = |rho: F| {
            let mut g = [F::ZERO; CELLS];
            let mut x = c.mu_lo;
            for o in g.iter_mut() {
                *o = x;
                x += c.mu_step.max(rho * x);
            }
            g
        };
        let last = |g: &[F; CELLS]| g.last().copied().unwrap_or(F::ZERO);
        let mut centre = build(F::ZERO);
        if last(&centre) < hi {
            // Bisection on ρ (40 halvings: far below any μ that matters).
            let (mut a, mut b) = (F::ZERO, F::ONE);
            for _ in 0..40 {
                let m = (a + b) * F::HALF;
                if last(&build(m)) < hi {
                    a = m;
                } else {
                    b = m;
                }
            }
            centre = build(b);
        }
        Grid {
            centre,
            step_half: c.mu_step * F::HALF,
        }
    }

    /// μ of cell `k`'s centre.
    pub fn mu_of(&self, k: usize) -> F {
        self.centre.get(k).copied().unwrap_or(F::ZERO)
    }

    /// How far cell `k`'s surface may move down and up from its centre: halfway to the
    /// neighbours (at the ends, the other half; never below half the centre). (Computed when
    /// asked, once per cell's fit: a table of them was 200 bytes of every wheel's state.)
    pub fn half(&self, k: usize) -> (F, F) {
        let Some(here) = self.centre.get(k).copied() else {
            return (F::ZERO, F::ZERO);
        };
        let up = self.centre.get(k + 1).map(|g| (*g - here) * F::HALF);
        let down = k
            .checked_sub(1)
            .and_then(|j| self.centre.get(j))
            .map(|g| (here - *g) * F::HALF);
        let step = self.step_half;
        (
            down.or(up).unwrap_or(step).min(here * F::HALF),
            up.or(down).unwrap_or(step),
        )
    }

    /// The lowest hypothesis.
    pub fn lowest(&self) -> F {
        self.mu_of(0)
    }

    /// The cell nearest μ `mu`.
    pub fn cell_of(&self, mu: F) -> usize {
        let mut best = 0;
        let mut d = F::from_f64(f64::MAX);
        for (k, g) in self.centre.iter().enumerate() {
            let e = (*g - mu).abs();
            if e < d {
                d = e;
                best = k;
            }
        }
        best
    }
}

/// μy0 of a tyre: μy at FNOMIN, zero slip and camber, nominal pressure (docs/architecture.md).
pub fn mu_y0<F: Float, M: Backend<F>>(p: &Params<F>) -> Option<F> {
    let pres = if p.nompres > F::ZERO {
        Some(p.nompres)
    } else {
        None
    };
    let vx = if p.longvl > F::ONE { p.longvl } else { F::ONE };
    let o = mf::eval::<F, M>(
        p,
        &Input {
            fz: p.fnomin,
            vx,
            p: pres,
            ..Input::default()
        },
        &Options::default(),
    )
    .ok()?;
    (o.mu_y.is_finite() && o.mu_y > F::ZERO).then_some(o.mu_y)
}
