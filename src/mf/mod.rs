//! Magic Formula steady-state tyre forces and moments: Delft Tyre 96, MF-Tyre 5.2, MF 6.1/6.2.
//!
//! One entry point, [`eval`], computes in book order (the order of MFeval's `Solver.m`, and of
//! the paper's appendix): conditioning of the inputs (`limits`) → `fx0` → `fy0` → `mz0`
//! intermediates (`pure`) → `fx` → `fy` (`combined`) → `mx` → `my` (`moments`) → `mz`
//! (`combined`) → relaxation lengths (`sigma`). Turn slip ([`turnslip`]) is an option. The
//! stage modules are the crate's own (`pure`, `limits`, `moments`, `sigma`); the equation map
//! below says where each equation is.
//!
//! [`eval`] runs in stages ([`prepared`]): the load stage (everything that depends on Fz, γ, p,
//! Vx and the scalings), the friction stage (λμ) and the slip stage (κ, α); [`prepared::Prepared`]
//! keeps the first two for many evaluations at one load, with derivatives in κ, α and λμ.
//!
//! ## Axes, units, signs
//! ISO-W (TYDEX W) at the contact point, SI units, angles in radians: α > 0 gives Fy < 0 and
//! (below the peak) Mz > 0; κ > 0 (driving) gives Fx > 0; κ = −1 is a locked wheel; γ > 0 tilts
//! the top of the wheel to the left (+y).
//!
//! ## Equation map
//! | quantity | paper (Delft Tyre 96, appendix) | MF 5.2 / 6.1 (Pacejka 2006, ch. 4; Besselink 2010) | fn |
//! |---|---|---|---|
//! | Fx0 | (22)–(31) | (4.E9)–(4.E18) | `pure::fx0_load`, `pure::fx0_mu`, `pure::fx0_slip` |
//! | Fy0 | (32)–(42) | (4.E19)–(4.E30) | `pure::fy0_load`, `pure::fy0_mu`, `pure::fy0_slip` |
//! | t, Mzr (pure) | (43)–(56), reconstructed | (4.E31)–(4.E49), (A58), (A60) | `pure::mz0_load`, `pure::mz0_mu` |
//! | Fx | (57)–(62), reconstructed | (4.E50)–(4.E57) | `combined::fx_slip` |
//! | Fy | (13)–(16), (63)–(68) | (4.E58)–(4.E67) | `combined::fy_slip` |
//! | Mz | (17), (18), (69)–(75) | (4.E71)–(4.E78), (A54)–(A56) | `combined::mz_slip` |
//! | Mx, My | — (MF 5.2 forms) | (A47)/(49 draft), (A48) | `moments::mx`, `moments::my` |
//! | σx, σy | — (MF 5.2 forms) | Besselink eqs. (17)–(19) | `sigma::sigma` |
//!
//! The scan of the paper is damaged in eqs. 43–68; those equations are reconstructed from the
//! body's eqs. (7)–(18) and from MF 5.2, which grew out of Delft Tyre 96. Each reconstruction is
//! marked `RECONSTRUCTED` where it is coded.
//!
//! ## What this module leaves out
//! The vertical model (loaded radius, contact patch, Fz from deflection) and the MF 6.2
//! loaded-radius search: Fz is an input here. Transient behaviour is in the `relax` module.

mod batch;
pub(crate) mod combined;
pub(crate) mod limits;
pub(crate) mod moments;
mod params;
pub mod prepared;
pub(crate) mod pure;
pub(crate) mod sigma;
pub mod turnslip;

pub use batch::{
    eval_batch, eval_batch_lanes, eval_batch_lanes_on, eval_batch_lanes_scaled, BatchError,
    Columns, Isa, Outputs, Scales,
};
pub use params::{Key, Need, Params, Side, Since, Version, IGNORED_KEYS};
pub use sigma::relaxation_lengths;

use crate::math::{Backend, Float, Mask, Real};
use core::ops::Mul;

