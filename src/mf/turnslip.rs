//! Turn slip (spin) for MF 6.x: the reduction factors ζ0..ζ8 of Pacejka (2006) §4.3.3,
//! (4.75)–(4.106), as the TNO MF-Tyre 6.1 solver applies them (MFeval reproduces it).
//!
//! Spin φ combines turn slip φt and camber: φ = −φt − (1 − εγ)·Ω·sin γ / Vc' (4.76), with the
//! wheel speed Ω from the effective rolling radius (Besselink et al. 2010, eqs. 1, 7: a fixed
//! point iteration, bounded here to [`RE_MAX_ITER`] steps and flagged when it does not settle).
//!
//! The value branches are masks and selects ([`Real`]), as in the rest of the formula, so that
//! lanes of points with different values take each its own side (`mf::eval_batch_lanes`); for one
//! point they are the `if`s they read as, with the same operations in the same order.

use super::limits::Cond;
use super::{cos_atan, FlagSet, Flags, Params, EPS};
use crate::math::{choose, Backend, Mask, Real};

/// Bound on the effective-rolling-radius fixed-point iteration (it contracts fast: typically
/// 3–5 steps reach 1e-9 m).
pub const RE_MAX_ITER: u32 = 30;

/// Spin state shared by the force and moment equations.
#[derive(Debug, Clone, Copy)]
pub struct Spin<F> {
    /// Spin φ \[1/m\] (4.76).
    pub phi: F,
    /// Camber reduction factor εγ (4.90).
    pub eps_gamma: F,
    /// ζ1: Fx peak reduction (4.105).
    pub zeta1: F,
    /// ζ2: Fy peak reduction (4.77).
    pub zeta2: F,
    /// ζ3: cornering stiffness reduction (4.79).
    pub zeta3: F,
    /// ζ5: pneumatic trail reduction (4.91).
    pub zeta5: F,
}

/// Does this parameter set support turn slip (MF 6.x with turn-slip coefficients)?
pub fn available<F: Real>(p: &Params<F>) -> bool {
    p.version.is_mf6()
        && [
            p.pdxp1, p.pdyp1, p.pkyp1, p.phyp1, p.qdtp1, p.qcrp1, p.qbrp1, p.qdrp1,
        ]
        .iter()
        .any(|&x| x != F::ZERO)
}

/// Wheel angular speed Ω \[rad/s\] from Vx and κ through the effective rolling radius Re, and
/// where it is guarded (no vertical stiffness: Ω from R0; or the iteration did not settle).
/// Each lane iterates until its own Re settles (the lanes that have are held).
fn omega<F: Real, M: Backend<F>>(p: &Params<F>, c: &Cond<F>) -> (F, F::Mask) {
    let (r0, fz0, v0) = (p.unloaded_radius, p.fnomin, p.longvl);
    let c_z = p.vertical_stiffness * (F::ONE + p.pfz1 * c.dpi);
    let no_cz = c_z.mask_eq(F::ZERO);
    let from_r0 = || c.vx * (F::ONE + c.kappa_u) / r0;
    if no_cz.all() {
        return (from_r0(), no_cz);
    }
    let c_z = F::select(no_cz, F::ONE, c_z);
    let fzn = c.fz_u / fz0;
    let deflection = (fz0 / c_z) * (p.dreff * M::atan(p.breff * fzn) + p.freff * fzn);
    let mut re = r0 * F::from_f64(0.965);
    let mut re_old = r0;
    let mut om = F::ZERO;
    let mut n = 0;
    let mut active = (re_old - re).abs().mask_gt(F::from_f64(1e-9));
    while active.any() && n < RE_MAX_ITER {
        let om_next = (c.kappa_u * c.vx + c.vx) / re; // (2.5) of the book
        let x = om_next * r0 / v0;
        let r_omega = r0 * (p.q_re0 + p.q_v1 * x * x); // eq. (1)
        re_old = F::select(active, re, re_old);
        om = F::select(active, om_next, om);
        re = F::select(active, r_omega - deflection, re); // eq. (7)
        n += 1;
        active = active.and((re_old - re).abs().mask_gt(F::from_f64(1e-9)));
    }
    // (Where `no_cz`, the guard is set anyway.)
    let unsettled = (re_old - re).abs().mask_gt(F::from_f64(1e-6) * r0);
    (F::select(no_cz, from_r0(), om), no_cz.or(unsettled))
}

