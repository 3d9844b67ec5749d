//! Transient slip through relaxation lengths: paper eqs. (19)–(21), safe through standstill.
//!
//! The tyre's contact patch must deflect before it can carry a force, so the force follows the
//! wheel slip with a lag over a travelled distance σ, the relaxation length. The paper's eq. (19)
//! for the deflection v of the string's leading edge,
//! `(1/Vx)·dv/dt + v/σ = tan α − a·φ`, multiplied through by σ·Vx and with the rolling speed Vr
//! in place of Vx (longitudinal slip present, turn slip neglected), becomes eq. (20):
//!
//! ```text
//! σα·dv/dt + Vr·v = σα·Vsy        (lateral; ISO-W: tan α = Vsy/|Vx|, the paper's −Vsy in SAE)
//! σκ·du/dt + Vr·u = −σκ·Vsx       (longitudinal twin; κ = −Vsx/|Vx|)
//! tan α' = v/σα  (21),    κ' = u/σκ
//! ```
//!
//! No division by a speed appears, so the states start and stop from standstill (Vr = Vx = 0).
//! α' and κ' feed the combined-slip Magic Formula ([`crate::mf::eval`]).
//!
//! ## Discretisation
//! Over a step h the inputs (Vr, Vsx, Vsy, σ) are held (or taken at the step's midpoint by the
//! caller); the linear first-order equation dv/dt = −a·v + b with a = |Vr|/σ ≥ 0 is then solved
//! exactly: `v(t+h) = v·e^(−a·h) + b·h·φ1(a·h)` with φ1(x) = (1 − e^(−x))/x (a series for small x),
//! so the update is exact for constant inputs, unconditionally stable (e^(−a·h) ∈ (0, 1]) for any
//! Vr ≥ 0 and any step, and never divides by zero.
//!
//! [`Transient::step`] holds the inputs. [`Transient::step_hold`] is the continuous model sampled:
//! every input, σ and the damping speed included, is linear in time between the step's two ends
//! (a first-order hold), the forcing is integrated exactly, the decay rate V/σ at the midpoint of
//! sub-steps taken where it changes fast, and α', κ' are formed with the end's own σ. Over a 10 ms
//! step with the load oscillating ±30 % at 8 Hz σ is not "little changed": there the held form
//! lags and mis-scales the slip, the hold form does not (see the tests).
//!
//! ## Low speed and standstill
//! - Damping speed: [`DampingSpeed::Rolling`] (the paper: Vr = Ω·Re = Vx − Vsx) or
//!   [`DampingSpeed::Forward`] (|Vx|, TNO MF-Tyre; then α' → α exactly in steady state also under
//!   braking). The paper's form is the default.
//! - Pacejka's low-speed damping: below VXLOW an artificial damping proportional to the carcass
//!   stiffness, `k = DAMP_VLOW·C·½(1 + cos(π·|Vx|/VXLOW))`, is added; as C = |K|/σ, its slip
//!   equivalent is `Δα' = DAMP_VLOW·w·Vsy/σα` and `Δκ' = −DAMP_VLOW·w·Vsx/σκ` (w the cosine fade).
//! - Clamps: |tan α'| ≤ [`Config::max_tan_alpha`] and |κ'| ≤ [`Config::max_kappa`], applied to the
//!   states themselves, so a wheel sliding at standstill (Vr = 0, Vsy ≠ 0) cannot wind the
//!   deflection up without bound; every clamp is flagged.
//! - σ has a floor [`Config::sigma_min`] (σ → 0 as Fz → 0 would make the lag vanish and the
//!   deflection meaningless).
//!
//! ## What it leaves out
//! Turn slip's contribution (the −a·φ term), the contact-patch mass of MF-Swift, and the
//! slip-dependent relaxation length inside the step (offered between steps by
//! [`decayed_sigma`], paper ref. \[8\]).

use crate::math::{Backend, Float, Mask};
use crate::mf::{self, EvalError, Input, Options, Output, Params};

