//! Turn slip (spin) for MF 6.x: the reduction factors ζ0..ζ8 of Pacejka (2006) §4.3.3,
//! (4.75)–(4.106), as the TNO MF-Tyre 6.1 solver applies them (MFeval reproduces it).
//!
//! Spin φ combines turn slip φt and camber: φ = −φt − (1 − εγ)·Ω·sin γ / Vc' (4.76), with the
//! wheel speed Ω from the effective rolling radius (Besselink et al. 2010, eqs. 1, 7: a fixed
//! point iteration, bounded here to [`RE_MAX_ITER`] steps and flagged when it does not settle).

use super::limits::Cond;
use super::{cos_atan, FlagSet, Flags, Params, EPS};
use crate::math::{Backend, Real};

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

/// Wheel angular speed Ω \[rad/s\] from Vx and κ through the effective rolling radius Re.
fn omega<F: Real, M: Backend<F>>(p: &Params<F>, c: &mut Cond<F>) -> F {
    let (r0, fz0, v0) = (p.unloaded_radius, p.fnomin, p.longvl);
    let c_z = p.vertical_stiffness * (F::ONE + p.pfz1 * c.dpi);
    if c_z == F::ZERO {
        c.flags.insert(Flags::GUARD);
        return c.vx * (F::ONE + c.kappa_u) / r0;
    }
    let fzn = c.fz_u / fz0;
    let deflection = (fz0 / c_z) * (p.dreff * M::atan(p.breff * fzn) + p.freff * fzn);
    let mut re = r0 * F::from_f64(0.965);
    let mut re_old = r0;
    let mut om = F::ZERO;
    let mut n = 0;
    while (re_old - re).abs() > F::from_f64(1e-9) && n < RE_MAX_ITER {
        re_old = re;
        om = (c.kappa_u * c.vx + c.vx) / re; // (2.5) of the book
        let x = om * r0 / v0;
        let r_omega = r0 * (p.q_re0 + p.q_v1 * x * x); // eq. (1)
        re = r_omega - deflection; // eq. (7)
        n += 1;
    }
    if (re_old - re).abs() > F::from_f64(1e-6) * r0 {
        c.flags.insert(Flags::GUARD);
    }
    om
}

/// Computes φ, εγ and the ζ factors that do not depend on the forces.
pub fn prepare<F: Real, M: Backend<F>>(p: &Params<F>, c: &mut Cond<F>) {
    let r0 = p.unloaded_radius;
    let dfz = c.dfz;
    let eps_gamma = p.pecp1 * (F::ONE + p.pecp2 * dfz); // (4.90)
    let vsy = -M::tan(c.alpha) * c.vx.abs();
    let mut vc_prime = M::sqrt(c.vx * c.vx + vsy * vsy);
    if c.vx.abs() < p.vxlow {
        vc_prime = p.vxlow * c.vx.sign_nz(); // singularity-protected speed (book p. 184)
    }
    if vc_prime == F::ZERO {
        vc_prime = F::from_f64(EPS);
    }
    let camber_spin = if c.gamma == F::ZERO {
        F::ZERO
    } else {
        (F::ONE - eps_gamma) * omega::<F, M>(p, c) * M::sin(c.gamma)
    };
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
    if den == F::ZERO {
        return F::ZERO; // D_Hyp = 0 (standstill) or no spin shift: SHyp = D_Hyp·sin(..) = 0
    }
    let b_hyp = k_yg0 / den; // (4.88), (4.89)
    super::magic_sin::<F, M, F, F, F, F>(b_hyp, c_hyp, d_hyp, e_hyp, r0 * s.phi) * c.vx.sign()
    // (4.80)
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
    let mut mzp_inf = p.qcrp1 * mu_y.abs() * r0 * fz * M::sqrt(fz / c.fz0_prime) * p.lmp; // (4.95)
    if mzp_inf < F::ZERO {
        mzp_inf = F::from_f64(1e-6); // (4.95) must be > 0: patched, and flagged
        c.flags.insert(Flags::GUARD);
    }
    let c_drp = p.qdrp1; // (4.96)
    let sin_c = M::sin(F::HALF * F::PI * c_drp);
    let one_m_eg = F::ONE - s.eps_gamma;
    // Kzγr0 as the TNO 6.1 solver has it (MFeval); (4.99) of the book reads
    // Fz·R0·(qDz8 + qDz9·dfz)·λKzγ.
    let k_zgr0 =
        fz * r0 * (p.qdz8 * p.qdz9 * dfz + (p.qdz10 + p.qdz11 * dfz * c.gamma.abs())) * p.lkzc;
    let (d_drp, d_rp) = if sin_c == F::ZERO || c_drp == F::ZERO || one_m_eg == F::ZERO {
        c.flags.insert(Flags::GUARD);
        (F::ZERO, F::ZERO)
    } else {
        let d_drp = mzp_inf / sin_c; // (4.94)
        let b_drp = if d_drp == F::ZERO {
            F::ZERO
        } else {
            k_zgr0 / (c_drp * d_drp * one_m_eg)
        };
        (d_drp, d_drp * M::sin(c_drp * M::atan(b_drp * r0 * phit))) // (4.93)
    };
    let mzp90 = mzp_inf * F::FRAC_2_PI * M::atan(p.qcrp2 * r0 * phit.abs()) * g_yk; // (4.103)
                                                                                    // ζ7 = (2/π)·acos(Mzp90/|Drp|) (4.104). Where the ratio leaves [−1, 1] the solvers' complex
                                                                                    // acos keeps its real part, which is the clamp; at φt = 0 the ratio is taken at its limit
                                                                                    // φt → 0 (MFeval returns NaN there).
    let ratio = if d_rp != F::ZERO {
        mzp90 / d_rp.abs()
    } else if k_zgr0 != F::ZERO && d_drp != F::ZERO {
        mzp_inf * F::FRAC_2_PI * p.qcrp2 * g_yk * one_m_eg.abs() / k_zgr0.abs()
    } else {
        F::ONE
    };
    let (ratio, _) = ratio.clamp_flag(-F::ONE, F::ONE);
    let zeta7 = F::FRAC_2_PI * M::acos(ratio);
    let zeta8 = F::ONE + d_rp;
    (F::ZERO, s.zeta2, zeta6, zeta7, zeta8)
}
