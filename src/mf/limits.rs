//! Conditioning of the inputs: range limits, low-speed reductions, the basic quantities.
//!
//! Implements Pacejka (2006) (4.E1)–(4.E8) and the MF-Tyre limit checks as the MF 6.1 solvers
//! (TNO MF-Tyre; MFeval `parseInputs`/`calculateBasic`) apply them:
//! - κ, α, γ, p clipped to KPUMIN..KPUMAX, ALPMIN..ALPMAX, CAMMIN..CAMMAX, PRESMIN..PRESMAX;
//!   Fz clipped to FZMAX (the forces), and FZMIN kept for the aligning-torque terms.
//! - Below VXLOW: κ and φt scale linearly with |Vx|/VXLOW; α with (|Vx| + |Vsy|)/VXLOW; the
//!   shifts and the trail/residual torque fade with the smooth factor 1 − ½(1 + cos(π·Vx/VXLOW)).
//!
//! Every clip sets its [`Flags`] bit; nothing is clipped silently.

use super::FlagSet;
use super::{EvalError, Flags, Input, InputField, Options, Params, Version, EPS};
use crate::math::{choose, Backend, Lift, Mask, Real};

/// Digressive friction factor Aμ of (4.E8): λμ' = Aμ·λμ*/(1 + (Aμ − 1)·λμ*). The book suggests
/// 10. With λμ = 1 (every bundled file) λμ' = 1 whatever Aμ is.
// DIFFERS FROM MFeval: MFeval 4.0 uses Aμ = 1 (λμ' = λμ). We follow the book's documented 10,
// so that on a slippery road (λμ < 1) the vertical shifts SVx, SVy shrink less than the peak,
// as (4.E8) intends. Test: `mf::tests::digressive_friction_factor`.
pub const A_MU: f64 = 10.0;

/// Post-processed inputs and the quantities every equation shares.
#[derive(Debug, Clone, Copy)]
pub struct Conditioned<F, L = Flags, K = bool> {
    /// Version of the parameter set.
    pub version: Version,
    /// Limits and low-speed handling on.
    pub limits: bool,
    /// α*, γ* definitions on.
    pub use_alpha_star: bool,
    /// Slips come from the transient model (`Options::transient`).
    pub transient: bool,
    /// Fz for the forces \[N\] (≥ 0, clipped at FZMAX).
    pub fz: F,
    /// Fz for the aligning-torque terms Dt, Dr \[N\]: Fz raised to FZMIN when limits are on.
    pub fz_low: F,
    /// Fz before any clip (negative → 0) \[N\]: rolling resistance and radius.
    pub fz_u: F,
    /// κ used by the equations (reduced at low speed, clipped).
    pub kappa: F,
    /// κ after the low-speed reduction, before clipping (reported).
    pub kappa_out: F,
    /// κ as given (rolling resistance, radius).
    pub kappa_u: F,
    /// α used by the equations \[rad\].
    pub alpha: F,
    /// γ used by the equations \[rad\].
    pub gamma: F,
    /// φt after conditioning \[1/m\].
    pub phit: F,
    /// Vx as given \[m/s\].
    pub vx: F,
    /// Inflation pressure after clipping \[Pa\].
    pub p: F,
    /// Fz0' = λFz0·Fz0 (4.E1) \[N\].
    pub fz0_prime: F,
    /// dfz = (Fz − Fz0')/Fz0' (4.E2a).
    pub dfz: F,
    /// dpi = (p − pi0)/pi0 (4.E2b).
    pub dpi: F,
    /// α* (4.E3): tan(α)·sign(Vx) with `alpha_star`, else α.
    pub alpha_star: F,
    /// γ* (4.E4): sin(γ) with `alpha_star`, else γ.
    pub gamma_star: F,
    /// cos α* \[-\], for Dr (4.E47).
    pub cos_alpha_star: F,
    /// cos α' = Vx/Vc' (4.E6), (4.E6a); cos(acos(x)) = x saves two calls.
    pub cos_alpha_prime: F,
    /// λμx* (4.E7); the slip-speed decay λμV is 0 (not a `.tir` key): λμx* = λμx.
    pub lmux_star: F,
    /// λμy* (4.E7).
    pub lmuy_star: F,
    /// λμx' (4.E8).
    pub lmux_prime: F,
    /// λμy' (4.E8).
    pub lmuy_prime: F,
    /// Low-speed smooth reduction factor (1 above VXLOW).
    pub red_smooth: F,
    /// Low-speed linear reduction factor |Vx|/VXLOW of κ (1 above VXLOW).
    pub red_linear: F,
    /// ALPMIN \[rad\] (the slips' ranges, for the slip stage).
    pub alpmin: F,
    /// ALPMAX \[rad\].
    pub alpmax: F,
    /// KPUMIN \[-\].
    pub kpumin: F,
    /// KPUMAX \[-\].
    pub kpumax: F,
    /// VXLOW \[m/s\].
    pub vxlow: F,
    /// |Vx| ≤ VXLOW with limits on (per lane).
    pub low_speed: K,
    /// Turn-slip state, when turn slip is evaluated.
    pub turn: Option<super::turnslip::Spin<F>>,
    /// Flags raised so far.
    pub flags: L,
}

