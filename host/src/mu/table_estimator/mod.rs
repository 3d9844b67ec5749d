//! The previous road-friction estimator, on tabulated Gough curves: μ from measured Fy, Mz and
//! Fz, without the slip angle. The product (the core's `gough::wheel`, the firmware, the C API)
//! runs the exact-model bank `gough::mu::bank`; this one is kept as a peer in the host's bench
//! (`gough mu bench`'s "gough" column, `gough mu estimate --method gough`, `gough mu map`, the
//! gap diagnosis's μ column). It moved here from the core's `gough::mu` in issue 39, unchanged.
//!
//! The paper: "When such a collection of curves \[the Gough plot: Fy against Mz, which spread in
//! radial direction with the friction coefficient\] is available ..., the friction coefficient may
//! be estimated when on the road the side force and the aligning torque are measured and the
//! value of the vertical load is available as well" (ref. \[2\], Pasterkamp & Pacejka 1994). The
//! pneumatic trail collapses long before the side force saturates, so the point's place on its
//! curve — and with it μ — is known early, at moderate utilisation.
//!
//! ## Per sample (bounded cost, no allocation, no loop without a constant bound)
//! 1. Gates: finite input, |Vx| ≥ `vx_min`, Fz ≥ `fz_min_rel`·Fz0, |Fy| ≥ `fy_min_rel`·Fz,
//!    |Fy| ≥ `fy_share_min`·|F| (lateral excitation must dominate).
//!    Inputs are low-pass filtered (time constant `lowpass_tau`) against sensor noise.
//! 2. Combined slip: the moment of Fx about the contact centre, s·Fx with the arm s of eq. (17)
//!    / (73) (`mf::combined::Arm`, the core's own formula), is removed from Mz; the force used
//!    for μ is the horizontal resultant on the friction ellipse, √((Fx·μy0/μx0)² + Fy²).
//! 3. The effective trail τ = −Mz/Fy is inverted through the model's tabulated Gough curves
//!    ([`table::GoughTable`], on four surfaces λμ) at the bracketing load and camber nodes:
//!    the trail ratio τ/τ0 is placed at one position along the curves' grids, which are
//!    aligned where each curve's trail collapses ([`table::ANCHOR_SHARE`]), and f = |Fy|/Fz
//!    read there is interpolated bilinearly; λμ = |F|/(Fz·f) about each surface, the estimate
//!    where it crosses its own surface. μ = λμ·μy0 (architecture: μ on the file's surface
//!    scale).
//! 4. Its variance from the measurement noise (σMz, σFy) through the local slopes of the table.
//!    The sample is *identifiable* when the trail has dropped by ≥ `trail_drop_min` and the
//!    model-induced σ of μ is ≤ `sigma_max` (measurement noise is left to the filter); otherwise the estimator says so instead of
//!    guessing ([`State::NotIdentifiable`]) and holds its last estimate with a growing σ.
//! 5. A scalar Kalman filter (random walk, intensity `q`) fuses identifiable readings; innovations
//!    beyond `gate` σ are outliers and rejected, and `change_count` consecutive outliers of one
//!    sign, none more than `run_gap` after the previous one, declare a change of surface
//!    (dry → ice): the filter restarts from the new evidence.
//!    Isolated outliers (noise) never move the estimate.
//!
//! Steps 1–4 and the ambiguity test's cheap checks run on the sample that takes a reading; the
//! ambiguity test's trail look-ups and step 5 on the next sample, which takes no reading of its
//! own (see [`MuEstimator::update`]): a reading's work is spread over two samples, so that no
//! sample pays for all of it.
//!
//! ## Leaves out
//! Pure longitudinal excitation (straight braking, no Fy): the trail carries no information
//! then; that is the slip-slope method's domain ([`super::peers::SlipSlope`]). Turn slip.

pub mod brush;
pub mod table;

use brush::Brush;
use gough::math::{Backend, Float};
use gough::mf::{combined::Arm, Params, Side};
pub use table::{GoughTable, Model, CAMBER_NODES, LAMBDA_NODES, LOAD_NODES};