/// Small number of the book's signed singularity guards, ε in (4.E6a), (4.E16), (4.E26),
/// (4.E39) ("ε is a small number ... explained on page 177"); the same value as MFeval and the
/// TNO manuals (1e-6, in the unit of the guarded quantity: m/s, N, N/rad).
pub const EPS: f64 = 1e-6;

/// Operating point of one tyre. SI units, ISO-W axes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Input<F> {
    /// Vertical load Fz \[N\], ≥ 0 in contact; Fz ≤ 0 means no contact (all outputs zero).
    pub fz: F,
    /// Longitudinal slip κ \[-\]: −1 locked wheel, 0 free rolling, > 0 driving.
    pub kappa: F,
    /// Slip angle α \[rad\], ISO-W: α > 0 gives Fy < 0.
    pub alpha: F,
    /// Inclination (camber) angle γ \[rad\].
    pub gamma: F,
    /// Turn slip φt \[1/m\] (path curvature at zero slip angle); used only with turn slip on.
    pub phit: F,
    /// Longitudinal speed of the wheel centre Vx \[m/s\]; < 0 runs backwards.
    pub vx: F,
    /// Inflation pressure p \[Pa\]; `None` takes `INFLPRES` from the parameter set. Used by MF 6.x.
    pub p: Option<F>,
}

/// Evaluation options. The default is TNO-like: limits checked, α* off, no turn slip, no
/// mirroring (MFeval useMode 111).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Options {
    /// Clip Fz, κ, α, γ, p to the parameter set's ranges (FZMAX, KPUMIN/KPUMAX, ALPMIN/ALPMAX,
    /// CAMMIN/CAMMAX, PRESMIN/PRESMAX), apply the low-speed reductions below VXLOW and clip the
    /// curvature factors E to ≤ 1. Each clip sets a flag in [`Output::flags`].
    pub limits: bool,
    /// Use α* = tan(α)·sign(Vx) and γ* = sin(γ) (Pacejka (4.E3), (4.E4)) instead of α and γ.
    pub alpha_star: bool,
    /// Evaluate turn slip (MF 6.x only; needs the `[TURNSLIP_COEFFICIENTS]`).
    pub turn_slip: bool,
    /// Side of the vehicle the tyre is mounted on. When it differs from the file's `TYRESIDE`,
    /// the tyre is mirrored: α, γ, φt change sign on the way in, Fy, Mx, Mz, Mzr on the way out.
    /// `None`: never mirror.
    pub mounted: Option<Side>,
    /// The slips come from a transient model ([`crate::relax`]): skip the steady-state
    /// low-speed reductions of κ and α (the transient model's own damping handles standstill),
    /// as TNO's and MFeval's dynamic modes do.
    pub transient: bool,
    /// Evaluate the overturning and rolling resistance moments Mx, My (on by default). Off,
    /// [`Output::mx`] and [`Output::my`] are 0 and an evaluation is the combined Fx, Fy, Mz
    /// (with μ, K, t, Mzr, σ) alone: what a friction or stability controller needs, at about
    /// a quarter less cost on the device.
    pub moments: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            limits: true,
            alpha_star: false,
            turn_slip: false,
            mounted: None,
            transient: false,
            moments: true,
        }
    }
}

impl Options {
    /// Options from MFeval's three-digit `useMode`: hundreds 1 = limits, 2 = no limits; tens
    /// 1 = α* off, 2 = α* on; units 1 = no turn slip, 2 = turn slip. `None` for other numbers.
    pub const fn from_use_mode(use_mode: u16) -> Option<Options> {
        let limits = match use_mode / 100 {
            1 => true,
            2 => false,
            _ => return None,
        };
        let alpha_star = match (use_mode / 10) % 10 {
            1 => false,
            2 => true,
            _ => return None,
        };
        let turn_slip = match use_mode % 10 {
            1 => false,
            2 => true,
            _ => return None,
        };
        Some(Options {
            limits,
            alpha_star,
            turn_slip,
            mounted: None,
            transient: false,
            moments: true,
        })
    }
}

/// Which inputs were clipped or regularised during an evaluation (a bit set).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Flags(pub u16);