/// [`Conditioned`] in `F`'s own flags and masks (one per lane for lanes).
pub type Cond<F> = Conditioned<F, <F as Real>::Flags, <F as Real>::Mask>;

fn check<F: Real>(x: F, field: InputField) -> Result<(), EvalError> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(EvalError::NonFinite(field))
    }
}

/// The finiteness check of an input, in the order of `Input`'s fields (the first non-finite one
/// is reported).
#[inline(always)]
pub fn check_finite<F: Real>(input: &Input<F>) -> Result<(), EvalError> {
    let Input {
        fz,
        kappa,
        alpha,
        gamma,
        phit,
        vx,
        p: p_in,
    } = *input;
    // An absent p is 0 here: finite.
    let finite = F::all_finite(&[fz, kappa, alpha, gamma, phit, vx, p_in.unwrap_or(F::ZERO)]);
    if !finite {
        check(fz, InputField::Fz)?;
        check(kappa, InputField::Kappa)?;
        check(alpha, InputField::Alpha)?;
        check(gamma, InputField::Gamma)?;
        check(phit, InputField::Phit)?;
        check(vx, InputField::Vx)?;
        if let Some(x) = p_in {
            check(x, InputField::P)?;
        }
    }
    Ok(())
}

/// Validates and conditions one input (see the module doc): the load stage
/// ([`condition_load`]) and the slips ([`slips`]) in one.
pub fn condition<F: Real, M: Backend<F>>(
    p: &Params<F>,
    input: &Input<F>,
    opts: &Options,
) -> Result<Cond<F>, EvalError> {
    check_finite(input)?;
    let mut c = condition_load_checked::<F, M>(p, input, opts)?;
    if opts.limits && opts.turn_slip {
        // Turn slip seen by the contact patch shrinks with the slip angle (MFeval "empirically
        // discovered"; TNO behaviour). φt is read by the turn-slip equations only.
        c.phit *= M::cos(input.alpha);
    }
    let s = slips::<F, F, M>(&c, input.kappa, input.alpha);
    c.kappa = s.kappa;
    c.kappa_out = s.kappa_out;
    c.kappa_u = input.kappa;
    c.alpha = s.alpha;
    c.alpha_star = s.alpha_star;
    c.cos_alpha_star = s.cos_alpha_star;
    c.cos_alpha_prime = s.cos_alpha_prime;
    c.flags.merge(s.flags);
    Ok(c)
}