/// Estimator settings. SI units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Config<F> {
    /// Camber of the wheel \[rad\] used when a sample carries none (its static camber).
    pub gamma: F,
    /// Aligning-torque sensor noise, rms \[N·m\].
    pub sigma_mz: F,
    /// Lateral-force sensor noise, rms, as a fraction of Fz \[-\].
    pub sigma_fy_rel: F,
    /// Below this |Vx| \[m/s\] no sample is used.
    pub vx_min: F,
    /// Below this Fz/Fz0 no sample is used.
    pub fz_min_rel: F,
    /// Below this |Fy|/Fz no sample is used (τ = −Mz/Fy undefined).
    pub fy_min_rel: F,
    /// Below this share |Fy|/|F| of the horizontal force no sample is used: when Fx dominates
    /// (straight braking) the trail says little and the combined-slip approximation is poor.
    pub fy_share_min: F,
    /// Minimum trail drop 1 − τ/τ0 for a sample to count as identifiable.
    pub trail_drop_min: F,
    /// Minimum absolute trail drop τ0 − τ \[m\]: where the small-slip trail itself is short
    /// (low load, strong camber), a relative drop is within the table's interpolation error.
    pub trail_drop_abs_min: F,
    /// Maximum model-induced σ of one sample's μ \[-\] for it to count as identifiable (the
    /// measurement noise is averaged by the filter; the model's error is not).
    pub sigma_max: F,
    /// Model uncertainty of the trail, as a fraction of τ0 (table interpolation between loads,
    /// the shifts that make λμ-scaling not exactly radial): added to the measurement variance,
    /// so that where the inversion is ill-conditioned the sample is not identifiable.
    pub trail_model_rel: F,
    /// Model uncertainty of the Fx moment s·Fx removed from Mz (eq. (17)), as a fraction of it:
    /// the arm s is a one-line fit and the combined-slip torque is the model's least certain
    /// part, so readings dominated by it (hard braking with camber) are not identifiable.
    pub arm_model_rel: F,
    /// Model uncertainty of the trail under combined slip, as a fraction of τ0 per unit share
    /// |Fx|/|F| of the longitudinal force: the table is pure side slip, and with Fx the
    /// residual torque Mzr no longer stands to Fy as it does there (Fy shrinks by Gyκ, Mzr
    /// by the equivalent slip of (A54)), so the trail of a braked wheel reads too short.
    pub combined_model_rel: F,
    /// Model uncertainty of λμ under combined slip, as a fraction of it per unit share
    /// |Fx|/|F|: the resultant of the combined-slip forces (weighting functions G, eq. (12))
    /// falls short of the pure-slip force at the equivalent slip by up to ~10 % at equal shares,
    /// which the friction ellipse does not capture.
    pub combined_force_rel: F,
    /// Model uncertainty of the residual torque Mzr (conicity, camber torque, the camber
    /// interpolation between table nodes), as a fraction of Fz·R0 \[-\]: it enters the trail as
    /// σ/|Fy|, so small lateral forces — where the residual torque, not the trail, shapes the
    /// Gough curve — are not identifiable.
    pub mzr_model_rel: F,
    /// Random-walk intensity of λμ \[1/s\] (variance growth per second).
    pub q: F,
    /// Outlier gate in standard deviations of the innovation.
    pub gate: F,
    /// Largest σ of μ the outlier gate grants the estimate \[-\]: while it is held, its σ grows
    /// (the road may change unseen), but a single reading must not move it further than this
    /// allows — a larger jump needs `change_count` consistent readings (change detection).
    pub gate_sigma_max: F,
    /// Smallest step of μ reported as a change of surface \[-\] (smaller re-alignments after
    /// `change_count` outliers move the estimate without the flag).
    pub change_min: F,
    /// Consecutive one-sided outliers (readings) that declare a change of surface. A reading
    /// takes two samples ([`MuEstimator::update`]): the default 30 is about 60 ms at 1 kHz.
    pub change_count: u16,
    /// Longest time \[s\] between two outliers of one run: a run interrupted by a longer stretch
    /// of uninformative samples (straight running, a hold) starts again, so readings from
    /// before and after it never add up to a change.
    pub run_gap: F,
    /// Mutually consistent identifiable readings needed before the first estimate is reported
    /// (a short burst of readings in a transient never becomes an estimate). The default 13
    /// is about 26 ms at 1 kHz (a reading takes two samples).
    pub init_count: u16,
    /// Prior μ reported before any identifiable sample, and when the estimate has aged out.
    pub mu_prior: F,
    /// σ of the prior; an estimate whose σ grows beyond it falls back to the prior.
    pub sigma_prior: F,
    /// Low-pass time constant of the inputs \[s\] (0: none). Its noise reduction is accounted
    /// for in each reading's variance; what it costs is smear: where the point moves fast
    /// along a bent Gough curve, the averaged Fy and Mz lie off it. The default 3 ms (was
    /// 10 ms) let readings start sooner after a reversal (`settle_distance`) with no false
    /// alarm and a lower worst p95 error in `gough mu bench`; without any low-pass (a scratch
    /// run with this default changed), noise raised false alarms there.
    pub lowpass_tau: F,
    /// Time after the lateral force changes side before readings count again \[s\], for
    /// samples without Vx (with Vx, `settle_distance` decides). The default 0.05 s is
    /// `settle_distance` at 12 m/s.
    pub settle: F,
    /// Distance \[m\] the wheel rolls after the lateral force changes side before readings
    /// count again, when every sample since carries Vx. While the force passes through zero
    /// the point sweeps the Gough plot's sharpest bend, where the low-passed Fy and Mz average
    /// points off the curve, and on a real tyre the contact patch's deflection rebuilds over
    /// the relaxation length σy (eqs. 19–20): both are over after a distance rolled, not a
    /// time. The default 0.6 m is σy of the benchmark's tyre at Fz0 (0.28–0.88 m from 0.5
    /// to 1.5·Fz0). In `gough mu bench` runs with this default changed (scratch, not a command
    /// of the repository) no false alarm came from 0.25 m to 2 m with the 3 ms low-pass; with a
    /// 10 ms one, 1 m already raised two.
    pub settle_distance: F,
    /// A reading is not identifiable when a surface grippier than the estimate by more than
    /// `ambiguity_margin` (in λμ) could hold the point: its curve's trail at the measured force
    /// lies within this many standard deviations of the measured trail (low-passed measurement
    /// noise and the model terms `trail_model_rel`, `arm_model_rel`, `mzr_model_rel`,
    /// `combined_model_rel`). Where that curve is flat, noise alone would pick the wrong surface.
    pub ambiguity_sigmas: F,
    /// See `ambiguity_sigmas` \[-\] (λμ).
    pub ambiguity_margin: F,
}

impl<F: Float> Default for Config<F> {
    fn default() -> Self {
        let c = F::from_f64;
        Config {
            gamma: F::ZERO,
            sigma_mz: c(2.0),
            sigma_fy_rel: c(0.01),
            vx_min: c(3.0),
            fz_min_rel: c(0.15),
            fy_min_rel: c(0.04),
            fy_share_min: c(0.5),
            trail_drop_min: c(0.2),
            trail_drop_abs_min: c(0.004),
            sigma_max: c(0.08),
            trail_model_rel: c(0.02),
            arm_model_rel: c(0.2),
            combined_model_rel: c(0.5),
            combined_force_rel: c(0.25),
            mzr_model_rel: c(0.0006),
            q: c(0.02),
            gate: c(4.0),
            gate_sigma_max: c(0.03),
            change_min: c(0.1),
            change_count: 30,
            run_gap: c(0.1),
            init_count: 13,
            mu_prior: c(0.8),
            sigma_prior: c(0.4),
            lowpass_tau: c(0.003),
            settle: c(0.05),
            settle_distance: c(0.6),
            ambiguity_sigmas: c(2.0),
            ambiguity_margin: c(0.1),
        }
    }
}

/// One measurement of one wheel. ISO-W, SI.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Sample<F> {
    /// Time \[s\] (monotonic).
    pub t: F,
    /// Vertical load Fz \[N\].
    pub fz: F,
    /// Lateral force Fy \[N\].
    pub fy: F,
    /// Aligning torque Mz \[N·m\].
    pub mz: F,
    /// Longitudinal force Fx \[N\], when measured. Without it the wheel is taken to roll free:
    /// its Fx is the free-rolling tyre's on each surface of the table (not 0: the shifts SHx,
    /// SVx), whose moment s·Fx (eq. 17) comes out of the trail as a measured Fx's would.
    pub fx: Option<F>,
    /// Forward speed Vx \[m/s\], when measured (the speed gate is skipped without it).
    pub vx: Option<F>,
    /// Inclination γ \[rad\] (static camber plus roll camber from the suspension kinematics),
    /// when known; `Config::gamma` otherwise.
    pub gamma: Option<F>,
}

/// What an estimate rests on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum State {
    /// The latest reading was informative and updated the estimate. (A reading takes two
    /// samples, see [`MuEstimator::update`]: the sample that takes one repeats the state the
    /// previous reading left, the next reports its outcome.)
    Identifiable,
    /// The latest reading carried no usable information (the trail has not dropped, or a gate
    /// failed); the last estimate is held with a growing σ.
    NotIdentifiable,
    /// No usable estimate (none yet, or it aged out): the prior is reported.
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