/// Which speed damps the deflection in eq. (20).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum DampingSpeed {
    /// Speed of rolling Vr = Vx − Vsx (the paper, eq. 20).
    Rolling,
    /// |Vx| (TNO MF-Tyre linear transient): steady state gives α' = α, κ' = κ exactly.
    Forward,
}

/// Configuration of the transient model. Units SI.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config<F> {
    /// Speed in the damping term of eq. (20).
    pub damping: DampingSpeed,
    /// Floor on σα and σκ \[m\]: the relaxation length never falls below it at low load.
    pub sigma_min: F,
    /// Low-speed damping time constant DAMP_VLOW \[s\] (0: none).
    pub damp_vlow: F,
    /// Speed below which the low-speed damping fades in, VXLOW \[m/s\].
    pub vxlow: F,
    /// Bound on |tan α'| (default 1.0, α' = 45°: far beyond any force peak).
    pub max_tan_alpha: F,
    /// Bound on |κ'| (default 1.0: a locked wheel).
    pub max_kappa: F,
}

impl<F: Float> Config<F> {
    /// Defaults from a parameter set: the paper's damping speed, DAMP_VLOW and VXLOW from the
    /// file, σ floor 1 % of R0.
    pub fn from_params(p: &Params<F>) -> Self {
        Config {
            damping: DampingSpeed::Rolling,
            sigma_min: p.unloaded_radius * F::from_f64(0.01),
            damp_vlow: p.damp_vlow,
            vxlow: p.vxlow,
            max_tan_alpha: F::ONE,
            max_kappa: F::ONE,
        }
    }
}

/// Kinematics of one wheel at the contact point over a step. ISO-W, SI.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Kinematics<F> {
    /// Forward speed of the wheel centre Vx \[m/s\] (< 0 backwards).
    pub vx: F,
    /// Longitudinal slip speed Vsx = Vx − Ω·Re \[m/s\] (> 0 braking).
    pub vsx: F,
    /// Lateral slip speed Vsy \[m/s\] (ISO-W: tan α = Vsy/|Vx|).
    pub vsy: F,
}

/// Relaxation lengths used for a step \[m\].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sigma<F> {
    /// Longitudinal σκ \[m\].
    pub sigma_kappa: F,
    /// Lateral σα \[m\].
    pub sigma_alpha: F,
}

/// The inputs of eq. (20) at one end of a step of [`Transient::step_hold`]: the kinematics and
/// the relaxation lengths at that instant (σ at that instant's load).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Sample<F> {
    /// Kinematics at the instant.
    pub kin: Kinematics<F>,
    /// Relaxation lengths at the instant \[m\].
    pub sigma: Sigma<F>,
}

/// Most sub-steps [`Transient::step_hold`] takes in one step.
pub const MAX_SUBSTEPS: u16 = 64;

/// Largest change of the decay rate a = V/σ that one sub-step of [`Transient::step_hold`]
/// takes with a held, as a fraction of a (times min(1, a·h): a slow decay barely feels it). The
/// local error of the held rate is about half of it in the slip where the state follows its
/// input closely, and less elsewhere. 2 %: at 100 Hz with Fz ±30 % at 8 Hz, the error against a
/// 10 kHz run is 3.3e-3 of the Fy swing at 10 m/s (3.1e-3 with 0.5 %), nearly all of it the
/// straight line between samples of the load itself (see the tests).
pub const HOLD_REL_STEP: f64 = 0.02;

/// What happened during a step (a bit set).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StepFlags(pub u8);

impl StepFlags {
    /// σ was raised to `sigma_min`.
    pub const SIGMA_FLOOR: StepFlags = StepFlags(1);
    /// The lateral state was clamped to `max_tan_alpha`.
    pub const ALPHA_CLAMPED: StepFlags = StepFlags(2);
    /// The longitudinal state was clamped to `max_kappa`.
    pub const KAPPA_CLAMPED: StepFlags = StepFlags(4);
    /// Low-speed damping was active.
    pub const LOW_SPEED: StepFlags = StepFlags(8);
    /// Are all bits of `o` set?
    pub const fn contains(self, o: StepFlags) -> bool {
        self.0 & o.0 == o.0
    }
}