/// The load stage of the conditioning — everything but κ and α (which it leaves 0; [`slips`]
/// conditions them) — of an input its caller has checked finite ([`check_finite`]): `mf::eval`
/// checks the whole input once.
#[inline(always)]
pub(crate) fn condition_load_checked<F: Real, M: Backend<F>>(
    p: &Params<F>,
    input: &Input<F>,
    opts: &Options,
) -> Result<Cond<F>, EvalError> {
    let Input {
        mut fz,
        mut gamma,
        mut phit,
        vx,
        p: p_in,
        ..
    } = *input;
    let mut pres = p_in.unwrap_or(p.inflpres);
    let mf6 = p.version.is_mf6();
    if mf6 && pres.mask_le(F::ZERO).any() {
        return Err(EvalError::NonPositivePressure);
    }
    let mut flags = F::Flags::default();
    flags.set_if(Flags::REVERSE, vx.mask_lt(F::ZERO));
    let no_contact = fz.mask_le(F::ZERO);
    flags.set_if(Flags::NO_CONTACT, no_contact);
    fz = F::select(no_contact, F::ZERO, fz);
    let fz_u = fz;
    let mut fz_low = fz;
    let mut red_smooth = F::ONE;
    let mut red_linear = F::ONE;
    let mut low_speed = F::Mask::splat(false);

    if opts.limits {
        let vxlow = p.vxlow;
        if vxlow > F::ZERO {
            let low = vx.abs().mask_le(vxlow);
            if low.any() {
                low_speed = low;
                flags.set_if(Flags::LOW_SPEED, low);
                // Smooth reduction 1 − ½(1 + cos(π·Vx/VXLOW)): 0 at standstill, 1 at VXLOW.
                red_smooth = F::select(
                    low,
                    F::ONE - F::HALF * (F::ONE + M::cos(F::PI * (vx / vxlow))),
                    F::ONE,
                );
                red_linear = F::select(low, (vx / vxlow).abs(), F::ONE);
                phit *= red_linear; // 1 in the lanes above VXLOW: exact
            }
        }
        phit = F::select(vx.mask_lt(F::ZERO), -phit, phit);
        let (g, fg) = gamma.clamp_flag(p.cammin, p.cammax);
        gamma = g;
        flags.set_if(Flags::GAMMA, fg);
        let high = fz.mask_gt(p.fzmax);
        fz = F::select(high, p.fzmax.max(F::ZERO), fz);
        flags.set_if(Flags::FZ_HIGH, high);
        let light = fz_u.mask_gt(F::ZERO).and(fz.mask_lt(p.fzmin));
        fz_low = F::select(light, p.fzmin, fz);
        flags.set_if(Flags::FZ_LOW, light);
        if mf6 {
            let (q, fp) = pres.clamp_flag(p.presmin, p.presmax);
            pres = q;
            flags.set_if(Flags::PRESSURE, fp);
        }
    }

    let fz0_prime = p.lfzo * p.fnomin; // (4.E1)
    let dfz = (fz - fz0_prime) / fz0_prime; // (4.E2a)
    let dpi = if mf6 {
        (pres - p.nompres) / p.nompres // (4.E2b)
    } else {
        F::ZERO
    };
    let gamma_star = if opts.alpha_star {
        M::sin(gamma) // (4.E4)
    } else {
        gamma
    };
    // (4.E7) with λμV = 0, (4.E8) with Aμ.
    let lmux_star = p.lmux;
    let lmuy_star = p.lmuy;

    Ok(Conditioned {
        version: p.version,
        limits: opts.limits,
        use_alpha_star: opts.alpha_star,
        transient: opts.transient,
        fz,
        fz_low,
        fz_u,
        kappa: F::ZERO,
        kappa_out: F::ZERO,
        kappa_u: F::ZERO,
        alpha: F::ZERO,
        gamma,
        phit,
        vx,
        p: pres,
        fz0_prime,
        dfz,
        dpi,
        alpha_star: F::ZERO,
        gamma_star,
        cos_alpha_star: F::ONE,
        cos_alpha_prime: F::ONE,
        lmux_star,
        lmuy_star,
        lmux_prime: digressive(lmux_star),
        lmuy_prime: digressive(lmuy_star),
        red_smooth,
        red_linear,
        low_speed,
        alpmin: p.alpmin,
        alpmax: p.alpmax,
        kpumin: p.kpumin,
        kpumax: p.kpumax,
        vxlow: p.vxlow,
        turn: None,
        flags,
    })
}