/// Why the latest reading did not update the estimate ([`MuEstimator::last_hold`]): which of
/// the estimator's gates held it. For diagnosis and for a controller that wants to tell "no
/// excitation" from "the road may be slippery, but the data cannot tell yet"
/// ([`Hold::Ambiguous`]). The gates are the ones [`Config`] sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Hold {
    /// A sample that is not finite or goes back in time.
    BadSample,
    /// Too little load, speed or lateral force for the trail to mean anything, or the
    /// longitudinal force dominates (`fz_min_rel`, `vx_min`, `fy_min_rel`, `fy_share_min`).
    NoExcitation,
    /// The lateral force changed side lately: readings wait until the wheel has rolled
    /// `settle_distance` (or `settle` has passed).
    Settling,
    /// The trail has not dropped far enough below its small-slip value on any surface the
    /// reading could be on for μ to be observable (`trail_drop_min`, `trail_drop_abs_min`),
    /// or no surface of the table explains the reading.
    TrailNotDropped,
    /// The inversion is too ill-conditioned for the model's own uncertainty (`sigma_max`), or
    /// a grippier surface reads the point as grippier still (a second crossing).
    ModelUncertain,
    /// A surface grippier than the reading's estimate (by more than `ambiguity_margin`) could
    /// produce the same point at smaller slip (`ambiguity_sigmas`).
    Ambiguous,
    /// The reading is consistent with those before it, but fewer than `init_count` readings
    /// have agreed so far: no first estimate yet.
    Confirming,
    /// The reading lies outside the outlier gate; it counts towards a change of surface
    /// (`change_count`) but does not move the estimate.
    Outlier,
}

impl Hold {
    /// Every reason, in declaration order (for tallies).
    pub const ALL: [Hold; 8] = [
        Hold::BadSample,
        Hold::NoExcitation,
        Hold::Settling,
        Hold::TrailNotDropped,
        Hold::ModelUncertain,
        Hold::Ambiguous,
        Hold::Confirming,
        Hold::Outlier,
    ];

    /// Name as in logs and tables: `bad_sample`, `no_excitation`, `settling`,
    /// `trail_not_dropped`, `model_uncertain`, `ambiguous`, `confirming`, `outlier`.
    pub const fn name(self) -> &'static str {
        match self {
            Hold::BadSample => "bad_sample",
            Hold::NoExcitation => "no_excitation",
            Hold::Settling => "settling",
            Hold::TrailNotDropped => "trail_not_dropped",
            Hold::ModelUncertain => "model_uncertain",
            Hold::Ambiguous => "ambiguous",
            Hold::Confirming => "confirming",
            Hold::Outlier => "outlier",
        }
    }
}

/// An estimate of the road friction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate<F> {
    /// μ \[-\] on the tyre file's test-surface scale (architecture.md).
    pub mu: F,
    /// Standard deviation of μ \[-\]: the filter's, plus the model's own uncertainty at the
    /// latest reading (which fusing many readings does not reduce: they share the model).
    pub sigma: F,
    /// The model's part of `sigma` \[-\] (σ² = filter's variance + `sigma_model`²): the
    /// wheels of an axle share it ([`fuse`]). 0 for the prior.
    pub sigma_model: F,
    /// What it rests on.
    pub state: State,
    /// A change of surface was declared at this sample.
    pub change: bool,
}

/// Why an estimator could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BuildError {
    /// The model gives no usable Gough curve (zero stiffness, nonsense parameters).
    NoGoughCurve,
}

impl core::fmt::Display for BuildError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str("the tyre model gives no usable Gough curve")
    }
}

impl core::error::Error for BuildError {}

/// One wheel's estimator: a few words of state and a reference to the tyre's shared
/// [`GoughTable`] (about 126 KB in f32, built once per tyre and side). No allocation.
///
/// ```
/// use gough::math::Libm;
/// use gough_host::mu::table_estimator::{Config, GoughTable, MuEstimator, Sample, State};
/// let text = include_str!("../../../../host-tests/data/tyres/MagicFormula61_Parameters.tir");
/// let tyre = gough::tir::parse(text).unwrap().params.cast::<f32>();
/// let table = GoughTable::for_tyre::<Libm>(&tyre).unwrap();
/// let mut est = MuEstimator::for_tyre(&table, &tyre, Config::default());
/// // Straight running tells nothing about friction: the prior is reported, and said so.
/// let e = est.update::<Libm>(&Sample { t: 0.0, fz: 6000.0, fy: 0.0, mz: 0.0, fx: None, vx: Some(20.0), gamma: None });
/// assert_eq!(e.state, State::Fallback);
/// ```
#[derive(Debug, Clone)]
pub struct MuEstimator<'t, F> {
    table: &'t GoughTable<F>,
    arm: Arm<F>,
    fz0: F,
    cfg: Config<F>,
    // filter
    lambda: F,
    p: F,
    have: bool,
    run: i32,
    // inverse-variance mean and variance of the current outlier run, time of its last outlier
    run_acc: (F, F),
    run_last: F,
    // candidate first estimate: inverse-variance mean, its variance, count
    cand: (F, F, u16),
    // low-pass state
    lp: Option<Sample<F>>,
    last_t: Option<F>,
    // side of the last clear lateral force (+1/−1, 0 none) and when it last changed
    fy_side: i8,
    side_since: F,
    /// Distance rolled since `side_since` \[m\], up to `settle_distance` (finite |Vx|·dt).
    side_dist: F,
    /// Whether every sample since `side_since` carried Vx.
    side_vx: bool,
    // rms of the low-passed noise relative to the raw noise (1 until a sample interval is known)
    noise_scale: F,
    /// The model's variance of λμ at the latest reading fused (`Raw::var_model`): added to the
    /// filter's `p` in the σ reported, not in the filter.
    var_model: F,
    /// √`var_model`·μy0: `Estimate::sigma_model` (taken once per reading fused).
    sigma_model: F,
    // the reading taken by the last sample, its ambiguity test left for this one (see `update`)
    pending: Option<Pending<'t, F>>,
    // the state reported for the latest sample that took or finished a reading
    last_state: State,
    // why that sample's reading (or the sample itself) did not update the estimate
    last_hold: Option<Hold>,
}

/// A per-sample λμ with its variance (before filtering).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Raw<F> {
    /// λμ \[-\].
    pub lambda: F,
    /// Its variance.
    pub var: F,
    /// The part of `var` from the model's uncertainty (the table, residual torque, Fx arm,
    /// combined slip): readings at one place share it, so it does not average out.
    pub var_model: F,
    /// Trail drop 1 − τ/τ0.
    pub drop: F,
}

impl<F: Float> GoughTable<F> {
    /// The table of a Magic Formula tyre, as the file describes it (no mirroring).
    pub fn for_tyre<M: Backend<F>>(tyre: &Params<F>) -> Result<Self, BuildError> {
        Self::for_wheel::<M>(tyre, None)
    }

    /// The table of a Magic Formula tyre mounted on side `mounted` (mirrored when that differs
    /// from the file's TYRESIDE, exactly as `mf::eval` does with `Options::mounted`).
    pub fn for_wheel<M: Backend<F>>(
        tyre: &Params<F>,
        mounted: Option<Side>,
    ) -> Result<Self, BuildError> {
        GoughTable::build::<M>(Model::Mf(tyre), mounted).ok_or(BuildError::NoGoughCurve)
    }