/// Transient slips after a step.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Slips<F> {
    /// κ' \[-\]: longitudinal deflection gradient, the κ input of the Magic Formula.
    pub kappa: F,
    /// α' \[rad\]: lateral deflection angle (21), the α input of the Magic Formula.
    pub alpha: F,
    /// What was clamped or damped.
    pub flags: StepFlags,
}

/// Why a step was refused (the state is left unchanged).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum StepError {
    /// An input was NaN or infinite.
    NonFinite,
    /// The step was ≤ 0 or longer than [`MAX_DT`].
    BadStep,
}

impl core::fmt::Display for StepError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            StepError::NonFinite => f.write_str("non-finite input to the transient step"),
            StepError::BadStep => f.write_str("time step must be in (0, 1] s"),
        }
    }
}

impl core::error::Error for StepError {}

/// Longest step accepted \[s\].
pub const MAX_DT: f64 = 1.0;

/// The deflection states of one tyre: lateral v and longitudinal u \[m\].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Transient<F> {
    /// Lateral deflection of the contact patch's leading edge v \[m\], eq. (20).
    pub v: F,
    /// Longitudinal deflection u \[m\].
    pub u: F,
}

/// φ1(x) = (1 − e^(−x))/x for x ≥ 0, with φ1(0) = 1; a 4-term series below 1e-3 where the
/// closed form loses digits.
fn phi1<F: Float, M: Backend<F>>(x: F) -> F {
    if x < F::from_f64(1e-3) {
        // 1 − x/2 + x²/6 − x³/24
        F::ONE - x * (F::HALF - x * (F::from_f64(1.0 / 6.0) - x * F::from_f64(1.0 / 24.0)))
    } else {
        (F::ONE - M::exp(-x)) / x
    }
}

/// e^(−x), φ1(x) and ψ(x) = (1 − (1 + x)·e^(−x))/x² for x ≥ 0: the decay and the weights of a
/// forcing that is linear over a step (see [`Transient::step_hold`]); φ1 and ψ by their Taylor
/// series (to x⁷, truncation below 2e-9) under x = 0.25, where the closed forms lose digits in
/// f32.
fn hold_weights<F: Float, M: Backend<F>>(x: F) -> (F, F, F) {
    let e = M::exp(-x);
    if x < F::from_f64(0.25) {
        // Horner from the highest power down.
        let mut p1 = F::ZERO;
        let mut ps = F::ZERO;
        for (c1, cs) in PHI1_SERIES.iter().zip(PSI_SERIES.iter()).rev() {
            p1 = F::from_f64(*c1) - x * p1;
            ps = F::from_f64(*cs) - x * ps;
        }
        (e, p1, ps)
    } else {
        (e, (F::ONE - e) / x, (F::ONE - (F::ONE + x) * e) / (x * x))
    }
}

/// φ1(x) = Σ (−x)^k/(k+1)!: coefficients 1/(k+1)!, k = 0..7.
const PHI1_SERIES: [f64; 8] = [
    1.0,
    1.0 / 2.0,
    1.0 / 6.0,
    1.0 / 24.0,
    1.0 / 120.0,
    1.0 / 720.0,
    1.0 / 5040.0,
    1.0 / 40320.0,
];

/// ψ(x) = Σ (−x)^k·(k+1)/(k+2)!: coefficients (k+1)/(k+2)!, k = 0..7.
const PSI_SERIES: [f64; 8] = [
    1.0 / 2.0,
    2.0 / 6.0,
    3.0 / 24.0,
    4.0 / 120.0,
    5.0 / 720.0,
    6.0 / 5040.0,
    7.0 / 40320.0,
    8.0 / 362880.0,
];

