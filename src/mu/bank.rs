//! The friction estimator: a bank of surface hypotheses, each fitted to the recent past with the
//! exact Magic Formula.
//!
//! ## Method
//! - **Hypotheses** ("cells"): [`CELLS`] intervals of road surface μ = `mu_lo + k·mu_step` ±
//!   `mu_step`/2 on the tyre file's scale (architecture.md: λμx = λμy = μ/μy0). Each is the
//!   wheel's own Magic Formula on its surface — no table: load, camber and combined slip enter
//!   through the model. A cell's surface within its interval is fitted (below), so that a road
//!   between two centres has a cell that is that road: with fixed points, near the limit both
//!   neighbours misfit every batch a little and a far surface that explains the same forces at
//!   another slip angle won (`gough mu bench --mu-shift 0.025`: 57 % of a case's samples
//!   identifiable and off by more than 0.2).
//! - **Batches**: the estimator works on means of `batch` samples (10 at 1 kHz: a 100 Hz
//!   estimator). Each batch's Fz, Fx, Fy, Mz, γ, Vx and the κ′ implied by the measured κ are
//!   averaged; their σ is the sensor noise over √n plus a model-error term.
//! - **Slips are nuisances, fitted per hypothesis**: the transient slips α′, κ′ (eqs. 19–21) are
//!   not measured (α never is; κ′ lags the measured κ by the relaxation length σκ). Each cell keeps
//!   its own α′, κ′ and moves them by one damped Gauss–Newton step per batch, from where the last
//!   batch left them, towards the values that explain (Fx, Fy, Mz) on its surface; where κ is
//!   measured, the κ′ that the relaxation filter (eq. 20) makes of it is one more residual. A
//!   step is kept when a trial evaluation finds that it lowers the batch's χ² (the trust region
//!   then grows; otherwise it shrinks), except a small one (at most [`TRUST_STEP`] in α′ and κ′,
//!   its linear model predicting a fall of χ² below [`TRUST_GAIN`]): that one is taken untried,
//!   and the batch's χ² is the one its linear model predicts. From batch to batch every cell's
//!   κ′ moves with the measured κ′, by the change shrunk towards 0 by the noise of a difference
//!   of two batch means. A cell that fits the batch badly tries a seed: the best cell's slips,
//!   the brush model's slip angle for the batch's |Fy| on its own surface, or a point of a scan
//!   (at most [`RESEEDS`] per batch in turn); a cell still in contention (ℓ within
//!   `exclude_nll` of the best) always tries the brush seed, so that a cell that lost its slips
//!   (a fast reversal out of the saturated range) is not excluded for it. After the slip step,
//!   the cell's surface offset (within ±`mu_step`/2) takes one recursive-least-squares step on
//!   the residuals the slip step leaves: their slope in μ comes with the slip slopes from one
//!   evaluation in dual numbers of three directions (`Prepared::eval_d_scale`; cells held at
//!   `switch_nll`, out of reach, take the two-direction one and keep their offset),
//!   the earlier batches' information is kept and forgotten as ℓ is, and a weak prior
//!   (σ 0.25) about the centre bounds the step while the batches say nothing of μ.
//!   Intervals cost some discrimination: a cell more than 0.1 away can come 0.025 nearer, and
//!   is excluded only when that nearer surface is.
//! - **Likelihood with memory**: each cell's negative log-likelihood ℓ is the sum of its batches'
//!   χ²/2 (each capped at `chi2_cap`, so that one batch the model cannot represent — a transient
//!   faster than the batch — never decides), forgotten at the rate exp(−Δt/`memory` −
//!   Δs/`memory_distance`) (time and distance rolled), and held at most `switch_nll` above the
//!   best cell: a surface once excluded can return within a few batches when the road changes
//!   (a switching hypothesis, as in an interacting-multiple-model filter over a discrete grid).
//!   A batch that no cell explains (`chi2_explain`) is not used.
//! - **Estimate**: the surface of the cell at the minimum of ℓ (centre plus offset); σ from ℓ's
//!   curvature and the spread of the posterior exp(−ℓ) over the cells' surfaces, with a floor.
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
//! On every sample, the running mean of the batch being collected is checked against the
//! reported μ: a horizontal force it cannot produce at this load (|F|/Fz less 3σ of the noise and
//! the model error above hypot(|Dx| + |SVx|, |Dy| + |SVy|)/Fz, the pure-slip peaks with their
//! vertical shifts — a bound, not the combined-slip maximum) ends the
//! identification at once (a change to a grippier surface is not reported as the old one for
//! a batch and its fit), drops the held value, and bounds μ from below (`mu_min` and the
//! reported μ) for the next two batches.
//!
//! Each batch's fit starts with the likeliest cell: when it no longer explains the new batch
//! (χ² above `chi2_identifiable`), an identifiable estimate is withdrawn then (its value held),
//! on the first sample of the fit rather than when the batch's fit is finished, and every cell
//! is fitted on that batch, as on a cold start: a cell out of contention is otherwise fitted on
//! every [`VISIT`]th batch, its last χ² standing in between, and after a change of surface those
//! χ² and its slips describe the old road (`gough mu bench`: the slalom onto μ 0.3 read on the
//! front-left in 93 ms instead of 251 ms, the rear-left in 209 ms instead of 389 ms).
//!
//! ## Time
//! Samples carry a `u32` microsecond timestamp; only wrapping differences are used, so the
//! estimator behaves identically whatever the clock read at its start, for as long as it runs.
//! A difference of 0, a backward step, or one over [`MAX_GAP_US`] restarts the batch (the
//! evidence ages by the gap).
//!
//! ## Cost
//! Bounded per sample, no allocation: a batch's cells are fitted over the next batch's samples,
//! `⌈CELLS/batch⌉` cells per sample, each one Magic Formula evaluation with the slip derivatives
//! and one without (the trial; none for a small step), plus one more for a poorly fitting cell
//! (at most [`RESEEDS`] per batch, and those in contention). M4F, `Fast`: see
//! docs/estimator.md ("Cost on the device") for the figures the firmware bench measures.

use crate::math::{Backend, Float};
use crate::mf::prepared::{Mu, Operating, Prepared, Slopes};
use crate::mf::{self, Input, Options, Params, Side};

/// Number of surface hypotheses.
pub const CELLS: usize = 25;
/// Cells out of contention per batch that may try a seed when their own fit is poor (cells in
/// contention always may).
pub const RESEEDS: usize = 6;
/// Prior information on a cell's surface offset \[1/μ²\]: σ 0.25 about the cell's centre, weak
/// beside one informative batch; it bounds the step while the batches say nothing of μ.
const OFFSET_PRIOR: f64 = 16.0;
/// Slip angles \[rad\] a poorly fitting cell tries in turn (on the side of the lateral force).
const SCAN: [f64; 8] = [0.01, 0.02, 0.035, 0.05, 0.08, 0.12, 0.2, 0.35];
/// A cell out of contention is fitted on every `VISIT`th batch (and on every batch the likeliest
/// cell does not explain).
pub const VISIT: usize = 4;

/// A sample's work ([`Bank::update`]): at least this many slots of a cell's fit (one for a
/// reading from ahead, one for the load stage on a sample that closes a batch).
pub const SLOTS: usize = 3;
/// A Gauss–Newton step no longer than this \[rad, -\] in α′ and κ′ …
pub const TRUST_STEP: f64 = 0.002;
/// … whose linear model predicts a fall of χ² below this is taken without a trial evaluation
/// (its χ² is the model's prediction).
pub const TRUST_GAIN: f64 = 1.0;
/// The longest sample interval \[µs\] inside a batch; a longer one restarts it.
pub const MAX_GAP_US: u32 = 200_000;

/// Estimator settings. SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
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
    /// A cell whose batch χ² exceeds this tries the best cell's slips (at most [`RESEEDS`]).
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

/// One measurement of one wheel. ISO-W at the contact point, SI units.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sample<F> {
    /// Timestamp \[µs\], wrapping: only differences between samples are used.
    pub t_us: u32,
    /// Vertical load Fz \[N\].
    pub fz: F,
    /// Lateral force Fy \[N\].
    pub fy: F,
    /// Aligning torque Mz \[N·m\].
    pub mz: F,
    /// Longitudinal force Fx \[N\], when measured (without it, κ′ is taken as the measured κ, or 0).
    pub fx: Option<F>,
    /// Longitudinal slip κ \[-\] (wheel speed against vehicle speed), when measured. Never α.
    pub kappa: Option<F>,
    /// Forward speed Vx \[m/s\], when measured.
    pub vx: Option<F>,
    /// Inclination γ \[rad\], when known; `Config::gamma` otherwise.
    pub gamma: Option<F>,
}

/// What an estimate rests on (see the module's "States").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum State {
    /// Within ±0.1 at 95 % by the estimator's own account: usable now.
    Identifiable,
    /// Some surfaces excluded, not enough to be usable; `mu_min` bounds μ from below.
    NotIdentifiable,
    /// Nothing excluded (or aged out): the prior is reported.
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

/// An estimate of the road friction.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Estimate<F> {
    /// μ \[-\] on the tyre file's scale (architecture.md); the prior in `Fallback`.
    pub mu: F,
    /// Standard deviation of μ \[-\] by the estimator's own account.
    pub sigma: F,
    /// The lowest μ not excluded \[-\] (a lower bound a controller may rely on; `mu_lo` when
    /// nothing is excluded).
    pub mu_min: F,
    /// What it rests on.
    pub state: State,
    /// A change of surface was declared at this sample: the identifiable μ jumped by more than
    /// `change_min` from the last identifiable value.
    pub change: bool,
}