/// λμ' = Aμ·λμ*/(1 + (Aμ − 1)·λμ*) (4.E8).
#[inline(always)]
pub fn digressive<F: Real>(lmu_star: F) -> F {
    let a_mu = F::from_f64(A_MU);
    a_mu * lmu_star / (F::ONE + (a_mu - F::ONE) * lmu_star)
}

/// κ and α after conditioning, and what the equations take from α.
#[derive(Debug, Clone, Copy)]
pub struct Slips<G, L = Flags> {
    /// κ used by the equations (reduced at low speed, clipped).
    pub kappa: G,
    /// κ after the low-speed reduction, before clipping (reported).
    pub kappa_out: G,
    /// α used by the equations \[rad\].
    pub alpha: G,
    /// α* (4.E3).
    pub alpha_star: G,
    /// cos α* (4.E47).
    pub cos_alpha_star: G,
    /// cos α' = Vx/Vc' (4.E6), (4.E6a).
    pub cos_alpha_prime: G,
    /// Clips of κ and α.
    pub flags: L,
}

/// The slip stage of the conditioning: κ and α at the load stage's speed and limits.
#[inline(always)]
pub fn slips<F: Real, G: Lift<F>, M: Backend<G>>(
    c: &Cond<F>,
    mut kappa: G,
    mut alpha: G,
) -> Slips<G, G::Flags> {
    let l = |x: F| G::lift(x);
    let vx = c.vx;
    let mut flags = G::Flags::default();
    let mut kappa_out = kappa;
    // tan α, reused below (computed again only if α is reduced or clipped).
    let alpha_in = alpha;
    let mut tan_alpha = M::tan(alpha);
    if c.limits {
        // The reductions are 1 above VXLOW (exact), so lanes may share them.
        if c.low_speed.any() {
            kappa_out = kappa * c.red_linear;
            if !c.transient {
                kappa = kappa * c.red_linear;
            }
        }
        // α fades when the total speed |Vx| + |Vsy| falls below VXLOW (Vsy = tan(α)·Vx).
        let speed_sum = (tan_alpha * vx).abs() + vx.abs();
        if !c.transient {
            let slow = speed_sum.mask_lt(l(c.vxlow));
            if slow.any() {
                alpha = G::select(slow, alpha * (speed_sum / c.vxlow), alpha);
            }
        }
        let (a, fa) = alpha.clamp_flag(l(c.alpmin), l(c.alpmax));
        alpha = a;
        flags.set_if(Flags::ALPHA, fa);
        let (k, fk) = kappa.clamp_flag(l(c.kpumin), l(c.kpumax));
        kappa = k;
        flags.set_if(Flags::KAPPA, fk);
    }
    let changed = alpha.mask_eq(alpha_in).not();
    if changed.any() {
        tan_alpha = G::select(changed, M::tan(alpha), tan_alpha);
    }
    let alpha_star = if c.use_alpha_star {
        tan_alpha * vx.sign() // (4.E3)
    } else {
        alpha
    };
    // cos α* for Dr (4.E47): without α*, from tan α as 1/√(1 + tan²α) where that is exact
    // (|α| < π/2, where cos α > 0): one square root instead of a cosine.
    let cos_alpha_star = if c.use_alpha_star {
        M::cos(alpha_star)
    } else {
        choose::<G>(
            alpha.abs().mask_lt(G::FRAC_PI_2),
            || G::ONE / M::sqrt(G::ONE + tan_alpha * tan_alpha),
            || M::cos(alpha_star),
        )
    };
    // (4.E6), (4.E6a): Vc' = Vc + ε·sign(Vc), with Vsy = tan(α)·|Vx| and Vcy = Vsy.
    let vsy = tan_alpha * vx.abs();
    let vc = M::sqrt(vsy * vsy + vx * vx);
    let vc_prime = vc + F::from_f64(EPS) * vc.value().sign_nz();
    let cos_alpha_prime = l(vx) / vc_prime;
    Slips {
        kappa,
        kappa_out,
        alpha,
        alpha_star,
        cos_alpha_star,
        cos_alpha_prime,
        flags,
    }
}