/// One exact step of dy/dt = −a·y + b over h (a ≥ 0).
fn exact_step<F: Float, M: Backend<F>>(y: F, a: F, b: F, h: F) -> F {
    let x = a * h;
    y * M::exp(-x) + b * h * phi1::<F, M>(x)
}

/// Checks a step's inputs: all finite, 0 < dt ≤ [`MAX_DT`].
fn check_step<F: Float>(dt: F, inputs: &[F]) -> Result<(), StepError> {
    if !(dt.is_finite() && inputs.iter().all(|x| x.is_finite())) {
        return Err(StepError::NonFinite);
    }
    if dt <= F::ZERO || dt > F::from_f64(MAX_DT) {
        return Err(StepError::BadStep);
    }
    Ok(())
}

impl<F: Float> Config<F> {
    /// |σ| with the floor `sigma_min` (flagged).
    fn floor(&self, s: F, flags: &mut StepFlags) -> F {
        let s = s.abs();
        if s < self.sigma_min {
            flags.0 |= StepFlags::SIGMA_FLOOR.0;
            self.sigma_min.max(F::from_f64(1e-6))
        } else {
            s
        }
    }

    /// The damping speed of eq. (20) for kinematics `k`.
    fn speed(&self, k: &Kinematics<F>) -> F {
        match self.damping {
            DampingSpeed::Rolling => (k.vx - k.vsx).abs(),
            DampingSpeed::Forward => k.vx.abs(),
        }
    }

    /// The deflections clamped to `max_tan_alpha·σα`, `max_kappa·σκ` (flagged).
    fn clamp(&self, v: F, u: F, s_a: F, s_k: F, flags: &mut StepFlags) -> (F, F) {
        let (v_max, u_max) = (self.max_tan_alpha * s_a, self.max_kappa * s_k);
        let (v, fv) = v.clamp_flag(-v_max, v_max);
        let (u, fu) = u.clamp_flag(-u_max, u_max);
        if fv.any() {
            flags.0 |= StepFlags::ALPHA_CLAMPED.0;
        }
        if fu.any() {
            flags.0 |= StepFlags::KAPPA_CLAMPED.0;
        }
        (v, u)
    }

    /// α', κ' of eq. (21) from the deflections and σ, with the low-speed damping (Pacejka's
    /// kVlow, faded in below VXLOW) of kinematics `k`.
    fn slips<M: Backend<F>>(
        &self,
        v: F,
        u: F,
        s_a: F,
        s_k: F,
        k: &Kinematics<F>,
        mut flags: StepFlags,
    ) -> Slips<F> {
        let mut tan_a = v / s_a; // (21)
        let mut kappa = u / s_k;
        if self.damp_vlow > F::ZERO && self.vxlow > F::ZERO && k.vx.abs() < self.vxlow {
            let w = F::HALF * (F::ONE + M::cos(F::PI * k.vx.abs() / self.vxlow));
            tan_a += self.damp_vlow * w * k.vsy / s_a;
            kappa -= self.damp_vlow * w * k.vsx / s_k;
            flags.0 |= StepFlags::LOW_SPEED.0;
        }
        Slips {
            kappa,
            alpha: M::atan(tan_a),
            flags,
        }
    }
}

impl<F: Float> Transient<F> {
    /// At rest, undeflected.
    pub const fn new(zero: F) -> Self {
        Transient { v: zero, u: zero }
    }

    /// The steady state of constant slips κ and tan α with relaxation lengths `sigma`: the
    /// deflections v = σα·tan α, u = σκ·κ that eq. (20) settles on, with σ floored and the
    /// deflections clamped as [`Transient::step`] floors and clamps them (so that a step with
    /// the same inputs stays there).
    pub fn steady(cfg: &Config<F>, sigma: &Sigma<F>, kappa: F, tan_alpha: F) -> Self {
        let mut flags = StepFlags::default();
        let s_a = cfg.floor(sigma.sigma_alpha, &mut flags);
        let s_k = cfg.floor(sigma.sigma_kappa, &mut flags);
        let (v, u) = cfg.clamp(s_a * tan_alpha, s_k * kappa, s_a, s_k, &mut flags);
        Transient { v, u }
    }