    /// [`GoughTable::for_wheel`] in place (no 126 KB temporary on the stack).
    pub fn for_wheel_into<M: Backend<F>>(
        &mut self,
        tyre: &Params<F>,
        mounted: Option<Side>,
    ) -> Result<(), BuildError> {
        GoughTable::build_into::<M>(self, Model::Mf(tyre), mounted).ok_or(BuildError::NoGoughCurve)
    }

    /// The table of the paper's brush model (no `.tir` at hand).
    pub fn for_brush<M: Backend<F>>(brush: Brush<F>) -> Result<Self, BuildError> {
        GoughTable::build::<M>(Model::Brush(brush), None).ok_or(BuildError::NoGoughCurve)
    }
}

/// A sample reduced to what the table needs: the curves bracketing its load and camber on its
/// side, with their weights; trail, force, load.
#[derive(Debug, Clone, Copy)]
struct Reading<'a, F> {
    /// The curves bracketing the reading's load and camber, every surface of each, with their
    /// bilinear weights: the first `n` of the four are those of nonzero weight (a reading on a
    /// camber or load node needs fewer), in the order (γ, Fz), (γ, Fz⁺), (γ⁺, Fz), (γ⁺, Fz⁺).
    corners: [(&'a [table::Curve<F>; table::LAMBDA_NODES.len()], F); 4],
    n: usize,
    /// The trail −(Mz − s·Fx)/Fy on each surface: the same on all when the sample carries Fx;
    /// without it, each surface's free-rolling Fx ([`table::Curve::fx_free`]).
    tau: [F; table::LAMBDA_NODES.len()],
    force: F,
    fz: F,
}

impl<F> Reading<'_, F> {
    /// The corners of nonzero weight.
    fn active(&self) -> &[(&[table::Curve<F>; table::LAMBDA_NODES.len()], F)] {
        self.corners.get(..self.n).unwrap_or(&[])
    }
}

/// A reading that passed every check but the ambiguity test: what that test needs, and the
/// λμ, variance and time it fuses with when the test lets it through.
#[derive(Debug, Clone, Copy)]
struct Pending<'a, F> {
    reading: Reading<'a, F>,
    /// Each surface's small-slip trail τ0 where the surface gave an estimate (> 0), 0 where
    /// it did not.
    tau0: [F; table::LAMBDA_NODES.len()],
    /// The trail's variance from the low-passed measurement noise \[m²\].
    var_tau: F,
    /// The model's variance of the trail (see `take`): τ0²·`trail_rel_sq` + `var_tau_arm`.
    trail_rel_sq: F,
    /// Its part from the Fx moment arm and the residual torque \[m²\].
    var_tau_arm: F,
    raw: Raw<F>,
    t: F,
}

/// One surface's radial estimate.
#[derive(Clone, Copy)]
struct NodeEst<F> {
    lambda: F,
    dl_dtau: F,
    tau0: F,
    drop: F,
    /// Relative spread of λ from a saturated reading (deep sliding), 0 otherwise.
    spread: F,
}

impl<'t, F: Float> MuEstimator<'t, F> {
    /// An estimator for one wheel of a Magic Formula tyre (its table built by
    /// [`GoughTable::for_tyre`] or [`GoughTable::for_wheel`]).
    pub fn for_tyre(table: &'t GoughTable<F>, tyre: &Params<F>, config: Config<F>) -> Self {
        Self::with_table(table, Arm::from_params(tyre), tyre.fnomin, config)
    }

    /// An estimator on the brush model's table (no Fx moment arm).
    pub fn for_brush(table: &'t GoughTable<F>, brush: &Brush<F>, config: Config<F>) -> Self {
        let arm = Arm {
            r0: F::ZERO,
            fz0: brush.fz0,
            ssz: [F::ZERO; 4],
            ls: F::ZERO,
        };
        Self::with_table(table, arm, brush.fz0, config)
    }

    fn with_table(table: &'t GoughTable<F>, arm: Arm<F>, fz0: F, cfg: Config<F>) -> Self {
        MuEstimator {
            table,
            arm,
            fz0,
            cfg,
            lambda: F::ZERO,
            p: F::ZERO,
            have: false,
            run: 0,
            run_acc: (F::ZERO, F::ZERO),
            run_last: F::ZERO,
            cand: (F::ZERO, F::ZERO, 0),
            lp: None,
            last_t: None,
            fy_side: 0,
            side_since: F::ZERO,
            side_dist: F::ZERO,
            side_vx: true,
            noise_scale: F::ONE,
            var_model: F::ZERO,
            sigma_model: F::ZERO,
            pending: None,
            last_state: State::Fallback,
            last_hold: None,
        }
    }

    /// μy0 of the model: μ of its test surface (λμ = 1).
    pub fn mu0(&self) -> F {
        self.table.mu0
    }

    /// The settings.
    pub fn config(&self) -> &Config<F> {
        &self.cfg
    }

    /// Why the estimate [`MuEstimator::update`] last returned is held: the gate that held the
    /// latest reading (or that sample), or `None` when the estimate is `Identifiable` (and
    /// before any sample). Like [`Estimate::state`], a sample that takes a reading repeats what
    /// the previous reading left (see [`MuEstimator::update`]). A held estimate
    /// (`NotIdentifiable` or `Fallback`) always has a reason.
    ///
    /// ```
    /// use gough::math::Libm;
    /// use gough_host::mu::table_estimator::{Config, GoughTable, Hold, MuEstimator, Sample};
    /// let text = include_str!("../../../../host-tests/data/tyres/MagicFormula61_Parameters.tir");
    /// let tyre = gough::tir::parse(text).unwrap().params.cast::<f32>();
    /// let table = GoughTable::for_tyre::<Libm>(&tyre).unwrap();
    /// let mut est = MuEstimator::for_tyre(&table, &tyre, Config::default());
    /// est.update::<Libm>(&Sample { t: 0.0, fz: 6000.0, fy: 0.0, mz: 0.0, fx: None, vx: Some(20.0), gamma: None });
    /// assert_eq!(est.last_hold(), Some(Hold::NoExcitation)); // straight running
    /// ```
    pub fn last_hold(&self) -> Option<Hold> {
        self.last_hold
    }

    /// Forgets everything learnt (e.g. after a reset command).
    pub fn reset(&mut self) {
        self.fy_side = 0;
        self.have = false;
        self.run = 0;
        self.cand = (F::ZERO, F::ZERO, 0);
        self.lp = None;
        self.last_t = None;
        self.pending = None;
        self.last_state = State::Fallback;
        self.last_hold = None;
    }