/// Computes φ, εγ and the ζ factors that do not depend on the forces.
pub fn prepare<F: Real, M: Backend<F>>(p: &Params<F>, c: &mut Cond<F>) {
    let r0 = p.unloaded_radius;
    let dfz = c.dfz;
    let eps_gamma = p.pecp1 * (F::ONE + p.pecp2 * dfz); // (4.90)
    let vsy = -M::tan(c.alpha) * c.vx.abs();
    let vc_prime = M::sqrt(c.vx * c.vx + vsy * vsy);
    // The singularity-protected speed (book p. 184).
    let low = c.vx.abs().mask_lt(p.vxlow);
    let vc_prime = F::select(low, p.vxlow * c.vx.sign_nz(), vc_prime);
    let vc_prime = F::select(vc_prime.mask_eq(F::ZERO), F::from_f64(EPS), vc_prime);
    let upright = c.gamma.mask_eq(F::ZERO);
    let camber_spin = choose(
        upright,
        || F::ZERO,
        || {
            let (om, guard) = omega::<F, M>(p, c);
            c.flags.set_if(Flags::GUARD, guard.and(upright.not()));
            (F::ONE - eps_gamma) * om * M::sin(c.gamma)
        },
    );
    let psi_dot = -c.phit * vc_prime; // (4.75)
    let phi = (psi_dot - camber_spin) / vc_prime; // (4.76), z up as in ISO-W
    let b_xp = p.pdxp1 * (F::ONE + p.pdxp2 * dfz) * cos_atan::<F, M>(p.pdxp3 * c.kappa); // (4.106)
    let zeta1 = cos_atan::<F, M>(b_xp * r0 * phi); // (4.105)
    let b_yp = p.pdyp1 * (F::ONE + p.pdyp2 * dfz) * cos_atan::<F, M>(p.pdyp3 * M::tan(c.alpha)); // (4.78)
    let r_phi = r0 * phi.abs();
    let zeta2 = cos_atan::<F, M>(b_yp * (r_phi + p.pdyp4 * M::sqrt(r_phi))); // (4.77)
    let zeta3 = cos_atan::<F, M>(p.pkyp1 * r0 * r0 * phi * phi); // (4.79)
    let zeta5 = cos_atan::<F, M>(p.qdtp1 * r0 * phi); // (4.91)
    c.turn = Some(Spin {
        phi,
        eps_gamma,
        zeta1,
        zeta2,
        zeta3,
        zeta5,
    });
}

/// Lateral shift SHyp of the Fy–α curve due to spin, (4.80)–(4.89).
pub fn s_hyp<F: Real, M: Backend<F>>(p: &Params<F>, c: &mut Cond<F>, k_yg0: F) -> F {
    let Some(s) = c.turn else { return F::ZERO };
    let (dfz, dpi, fz0p, r0) = (c.dfz, c.dpi, c.fz0_prime, p.unloaded_radius);
    // Kyα0: cornering stiffness at γ = 0 (4.E25 with γ = 0).
    let k_ya0 = p.pky1
        * fz0p
        * (F::ONE + p.ppy1 * dpi)
        * M::sin(p.pky4 * M::atan((c.fz / fz0p) / (p.pky2 * (F::ONE + p.ppy2 * dpi))))
        * s.zeta3
        * p.lky;
    let k_ya0_prime = k_ya0 + F::from_f64(EPS) * k_ya0.sign_nz();
    let c_hyp = p.phyp1; // (4.85)
    let d_hyp = (p.phyp2 + p.phyp3 * dfz) * c.vx.sign(); // (4.86)
    let e_hyp = super::clip_e(p.phyp4, c.limits, &mut c.flags); // (4.87)
    let one_m_eg = F::ONE - s.eps_gamma;
    let den = c_hyp * d_hyp * k_ya0_prime * one_m_eg;
    // D_Hyp = 0 (standstill) or no spin shift: SHyp = D_Hyp·sin(..) = 0.
    let none = den.mask_eq(F::ZERO);
    if none.all() {
        return F::ZERO;
    }
    let b_hyp = k_yg0 / F::select(none, F::ONE, den); // (4.88), (4.89)
    let s_hyp =
        super::magic_sin::<F, M, F, F, F, F>(b_hyp, c_hyp, d_hyp, e_hyp, r0 * s.phi) * c.vx.sign(); // (4.80)
    F::select(none, F::ZERO, s_hyp)
}