impl Flags {
    /// Fz was above FZMAX and was clipped.
    pub const FZ_HIGH: Flags = Flags(1 << 0);
    /// Fz was below FZMIN: the aligning-torque and moment terms used FZMIN / the low-load
    /// reductions (forces still use Fz).
    pub const FZ_LOW: Flags = Flags(1 << 1);
    /// Fz ≤ 0: no contact, every output is zero.
    pub const NO_CONTACT: Flags = Flags(1 << 2);
    /// κ was outside KPUMIN..KPUMAX and was clipped.
    pub const KAPPA: Flags = Flags(1 << 3);
    /// α was outside ALPMIN..ALPMAX and was clipped.
    pub const ALPHA: Flags = Flags(1 << 4);
    /// γ was outside CAMMIN..CAMMAX and was clipped.
    pub const GAMMA: Flags = Flags(1 << 5);
    /// p was outside PRESMIN..PRESMAX and was clipped.
    pub const PRESSURE: Flags = Flags(1 << 6);
    /// |Vx| ≤ VXLOW: low-speed reductions were applied.
    pub const LOW_SPEED: Flags = Flags(1 << 7);
    /// A curvature factor E (Ex, Ey, Et, Exα, Eyκ, EHyp) exceeded 1 and was clipped to 1.
    pub const E_CLIPPED: Flags = Flags(1 << 8);
    /// Vx < 0: the tyre runs backwards.
    pub const REVERSE: Flags = Flags(1 << 9);
    /// The result was mirrored (mounted side differs from TYRESIDE).
    pub const MIRRORED: Flags = Flags(1 << 10);
    /// A regularisation beyond the ε guards acted: a combined-slip weighting function's
    /// denominator G0 vanished, a turn-slip moment was patched, or the effective rolling
    /// radius iteration did not converge. The output is finite but outside the model's range.
    pub const GUARD: Flags = Flags(1 << 11);

    /// Are all bits of `other` set?
    pub const fn contains(self, other: Flags) -> bool {
        self.0 & other.0 == other.0
    }
    /// Sets the bits of `other`.
    pub fn insert(&mut self, other: Flags) {
        self.0 |= other.0;
    }
    /// Sets the bits of `other` when `cond` holds.
    pub fn set_if(&mut self, other: Flags, cond: bool) {
        if cond {
            self.0 |= other.0;
        }
    }
    /// No bit set.
    pub const fn is_empty(self) -> bool {
        self.0 == 0
    }
}

/// The flags an evaluation raises, as the generic formula sets them: [`Flags`] itself for one
/// point (the mask a `bool`), one [`Flags`] per lane for [`crate::math::Lanes`].
pub trait FlagSet<M>: Copy + Default + PartialEq + core::fmt::Debug {
    /// Sets the bits of `other` (in every lane).
    fn insert(&mut self, other: Flags);
    /// Sets the bits of `other` where `m` holds.
    fn set_if(&mut self, other: Flags, m: M);
    /// Sets the bits set in `other` (lane by lane).
    fn merge(&mut self, other: Self);
}

impl FlagSet<bool> for Flags {
    #[inline(always)]
    fn insert(&mut self, other: Flags) {
        self.0 |= other.0;
    }
    #[inline(always)]
    fn set_if(&mut self, other: Flags, m: bool) {
        if m {
            self.0 |= other.0;
        }
    }
    #[inline(always)]
    fn merge(&mut self, other: Flags) {
        self.0 |= other.0;
    }
}