    /// Advances the states by `dt` \[s\] with the kinematics and relaxation lengths held over the
    /// step (eq. 20, exact), and returns α', κ' (eq. 21) with the low-speed damping added.
    pub fn step<M: Backend<F>>(
        &mut self,
        cfg: &Config<F>,
        dt: F,
        k: &Kinematics<F>,
        sigma: &Sigma<F>,
    ) -> Result<Slips<F>, StepError> {
        check_step(
            dt,
            &[k.vx, k.vsx, k.vsy, sigma.sigma_alpha, sigma.sigma_kappa],
        )?;
        let mut flags = StepFlags::default();
        let s_a = cfg.floor(sigma.sigma_alpha, &mut flags);
        let s_k = cfg.floor(sigma.sigma_kappa, &mut flags);
        let speed = cfg.speed(k);
        // (20): dv/dt = −(Vr/σα)·v + Vsy;  du/dt = −(Vr/σκ)·u − Vsx.
        let v = exact_step::<F, M>(self.v, speed / s_a, k.vsy, dt);
        let u = exact_step::<F, M>(self.u, speed / s_k, -k.vsx, dt);
        let (v, u) = cfg.clamp(v, u, s_a, s_k, &mut flags);
        self.v = v;
        self.u = u;
        Ok(cfg.slips::<M>(v, u, s_a, s_k, k, flags))
    }
}