    /// The radial estimate on surface node `si` (small-slip trail `tau0`) for the reading `q`.
    fn node(&self, si: usize, q: &Reading<F>, tau0: F, anchor: F) -> Option<NodeEst<F>> {
        let Reading { force, fz, .. } = *q;
        let tau = *q.tau.get(si)?;
        // Bilinear in (load, camber) over the bracketing curves; `tau0` is this surface's τ0
        // interpolated so.
        let corners = q.active();
        // The trail's length scales with load (Dt ∝ Fz·(qDz1 + qDz2·dfz)): compare curves at
        // the same fraction ρ of their own small-slip trail τ0, not at the same τ, and at the
        // same stage of its collapse: the same position on their grids, ρ placed on the grid
        // of the interpolated anchor (`anchor`). One place on the grid serves every corner.
        if tau0 <= F::ZERO {
            return None;
        }
        let at = table::RhoAt::new(tau / tau0, anchor);
        let (mut f, mut f_spread, mut dfdrho) = (F::ZERO, F::ZERO, F::ZERO);
        for &(cs, wt) in corners {
            let inv = cs.get(si)?.read(&at)?;
            f += wt * inv.f;
            f_spread += wt * inv.f_spread;
            dfdrho += wt * inv.df_drho;
        }
        if f <= F::ZERO {
            return None;
        }
        let lam_node = *self.table.lam.get(si)?;
        let lambda = lam_node * force / (fz * f); // radial scaling about the node
        Some(NodeEst {
            lambda,
            // ∂f/∂τ = (∂f/∂ρ)/τ0.
            dl_dtau: -lambda * dfdrho / (tau0 * f),
            tau0,
            drop: F::ONE - at.rho,
            spread: f_spread / f,
        })
    }

    /// λμ and its variance from one (filtered) sample, or `None` when the sample is not
    /// identifiable. Pure function of the sample; exposed for tests and diagnosis.
    /// [`MuEstimator::update`] spreads the same work over two samples.
    pub fn raw<M: Backend<F>>(&self, s: &Sample<F>) -> Option<Raw<F>> {
        let p = self.take::<M>(s, &mut Hold::TrailNotDropped)?;
        (!self.held_by_grippier(&p)).then_some(p.raw)
    }