/// Forces, moments and the intermediate quantities users look at. ISO-W, SI. (`L` is the
/// flags' type: [`Flags`]; one set per lane where the crate evaluates lanes.)
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Output<F, L = Flags> {
    /// Longitudinal force Fx \[N\]; κ > 0 gives Fx > 0.
    pub fx: F,
    /// Lateral force Fy \[N\]; α > 0 gives Fy < 0.
    pub fy: F,
    /// Vertical load used \[N\] (after clipping to FZMAX when limits are on).
    pub fz: F,
    /// Overturning moment Mx \[N·m\].
    pub mx: F,
    /// Rolling resistance moment My \[N·m\] (negative when rolling forwards).
    pub my: F,
    /// Aligning moment Mz \[N·m\]; α > 0 gives Mz > 0 below the peak.
    pub mz: F,
    /// Longitudinal peak friction coefficient μx \[-\] (4.E13), at the actual load/pressure/camber.
    pub mu_x: F,
    /// Lateral peak friction coefficient μy \[-\] (4.E23), as a magnitude (files that fit with
    /// negative PDY1 carry the sign in Dy instead).
    pub mu_y: F,
    /// Longitudinal slip stiffness Kxκ \[N\] (4.E15), ∂Fx0/∂κ at κx = 0.
    pub k_xk: F,
    /// Cornering stiffness Kyα \[N/rad\] (4.E25), ∂Fy0/∂α at αy = 0 (negative in ISO-W files).
    pub k_ya: F,
    /// Pneumatic trail t \[m\] (4.E73), at the combined-slip equivalent angle.
    pub t: F,
    /// Residual aligning torque Mzr \[N·m\] (4.E75).
    pub m_zr: F,
    /// Longitudinal relaxation length σx \[m\] (0 when the file gives no carcass stiffness).
    pub sigma_x: F,
    /// Lateral relaxation length σy \[m\] (0 when the file gives no carcass stiffness).
    pub sigma_y: F,
    /// κ after the low-speed reduction (as MFeval's `out_kappa`) \[-\].
    pub kappa: F,
    /// What was clipped or regularised.
    pub flags: L,
}

/// Which input was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum InputField {
    /// `fz`
    Fz,
    /// `kappa`
    Kappa,
    /// `alpha`
    Alpha,
    /// `gamma`
    Gamma,
    /// `phit`
    Phit,
    /// `vx`
    Vx,
    /// `p`
    P,
}

/// Why an evaluation produced no result. Nothing is computed from a rejected input.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum EvalError {
    /// An input was NaN or infinite.
    NonFinite(InputField),
    /// The inflation pressure was ≤ 0.
    NonPositivePressure,
    /// Turn slip was requested but the version is not MF 6.x or the file has no
    /// `[TURNSLIP_COEFFICIENTS]`.
    TurnSlipUnavailable,
    /// The inputs were finite but so far outside the model's range (limits off) that a result
    /// overflowed; no partial result is returned.
    Overflow,
}

impl core::fmt::Display for EvalError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            EvalError::NonFinite(field) => write!(f, "input {field:?} is not finite"),
            EvalError::NonPositivePressure => f.write_str("inflation pressure must be > 0"),
            EvalError::TurnSlipUnavailable => {
                f.write_str("turn slip needs an MF 6.x file with [TURNSLIP_COEFFICIENTS]")
            }
            EvalError::Overflow => f.write_str("result overflowed: inputs far outside the model"),
        }
    }
}

impl core::error::Error for EvalError {}

/// Evaluates the steady-state Magic Formula of `p.version` at one operating point.
///
/// `F` is the float type (f32 on the device, f64 on the host), `M` the math backend
/// ([`crate::math::Libm`] for reference accuracy). Never panics; never returns a non-finite
/// number inside `Ok`.
///
/// ```
/// use gough::{math::Libm, mf::{self, Input, Options, Params, Version}};
/// let mut p = Params::<f64>::zeroed(Version::Mf52); // a made-up tyre, for the example
/// p.fnomin = 4000.0; p.unloaded_radius = 0.3; p.longvl = 16.7; p.vxlow = 1.0;
/// p.pcy1 = 1.3; p.pdy1 = 1.0; p.pky1 = -20.0; p.pky2 = 2.0; p.pcx1 = 1.6; p.pdx1 = 1.0;
/// p.pkx1 = 20.0; p.qcz1 = 1.2; p.qbz1 = 10.0; p.qdz1 = 0.1;
/// let out = mf::eval::<f64, Libm>(
///     &p,
///     &Input { fz: 4000.0, alpha: 0.05, vx: 20.0, ..Default::default() },
///     &Options { limits: false, ..Options::default() },
/// )
/// .unwrap();
/// assert!(out.fy < 0.0 && out.mz > 0.0); // ISO-W: α > 0 → Fy < 0, Mz > 0
/// ```
// Not inlined: with the body in `eval_in`, the compiler inlined `eval` into the M4F bench's
// loop, and a combined evaluation (f32, `Fast`) counted 2,733 instructions instead of 2,407;
// as a call of its own it counts 2,411 (`cargo xtask firmware`, the `fast:` line).
#[inline(never)]
pub fn eval<F: Float, M: Backend<F>>(
    p: &Params<F>,
    input: &Input<F>,
    opts: &Options,
) -> Result<Output<F>, EvalError> {
    eval_in::<F, M>(p, input, opts)
}