/// Why an estimator could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BuildError {
    /// The model's μy0 at FNOMIN is not a positive number (nonsense parameters).
    NoFriction,
    /// The grid of hypotheses is empty or not positive (`mu_lo`, `mu_step`), or `batch` is 0.
    BadConfig,
}

impl core::fmt::Display for BuildError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            BuildError::NoFriction => "the tyre model has no positive friction at FNOMIN",
            BuildError::BadConfig => "the estimator's grid or batch is not positive",
        })
    }
}

impl core::error::Error for BuildError {}

/// A surface hypothesis.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Cell<F> {
    /// Transient slip angle α′ \[rad\].
    alpha: F,
    /// Transient longitudinal slip κ′ \[-\].
    kappa: F,
    /// Negative log-likelihood, relative to the best cell.
    nll: F,
    /// Trust-region radius of the next step (α′ \[rad\] and κ′ alike).
    damp: F,
    /// The surface's offset from the cell's centre \[-\], fitted within ±`mu_step`/2.
    dmu: F,
    /// Information on `dmu` from the batches fitted so far \[1/μ²\], forgotten as ℓ is.
    info: F,
}

/// Sums of one batch.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Acc<F> {
    n: u16,
    n_fx: u16,
    n_kappa: u16,
    n_vx: u16,
    fz: F,
    fx: F,
    fy: F,
    mz: F,
    gamma: F,
    vx: F,
    kappa: F,
    /// Sums of squares of Fx, Fy, Mz, κ′ (the spread within the batch).
    sq: [F; 4],
    /// Duration \[µs\] and distance \[m\] the batch covers.
    us: u32,
    dist: F,
}

impl<F: Float> Acc<F> {
    fn new() -> Self {
        Acc {
            n: 0,
            n_fx: 0,
            n_kappa: 0,
            n_vx: 0,
            fz: F::ZERO,
            fx: F::ZERO,
            fy: F::ZERO,
            mz: F::ZERO,
            gamma: F::ZERO,
            vx: F::ZERO,
            kappa: F::ZERO,
            sq: [F::ZERO; 4],
            us: 0,
            dist: F::ZERO,
        }
    }
}

/// A batch's means and their σ.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Batch<F> {
    fz: F,
    gamma: F,
    vx: F,
    /// (value, σ) of Fx (absent: None), Fy, Mz, κ′ (absent: None).
    fx: Option<(F, F)>,
    fy: (F, F),
    mz: (F, F),
    kappa: Option<(F, F)>,
    /// Seconds and metres covered.
    dt: F,
    dist: F,
}

/// What one [`Bank::update`]'s calls of `work` did (tests of the per-sample budget).
#[cfg(test)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
struct WorkTrace {
    /// Cells fitted over the update.
    fits: usize,
    /// Cells fitted by the calls that finish a batch that did not end before the next closed.
    forced_fits: usize,
    /// The most cells fitted (and readings mixed in) by one call.
    load: usize,
    /// The same, over the calls that also finished their batch.
    load_finishing: usize,
    /// A call refitted every cell (the likeliest did not explain the batch).
    refit: bool,
    /// A reading that had waited a sample was mixed in, in a slot of its own.
    own_slot: bool,
}

/// One wheel's friction estimator. A few hundred bytes of state and a reference to the tyre's
/// parameters; no allocation; bounded work per sample.
#[derive(Debug, Clone)]
pub struct Bank<F> {
    /// FNOMIN \[N\] and the file's λμx, λμy, of the parameters the bank was built for.
    fnomin: F,
    lmux: F,
    lmuy: F,
    /// The Magic Formula's load stage at the pending batch's Fz, γ, Vx.
    prep: Option<Prepared<F>>,
    opts: Options,
    mu_y0: F,
    cfg: Config<F>,
    cells: [Cell<F>; CELLS],
    acc: Acc<F>,
    /// The batch being fitted, the next cell to fit, and the χ² found so far.
    pending: Option<Batch<F>>,
    next: usize,
    chi2: [F; CELLS],
    reseeds: usize,
    /// Slips of the best cell of the last batch (a seed for poorly fitting cells).
    best: (F, F),
    /// The measured κ′ of the last batch fitted (cells' κ′ follow its changes).
    kappa_prev: Option<F>,
    /// Where the round robin of re-seeds starts.
    reseed_from: usize,
    /// Position in the re-seed scan.
    scan: usize,
    /// The cells fitted in the pending batch, and how many (see [`Bank::select`]).
    active: [bool; CELLS],
    n_active: usize,
    /// Batches so far (modulo [`VISIT`]), for the visits of far cells.
    round: usize,
    last_t: Option<u32>,
    /// κ′ implied by the measured κ (first-order lag over σκ/|Vx|), and σκ \[m\].
    kappa_lag: Option<F>,
    sigma_kappa_len: F,
    /// Whether any batch has been used.
    evidence: bool,
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
    bad: u32,
    /// A bound of |F|/Fz on the reported μ's surface at the last batch's load, over μ:
    /// hypot(|Dx| + |SVx|, |Dy| + |SVy|)/(Fz·μ) ([`Mu::f_peak`]; the shifts scale with λμ′, so
    /// on ice the resultant exceeds μx·Fz and μy·Fz).
    peak_ratio: F,
    /// A lower bound of μ from a measured force the reported μ cannot produce, and the batches
    /// it stays in force (until the likelihoods have taken that force in).
    floor: F,
    floor_batches: u8,
    /// The cell fitted first in the pending batch (the likeliest), if not yet fitted.
    first: Option<u8>,
    /// The cell fitted first, skipped in the rotation.
    skip: Option<u8>,
    /// Cells of the pending batch fitted so far.
    fitted: usize,
    /// A reading from ahead ([`Bank::preview`]: profile, weight) not yet mixed in: it takes
    /// one of a sample's slots in [`Bank::work`], as a cell's fit does.
    mixing: Option<([F; CELLS], F)>,
    /// Whether that reading has waited a sample for a slot.
    mix_waited: bool,
    /// What the last [`Bank::update`]'s work did (tests of the per-sample budget).
    #[cfg(test)]
    trace: WorkTrace,
}

impl<F: Float> Bank<F> {
    /// An estimator for a wheel with tyre `params` mounted on `side` (mirrored as `mf::eval`
    /// mirrors with `Options::mounted`; `None`: as the file describes it).
    ///
    /// The bank keeps no reference to `params`: [`Bank::update`] takes them with each sample
    /// (so that a device can own its parameters and its estimators side by side). Pass the same
    /// parameters every time; after loading others, build a new bank.
    pub fn new<M: Backend<F>>(
        params: &Params<F>,
        side: Option<Side>,
        cfg: Config<F>,
    ) -> Result<Self, BuildError> {
        if cfg.batch == 0
            || cfg.mu_lo.partial_cmp(&F::ZERO) != Some(core::cmp::Ordering::Greater)
            || cfg.mu_step.partial_cmp(&F::ZERO) != Some(core::cmp::Ordering::Greater)
        {
            return Err(BuildError::BadConfig);
        }
        let mu_y0 = mu_y0::<F, M>(params).ok_or(BuildError::NoFriction)?;
        let opts = Options {
            transient: true,
            mounted: side,
            moments: false,
            ..Options::default()
        };
        let cell = Cell {
            alpha: F::ZERO,
            kappa: F::ZERO,
            nll: F::ZERO,
            damp: F::from_f64(0.02),
            dmu: F::ZERO,
            info: F::ZERO,
        };
        Ok(Bank {
            fnomin: params.fnomin,
            lmux: params.lmux,
            lmuy: params.lmuy,
            prep: None,
            opts,
            mu_y0,
            cfg,
            cells: [cell; CELLS],
            acc: Acc::new(),
            pending: None,
            next: 0,
            chi2: [F::ZERO; CELLS],
            reseeds: 0,
            best: (F::ZERO, F::ZERO),
            kappa_prev: None,
            reseed_from: 0,
            scan: 0,
            active: [false; CELLS],
            n_active: 0,
            round: 0,
            last_t: None,
            kappa_lag: None,
            sigma_kappa_len: F::from_f64(0.3),
            evidence: false,
            held: None,
            last_mu: None,
            age_s: F::ZERO,
            age_m: F::ZERO,
            gap_m: F::ZERO,
            quiet_s: F::ZERO,
            quiet_m: F::ZERO,
            est: Estimate {
                mu: cfg.mu_prior,
                sigma: cfg.sigma_prior,
                mu_min: cfg.mu_lo,
                state: State::Fallback,
                change: false,
            },
            bad: 0,
            peak_ratio: F::ONE,
            floor: F::ZERO,
            floor_batches: 0,
            first: None,
            skip: None,
            fitted: 0,
            mixing: None,
            mix_waited: false,
            #[cfg(test)]
            trace: WorkTrace::default(),
        })
    }

    /// μy0 of the tyre: μ of its test surface.
    pub fn mu0(&self) -> F {
        self.mu_y0
    }

    /// The settings.
    pub fn config(&self) -> &Config<F> {
        &self.cfg
    }

    /// Samples refused so far (not finite, Fz ≤ 0, a timestamp that does not advance).
    pub fn bad_samples(&self) -> u32 {
        self.bad
    }

    /// Per cell: μ, α′, κ′, ℓ and the last batch's χ² (for diagnosis and the bench).
    pub fn cells(&self) -> [(F, F, F, F, F); CELLS] {
        let mut out = [(F::ZERO, F::ZERO, F::ZERO, F::ZERO, F::ZERO); CELLS];
        for (k, o) in out.iter_mut().enumerate() {
            if let (Some(c), Some(x)) = (self.cells.get(k), self.chi2.get(k)) {
                *o = (self.mu_c(k), c.alpha, c.kappa, c.nll, *x);
            }
        }
        out
    }