    /// The first stage of [`MuEstimator::raw`]: every check but the ambiguity test's trail
    /// look-ups ([`MuEstimator::held_by_grippier`]). When a gate holds the reading it says
    /// which in `why` (a failed look-up into the table, which no table the builder made gives,
    /// leaves `why` as it was). (An out-parameter rather than a `Result`: with the reading's
    /// 108 bytes in a `Result`, the M4F's worst sample took some 500 instructions more.)
    #[inline(always)]
    fn take<M: Backend<F>>(&self, s: &Sample<F>, why: &mut Hold) -> Option<Pending<'t, F>> {
        let cfg = &self.cfg;
        if s.fz < cfg.fz_min_rel * self.fz0 {
            *why = Hold::NoExcitation;
            return None;
        }
        if let Some(vx) = s.vx {
            if vx.abs() < cfg.vx_min {
                *why = Hold::NoExcitation;
                return None;
            }
        }
        let fy = s.fy;
        if fy.abs() < cfg.fy_min_rel * s.fz {
            *why = Hold::NoExcitation;
            return None;
        }
        // Without Fx the wheel is taken to roll free: its Fx, per surface, comes with the
        // corners below; here it counts as 0.
        let fx = s.fx.unwrap_or(F::ZERO);
        let dfz = (s.fz - self.fz0) / self.fz0;
        let gamma = s.gamma.filter(|g| g.is_finite()).unwrap_or(cfg.gamma);
        // (17): remove s·Fx, with the arm of the tyre as mounted (as the table did).
        let arm = self.arm.s_mounted(self.table.mirrored, fy, dfz, gamma);
        let mz = s.mz - arm * fx;
        // Trail variance of the model's Fx moment.
        let mut var_tau_arm = (cfg.arm_model_rel * arm * fx / fy).sq()
            + (cfg.mzr_model_rel * s.fz * self.arm.r0 / fy).sq();
        let tau = -mz / fy;
        // Side: Fy along the model's α > 0 direction → side 0.
        let side = if fy * self.table.fy_sign > F::ZERO {
            0
        } else {
            1
        };
        // Friction ellipse: Fx counts at the lateral scale μy0/μx0 of the model.
        let fxe = fx * self.table.mu_ratio;
        let force = M::sqrt(fxe * fxe + fy * fy);
        if fy.abs() < cfg.fy_share_min * force {
            *why = Hold::NoExcitation;
            return None;
        }
        let fx_share = fxe.abs() / force;
        // The model's uncertainty of the trail on a curve whose small-slip trail is τ0: the
        // table, the Fx moment and residual torque (`var_tau_arm`), combined slip.
        let trail_rel_sq = cfg.trail_model_rel.sq() + (cfg.combined_model_rel * fx_share).sq();
        // Load nodes bracketing Fz (clamped at the ends).
        let nodes = &self.table.fz;
        let n = nodes.len();
        let mut j = 0;
        while j + 2 < n && nodes.get(j + 1).is_some_and(|&x| s.fz > x) {
            j += 1;
        }
        let (za, zb) = (*nodes.get(j)?, *nodes.get(j + 1)?);
        let w = ((s.fz - za) / (zb - za)).max(F::ZERO).min(F::ONE);
        // Camber nodes bracketing γ (clamped at the ends).
        let cn = &self.table.cam;
        let mut g = 0;
        while g + 2 < cn.len() && cn.get(g + 1).is_some_and(|&x| gamma > x) {
            g += 1;
        }
        let (ga, gb) = (*cn.get(g)?, *cn.get(g + 1)?);
        let u = ((gamma - ga) / (gb - ga)).max(F::ZERO).min(F::ONE);
        let t = self.table;
        let all = [
            (t.surfaces(g, j, side)?, (F::ONE - u) * (F::ONE - w)),
            (t.surfaces(g, j + 1, side)?, (F::ONE - u) * w),
            (t.surfaces(g + 1, j, side)?, u * (F::ONE - w)),
            (t.surfaces(g + 1, j + 1, side)?, u * w),
        ];
        let mut reading = Reading {
            corners: all,
            n: 0,
            tau: [tau; table::LAMBDA_NODES.len()],
            force,
            fz: s.fz,
        };
        for c in all {
            if c.1 != F::ZERO {
                *reading.corners.get_mut(reading.n)? = c;
                reading.n += 1;
            }
        }
        if s.fx.is_none() && arm != F::ZERO {
            // The free-rolling Fx of each surface at this force (bilinear over the corners, as
            // the curves), and its moment s·Fx (eq. (17)) out of the trail: τ += s·Fx/Fy.
            let f_sq = (force / s.fz).sq();
            let k = arm * s.fz / fy;
            let mut taus = reading.tau;
            for &(cs, wt) in reading.active() {
                for (slot, c) in taus.iter_mut().zip(cs) {
                    let [c0, c2] = c.fx_free;
                    *slot += wt * k * (c0 + c2 * f_sq);
                }
            }
            reading.tau = taus;
            // That moment is the model's too (`arm_model_rel`, as for a measured Fx): its
            // largest share over the surfaces.
            let mut moment = F::ZERO;
            for &t in &taus {
                moment = moment.max((t - tau).abs());
            }
            var_tau_arm += (cfg.arm_model_rel * moment).sq();
        }
        let var_tau_model = |tau0: F| tau0.sq() * trail_rel_sq + var_tau_arm;
        // Radial estimates about each surface node; the consistent one is where the estimate
        // crosses its own node (d = λ̂ − λnode changes sign), interpolated between the two.
        // First each surface's small-slip trail τ0 (bilinear over the corners) and the trail
        // drop 1 − τ/τ0 the reading shows on it: the estimate's drop lies between two of
        // these (it is one surface's, or interpolated between two), so a reading whose drop is
        // short of `trail_drop_min` on every surface is not identifiable whatever the curves
        // say — decided here, before any curve is read. (The margin covers the rounding of
        // that interpolation: no reading the full test would accept is turned away.)
        let mut tau0s = [F::ZERO; table::LAMBDA_NODES.len()];
        let mut anchors = [F::ZERO; table::LAMBDA_NODES.len()];
        // (From 0: with a `trail_drop_min` ≤ 0 nothing is decided here.)
        let mut most = F::ZERO;
        for &(cs, wt) in reading.active() {
            for ((slot, anchor), c) in tau0s.iter_mut().zip(anchors.iter_mut()).zip(cs) {
                *slot += wt * c.tau0;
                *anchor += wt * c.anchor;
            }
        }
        for (&tau0, &tau) in tau0s.iter().zip(&reading.tau) {
            if tau0 > F::ZERO {
                most = most.max(F::ONE - tau / tau0);
            }
        }
        if most < cfg.trail_drop_min * F::from_f64(1.0 - 1e-4) {
            *why = Hold::TrailNotDropped;
            return None;
        }
        let mut ests: [Option<NodeEst<F>>; table::LAMBDA_NODES.len()] =
            [None; table::LAMBDA_NODES.len()];
        for (si, (slot, (&tau0, &anchor))) in
            ests.iter_mut().zip(tau0s.iter().zip(&anchors)).enumerate()
        {
            *slot = self.node(si, &reading, tau0, anchor);
        }
        let mut prev: Option<(F, NodeEst<F>)> = None;
        let mut pick: Option<NodeEst<F>> = None;
        for (si, e) in ests.iter().enumerate() {
            let Some(e) = *e else { continue };
            let d = e.lambda - *self.table.lam.get(si)?;
            match prev {
                Some((dp, ep)) if dp >= F::ZERO && d < F::ZERO => {
                    let u = dp / (dp - d);
                    let mix = |a: F, b: F| a + u * (b - a);
                    pick = Some(NodeEst {
                        lambda: mix(ep.lambda, e.lambda),
                        dl_dtau: mix(ep.dl_dtau, e.dl_dtau),
                        tau0: mix(ep.tau0, e.tau0),
                        drop: mix(ep.drop, e.drop),
                        spread: mix(ep.spread, e.spread),
                    });
                    break;
                }
                None if d < F::ZERO => {
                    pick = Some(e); // below the lowest usable node
                    break;
                }
                _ => {}
            }
            prev = Some((d, e));
            pick = Some(e); // above every node so far: the highest one
        }
        // Variance of the trail from the (low-passed) measurement noise.
        let s_m = cfg.sigma_mz * self.noise_scale;
        let s_f = cfg.sigma_fy_rel * s.fz * self.noise_scale;
        let var_tau = (s_m / fy).sq() + (tau * s_f / fy).sq();
        let Some(e) = pick else {
            *why = Hold::TrailNotDropped;
            return None;
        };
        // Ambiguity guard: the same (τ, |F|) can be a slippery surface at moderate slip or a
        // grippy one at small slip, where the trail has not dropped (or is still rising, with
        // the residual torque). An estimate is believed only if no surface grippier than it by
        // more than `ambiguity_margin` could produce the point too: its curve's trail at the
        // measured force must differ from the measured trail by more than `ambiguity_sigmas`
        // standard deviations (measurement noise after the low-pass, residual-torque, Fx-arm,
        // combined-slip and table uncertainty); and none may read the point as grippier than
        // itself (a second crossing).
        // The outcome does not depend on the order of the checks, only the cost: the cheap
        // ones here, the curves' trails last (`held_by_grippier`, from the grippiest surface
        // down: the one most likely to hold a small-slip point).
        for (si, est) in ests.iter().enumerate() {
            let lam_k = *self.table.lam.get(si)?;
            if lam_k <= e.lambda {
                continue;
            }
            let Some(k) = est else {
                *why = Hold::ModelUncertain;
                return None;
            };
            if k.lambda >= lam_k {
                *why = Hold::ModelUncertain;
                return None;
            }
        }
        let lambda = e.lambda;
        // Error propagation: λ = |F|/(Fz·f(τ)), τ = −M/Fy.
        //   ∂λ/∂τ = −λ·f'/f;  ∂τ/∂M = −1/Fy;  ∂τ/∂Fy = −τ/Fy;  ∂λ/∂|F| = λ/|F|.
        let s_m = cfg.sigma_mz;
        let s_f = cfg.sigma_fy_rel * s.fz;
        let var_meas = e.dl_dtau.sq() * ((s_m / fy).sq() + (tau * s_f / fy).sq())
            + (lambda * s_f / force).sq();
        // The model's own uncertainty does not average out over samples: it alone decides
        // whether the inversion is well-conditioned enough to be believed at all.
        let var_model = e.dl_dtau.sq() * var_tau_model(e.tau0)
            + (lambda * e.spread).sq()
            + (cfg.combined_force_rel * fx_share * lambda).sq();
        let mu0 = self.table.mu0;
        if e.drop < cfg.trail_drop_min || e.drop * e.tau0 < cfg.trail_drop_abs_min {
            *why = Hold::TrailNotDropped;
            return None;
        }
        if var_model * mu0.sq() > cfg.sigma_max.sq() || lambda <= F::ZERO || !lambda.is_finite() {
            *why = Hold::ModelUncertain;
            return None;
        }
        Some(Pending {
            reading,
            tau0: ests.map(|k| k.map_or(F::ZERO, |k| k.tau0)),
            var_tau,
            trail_rel_sq,
            var_tau_arm,
            raw: Raw {
                lambda,
                var: var_meas + var_model,
                var_model,
                drop: e.drop,
            },
            t: s.t,
        })
    }

    /// The ambiguity guard's trail test (see [`MuEstimator::raw`]): whether a surface grippier
    /// than the reading's estimate by more than `ambiguity_margin` holds the reading within
    /// `ambiguity_sigmas` standard deviations (of the trail on that surface's curves: `var_tau`
    /// and the model's part). Out of line: the dry road, where nothing is
    /// grippier, does not pay for it.
    #[inline(never)]
    fn held_by_grippier(&self, p: &Pending<'_, F>) -> bool {
        let cfg = &self.cfg;
        let reading = &p.reading;
        let lambda = p.raw.lambda;
        let f_m = reading.force / reading.fz;
        for (si, (tau0, &lam_k)) in p.tau0.iter().zip(&self.table.lam).enumerate().rev() {
            let tau0 = *tau0;
            let Some(&tau) = reading.tau.get(si) else {
                continue;
            };
            if tau0 <= F::ZERO || lam_k <= lambda || lam_k - lambda <= cfg.ambiguity_margin {
                continue;
            }
            // The grippier curve's trail at the measured force (interpolated like the
            // table); a curve that never reaches this force cannot hold the point. First
            // its bounds, from each curve's force cell (the chord across the cell, and how far
            // the curve strays from it; no search): they decide the test unless the measured
            // trail lies near them; only then are the curves searched (same outcome either
            // way: the bounds enclose the look-up with a margin).
            let (mut lo, mut hi, mut wsum) = (F::ZERO, F::ZERO, F::ZERO);
            for &(cs, wt) in reading.active() {
                if let Some((l, h)) = cs.get(si).and_then(|c| c.tau_band(f_m)) {
                    lo += wt * l;
                    hi += wt * h;
                    wsum += wt;
                }
            }
            if wsum <= F::HALF {
                continue;
            }
            let tol_sq = cfg.ambiguity_sigmas.sq()
                * (p.var_tau + (tau0.sq() * p.trail_rel_sq + p.var_tau_arm));
            let (lo, hi) = (lo / wsum, hi / wsum);
            if (tau > hi && (tau - hi).sq() > tol_sq) || (tau < lo && (lo - tau).sq() > tol_sq) {
                continue; // apart from every trail the curve can have here
            }
            if (tau - lo).sq() <= tol_sq && (hi - tau).sq() <= tol_sq {
                return true; // within the tolerance of all of them
            }
            let (mut tk, mut wsum) = (F::ZERO, F::ZERO);
            let mut hint = 0;
            for &(cs, wt) in reading.active() {
                if let Some(x) = cs.get(si).and_then(|c| c.tau_at_from(f_m, &mut hint)) {
                    tk += wt * x;
                    wsum += wt;
                }
            }
            if wsum > F::HALF && (tau - tk / wsum).sq() <= tol_sq {
                return true;
            }
        }
        false
    }

    /// Processes one sample and returns the current estimate. Non-finite or out-of-order samples
    /// are not identifiable (the estimate is held); nothing earlier is lost.
    ///
    /// Every sample is low-passed. A reading ([`MuEstimator::raw`]) is spread over two
    /// samples so that no sample pays for all of it: a sample takes a reading (the gates, the
    /// table reads, the crossing, the cheap ambiguity checks) and, if the reading survives
    /// them, the next sample finishes it (the ambiguity test's trail look-ups on the grippier
    /// surfaces, then the fusion) and takes none of its own. The sample that takes a reading
    /// reports the estimate as the previous reading left it; the outcome comes one sample
    /// later. Readings therefore come at most every other sample (`init_count` and
    /// `change_count` count readings).
    pub fn update<M: Backend<F>>(&mut self, s: &Sample<F>) -> Estimate<F> {
        let finite = s.t.is_finite()
            && s.fz.is_finite()
            && s.fy.is_finite()
            && s.mz.is_finite()
            && s.fx.is_none_or(|x| x.is_finite())
            && s.vx.is_none_or(|x| x.is_finite())
            && s.gamma.is_none_or(|x| x.is_finite());
        let dt = match (self.last_t, finite) {
            (_, false) => None,
            (None, true) => Some(F::ZERO),
            (Some(t0), true) => {
                let d = s.t - t0;
                if d < F::ZERO {
                    None
                } else {
                    Some(d.min(F::ONE))
                }
            }
        };
        let Some(dt) = dt else {
            self.last_hold = Some(Hold::BadSample);
            return self.hold::<M>();
        };
        self.last_t = Some(s.t);
        // Low-pass the inputs (first order, α = dt/(τ + dt)).
        let filt = match self.lp {
            None => *s,
            Some(prev) => {
                let a = if self.cfg.lowpass_tau > F::ZERO {
                    dt / (self.cfg.lowpass_tau + dt)
                } else {
                    F::ONE
                };
                let mix = |p: F, x: F| p + a * (x - p);
                Sample {
                    t: s.t,
                    fz: mix(prev.fz, s.fz),
                    fy: mix(prev.fy, s.fy),
                    mz: mix(prev.mz, s.mz),
                    fx: match (prev.fx, s.fx) {
                        (Some(p), Some(x)) => Some(mix(p, x)),
                        (_, x) => x,
                    },
                    vx: s.vx,
                    gamma: s.gamma,
                }
            }
        };
        self.lp = Some(filt);
        if dt > F::ZERO && self.cfg.lowpass_tau > F::ZERO {
            // First-order low-pass of white noise: variance × a/(2 − a), a = dt/(τ + dt).
            let a = dt / (self.cfg.lowpass_tau + dt);
            self.noise_scale = M::sqrt(a / (F::TWO - a));
        }
        if self.have {
            self.p += self.cfg.q * dt;
        }
        // After the lateral force changes side (a steering reversal) the contact patch's
        // deflection rebuilds over a relaxation length: the steady-state Gough curve does not
        // hold yet, and a force passing through zero with the residual torque still there reads
        // like ice. Readings wait `settle` after each reversal.
        let clear = filt.fy.abs() > self.cfg.fy_min_rel * filt.fz;
        if clear {
            let side: i8 = if filt.fy > F::ZERO { 1 } else { -1 };
            if side != self.fy_side {
                self.fy_side = side;
                self.side_since = filt.t;
                self.side_dist = F::ZERO;
                self.side_vx = true;
            }
        }
        match filt.vx {
            Some(vx) if self.side_dist < self.cfg.settle_distance => {
                self.side_dist += vx.abs() * dt;
            }
            Some(_) => {}
            None => self.side_vx = false,
        }
        let settled = if self.side_vx {
            self.side_dist >= self.cfg.settle_distance
        } else {
            filt.t - self.side_since >= self.cfg.settle
        };
        // A reading's work is spread over two samples, so that no sample pays for all of it:
        // this one finishes the reading the previous sample took (the ambiguity test's trail
        // look-ups, then the fusion) and takes none of its own.
        let e = if let Some(p) = &self.pending {
            // (By reference: the pending reading is not copied out.)
            let held = self.held_by_grippier(p);
            let (raw, t) = (p.raw, p.t);
            self.pending = None;
            if held {
                self.last_hold = Some(Hold::Ambiguous);
                self.hold::<M>()
            } else {
                self.fuse::<M>(raw, t)
            }
        } else if !clear || !settled {
            self.last_hold = Some(if clear {
                Hold::Settling
            } else {
                Hold::NoExcitation
            });
            self.hold::<M>()
        } else {
            let mut why = Hold::TrailNotDropped;
            match self.take::<M>(&filt, &mut why) {
                None => {
                    self.last_hold = Some(why);
                    self.hold::<M>()
                }
                Some(p) => {
                    // Taken; the next sample finishes it. Meanwhile the estimate stands as the
                    // latest reading left it, and so does its reason — unless a bad sample came
                    // between (an estimate reported `Identifiable` has none), or this is the
                    // first reading since the start (no estimate yet: confirming).
                    self.pending = Some(p);
                    let e = self.latest::<M>();
                    self.last_hold = match e.state {
                        State::Identifiable => None,
                        _ => self.last_hold.or(Some(Hold::Confirming)),
                    };
                    return e;
                }
            }
        };
        self.last_state = e.state;
        e
    }

    /// The estimate as the latest finished reading left it (with the σ grown since).
    fn latest<M: Backend<F>>(&self) -> Estimate<F> {
        if self.have && self.last_state == State::Identifiable {
            self.identifiable::<M>(false)
        } else {
            self.hold::<M>()
        }
    }

    /// The filter's estimate, as a reading that updated it reports it.
    fn identifiable<M: Backend<F>>(&self, change: bool) -> Estimate<F> {
        let mu0 = self.table.mu0;
        Estimate {
            mu: self.lambda * mu0,
            sigma: self.sigma::<M>(),
            sigma_model: self.sigma_model,
            state: State::Identifiable,
            change,
        }
    }

    /// The model's variance of the reading just fused (`Raw::var_model`), kept for σ.
    fn set_model<M: Backend<F>>(&mut self, var_model: F) {
        self.var_model = var_model;
        self.sigma_model = M::sqrt(var_model) * self.table.mu0;
    }

    /// σ of μ as reported: the filter's `p` plus the latest reading's model variance.
    fn sigma<M: Backend<F>>(&self) -> F {
        M::sqrt(self.p + self.var_model) * self.table.mu0
    }

    fn hold<M: Backend<F>>(&self) -> Estimate<F> {
        let mu0 = self.table.mu0;
        if self.have {
            // Aged out by the filter's own σ (the model's part does not age); compared
            // squared, so that a held sample takes one square root, not two.
            if self.p * mu0.sq() <= self.cfg.sigma_prior.sq() {
                return Estimate {
                    mu: self.lambda * mu0,
                    sigma: self.sigma::<M>(),
                    sigma_model: self.sigma_model,
                    state: State::NotIdentifiable,
                    change: false,
                };
            }
        }
        Estimate {
            mu: self.cfg.mu_prior,
            sigma: self.cfg.sigma_prior,
            sigma_model: F::ZERO,
            state: State::Fallback,
            change: false,
        }
    }

    /// Folds the reading `r`, taken at time `t` \[s\], into the estimate.
    fn fuse<M: Backend<F>>(&mut self, r: Raw<F>, t: F) -> Estimate<F> {
        let mu0 = self.table.mu0;
        let mut change = false;
        if !self.have {
            // Debounce: the first estimate needs `init_count` mutually consistent readings.
            let (mean, var, n) = self.cand;
            let consistent = n > 0 && (r.lambda - mean).sq() <= self.cfg.gate.sq() * (var + r.var);
            self.cand = if consistent {
                let w = var / (var + r.var);
                (
                    mean + (F::ONE - w) * (r.lambda - mean),
                    var * r.var / (var + r.var),
                    n.saturating_add(1),
                )
            } else {
                (r.lambda, r.var, 1)
            };
            if self.cand.2 < self.cfg.init_count {
                self.last_hold = Some(Hold::Confirming);
                return self.hold::<M>();
            }
            self.lambda = self.cand.0;
            self.p = self
                .cand
                .1
                .max(r.var / F::from_f64(f64::from(self.cfg.init_count)));
            self.set_model::<M>(r.var_model);
            self.have = true;
            self.run = 0;
        } else {
            let e = r.lambda - self.lambda;
            let s = self.p + r.var;
            let p_gate = self.p.min((self.cfg.gate_sigma_max / mu0).sq());
            if e * e > self.cfg.gate.sq() * (p_gate + r.var) {
                // Outlier: counted, not used, unless it persists on one side (a new surface).
                let dir = if e > F::ZERO { 1 } else { -1 };
                if self.run.signum() == dir && t - self.run_last <= self.cfg.run_gap {
                    self.run += dir;
                    let (m, v) = self.run_acc;
                    self.run_acc = (
                        m + v / (v + r.var) * (r.lambda - m),
                        v * r.var / (v + r.var),
                    );
                } else {
                    self.run = dir;
                    self.run_acc = (r.lambda, r.var);
                }
                self.run_last = t;
                if self.run.unsigned_abs() >= u32::from(self.cfg.change_count) {
                    // The run's evidence replaces the estimate. A change of surface is declared
                    // only when that moves μ by at least `change_min`: a smaller step is the
                    // estimate re-aligning within its accuracy, not a new road.
                    let (m, v) = self.run_acc;
                    change = (m - self.lambda).abs() * mu0 >= self.cfg.change_min;
                    self.lambda = m;
                    self.p = v.max(r.var / F::from_f64(f64::from(self.cfg.change_count)));
                    self.set_model::<M>(r.var_model);
                    self.run = 0;
                } else {
                    // Not used: the estimate is held, as for any uninformative sample.
                    self.last_hold = Some(Hold::Outlier);
                    return self.hold::<M>();
                }
            } else {
                let k = self.p / s;
                self.lambda += k * e;
                self.p = (F::ONE - k) * self.p;
                self.set_model::<M>(r.var_model);
                self.run = 0;
            }
        }
        self.last_hold = None;
        self.identifiable::<M>(change)
    }
}