impl<F: Float> Transient<F> {
    /// Advances the states by `dt` \[s\] with every input of eq. (20) **linear in time** between
    /// its values at the step's start `s0` and end `s1` (a first-order hold: the kinematics, the
    /// relaxation lengths and with them the damping speed and the decay rate a = V/σ), and
    /// returns α', κ' of eq. (21) at the end, formed with the end's own σ.
    ///
    /// Within a sub-step the forcing (Vsy, −Vsx) is linear and solved exactly,
    /// `v(h) = v·e^(−x) + h·(b0·ψ(x) + b1·(φ1(x) − ψ(x)))`, x = ā·h, with the decay rate ā at the
    /// sub-step's midpoint (exponential midpoint rule: second order in the variation of a). The
    /// step is split into n ≤ [`MAX_SUBSTEPS`] equal sub-steps so that a changes by at most
    /// [`HOLD_REL_STEP`] of itself per sub-step (weighted by min(1, a·h)): where the load, and
    /// so σ, moves faster than the step resolves. Constant inputs give [`Transient::step`]'s state
    /// up to rounding (one sub-step; the two weights sum to φ1). The clamps of [`Config`] apply after each
    /// sub-step with that instant's σ; the low-speed damping uses the end's kinematics.
    pub fn step_hold<M: Backend<F>>(
        &mut self,
        cfg: &Config<F>,
        dt: F,
        s0: &Sample<F>,
        s1: &Sample<F>,
    ) -> Result<Slips<F>, StepError> {
        check_step(
            dt,
            &[
                s0.kin.vx,
                s0.kin.vsx,
                s0.kin.vsy,
                s0.sigma.sigma_alpha,
                s0.sigma.sigma_kappa,
                s1.kin.vx,
                s1.kin.vsx,
                s1.kin.vsy,
                s1.sigma.sigma_alpha,
                s1.sigma.sigma_kappa,
            ],
        )?;
        let mut flags = StepFlags::default();
        let (sa0, sk0) = (
            cfg.floor(s0.sigma.sigma_alpha, &mut flags),
            cfg.floor(s0.sigma.sigma_kappa, &mut flags),
        );
        let (sa1, sk1) = (
            cfg.floor(s1.sigma.sigma_alpha, &mut flags),
            cfg.floor(s1.sigma.sigma_kappa, &mut flags),
        );
        let (v0, v1) = (cfg.speed(&s0.kin), cfg.speed(&s1.kin));
        // Sub-steps: relative change of each decay rate over the step, weighted by min(1, a·h).
        let rel = |s_0: F, s_1: F| {
            let (a0, a1) = (v0 / s_0, v1 / s_1);
            let amax = a0.max(a1);
            if amax > F::ZERO {
                (a1 - a0).abs() / amax * (amax * dt).min(F::ONE)
            } else {
                F::ZERO
            }
        };
        let r = rel(sa0, sa1).max(rel(sk0, sk1));
        let n_max = MAX_SUBSTEPS;
        // ⌈r / HOLD_REL_STEP⌉ in 1..=MAX_SUBSTEPS, without a float-to-int cast of r itself.
        let n = (r / F::from_f64(HOLD_REL_STEP)).floor_index(usize::from(n_max - 1)) as u16 + 1;
        let nf = F::from_index(n);
        let h = dt / nf;
        let lin = |x0: F, x1: F, w: F| x0 + w * (x1 - x0);
        let (mut v, mut u) = (self.v, self.u);
        let mut j = 0u16;
        while j < n {
            let (wa, wb) = (F::from_index(j) / nf, F::from_index(j + 1) / nf);
            let wm = F::HALF * (wa + wb);
            let sp = lin(v0, v1, wm);
            let (sa_m, sk_m) = (lin(sa0, sa1, wm), lin(sk0, sk1, wm));
            let (sa_b, sk_b) = (lin(sa0, sa1, wb), lin(sk0, sk1, wb));
            // (20): dv/dt = −(Vr/σα)·v + Vsy;  du/dt = −(Vr/σκ)·u − Vsx; forcing linear in t.
            let (ea, p1a, psa) = hold_weights::<F, M>(sp / sa_m * h);
            let (ek, p1k, psk) = hold_weights::<F, M>(sp / sk_m * h);
            let (by0, by1) = (
                lin(s0.kin.vsy, s1.kin.vsy, wa),
                lin(s0.kin.vsy, s1.kin.vsy, wb),
            );
            let (bx0, bx1) = (
                -lin(s0.kin.vsx, s1.kin.vsx, wa),
                -lin(s0.kin.vsx, s1.kin.vsx, wb),
            );
            (v, u) = cfg.clamp(
                v * ea + h * (by0 * psa + by1 * (p1a - psa)),
                u * ek + h * (bx0 * psk + bx1 * (p1k - psk)),
                sa_b,
                sk_b,
                &mut flags,
            );
            j += 1;
        }
        self.v = v;
        self.u = u;
        // (21) at the end's own σ.
        Ok(cfg.slips::<M>(v, u, sa1, sk1, &s1.kin, flags))
    }
}

/// Slip-dependent decay of a relaxation length (paper, ref. \[8\]): σ is adapted so that the
/// deflection stays equal to the force over the carcass stiffness, i.e. σ = σ0·|F|/|K·s| where s
/// is the transient slip (tan α' or κ') and F the force it produced, K the slip stiffness at zero
/// slip. Equals σ0 at small slip and decays as the force saturates; never above σ0, never
/// negative. Apply between steps with the previous step's force.
pub fn decayed_sigma<F: Float>(sigma0: F, force: F, stiffness: F, slip: F) -> F {
    let lin = (stiffness * slip).abs();
    if lin <= force.abs() || lin == F::ZERO {
        sigma0
    } else {
        sigma0 * force.abs() / lin
    }
}