/// [`eval`] in any [`Real`] — lanes ([`crate::math::Lanes`]) too, with their flags. A lane
/// type's caller keeps to what the lanes' value branches need: every lane in contact or none
/// (`mf::eval_batch_lanes` does; `prepared::stages`). An error means that some lane failed: that
/// caller evaluates the lanes again one by one to learn which and why.
#[inline(always)]
pub(crate) fn eval_in<F: Real, M: Backend<F>>(
    p: &Params<F>,
    input: &Input<F>,
    opts: &Options,
) -> Result<Output<F, F::Flags>, EvalError> {
    if opts.turn_slip && !turnslip::available(p) {
        return Err(EvalError::TurnSlipUnavailable);
    }
    limits::check_finite(input)?;
    let (c, mirrored, turn) = prepared::for_eval::<F, M>(p, input, opts)?;
    // The load stage (with turn slip: every stage's load part at this point) on locals, then
    // the slip stage: the `prepared` module's, so that its results are this function's.
    /// The friction and slip stages, Mx, My and σ at the load stage's view.
    struct Rest<'a, F: Real, M> {
        p: &'a Params<F>,
        input: &'a Input<F>,
        opts: &'a Options,
        mirrored: bool,
        backend: core::marker::PhantomData<M>,
    }
    impl<F: Real, M: Backend<F>> prepared::Then<F> for Rest<'_, F, M> {
        type Out = Result<Output<F, F::Flags>, EvalError>;
        // Inlined where the lanes run (x86_64, aarch64: else it is compiled without their
        // target features); left to the compiler on the devices, where, as a function of its
        // own, an M4F combined evaluation (f32, `Fast`) counts 2,434 instructions (2,407
        // before the lanes), inlined 2,536 (`cargo xtask firmware`, the `fast:` line).
        #[cfg_attr(any(target_arch = "x86_64", target_arch = "aarch64"), inline(always))]
        fn then(self, prep: prepared::View<'_, F>) -> Self::Out {
            let (p, input, opts, mirrored) = (self.p, self.input, self.opts, self.mirrored);
            let mu = prep.mu_stage::<F>(prep.c.lmux_star, prep.c.lmuy_star);
            // The slips were checked finite above; the results are, with the rest, below.
            let f = prep.slip::<F, F, M>(&mu, input.kappa, input.alpha);
            if !prep.contact {
                // No contact: no force, no moment (MFeval gives the same, see the `load` oracle sweep).
                return Ok(Output {
                    kappa: f.kappa,
                    flags: f.flags,
                    ..Output::default()
                });
            }
            let c = prep.c;
            let (mx, my) = if opts.moments {
                // Mx of the file's tyre (unmirrored Fy), mirrored back below.
                let fy = if mirrored { -f.fy } else { f.fy };
                let mx = moments::mx::<F, M>(p, c, fy);
                (
                    if mirrored { -mx } else { mx },
                    moments::my::<F, M>(p, c, f.fx, input.kappa),
                )
            } else {
                (F::ZERO, F::ZERO)
            };
            let (k_xk, k_ya) = (prep.fx0.k_xk, prep.fy0.k_ya);
            let (sigma_x, sigma_y) = sigma::sigma::<F, M>(p, c, k_xk, k_ya);
            let out = Output {
                fx: f.fx,
                fy: f.fy,
                fz: c.fz,
                mx,
                my,
                mz: f.mz,
                mu_x: mu.mu_x(),
                mu_y: mu.mu_y(),
                k_xk,
                k_ya,
                t: f.t,
                m_zr: f.m_zr,
                sigma_x,
                sigma_y,
                kappa: f.kappa,
                flags: f.flags,
            };
            let all = [
                out.fx,
                out.fy,
                out.mz,
                out.t,
                out.m_zr,
                out.mx,
                out.my,
                out.mu_x,
                out.mu_y,
                out.k_xk,
                out.k_ya,
                out.sigma_x,
                out.sigma_y,
            ];
            if F::all_finite(&all) {
                Ok(out)
            } else {
                Err(EvalError::Overflow)
            }
        }
    }
    let rest = Rest::<F, M> {
        p,
        input,
        opts,
        mirrored,
        backend: core::marker::PhantomData,
    };
    prepared::stages::<F, M, _>(p, c, mirrored, turn, rest)
}