/// ζ0, ζ2, ζ6, ζ7, ζ8 of the residual torque, (4.92)–(4.104); `fz` is the moment load,
/// `mu_y` and `g_yk` from the turn-slip Fy.
pub fn mz_zetas<F: Real, M: Backend<F>>(
    p: &Params<F>,
    c: &mut Cond<F>,
    fz: F,
    mu_y: F,
    g_yk: F,
) -> (F, F, F, F, F) {
    let Some(s) = c.turn else {
        return (F::ONE, F::ONE, F::ONE, F::ONE, F::ONE);
    };
    let (r0, dfz, phit) = (p.unloaded_radius, c.dfz, c.phit);
    let zeta6 = cos_atan::<F, M>(p.qbrp1 * r0 * s.phi); // (4.102)
    let mzp_inf = p.qcrp1 * mu_y.abs() * r0 * fz * M::sqrt(fz / c.fz0_prime) * p.lmp; // (4.95)
                                                                                      // (4.95) must be > 0: patched, and flagged.
    let negative = mzp_inf.mask_lt(F::ZERO);
    c.flags.set_if(Flags::GUARD, negative);
    let mzp_inf = F::select(negative, F::from_f64(1e-6), mzp_inf);
    let c_drp = p.qdrp1; // (4.96)
    let sin_c = M::sin(F::HALF * F::PI * c_drp);
    let one_m_eg = F::ONE - s.eps_gamma;
    // Kzγr0 as the TNO 6.1 solver has it (MFeval); (4.99) of the book reads
    // Fz·R0·(qDz8 + qDz9·dfz)·λKzγ.
    let k_zgr0 =
        fz * r0 * (p.qdz8 * p.qdz9 * dfz + (p.qdz10 + p.qdz11 * dfz * c.gamma.abs())) * p.lkzc;
    let degenerate = sin_c
        .mask_eq(F::ZERO)
        .or(c_drp.mask_eq(F::ZERO))
        .or(one_m_eg.mask_eq(F::ZERO));
    c.flags.set_if(Flags::GUARD, degenerate);
    let (d_drp, d_rp) = if degenerate.all() {
        (F::ZERO, F::ZERO)
    } else {
        let safe = |x: F| F::select(degenerate, F::ONE, x);
        let (sin_c, c_drp, one_m_eg) = (safe(sin_c), safe(c_drp), safe(one_m_eg));
        let d_drp = mzp_inf / sin_c; // (4.94)
        let flat = d_drp.mask_eq(F::ZERO);
        let b_drp = F::select(
            flat,
            F::ZERO,
            k_zgr0 / (c_drp * F::select(flat, F::ONE, d_drp) * one_m_eg),
        );
        let d_rp = d_drp * M::sin(c_drp * M::atan(b_drp * r0 * phit)); // (4.93)
        (
            F::select(degenerate, F::ZERO, d_drp),
            F::select(degenerate, F::ZERO, d_rp),
        )
    };
    let mzp90 = mzp_inf * F::FRAC_2_PI * M::atan(p.qcrp2 * r0 * phit.abs()) * g_yk; // (4.103)
                                                                                    // ζ7 = (2/π)·acos(Mzp90/|Drp|) (4.104). Where the ratio leaves [−1, 1] the solvers' complex
                                                                                    // acos keeps its real part, which is the clamp; at φt = 0 the ratio is taken at its limit
                                                                                    // φt → 0 (MFeval returns NaN there).
    let has_rp = d_rp.mask_eq(F::ZERO).not();
    let limit = k_zgr0
        .mask_eq(F::ZERO)
        .not()
        .and(d_drp.mask_eq(F::ZERO).not());
    let ratio = choose(
        has_rp,
        || mzp90 / F::select(has_rp, d_rp.abs(), F::ONE),
        || {
            choose(
                limit,
                || {
                    mzp_inf * F::FRAC_2_PI * p.qcrp2 * g_yk * one_m_eg.abs()
                        / F::select(limit, k_zgr0.abs(), F::ONE)
                },
                || F::ONE,
            )
        },
    );
    let (ratio, _) = ratio.clamp_flag(-F::ONE, F::ONE);
    let zeta7 = F::FRAC_2_PI * M::acos(ratio);
    let zeta8 = F::ONE + d_rp;
    (F::ZERO, s.zeta2, zeta6, zeta7, zeta8)
}