    /// The estimate of the last [`Bank::update`] (its `change` set only on that update).
    pub fn current(&self) -> Estimate<F> {
        self.est
    }

    /// Distance \[m\] rolled between the last identifiable estimate before the current one and
    /// the current one: on a change of surface ([`Estimate::change`]), about how far back the
    /// old surface's reading ended — where this wheel met the new one.
    pub fn identification_gap(&self) -> F {
        self.gap_m
    }

    /// The likelihood profile: ℓ per cell, the likeliest at 0 — what a wheel that follows this
    /// one on its track takes in with [`Bank::preview`] when it gets here.
    pub fn profile(&self) -> [F; CELLS] {
        let mut out = [F::ZERO; CELLS];
        for (o, c) in out.iter_mut().zip(self.cells.iter()) {
            *o = c.nll;
        }
        out
    }

    /// Takes in a reading of the surface this wheel is running onto: another wheel's
    /// [`Bank::profile`] where it ran over the same place ([`crate::mu::preview`]), with weight
    /// `p` (0 < p < 1: the probability that it applies here). The cells' likelihoods become the
    /// mixture (1 − p)·e^−ℓ + p·e^−ℓ′ — a switch of surface this wheel is told of rather than
    /// one it must find alone; its own batches then confirm or overrule it. A held value the
    /// reading excludes (ℓ′ above `hold_nll`) is dropped. The estimate follows at the end of the
    /// batch being fitted. A profile that is not finite and non-negative, or a weight outside
    /// (0, 1), is ignored.
    ///
    /// The mixture is not computed here: the reading waits for a slot in the next samples'
    /// work (it costs about half a cell's fit; [`Bank::update`] gives it a slot of its own, or
    /// the first it can spare without pushing the batch's last fits onto the sample that
    /// closes the next batch — within a few samples, all mixed before the batch's estimate).
    /// While one waits ([`Bank::previewing`]) a second one first mixes the waiting one in, at
    /// once: hand one per sample, as [`crate::mu::preview::Preview::rear`] does.
    pub fn preview<M: Backend<F>>(&mut self, profile: &[F; CELLS], p: F) {
        let ok = profile.iter().all(|x| x.is_finite() && *x >= F::ZERO);
        if ok && p > F::ZERO && p < F::ONE {
            self.mix_waiting::<M>();
            self.mixing = Some((*profile, p));
        }
    }

    /// Whether a reading from ahead ([`Bank::preview`]) waits to be mixed in.
    pub fn previewing(&self) -> bool {
        self.mixing.is_some()
    }

    /// The cell nearest μ `mu`.
    fn cell_of(&self, mu: F) -> usize {
        let c = &self.cfg;
        ((mu - c.mu_lo) / c.mu_step + F::HALF)
            .max(F::ZERO)
            .floor_index(CELLS - 1)
    }

    /// μ of cell `k`.
    fn mu_of(&self, k: usize) -> F {
        self.cfg.mu_lo + self.cfg.mu_step * F::from_index(k as u16)
    }

    /// Cell `k`'s surface: its centre plus its fitted offset.
    fn mu_c(&self, k: usize) -> F {
        self.mu_of(k) + self.cells.get(k).map_or(F::ZERO, |c| c.dmu)
    }

    /// Takes one sample of a wheel with tyre `params` (those the bank was built with) and
    /// returns the current estimate.
    pub fn update<M: Backend<F>>(&mut self, params: &Params<F>, s: &Sample<F>) -> Estimate<F> {
        self.est.change = false;
        #[cfg(test)]
        {
            self.trace = WorkTrace::default();
        }
        // Spread the pending batch's fit over this sample.
        self.work::<M>();
        let finite = F::all_finite(&[s.fz, s.fy, s.mz])
            && s.fx.is_none_or(|x| x.is_finite())
            && s.kappa.is_none_or(|x| x.is_finite())
            && s.vx.is_none_or(|x| x.is_finite())
            && s.gamma.is_none_or(|x| x.is_finite());
        let dt_us = match self.last_t {
            None => 0,
            Some(t0) => s.t_us.wrapping_sub(t0),
        };
        let advancing = self.last_t.is_none() || (dt_us > 0 && dt_us < 0x8000_0000);
        let fz0 = self.fnomin;
        if !finite
            || !advancing
            || s.fz <= self.cfg.fz_min_rel * fz0
            || s.fz > F::from_f64(10.0) * fz0
        {
            if !finite || !advancing || s.fz <= F::ZERO {
                self.bad = self.bad.saturating_add(1);
            }
            if advancing {
                self.last_t = Some(s.t_us);
            }
            return self.est;
        }
        self.last_t = Some(s.t_us);
        if dt_us > MAX_GAP_US {
            self.acc = Acc::new();
            self.kappa_lag = None;
            self.age::<M>(F::from_micros(dt_us), F::ZERO);
        }
        if let Some(vx) = s.vx {
            if vx.abs() < self.cfg.vx_min {
                self.acc = Acc::new();
                self.kappa_lag = None;
                return self.est;
            }
        }
        let dt = F::from_micros(dt_us.min(MAX_GAP_US));
        // κ′ from the measured κ: first-order lag over σκ/|Vx| (eq. 20 for a constant σκ).
        if let Some(k) = s.kappa {
            let lag = match (self.kappa_lag, s.vx) {
                (Some(prev), Some(vx)) => {
                    let x = dt * vx.abs() / self.sigma_kappa_len.max(F::from_f64(0.01));
                    prev + (F::ONE - M::exp(-x)) * (k - prev)
                }
                _ => k,
            };
            self.kappa_lag = Some(lag);
        } else {
            self.kappa_lag = None;
        }
        let a = &mut self.acc;
        a.n += 1;
        a.fz += s.fz;
        a.fy += s.fy;
        a.mz += s.mz;
        a.sq[1] += s.fy * s.fy;
        a.sq[2] += s.mz * s.mz;
        a.gamma += s.gamma.unwrap_or(self.cfg.gamma);
        if let Some(fx) = s.fx {
            a.n_fx += 1;
            a.fx += fx;
            a.sq[0] += fx * fx;
        }
        if let Some(k) = self.kappa_lag {
            a.n_kappa += 1;
            a.kappa += k;
            a.sq[3] += k * k;
        }
        if let Some(vx) = s.vx {
            a.n_vx += 1;
            a.vx += vx;
            a.dist += vx.abs() * dt;
        }
        a.us = a.us.saturating_add(dt_us.min(MAX_GAP_US));
        self.check_force::<M>();
        if self.acc.n >= self.cfg.batch {
            let b = self.batch_of::<M>(&self.acc);
            self.acc = Acc::new();
            if self.pending.is_some() {
                // The previous batch's fit did not finish (cannot happen with ⌈CELLS/batch⌉
                // cells per sample); finish it now rather than lose it.
                while self.pending.is_some() {
                    #[cfg(test)]
                    let before = self.trace.fits;
                    self.work::<M>();
                    #[cfg(test)]
                    {
                        self.trace.forced_fits += self.trace.fits - before;
                    }
                }
            }
            // Every cell's κ′ follows the measured κ′ from batch to batch (its own offset kept),
            // by the change shrunk towards 0 by the noise of a difference of two batch means
            // (d·d²/(d² + 2σκ²/n)): a change well above the noise (ABS) passes whole, the
            // noise of a steady κ is not fed into every cell's slip (it once moved a saturated
            // cell's κ′ by most of its value each batch, and the true surface lost to a wrong
            // one over a long steady turn on ice).
            if let (Some((k, _)), Some(prev)) = (b.kappa, self.kappa_prev) {
                let raw = k - prev;
                let v = F::TWO * self.cfg.sigma_kappa.sq() / F::from_index(self.cfg.batch);
                let d = if raw * raw + v > F::ZERO {
                    raw * raw * raw / (raw * raw + v)
                } else {
                    raw
                };
                for c in self.cells.iter_mut() {
                    c.kappa = clamp(c.kappa + d, F::ONE);
                }
            }
            self.kappa_prev = b.kappa.map(|(k, _)| k);
            let op = Operating {
                fz: b.fz,
                gamma: b.gamma,
                phit: F::ZERO,
                vx: b.vx,
                p: None,
            };
            self.select(&b);
            self.prep = if self.n_active > 0 {
                Prepared::new::<M>(params, &op, &self.opts).ok()
            } else {
                None
            };
            if let Some(pr) = &self.prep {
                let (sx, _) =
                    mf::sigma::sigma::<F, M>(params, pr.conditioned(), pr.k_xk(), pr.k_ya());
                if sx.is_finite() && sx > F::ZERO {
                    self.sigma_kappa_len = sx;
                }
            }
            if self.prep.is_some() {
                self.pending = Some(b);
            } else {
                // Nothing to fit (no excitation, or no contact): the evidence only ages.
                self.finish::<M>(&b);
            }
            self.next = 0;
            self.fitted = 0;
            self.reseeds = 0;
        }
        self.est
    }