/// A tyre with transient slip: the states of eq. (20), then the Magic Formula at (α', κ') — the
/// one composition of the filter and the model, which the per-wheel pipeline
/// (`wheel::Corner`), the host's vehicle simulation and its gap diagnosis run.
///
/// One Magic Formula evaluation per step ([`TransientTyre::step`]); the relaxation lengths of a
/// step are those the previous step's evaluation returned (σ varies with Fz, which changes
/// little over one short step), on the first step σ at the step's load and zero slip. With
/// [`TransientTyre::hold`] the step is a first-order hold between the previous operating point
/// and this one, with σ at both ends (for steps over which the load moves). A caller with σ of
/// its own at both ends steps with [`TransientTyre::step_between`]. It starts undeflected
/// ([`TransientTyre::new`]) or in the steady state of given slips ([`TransientTyre::start`],
/// [`TransientTyre::restart`]).
#[derive(Debug, Clone)]
pub struct TransientTyre<F> {
    /// Deflection states.
    pub state: Transient<F>,
    /// Configuration.
    pub config: Config<F>,
    /// Apply [`decayed_sigma`] (paper ref. \[8\]) between steps.
    pub slip_decay: bool,
    /// Step with [`Transient::step_hold`]: the operating point of the previous step and of this
    /// one are the two ends of a first-order hold, σ at this step's end is evaluated at its load
    /// (one more Magic Formula evaluation per step), and α', κ' are formed with it. Off: the
    /// inputs are held over the step with the previous step's σ ([`Transient::step`]).
    pub hold: bool,
    /// σ the next step starts from: the last evaluation's (decayed with `slip_decay`); `None`
    /// before the first step.
    sigma: Option<Sigma<F>>,
    /// The last step's kinematics (the start of a first-order hold).
    last_kin: Option<Kinematics<F>>,
}

/// Operating point of a transient step: the kinematics plus the load, camber, turn slip and
/// pressure.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Operating<F> {
    /// Wheel kinematics.
    pub kin: Kinematics<F>,
    /// Vertical load Fz \[N\].
    pub fz: F,
    /// Inclination γ \[rad\].
    pub gamma: F,
    /// Turn slip φt \[1/m\] (used only with `Options::turn_slip`).
    pub phit: F,
    /// Inflation pressure \[Pa\] (`None`: INFLPRES).
    pub p: Option<F>,
}

impl<F: Float> Operating<F> {
    /// The Magic Formula's input at this point with slips κ, α.
    fn input(&self, kappa: F, alpha: F) -> Input<F> {
        Input {
            fz: self.fz,
            kappa,
            alpha,
            gamma: self.gamma,
            phit: self.phit,
            vx: self.kin.vx,
            p: self.p,
        }
    }
}

/// Why a transient-tyre step failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum TyreError {
    /// The transient step refused its input.
    Step(StepError),
    /// The Magic Formula refused its input.
    Eval(EvalError),
}

impl core::fmt::Display for TyreError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            TyreError::Step(e) => write!(f, "relaxation step: {e}"),
            TyreError::Eval(e) => write!(f, "Magic Formula: {e}"),
        }
    }
}

impl core::error::Error for TyreError {}

/// The relaxation lengths an evaluation gives.
fn sigma_of<F: Float>(o: &Output<F>) -> Sigma<F> {
    Sigma {
        sigma_kappa: o.sigma_x,
        sigma_alpha: o.sigma_y,
    }
}

impl<F: Float> TransientTyre<F> {
    /// Undeflected tyre with the parameter set's defaults.
    pub fn new(p: &Params<F>) -> Self {
        TransientTyre {
            state: Transient::new(F::ZERO),
            config: Config::from_params(p),
            slip_decay: false,
            hold: false,
            sigma: None,
            last_kin: None,
        }
    }

    /// σ the next step starts from, if any step or start has run.
    pub fn sigma(&self) -> Option<Sigma<F>> {
        self.sigma
    }

    /// Sets the deflections to the steady state of slips κ, tan α with relaxation lengths
    /// `sigma` ([`Transient::steady`]), and `sigma` as the next step's σ.
    pub fn restart(&mut self, sigma: Sigma<F>, kappa: F, tan_alpha: F) {
        self.state = Transient::steady(&self.config, &sigma, kappa, tan_alpha);
        self.sigma = Some(sigma);
    }

