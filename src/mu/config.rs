//! The bank's settings: the grid of surface hypotheses on the tyre file's scale, the sensors'
//! noise and the model's error, the gates of the likelihood and of the states.
//!
//! ## The grid
//! [`CELLS`] hypotheses ("cells") of road surface μ = `mu_lo + k·mu_step`, each an interval of
//! ±`mu_step`/2 about its centre ([`crate::mu::fit`] fits the surface within it), on the tyre
//! file's scale: a surface μ is the wheel's own Magic Formula with λμx = λμy = μ/μy0 times the
//! file's λμ, μy0 the file's μy at FNOMIN ([`mu_y0`]; architecture.md).

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
    /// Spacing of the hypotheses \[-\]; the highest is `mu_lo + (CELLS−1)·mu_step`.
    pub mu_step: F,
    /// Samples per batch (the estimator's update rate is the sample rate over this).
    pub batch: u16,
    /// Camber \[rad\] used when a sample carries none.
    pub gamma: F,
    /// Aligning-torque sensor noise, rms \[N·m\].
    pub sigma_mz: F,
    /// Force sensor noise (Fx, Fy, Fz), rms, as a fraction of Fz \[-\].
    pub sigma_f_rel: F,
    /// Longitudinal slip sensor noise, rms \[-\] (κ from wheel speed and a vehicle-speed estimate).
    pub sigma_kappa: F,
    /// Model error of the forces, as a fraction of |F| \[-\].
    pub model_f_rel: F,
    /// Model error of the forces, as a fraction of Fz \[-\] (the shifts SHy, SVy, SVx, ply
    /// steer and sensor offsets: what the model says at zero slip is not evidence of μ).
    pub model_f_abs: F,
    /// Model error of the aligning torque, as a fraction of |Mz| \[-\].
    pub model_mz_rel: F,
    /// Model error of the aligning torque, absolute \[N·m\] (residual torque, conicity).
    pub model_mz_abs: F,
    /// Model error of κ′ from the measured κ \[-\] (the relaxation filter's lag and σκ).
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
}

impl<F: Float> Default for Config<F> {
    fn default() -> Self {
        let c = F::from_f64;
        Config {
            mu_lo: c(0.1),
            mu_step: c(0.05),
            batch: 10,
            gamma: F::ZERO,
            sigma_mz: c(2.0),
            sigma_f_rel: c(0.01),
            sigma_kappa: c(0.005),
            model_f_rel: c(0.01),
            model_f_abs: c(0.005),
            model_mz_rel: c(0.03),
            model_mz_abs: c(1.0),
            model_kappa: c(0.005),
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
        }
    }
}

impl<F: Float> Config<F> {
    /// Whether the grid and the batch can be used: `batch` > 0, `mu_lo` and `mu_step` positive.
    pub(crate) fn usable(&self) -> bool {
        self.batch > 0
            && self.mu_lo.partial_cmp(&F::ZERO) == Some(core::cmp::Ordering::Greater)
            && self.mu_step.partial_cmp(&F::ZERO) == Some(core::cmp::Ordering::Greater)
    }

    /// The cell nearest μ `mu`.
    pub(crate) fn cell_of(&self, mu: F) -> usize {
        ((mu - self.mu_lo) / self.mu_step + F::HALF)
            .max(F::ZERO)
            .floor_index(CELLS - 1)
    }

    /// μ of cell `k`'s centre.
    pub(crate) fn mu_of(&self, k: usize) -> F {
        self.mu_lo + self.mu_step * F::from_index(k as u16)
    }
}

/// μy0 of a tyre: μy at FNOMIN, zero slip and camber, nominal pressure (architecture.md).
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