    /// A force the reported μ cannot produce: checked on every sample against the running mean
    /// of the batch being collected (from its 3rd sample), so that a change to a grippier
    /// surface ends a stale identification within a few samples instead of after the batch and
    /// its fit. The mean |F|/Fz, less 3σ of its noise and the model error, above the bound of
    /// what the reported μ gives at this load (`peak_ratio`) makes the estimate
    /// not identifiable, drops the held value, and sets a lower bound of μ (`mu_min`, and the
    /// reported μ at least) for the next two batches.
    fn check_force<M: Backend<F>>(&mut self) {
        let a = &self.acc;
        if a.n < 3 || self.est.state == State::Fallback {
            return;
        }
        let c = &self.cfg;
        let n = F::from_index(a.n);
        let fz = a.fz / n;
        let fx = if a.n_fx == a.n { a.fx / n } else { F::ZERO };
        let fy = a.fy / n;
        if fz <= F::ZERO {
            return;
        }
        let f = M::sqrt(fx * fx + fy * fy) / fz;
        let noise = M::sqrt(F::TWO * c.sigma_f_rel.sq() / n + c.model_f_abs.sq());
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

    /// The means and σ of a full batch.
    fn batch_of<M: Backend<F>>(&self, a: &Acc<F>) -> Batch<F> {
        let n = F::from_index(a.n);
        let c = &self.cfg;
        let fz = a.fz / n;
        let sf_meas = c.sigma_f_rel * fz;
        let sqrt_n = M::sqrt(n);
        // The spread within the batch beyond the sensor noise: where the point moves along a bent
        // curve within the batch, the mean of the forces is not the force at the mean slips,
        // and the batch says correspondingly less (`spread` of that spread counts as error).
        let spread = |sum: F, sq: F, noise: F| {
            let v = sum / n;
            (sq / n - v * v - noise * noise).max(F::ZERO) * c.spread
        };
        let force = |sum: F, sq: F| {
            let v = sum / n;
            let s2 = (sf_meas / sqrt_n).sq()
                + (c.model_f_rel * v).sq()
                + (c.model_f_abs * fz).sq()
                + (c.sigma_f_rel * v / sqrt_n).sq()
                + spread(sum, sq, sf_meas);
            (v, M::sqrt(s2).max(F::from_f64(1e-3)))
        };
        let [sq_fx, sq_fy, sq_mz, sq_k] = a.sq;
        let mz = a.mz / n;
        let smz = M::sqrt(
            (c.sigma_mz / sqrt_n).sq()
                + (c.model_mz_rel * mz).sq()
                + c.model_mz_abs.sq()
                + spread(a.mz, sq_mz, c.sigma_mz),
        )
        .max(F::from_f64(1e-3));
        let fx = (a.n_fx == a.n).then(|| force(a.fx, sq_fx));
        let kappa = (a.n_kappa == a.n).then(|| {
            let k = a.kappa / n;
            (
                k,
                M::sqrt(
                    (c.sigma_kappa / sqrt_n).sq()
                        + c.model_kappa.sq()
                        + spread(a.kappa, sq_k, F::ZERO),
                )
                .max(F::from_f64(1e-4)),
            )
        });
        Batch {
            fz,
            gamma: a.gamma / n,
            vx: if a.n_vx == a.n {
                a.vx / n
            } else {
                F::from_f64(20.0)
            },
            fx,
            fy: force(a.fy, sq_fy),
            mz: (mz, smz),
            kappa,
            dt: F::from_micros(a.us),
            dist: a.dist,
        }
    }

    /// Chooses the cells to fit on batch `b`: none without excitation (the batch is no
    /// evidence, and the slips need not follow); otherwise every cell still in contention (ℓ
    /// below the switching cap), the best cell's neighbours, and every [`VISIT`]th of the
    /// others in turn (so that a surface excluded long ago is looked at again within [`VISIT`]
    /// batches; in between its last χ² stands). [`Bank::work`] adds the others when the
    /// likeliest cell does not explain the batch.
    fn select(&mut self, b: &Batch<F>) {
        let f = b.fy.0.abs().max(b.fx.map_or(F::ZERO, |(v, _)| v.abs()));
        let excited = f >= self.cfg.excitation * b.fz;
        self.round = (self.round + 1) % VISIT;
        let mut best = 0;
        let mut lo = F::from_f64(f64::MAX);
        for (k, c) in self.cells.iter().enumerate() {
            if c.nll < lo {
                lo = c.nll;
                best = k;
            }
        }
        let cap = self.cfg.switch_nll - F::HALF;
        self.n_active = 0;
        for (k, (a, c)) in self.active.iter_mut().zip(self.cells.iter()).enumerate() {
            *a = excited && (c.nll < cap || k.abs_diff(best) <= 2 || k % VISIT == self.round);
            self.n_active += usize::from(*a);
        }
        self.first = u8::try_from(best).ok().filter(|_| excited);
        self.skip = None;
    }

    /// Fits the next cells of the pending batch (and mixes in a waiting reading from ahead);
    /// finishes the batch after the last.
    ///
    /// A sample has `per` = ⌈active cells/batch⌉ slots of a cell's fit, at least [`SLOTS`]; the
    /// sample that closes a batch spends one on the load stage of the next, and the batch's
    /// finish takes one (a sample whose fits filled its slots leaves it to the next sample).
    /// The batch's first sample fits the likeliest cell before it plans the mixture: that
    /// cell's χ² may call for every cell (and ⌈CELLS/batch⌉ fits per sample). A waiting reading
    /// takes a free slot, or one of this sample's fits if the samples before the closing one
    /// have room for it; otherwise it waits for the next sample, and no longer (then it takes a
    /// slot of its own: with one sample per batch every sample closes one).
    fn work<M: Backend<F>>(&mut self) {
        let batch = usize::from(self.cfg.batch.max(1));
        let Some(b) = self.pending else {
            self.mix_waiting::<M>();
            return;
        };
        let mut per = self.n_active.div_ceil(batch).max(1);
        let mut fits = per;
        let mut done = 0;
        // The likeliest cell first: when it no longer explains the new batch, an identifiable
        // estimate is withdrawn on the batch's first fitted sample instead of after the last.
        if let Some(k8) = self.first.take() {
            let k = usize::from(k8);
            done += 1;
            self.fitted += 1;
            self.skip = Some(k8);
            let chi2 = self.fit_cell::<M>(k, &b);
            if let Some(slot) = self.chi2.get_mut(k) {
                *slot = chi2;
            }
            // (NaN counts as not explained.)
            let explains = chi2 <= self.cfg.chi2_identifiable;
            if self.est.state == State::Identifiable && !explains {
                self.est.state = State::NotIdentifiable;
                self.est.change = false;
            }
            // Nor are the other cells' last χ² evidence any longer (a cell out of contention
            // keeps its last one between visits, and its slips are as old): the road may have
            // changed, so every cell is fitted on this batch, as on a cold start — this sample
            // and the next ones take ⌈CELLS/batch⌉ fits each, so that the batch's fit ends
            // before the next batch closes (the mixture below plans with them).
            if !explains && self.n_active < CELLS {
                self.active = [true; CELLS];
                self.n_active = CELLS;
                per = CELLS.div_ceil(batch);
                fits = per;
                #[cfg(test)]
                {
                    self.trace.refit = true;
                }
            }
        }
        let slots = per.max(SLOTS);
        let mut mixed = false;
        if self.mixing.is_some() {
            let n = usize::from(self.acc.n);
            let closing = usize::from(n + 1 >= batch);
            // Cells still to fit (the likeliest, if fitted above, is counted in `done`).
            let left = self.n_active.saturating_sub(self.fitted);
            let planned = fits.saturating_sub(done).min(left);
            let room = slots > done + planned + closing;
            // One fit fewer now: the samples after this one, short of the closing one, take it.
            let later = batch.saturating_sub(n + 2);
            let spare = closing == 0 && done + planned > 1 && per * later > left - planned;
            // (A reading that waited a sample already is mixed in now, in a slot of its own:
            // with one sample per batch every sample closes one, and no later one has room.)
            if room || spare || self.mix_waited {
                if !room && spare {
                    fits = done + planned - 1;
                }
                #[cfg(test)]
                {
                    self.trace.own_slot |= !room && !spare;
                }
                mixed = true;
                self.mix_waiting::<M>();
            } else {
                self.mix_waited = true;
            }
        }
        while self.next < CELLS && done < fits {
            // Rotated order, so that the re-seeds of successive batches go to different cells.
            let k = (self.next + self.reseed_from) % CELLS;
            self.next += 1;
            if self.skip.map(usize::from) != Some(k) && self.active.get(k).copied().unwrap_or(false)
            {
                done += 1;
                self.fitted += 1;
                let chi2 = self.fit_cell::<M>(k, &b);
                if let Some(slot) = self.chi2.get_mut(k) {
                    *slot = chi2;
                }
            }
        }
        // The batch's finish takes a slot too: a sample whose fits (and mixture) filled its
        // slots leaves it to the next sample.
        let finish = self.next >= CELLS && done + usize::from(mixed) < slots;
        #[cfg(test)]
        {
            let load = done + usize::from(mixed);
            self.trace.fits += done;
            self.trace.load = self.trace.load.max(load);
            if finish {
                self.trace.load_finishing = self.trace.load_finishing.max(load);
            }
        }
        if finish {
            self.pending = None;
            self.reseed_from = (self.reseed_from + 7) % CELLS;
            self.finish::<M>(&b);
        }
    }

    /// One Gauss–Newton step of cell `k` on batch `b`; returns the batch's χ² after it.
    fn fit_cell<M: Backend<F>>(&mut self, k: usize, b: &Batch<F>) -> F {
        let Some(cell) = self.cells.get(k).copied() else {
            return F::ZERO;
        };
        let mu_c = self.mu_c(k);
        let lambda = mu_c / self.mu_y0;
        let Some(prep) = self.prep.as_ref() else {
            return F::ZERO;
        };
        // The friction stage of this surface: λμx = λμy = μ/μy0 times the file's (architecture.md).
        let (lx, ly) = (self.lmux * lambda, self.lmuy * lambda);
        let mu = prep.with_mu(lx, ly);
        // The residuals, their slopes in (α′, κ′) and — but for a cell held at the cap, out of
        // reach of the best, which keeps its offset — in the cell's surface μ: the friction
        // stage in dual numbers too (∂/∂μ = ∂/∂s / μ with both scalings times s).
        let fitted = if cell.nll < self.cfg.switch_nll && mu_c > F::from_f64(1e-3) {
            self.residuals_mu::<M>(lx, ly, mu_c, b, cell.alpha, cell.kappa)
                .map(|(r, j, jm)| (r, j, Some(jm)))
        } else {
            self.residuals::<M>(&mu, b, cell.alpha, cell.kappa, true)
                .map(|(r, j)| (r, j, None))
        };
        let Some((r0, jac, jmu)) = fitted else {
            return self.cfg.chi2_cap;
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
        // A trust region of radius `cell.damp` (in α′ and κ′ alike) around a barely damped
        // Gauss–Newton step: it grows while steps succeed and shrinks when one fails.
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
            let len = da.abs().max(dk.abs());
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
            let small = sa.abs().max(sk.abs()) <= F::from_f64(TRUST_STEP)
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
                        next.damp = (cell.damp * F::TWO).min(F::from_f64(0.2));
                    }
                    _ => {
                        next.damp = (len.min(cell.damp) * F::from_f64(0.25)).max(F::from_f64(1e-4));
                    }
                }
            }
        }
        // Then the surface within the cell: a step of its offset on the residuals the slip step
        // leaves (predicted by the slopes), within ±mu_step/2.
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
            let half = F::HALF * self.cfg.mu_step;
            let p0 = F::from_f64(OFFSET_PRIOR);
            let nd = clamp(
                cell.dmu + (jr - p0 * cell.dmu) / (cell.info + jj + p0),
                half,
            );
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
        let contending = cell.nll <= self.cfg.exclude_nll;
        if chi > self.cfg.reseed_chi2 && (self.reseeds < RESEEDS || contending) {
            if !contending {
                self.reseeds += 1;
            }
            // Alternately the best cell's slips, the brush model's slip angle and a point of a
            // scan of α′ on the side the lateral force gives (α′ > 0 gives Fy < 0, ISO-W), κ′ at
            // the measured value.
            let (sa, sk) = self.best;
            let sk = b.kappa.map_or(sk, |(k, _)| k);
            self.scan = self.scan.wrapping_add(1);
            let side = |a: F| if b.fy.0 > F::ZERO { -a } else { a };
            let pick = if contending { 1 } else { self.scan % 3 };
            let sa = match pick {
                0 => sa,
                1 => side(self.brush_alpha::<M>(k, b)),
                _ => {
                    let i = (self.scan / 3) % SCAN.len();
                    side(F::from_f64(SCAN.get(i).copied().unwrap_or(0.0)))
                }
            };
            if let Some((r2, _)) = self.residuals::<M>(&mu, b, sa, sk, false) {
                if norm2(&r2) < chi {
                    chi = norm2(&r2);
                    next.alpha = sa;
                    next.kappa = sk;
                    next.damp = F::from_f64(0.02);
                }
            }
        }
        if let Some(c) = self.cells.get_mut(k) {
            *c = next;
        }
        if chi.is_finite() {
            chi
        } else {
            self.cfg.chi2_cap
        }
    }

    /// |α′| at which the brush model (parabolic pressure, one friction coefficient) gives the
    /// batch's |Fy| on cell `k`'s surface: Fy = μFz·(1 − (1 − θ|α|)³), θ = Kyα/(3μFz), solved
    /// for |α|; the onset of full sliding (1/θ) when |Fy| ≥ μFz. A seed for a cell that lost
    /// its slips (e.g. deep in the saturated range after a fast reversal on a slippery road).
    fn brush_alpha<M: Backend<F>>(&self, k: usize, b: &Batch<F>) -> F {
        let cap = F::from_f64(SCAN.last().copied().unwrap_or(0.35));
        let mu_fz = self.mu_c(k) * b.fz;
        let kya = self.prep.as_ref().map_or(F::ZERO, |p| p.k_ya().abs());
        if !(mu_fz > F::ZERO && kya > F::ZERO) {
            return F::from_f64(SCAN.first().copied().unwrap_or(0.01));
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
            j = Self::jac_of(b, &d);
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
        Some((self.res_of(b, &m, kappa), j))
    }

    /// [`Bank::residuals`] with the slopes, at λμx* = `lx`, λμy* = `ly` (surface `mu_c`), and
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
        let j = Self::jac_of(b, &d.slip);
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
        Some((self.res_of(b, &m, kappa), j, jm))
    }

    /// The slopes of the normalised residuals' model part in (α′, κ′), from the slip stage's.
    fn jac_of(b: &Batch<F>, d: &Slopes<F>) -> [[F; 2]; 4] {
        let sx = b.fx.map_or(F::ZERO, |(_, s)| F::ONE / s);
        [
            [d.alpha.fx * sx, d.kappa.fx * sx],
            [d.alpha.fy / b.fy.1, d.kappa.fy / b.fy.1],
            [d.alpha.mz / b.mz.1, d.kappa.mz / b.mz.1],
            match (b.kappa, b.fx) {
                (Some((_, s)), _) => [F::ZERO, F::ONE / s],
                (None, None) => [F::ZERO, F::ONE / F::from_f64(0.01)],
                (None, Some(_)) => [F::ZERO, F::ZERO],
            },
        ]
    }

    fn res_of(&self, b: &Batch<F>, f: &[F; 3], kappa: F) -> [F; 4] {
        let rx = b.fx.map_or(F::ZERO, |(v, s)| (v - f[0]) / s);
        let ry = (b.fy.0 - f[1]) / b.fy.1;
        let rm = (b.mz.0 - f[2]) / b.mz.1;
        let rk = match (b.kappa, b.fx) {
            (Some((v, s)), _) => (v - kappa) / s,
            // Neither κ nor Fx: κ′ is pinned near free rolling.
            (None, None) => -kappa / F::from_f64(0.01),
            (None, Some(_)) => F::ZERO,
        };
        [rx, ry, rm, rk]
    }

    /// σ of an estimate `sigma` aged over `s` seconds and `m` metres without informative force
    /// (σ² grows by `age_q_time` per second and `age_q_distance` per metre).
    fn aged<M: Backend<F>>(&self, sigma: F, s: F, m: F) -> F {
        let c = &self.cfg;
        M::sqrt(sigma * sigma + c.age_q_time * s + c.age_q_distance * m)
    }

    /// Forgets evidence over `dt` seconds and `dist` metres.
    fn age<M: Backend<F>>(&mut self, dt: F, dist: F) {
        let x = dt / self.cfg.memory.max(F::from_f64(1e-3))
            + dist / self.cfg.memory_distance.max(F::from_f64(1e-3));
        let d = M::exp(-x);
        for c in self.cells.iter_mut() {
            c.nll *= d;
            c.info *= d;
        }
    }

    /// Folds a fitted batch into the likelihoods and updates the estimate.
    fn finish<M: Backend<F>>(&mut self, b: &Batch<F>) {
        self.age::<M>(b.dt, b.dist);
        self.age_s += b.dt;
        self.age_m += b.dist;
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
        // Excitation: a batch whose horizontal force is below `excitation`·Fz says nothing of
        // μ that the model can be trusted with (its free-rolling shifts SVy, Mzr scale with λμ
        // in the model; a real tyre's conicity, ply steer and the sensors' offsets do not).
        let f = b.fy.0.abs().max(b.fx.map_or(F::ZERO, |(v, _)| v.abs()));
        let excited = f >= self.cfg.excitation * b.fz;
        if excited && f >= self.cfg.inform_util * self.est.mu * b.fz {
            self.quiet_s = F::ZERO;
            self.quiet_m = F::ZERO;
        } else {
            self.quiet_s += b.dt;
            self.quiet_m += b.dist;
        }
        if excited && best <= self.cfg.chi2_explain {
            let cap = self.cfg.chi2_cap;
            // Each batch's excess χ² over the best, through a soft dead zone: differences a
            // model error could make in one batch (≲ `deadzone`) add little, so that evidence
            // accumulates from batches that discriminate, not from many that barely do.
            let dz = self.cfg.deadzone;
            for (c, x) in self.cells.iter_mut().zip(self.chi2.iter()) {
                let d = (*x - best).min(cap).max(F::ZERO);
                c.nll += F::HALF * d * d / (d + dz);
            }
            self.evidence = true;
        }
        // Normalise: the best cell at 0, none more than `switch_nll` above it.
        let mut lo = F::from_f64(f64::MAX);
        for c in self.cells.iter() {
            lo = lo.min(c.nll);
        }
        for c in self.cells.iter_mut() {
            c.nll = (c.nll - lo).min(self.cfg.switch_nll);
        }
        if self.floor_batches > 0 {
            self.floor_batches -= 1;
        } else {
            self.floor = F::ZERO;
        }
        self.estimate::<M>();
        if self.floor > F::ZERO && self.est.state != State::Fallback {
            self.est.mu = self.est.mu.max(self.floor);
            self.est.mu_min = self.est.mu_min.max(self.floor);
        }
        if let Some(pr) = &self.prep {
            let lambda = self.est.mu / self.mu_y0;
            let (px, py) = pr.with_mu(self.lmux * lambda, self.lmuy * lambda).f_peak();
            let r = M::sqrt(px * px + py * py) / (pr.fz() * self.est.mu);
            if r.is_finite() && r > F::ZERO {
                self.peak_ratio = r;
            }
        }
    }

    /// Mixes in the reading from ahead that waits, if any.
    fn mix_waiting<M: Backend<F>>(&mut self) {
        self.mix_waited = false;
        if let Some((pf, w)) = self.mixing.take() {
            self.mix::<M>(&pf, w);
        }
    }

    /// The mixture of the cells' likelihoods with a reading from ahead (see [`Bank::preview`]).
    fn mix<M: Backend<F>>(&mut self, pf: &[F; CELLS], p: F) {
        let mut lo = F::from_f64(f64::MAX);
        for c in self.cells.iter() {
            lo = lo.min(c.nll);
        }
        let (la, lb) = (M::ln(F::ONE - p), M::ln(p));
        for (c, l2) in self.cells.iter_mut().zip(pf.iter()) {
            let a = la - (c.nll - lo);
            let b = lb - *l2;
            let m = a.max(b);
            c.nll = -(m + M::ln(F::ONE + M::exp(-(a - b).abs())));
        }
        if let Some((h, _)) = self.held {
            if pf
                .get(self.cell_of(h))
                .is_some_and(|l| *l > self.cfg.hold_nll)
            {
                self.held = None;
            }
        }
        self.evidence = true;
    }

    /// The estimate from the cells' likelihoods.
    fn estimate<M: Backend<F>>(&mut self) {
        let c = self.cfg;
        let mut m = 0;
        let mut lo = F::from_f64(f64::MAX);
        for (k, cell) in self.cells.iter().enumerate() {
            if cell.nll < lo {
                lo = cell.nll;
                m = k;
            }
        }
        let nll = |k: usize| self.cells.get(k).map(|c| c.nll);
        let h = c.mu_step;
        // The best cell's own surface (its centre and fitted offset).
        let mu = self.mu_c(m);
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
        for (k, cell) in self.cells.iter().enumerate() {
            let mk = self.mu_c(k);
            let w = M::exp(-cell.nll);
            sw += w;
            s1 += w * mk;
            s2 += w * mk * mk;
            if cell.nll <= c.exclude_nll {
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
        let sigma = M::sqrt(var + c.sigma_floor.sq());
        // The reported surface must explain the latest batch (a cell that wins only because
        // the true one lost its slips is no identification).
        let fits = self.chi2.get(m).is_some_and(|x| *x <= c.chi2_identifiable);
        // Aged since the last batch that used enough of the reported surface to say something
        // of it.
        let aged_now = self.aged::<M>(sigma, self.quiet_s, self.quiet_m);
        let identifiable = self.evidence
            && excluded > 0
            && aged_now <= c.sigma_identifiable
            && !far_open
            && fits
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
                mu_min,
                state: State::Identifiable,
                change,
            };
            return;
        }
        // Not identifiable now. The last identifiable value is held — through a zero crossing
        // of the force, a stretch of straight running — while the evidence does not turn
        // against it (`hold_nll`), its σ growing with time and distance (`age_q_time`,
        // `age_q_distance`) until it reaches the prior's.
        if let Some((h, hs)) = self.held {
            let against = self
                .cells
                .get(self.cell_of(h))
                .is_some_and(|cell| cell.nll > c.hold_nll);
            let aged = self.aged::<M>(hs, self.age_s, self.age_m);
            // Aged to the prior's σ, it is still kept while the evidence excludes some surface
            // (the data say something, and not that the held value is wrong): a steady
            // state that two surfaces explain alike does not make the estimate jump between them.
            if !against && (aged < c.sigma_prior || excluded > 0) {
                self.est = Estimate {
                    mu: h,
                    sigma: aged.min(c.sigma_prior).max(sigma.min(c.sigma_prior)),
                    mu_min,
                    state: State::NotIdentifiable,
                    change: false,
                };
                return;
            }
            self.held = None;
        }
        self.est = if self.evidence && excluded > 0 {
            Estimate {
                mu,
                sigma,
                mu_min,
                state: State::NotIdentifiable,
                change: false,
            }
        } else {
            Estimate {
                mu: c.mu_prior,
                sigma: c.sigma_prior,
                mu_min: c.mu_lo,
                state: State::Fallback,
                change: false,
            }
        };
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

fn norm2<F: Float>(r: &[F; 4]) -> F {
    r.iter().fold(F::ZERO, |s, x| s + *x * *x)
}

fn clamp<F: Float>(x: F, lim: F) -> F {
    x.max(-lim).min(lim)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::math::Libm;
    use proptest::prelude::*;
    extern crate std;
    use std::vec::Vec;

    pub(crate) fn tyre() -> Params<f64> {
        let text = include_str!("../../host-tests/data/tyres/MagicFormula61_Parameters.tir");
        crate::tir::parse(text).unwrap().params
    }

    /// Samples of a wheel at slips (α(t), κ(t)) and speed `vx` (steady-state Magic Formula on
    /// surface μ, the transient option as the estimator evaluates it; κ measured without noise),
    /// 1 kHz, clock starting at `t0_us`.
    pub(crate) fn slips_stream(
        p: &Params<f64>,
        mu: f64,
        slips: impl Fn(f64) -> (f64, f64),
        vx: f64,
        n: usize,
        t0_us: u32,
    ) -> Vec<Sample<f64>> {
        let mu0 = mu_y0::<f64, Libm>(p).unwrap();
        let mut q = p.clone();
        q.lmux = p.lmux * mu / mu0;
        q.lmuy = p.lmuy * mu / mu0;
        let opts = Options {
            transient: true,
            moments: false,
            ..Options::default()
        };
        (0..n)
            .map(|i| {
                let (alpha, kappa) = slips(i as f64 * 1e-3);
                let input = Input {
                    fz: p.fnomin,
                    alpha,
                    kappa,
                    vx,
                    ..Input::default()
                };
                let o = mf::eval::<f64, Libm>(&q, &input, &opts).unwrap();
                Sample {
                    t_us: t0_us.wrapping_add((i as u32).wrapping_mul(1000)),
                    fz: p.fnomin,
                    fy: o.fy,
                    mz: o.mz,
                    fx: Some(o.fx),
                    kappa: Some(kappa),
                    vx: Some(vx),
                    gamma: Some(0.0),
                }
            })
            .collect()
    }

    /// A noisy slalom (α = 0.06 rad·sin(π·t), bench noise) on μ 1.0 for `n` samples, then `len`
    /// more on `mu`: a change of road at the phase `n` picks.
    fn slalom_onto(p: &Params<f64>, mu: f64, n: usize, len: usize) -> Vec<Sample<f64>> {
        let alpha = |t: f64| 0.06 * (core::f64::consts::TAU * 0.5 * t).sin();
        let mut s = stream(p, 1.0, alpha, n, 0);
        s.extend(stream(
            p,
            mu,
            |t| alpha(t + n as f64 * 1e-3),
            len,
            n as u32 * 1000,
        ));
        noisy(s)
    }

    /// Samples of [`onto_grippier`] on μ 0.3, before the change.
    const ONTO_GRIPPIER: usize = 1500;

    /// A wheel identified on μ 0.3 in a turn (α ramped to 0.1 rad), then 0.5 s on μ 1.0 at α
    /// 0.1 rad: |Fy| near 1.0·Fz, a force the old estimate cannot produce.
    fn onto_grippier(p: &Params<f64>) -> Vec<Sample<f64>> {
        let n = ONTO_GRIPPIER;
        let mut s = stream(p, 0.3, |t| 0.1 * (t / 0.5).min(1.0), n, 0);
        s.extend(stream(p, 1.0, |_| 0.1, 500, n as u32 * 1000));
        s
    }

    /// Samples of a freely rolling wheel (κ 0) at slip angle α(t), 20 m/s.
    fn stream(
        p: &Params<f64>,
        mu: f64,
        alpha: impl Fn(f64) -> f64,
        n: usize,
        t0_us: u32,
    ) -> Vec<Sample<f64>> {
        slips_stream(p, mu, |t| (alpha(t), 0.0), 20.0, n, t0_us)
    }

    /// On a surface midway between two cells' centres, held near its limit, no far surface is
    /// reported identifiable (docs/estimator.md, "Off the grid"; `gough mu bench --mu-shift
    /// 0.025`). With fixed hypotheses (before the fitted offsets) μ 0.125 was: 36 of 5,000
    /// samples identifiable and off by more than 0.2.
    #[test]
    fn a_surface_between_two_hypotheses_is_never_read_as_a_far_one() {
        let p = tyre();
        let mut worst = std::vec::Vec::new();
        for mu in [0.125, 0.325, 0.525] {
            let peak = -0.08 * mu / 0.525;
            let s = noisy(stream(&p, mu, |t| peak * (t / 1.0).min(1.0), 5000, 0));
            let est = run(&p, &s);
            let ident = |e: &&Estimate<f64>| e.state == State::Identifiable;
            let off = est
                .iter()
                .filter(ident)
                .filter(|e| (e.mu - mu).abs() > 0.2)
                .count();
            let near = est
                .iter()
                .filter(ident)
                .filter(|e| (e.mu - mu).abs() <= 0.05)
                .count();
            worst.push((mu, off, near));
        }
        // (μ, identifiable and off by > 0.2, identifiable within ±0.05; samples of 5,000)
        std::println!("{worst:?}");
        // Never confidently wrong, and read on each.
        assert!(
            worst.iter().all(|&(_, off, near)| off == 0 && near > 500),
            "{worst:?}"
        );
    }

    fn run(p: &Params<f64>, s: &[Sample<f64>]) -> Vec<Estimate<f64>> {
        let mut e = Bank::new::<Libm>(p, None, Config::default()).unwrap();
        s.iter().map(|x| e.update::<Libm>(p, x)).collect()
    }

    /// Adds the bench's sensor noise (forces 1 % of Fz, Mz 2 N·m, κ 0.005 rms; a fixed LCG).
    pub(crate) fn noisy(mut s: Vec<Sample<f64>>) -> Vec<Sample<f64>> {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut gauss = move || {
            // Sum of 12 uniforms − 6: unit variance, deterministic.
            (0..12)
                .map(|_| {
                    x = x
                        .wrapping_mul(6_364_136_223_846_793_005)
                        .wrapping_add(1_442_695_040_888_963_407);
                    (x >> 11) as f64 / (1u64 << 53) as f64
                })
                .sum::<f64>()
                - 6.0
        };
        for r in s.iter_mut() {
            let sf = 0.01 * r.fz;
            r.fy += sf * gauss();
            r.mz += 2.0 * gauss();
            r.fx = r.fx.map(|v| v + sf * gauss());
            r.fz += sf * gauss();
            r.kappa = r.kappa.map(|v| v + 0.005 * gauss());
        }
        s
    }

    #[test]
    fn straight_running_is_never_identifiable() {
        let p = tyre();
        // With the sensors' noise: nothing to read.
        for mu in [0.3, 1.0] {
            let est = run(&p, &noisy(stream(&p, mu, |_| 0.0, 3000, 0)));
            assert!(
                est.iter().all(|e| e.state != State::Identifiable),
                "μ {mu}: {:?}",
                est.last()
            );
        }
        // Without noise, the free-rolling shifts (SVy, Mzr) carry a little of μ: whatever is
        // reported identifiable is right.
        let est = run(&p, &stream(&p, 0.3, |_| 0.0, 3000, 0));
        for e in &est {
            if e.state == State::Identifiable {
                assert!((e.mu - 0.3).abs() <= 0.1, "{e:?}");
            }
        }
    }

    #[test]
    fn a_hard_turn_on_a_wet_road_reads_its_friction() {
        let p = tyre();
        // α ramps to 0.1 rad over 0.5 s: beyond the peak on μ 0.5.
        let est = run(&p, &stream(&p, 0.5, |t| 0.1 * (t / 0.5).min(1.0), 1500, 0));
        let last = est.last().unwrap();
        assert_eq!(last.state, State::Identifiable, "{last:?}");
        assert!((last.mu - 0.5).abs() < 0.05, "{last:?}");
        // Never identifiable with a wrong value on the way.
        for e in &est {
            if e.state == State::Identifiable {
                assert!((e.mu - 0.5).abs() <= 0.1, "{e:?}");
            }
        }
    }

    /// A reading from ahead waits at most one sample for a slot of the rear's work (`work`),
    /// wherever in a batch's fit it arrives; a second one arriving while one waits mixes that
    /// one in first.
    #[test]
    fn a_reading_from_ahead_is_mixed_in_within_a_sample() {
        let p = tyre();
        let s = stream(&p, 0.5, |t| 0.1 * (t / 0.5).min(1.0), 1500, 0);
        let mut b = Bank::new::<Libm>(&p, None, Config::default()).unwrap();
        let profile: [f64; CELLS] = core::array::from_fn(|k| 0.5 * (k as f64 - 4.0).powi(2));
        let mut waits = [0usize; 2];
        for (i, x) in s.iter().enumerate() {
            if i >= 300 {
                let mut r = b.clone();
                r.preview::<Libm>(&profile, 0.9);
                assert!(r.previewing());
                let n = s[i..].iter().take_while(|y| {
                    r.update::<Libm>(&p, y);
                    r.previewing()
                });
                let n = n.count();
                assert!(n <= 1, "sample {i}: waited {n} samples");
                waits[n] += 1;
                // The first is mixed in by the second's arrival (the likelihoods move at once),
                // the second waits.
                let mut r = b.clone();
                r.preview::<Libm>(&profile, 0.9);
                assert_eq!(r.profile(), b.profile());
                r.preview::<Libm>(&profile, 0.5);
                assert_ne!(r.profile(), b.profile(), "sample {i}");
                assert!(r.previewing());
            }
            b.update::<Libm>(&p, x);
        }
        // Mostly at once; a wait only on the samples that close a batch with fits to do.
        assert!(waits[0] > 10 * waits[1], "{waits:?}");
        // One sample per batch (the 100 Hz configuration): every sample closes a batch and
        // fits every cell in contention, and a reading still waits one sample at most.
        let cfg = Config {
            batch: 1,
            ..Config::default()
        };
        let mut b = Bank::new::<Libm>(&p, None, cfg).unwrap();
        for (i, x) in s.iter().enumerate().step_by(10) {
            if i >= 300 && i % 50 == 0 {
                let mut r = b.clone();
                r.preview::<Libm>(&profile, 0.9);
                r.update::<Libm>(&p, x);
                r.update::<Libm>(&p, x);
                assert!(!r.previewing(), "sample {i}");
            }
            b.update::<Libm>(&p, x);
        }
    }

    /// A slalom on μ 1.0 (cells far from it excluded, fitted on every [`VISIT`]th batch only),
    /// then the road drops to 0.3, at eight phases of the slalom: the batch the likeliest cell
    /// no longer explains is fitted on every cell (the first batch on the new road), and the
    /// new surface is read within 80 ms at every phase (55–78 ms). Without the refit (each far
    /// cell's last χ² and slips standing until its visit) it took 89–95 ms at three of them.
    #[test]
    fn a_drop_in_friction_refits_every_cell_at_once() {
        let p = tyre();
        for n in [2650usize, 2700, 2750, 2800, 2850, 2900, 3100, 3300] {
            let s = slalom_onto(&p, 0.3, n, 900);
            let mut b = Bank::new::<Libm>(&p, None, Config::default()).unwrap();
            let (mut refit, mut read) = (None, None);
            for (i, x) in s.iter().enumerate() {
                let before = b.n_active;
                let e = b.update::<Libm>(&p, x);
                if i < n {
                    continue;
                }
                if refit.is_none() && before < CELLS && b.n_active == CELLS {
                    refit = Some(i - n);
                }
                if read.is_none() && e.state == State::Identifiable && (e.mu - 0.3).abs() <= 0.1 {
                    read = Some(i - n);
                }
            }
            assert!(refit.is_some_and(|k| k < 20), "change at {n} ms: {refit:?}");
            assert!(read.is_some_and(|k| k <= 80), "change at {n} ms: {read:?}");
        }
    }

    /// Issue 39's dry → ice step, at nine phases of a slalom (the step at full lateral force,
    /// on the way down, at a zero crossing, on the way up): the ice (μ 0.1) is read —
    /// identifiable within ±0.1, and within ±0.1 from then on — within 150 ms of meeting it at
    /// every phase (69–138 ms; at the zero crossing the slowest), and that first identification
    /// carries the change flag; no flag on the dry road before.
    #[test]
    fn a_dry_to_ice_step_is_read_and_flagged_within_150_ms() {
        let p = tyre();
        for n in [2650usize, 2700, 2750, 2800, 2850, 2900, 3000, 3100, 3300] {
            let est = run(&p, &slalom_onto(&p, 0.1, n, 900));
            assert!(est[..n].iter().all(|e| !e.change), "step at {n} ms");
            let read = est[n..]
                .iter()
                .position(|e| e.state == State::Identifiable && (e.mu - 0.1).abs() <= 0.1);
            assert!(read.is_some_and(|k| k <= 150), "step at {n} ms: {read:?}");
            let k = read.unwrap_or(0);
            assert!(est[n + k].change, "step at {n} ms: {:?}", est[n + k]);
            assert!(
                est[n + k..].iter().all(|e| (e.mu - 0.1).abs() <= 0.1),
                "step at {n} ms"
            );
        }
    }

    /// The change flag compares with the last identifiable value, also when the value held
    /// after it was dropped on the way — by the evidence turning against it, or here by a
    /// force it cannot produce (μ 0.3 → 1.0 at α 0.1 rad, as in the test below): the first
    /// identification of the new road is flagged, nothing before it. Compared with the held
    /// value, the flag was lost (and the preview handed the rear wheel nothing; `gough mu
    /// bench` counts 25 change flags per seed with this, each a change of road; a scratch
    /// listing found 8–10 before).
    #[test]
    fn a_change_is_flagged_also_when_the_held_value_was_dropped() {
        let p = tyre();
        let n = ONTO_GRIPPIER;
        let est = run(&p, &onto_grippier(&p));
        assert!(est[..n].iter().all(|e| !e.change));
        // The first identification that is not the old road's.
        let first = est[n..]
            .iter()
            .position(|e| e.state == State::Identifiable && (e.mu - 0.3).abs() > 0.1)
            .map(|k| est[n + k]);
        assert!(
            first.is_some_and(|e| e.change && (e.mu - 1.0).abs() <= 0.1),
            "{first:?}"
        );
        assert_eq!(est.iter().filter(|e| e.change).count(), 1);
    }

    /// The per-sample budget's structure, on streams that make every kind of sample: a slalom
    /// on μ 1.0 onto 0.3 (the refit of every cell) with sensor noise, the rear's own profile
    /// handed to it every 7th sample (the bench's stress of the preview). With batches of 2 to
    /// 10 samples no sample fits more than ⌈CELLS/batch⌉ cells (at least [`SLOTS`]) counting a
    /// mixture as one — but for a reading that already waited a sample, which takes a slot of
    /// its own (never at 1 kHz's batches of 10) —, a sample that finishes a batch fits fewer
    /// than that, and no batch's fit is left for the next batch's close; with one sample per
    /// batch (100 Hz) the last holds too.
    #[test]
    fn no_sample_takes_more_than_its_slots() {
        let p = tyre();
        let n = 2850;
        let s = slalom_onto(&p, 0.3, n, 1500);
        for batch in [10u16, 7, 5, 3, 2, 1] {
            let cfg = Config {
                batch,
                ..Config::default()
            };
            let slots = CELLS.div_ceil(usize::from(batch)).max(SLOTS);
            let mut b = Bank::new::<Libm>(&p, None, cfg).unwrap();
            let (mut refits, mut finishing, mut full) = (0, 0, 0);
            for (i, x) in s.iter().enumerate() {
                if i % 7 == 0 {
                    let profile = b.profile();
                    b.preview::<Libm>(&profile, 0.9);
                }
                b.update::<Libm>(&p, x);
                let t = b.trace;
                refits += usize::from(t.refit);
                assert_eq!(t.forced_fits, 0, "batch {batch}, sample {i}: {t:?}");
                if batch > 1 {
                    let own = usize::from(t.own_slot);
                    assert!(batch < 10 || own == 0, "sample {i}: {t:?}");
                    assert!(t.load <= slots + own, "batch {batch}, sample {i}: {t:?}");
                    assert!(t.load_finishing < slots, "batch {batch}, sample {i}: {t:?}");
                    full += usize::from(t.load == slots);
                    finishing += usize::from(t.load_finishing > 0);
                }
            }
            assert!(refits > 0, "batch {batch}: the stream refits every cell");
            if batch > 1 {
                // The stream reaches both limits (at batch 2 on about ten samples, 9 to 12
                // as the gates change; hundreds at the larger batches).
                assert!(
                    full >= 5 && finishing >= 5,
                    "batch {batch}: {full} {finishing}"
                );
            }
        }
    }

    #[test]
    fn a_force_the_estimate_cannot_produce_ends_the_identification_at_once() {
        let p = tyre();
        // Identified on μ 0.3, then the wheel runs onto μ 1.0 at α 0.1 rad: |Fy| near 1.0·Fz.
        let n = ONTO_GRIPPIER;
        let est = run(&p, &onto_grippier(&p));
        let before = est[n - 1];
        assert_eq!(before.state, State::Identifiable, "{before:?}");
        assert!((before.mu - 0.3).abs() < 0.05, "{before:?}");
        // From the batch's 3rd sample on the new surface: not the old value, not identifiable,
        // and μ bounded from below — a batch and its fit (20 samples) would have been too late.
        for (i, e) in est.iter().enumerate().skip(n + 3).take(30) {
            assert_ne!(e.state, State::Identifiable, "{i}: {e:?}");
            assert!(e.mu >= 0.5 && e.mu_min >= 0.5, "{i}: {e:?}");
        }
        // and then the new surface is read.
        let last = est.last().unwrap();
        assert_eq!(last.state, State::Identifiable, "{last:?}");
        assert!((last.mu - 1.0).abs() < 0.05, "{last:?}");
    }

    #[test]
    fn an_identification_ages_while_the_force_says_nothing_of_the_surface() {
        let p = tyre();
        // Identified on μ 1.0 in a hard turn (α 0.1 rad), then 0.6 s at α 0.005 rad (|Fy| about
        // 0.1·Fz: the linear range, every surface above it explains it alike), then α 0.1 again.
        let alpha = |t: f64| {
            if t < 1.5 {
                0.1 * (t / 0.5).min(1.0)
            } else if t < 2.1 {
                0.005
            } else {
                0.1
            }
        };
        let est = run(&p, &noisy(stream(&p, 1.0, alpha, 2600, 0)));
        let at = |t: f64| est[(t * 1000.0) as usize];
        assert_eq!(at(1.499).state, State::Identifiable, "{:?}", at(1.499));
        // Within 0.25 s of the low force (at 20 m/s, σ² grows by 0.02 per second from the last
        // batch that used 0.3 of the surface; from about 0.015 it passes 0.1/1.96 in ~0.12 s):
        // no longer identifiable, the value held.
        for (i, e) in est.iter().enumerate().take(2100).skip(1750) {
            assert_ne!(e.state, State::Identifiable, "{i}: {e:?}");
            assert!((e.mu - 1.0).abs() < 0.1, "{i}: {e:?}");
        }
        // Back in the turn: identifiable again, on the same value.
        let last = est.last().unwrap();
        assert_eq!(last.state, State::Identifiable, "{last:?}");
        assert!((last.mu - 1.0).abs() < 0.05, "{last:?}");
        // Without the rule (`inform_util` 0) the identification stood through the quiet stretch.
        let mut e = Bank::new::<Libm>(
            &p,
            None,
            Config {
                inform_util: 0.0,
                ..Config::default()
            },
        )
        .unwrap();
        let old: Vec<_> = noisy(stream(&p, 1.0, alpha, 2600, 0))
            .iter()
            .map(|x| e.update::<Libm>(&p, x))
            .collect();
        assert_eq!(old[2099].state, State::Identifiable, "{:?}", old[2099]);
    }

    /// A turn under drive at 15 m/s: slips α, κ ramped in over 1 s and held, measured with the
    /// bench's noise.
    fn steady(p: &Params<f64>, mu: f64, alpha: f64, kappa: f64, n: usize) -> Vec<Sample<f64>> {
        let ramp = |t: f64| t.min(1.0);
        noisy(slips_stream(
            p,
            mu,
            |t| (alpha * ramp(t), kappa * ramp(t)),
            15.0,
            n,
            0,
        ))
    }

    #[test]
    fn a_long_steady_turn_on_ice_is_read_and_never_as_another_surface() {
        let p = tyre();
        // α −0.02 rad, κ 0.01 under drive on μ 0.1 for 40 s, the measured κ with 0.005 rms of
        // noise (half the slip): never identifiable as another surface.
        let st = steady(&p, 0.1, -0.02, 0.01, 40_000);
        let est = run(&p, &st);
        let wrong = est
            .iter()
            .filter(|e| e.state == State::Identifiable && (e.mu - 0.1).abs() > 0.1)
            .count();
        let ident = est
            .iter()
            .filter(|e| e.state == State::Identifiable)
            .count();
        // Read, and held, on its own surface: the resultant exceeds μx·Fz and μy·Fz here (the
        // vertical shift SVx scales with λμ′, not λμ*), which a force check against the friction
        // ellipse's axes took for a grippier surface and kept the estimate from ever settling.
        assert!(
            ident > 30_000,
            "identifiable on {ident} samples; {:?}",
            est.last()
        );
        assert_eq!(wrong, 0, "{:?}", est.last());
    }

    #[test]
    fn the_clock_origin_does_not_matter() {
        let p = tyre();
        let a = |t: f64| 0.08 * (t / 0.4).min(1.0);
        let e0 = run(&p, &stream(&p, 0.7, a, 1200, 0));
        // 10⁶ s later, and across the u32 wrap.
        let e1 = run(
            &p,
            &stream(
                &p,
                0.7,
                a,
                1200,
                (1_000_000_000_000u64 % (1u64 << 32)) as u32,
            ),
        );
        let e2 = run(&p, &stream(&p, 0.7, a, 1200, u32::MAX - 500_000));
        assert_eq!(e0, e1);
        assert_eq!(e0, e2);
    }

    #[test]
    fn bad_samples_are_held_and_counted() {
        let p = tyre();
        let mut s = stream(&p, 0.5, |t| 0.1 * (t / 0.5).min(1.0), 1500, 0);
        let mut e = Bank::new::<Libm>(&p, None, Config::default()).unwrap();
        let mut last = None;
        for (i, x) in s.iter_mut().enumerate() {
            if i % 97 == 0 {
                x.fy = f64::NAN;
            }
            if i % 89 == 0 {
                x.fz = -5.0;
            }
            if i % 83 == 0 {
                x.mz = f64::INFINITY;
            }
            let est = e.update::<Libm>(&p, x);
            assert!(est.mu.is_finite() && est.sigma.is_finite());
            last = Some(est);
        }
        assert!(e.bad_samples() >= 40, "{}", e.bad_samples());
        let last = last.unwrap();
        assert!((last.mu - 0.5).abs() < 0.05, "{last:?}");
    }

    #[test]
    fn a_config_without_a_grid_or_a_batch_is_refused() {
        let p = tyre();
        for cfg in [
            Config {
                batch: 0,
                ..Config::default()
            },
            Config {
                mu_step: 0.0,
                ..Config::default()
            },
            Config {
                mu_lo: f64::NAN,
                ..Config::default()
            },
        ] {
            assert_eq!(
                Bank::new::<Libm>(&p, None, cfg).err(),
                Some(BuildError::BadConfig)
            );
        }
        let mut flat = p.clone();
        flat.lmuy = 0.0;
        assert_eq!(
            Bank::new::<Libm>(&flat, None, Config::default()).err(),
            Some(BuildError::NoFriction)
        );
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]
        #[test]
        fn any_finite_stream_gives_finite_estimates(
            rows in proptest::collection::vec(
                (0u32..3000, -2e4f64..2e4, -1e4f64..1e4, -500f64..500.0, -1e4f64..1e4, -1.5f64..1.5, -60f64..60.0, -0.3f64..0.3),
                1..400,
            )
        ) {
            let p = tyre();
            let mut e = Bank::new::<Libm>(&p, Some(Side::Right), Config::default()).unwrap();
            let mut t = 0u32;
            for (dt, fz, fy, mz, fx, k, vx, g) in rows {
                t = t.wrapping_add(dt);
                let est = e.update::<Libm>(&p, &Sample { t_us: t, fz, fy, mz, fx: Some(fx), kappa: Some(k), vx: Some(vx), gamma: Some(g) });
                prop_assert!(est.mu.is_finite() && est.sigma.is_finite() && est.sigma >= 0.0);
                prop_assert!(est.mu_min.is_finite());
            }
        }
    }
}