    /// Starts in the steady state of slips κ, α at `op`: the Magic Formula there with `opts`
    /// (the steady-state answer), and the deflections that give it ([`TransientTyre::restart`]
    /// with the evaluation's σ). Nothing changes on an error.
    pub fn start<M: Backend<F>>(
        &mut self,
        p: &Params<F>,
        opts: &Options,
        op: &Operating<F>,
        kappa: F,
        alpha: F,
    ) -> Result<Output<F>, TyreError> {
        let out = mf::eval::<F, M>(p, &op.input(kappa, alpha), opts).map_err(TyreError::Eval)?;
        self.restart(sigma_of(&out), kappa, M::tan(alpha));
        self.last_kin = Some(op.kin);
        Ok(out)
    }

    /// Advances by `dt` \[s\] to `op` and evaluates the Magic Formula at the transient slips:
    /// the output and the slips it was evaluated at. Nothing changes on an error.
    pub fn step<M: Backend<F>>(
        &mut self,
        p: &Params<F>,
        opts: &Options,
        dt: F,
        op: &Operating<F>,
    ) -> Result<(Output<F>, Slips<F>), TyreError> {
        // σ at this sample's load and zero slip (the relaxation lengths depend on the load only).
        let zero_slip = || -> Result<Sigma<F>, TyreError> {
            let input = Input {
                phit: F::ZERO,
                ..op.input(F::ZERO, F::ZERO)
            };
            let o = mf::eval::<F, M>(p, &input, opts).map_err(TyreError::Eval)?;
            Ok(sigma_of(&o))
        };
        let sigma = match self.sigma {
            Some(s) => s,
            // First step: σ at this load, zero slip.
            None => zero_slip()?,
        };
        let mut state = self.state;
        let s = if self.hold {
            // The end's σ; on the first step that is `sigma` itself (evaluated once).
            let s1 = Sample {
                kin: op.kin,
                sigma: if self.sigma.is_some() {
                    zero_slip()?
                } else {
                    sigma
                },
            };
            let s0 = Sample {
                kin: self.last_kin.unwrap_or(op.kin),
                sigma,
            };
            state.step_hold::<M>(&self.config, dt, &s0, &s1)
        } else {
            state.step::<M>(&self.config, dt, &op.kin, &sigma)
        }
        .map_err(TyreError::Step)?;
        self.eval_commit::<M>(p, opts, op, state, s)
    }

    /// [`TransientTyre::step`] with the caller's relaxation lengths: a first-order hold
    /// ([`Transient::step_hold`]) from `s0` (the previous step's end) to `s1` (this one's, at
    /// `op`), then the Magic Formula at the slips. Nothing changes on an error.
    pub fn step_between<M: Backend<F>>(
        &mut self,
        p: &Params<F>,
        opts: &Options,
        dt: F,
        s0: &Sample<F>,
        s1: &Sample<F>,
        op: &Operating<F>,
    ) -> Result<(Output<F>, Slips<F>), TyreError> {
        let mut state = self.state;
        let s = state
            .step_hold::<M>(&self.config, dt, s0, s1)
            .map_err(TyreError::Step)?;
        self.eval_commit::<M>(p, opts, op, state, s)
    }

    /// The Magic Formula at the slips `s` of the new deflections `state`; on success the tyre
    /// moves on to them, with the evaluation's σ (decayed with `slip_decay`) for the next step.
    fn eval_commit<M: Backend<F>>(
        &mut self,
        p: &Params<F>,
        opts: &Options,
        op: &Operating<F>,
        state: Transient<F>,
        s: Slips<F>,
    ) -> Result<(Output<F>, Slips<F>), TyreError> {
        let out =
            mf::eval::<F, M>(p, &op.input(s.kappa, s.alpha), opts).map_err(TyreError::Eval)?;
        let mut next = sigma_of(&out);
        if self.slip_decay {
            next.sigma_kappa = decayed_sigma(out.sigma_x, out.fx, out.k_xk, s.kappa);
            next.sigma_alpha = decayed_sigma(out.sigma_y, out.fy, out.k_ya, M::tan(s.alpha));
        }
        self.state = state;
        self.sigma = Some(next);
        self.last_kin = Some(op.kin);
        Ok((out, s))
    }
}

#[cfg(test)]
mod tests;