/// Fuses two wheels' estimates (an axle) by inverse variance when they agree within 3σ; `None`
/// when either has no estimate of its own or they disagree (μ-split: keep them apart). The
/// filters' parts of σ are independent and shrink as usual; the model's parts
/// (`Estimate::sigma_model`) come from one tyre model and are taken as fully correlated: they
/// add linearly, w·σa + (1 − w)·σb, and fusing does not shrink them.
pub fn fuse<F: Float, M: Backend<F>>(a: &Estimate<F>, b: &Estimate<F>) -> Option<Estimate<F>> {
    if a.state == State::Fallback || b.state == State::Fallback {
        return None;
    }
    let (va, vb) = (a.sigma.sq(), b.sigma.sq());
    if va <= F::ZERO || vb <= F::ZERO {
        return None;
    }
    let d = a.mu - b.mu;
    if d * d > F::from_f64(9.0) * (va + vb) {
        return None;
    }
    let w = vb / (va + vb);
    let state = if a.state == State::Identifiable || b.state == State::Identifiable {
        State::Identifiable
    } else {
        State::NotIdentifiable
    };
    // The filters' variances (what is left after the model's part).
    let (ma, mb) = (a.sigma_model.min(a.sigma), b.sigma_model.min(b.sigma));
    let (na, nb) = (va - ma.sq(), vb - mb.sq());
    let wb = F::ONE - w;
    let sigma_model = w * ma + wb * mb;
    Some(Estimate {
        mu: w * a.mu + wb * b.mu,
        sigma: M::sqrt(w * w * na + wb * wb * nb + sigma_model.sq()),
        sigma_model,
        state,
        change: a.change || b.change,
    })
}

#[cfg(test)]
mod tests;