/// The sine version of the Magic Formula, eq. (3): D·sin[C·atan{B·x − E·(B·x − atan(B·x))}].
///
/// Computed in the type `G` of the slip x; each coefficient may be a `G` or a plain value
/// (`B`, `C`, `D`, `E`: a load- or friction-stage coefficient, a constant in dual numbers),
/// multiplied in as it is (x·B, not B·x: the same product).
#[inline(always)]
pub fn magic_sin<G, M, B, C, D, E>(b: B, c: C, d: D, e: E, x: G) -> G
where
    G: Real + Mul<B, Output = G> + Mul<C, Output = G> + Mul<D, Output = G> + Mul<E, Output = G>,
    M: Backend<G>,
    E: Real,
{
    M::sin(M::atan(magic_arg::<G, M, B, E>(b, e, x)) * c) * d
}

/// B·x − E·(B·x − atan(B·x)), the argument of the outer atan in eqs. (3) and (8); with E = 0
/// it is B·x exactly, and the inner atan is skipped.
#[inline(always)]
fn magic_arg<G, M, B, E>(b: B, e: E, x: G) -> G
where
    G: Real + Mul<B, Output = G> + Mul<E, Output = G>,
    M: Backend<G>,
    E: Real,
{
    let bx = x * b;
    // E = 0 in every lane: B·x exactly, without the inner atan. Where only some lanes have
    // E = 0, the general form gives them B·x too (B·x − (B·x − atan B·x)·0).
    if e.mask_eq(E::ZERO).all() {
        bx
    } else {
        bx - (bx - M::atan(bx)) * e
    }
}

/// The cosine version of the Magic Formula, eq. (8) without its D: cos[C·atan{B·x − E·(B·x −
/// atan(B·x))}]. Also the weighting functions G, eq. (12). Coefficients as [`magic_sin`]'s.
#[inline(always)]
pub fn magic_cos<G, M, B, C, E>(b: B, c: C, e: E, x: G) -> G
where
    G: Real + Mul<B, Output = G> + Mul<C, Output = G> + Mul<E, Output = G>,
    M: Backend<G>,
    E: Real,
{
    M::cos(M::atan(magic_arg::<G, M, B, E>(b, e, x)) * c)
}

/// cos(atan(x)) = 1/√(1 + x²), exactly; one square root instead of two trigonometric calls.
#[inline(always)]
pub(crate) fn cos_atan<F: Real, M: Backend<F>>(x: F) -> F {
    F::ONE / M::sqrt(F::ONE + x * x)
}

/// Clips a curvature factor to ≤ 1 when limits are on ("(≤ 1)" in eqs. (27), (38), (4.E14),
/// (4.E24), (4.E44), (4.E56), (4.E64)) and flags it.
#[inline(always)]
pub(crate) fn clip_e<F: Real>(e: F, limits: bool, flags: &mut F::Flags) -> F {
    if !limits {
        return e;
    }
    let over = e.mask_gt(F::ONE);
    flags.set_if(Flags::E_CLIPPED, over);
    F::select(over, F::ONE, e)
}

#[cfg(test)]
mod tests;
