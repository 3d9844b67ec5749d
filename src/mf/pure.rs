//! Pure-slip Magic Formula: Fx0(κ), Fy0(α), and the pneumatic trail / residual torque factors.
//!
//! Paper (Delft Tyre 96) eqs. (22)–(56); MF 5.2/6.1 (4.E9)–(4.E49) with the TNO corrections
//! (A58), (A60) of Besselink et al. (2010). Version differences are coded where they occur:
//! - Delft 96: Kx = Fz(pKx1 + pKx2·dfz)·exp(−pKx3·dfz) (28) — note the minus sign; camber
//!   enters Fy through γy = γ·λγy in the shifts, and λHy, λVy scale the camber shifts too (41),
//!   (42); no μx camber term, no E in the combined-slip weights.
//! - MF 5.2: exp(+PKX3·dfz); SHy = (PHY1 + PHY2·dfz)·λHy + PHY3·γy; γx, γy, γz with λγ.
//! - MF 6.x: pressure terms; camber through Kyγ0 (4.E30) and the shift (4.E27); PKY4..7, PEY5.

use super::limits::Conditioned;
use super::{clip_e, magic_sin, Params, Version, EPS};
use crate::math::{Backend, Float};

/// Results of [`fx0`].
#[derive(Debug, Clone, Copy)]
pub struct Fx0<F> {
    /// Pure longitudinal force Fx0 \[N\] (22), (4.E9).
    pub fx0: F,
    /// μx \[-\] (26), (4.E13).
    pub mu_x: F,
    /// Kxκ \[N\] (28), (4.E15).
    pub k_xk: F,
}

/// γx: camber as Fx sees it — γ·λγx (MF 5.x), γ (MF 6.x, Delft 96 has no μx camber term).
fn gamma_x<F: Float>(p: &Params<F>, gamma: F) -> F {
    match p.version {
        Version::Mf52 => gamma * p.lgax,
        _ => gamma,
    }
}

/// Pure longitudinal slip force, eqs. (22)–(31) / (4.E9)–(4.E18).
pub fn fx0<F: Float, M: Backend<F>>(p: &Params<F>, c: &mut Conditioned<F>) -> Fx0<F> {
    let (fz, dfz, dpi) = (c.fz, c.dfz, c.dpi);
    let zeta1 = c.turn.map_or(F::ONE, |t| t.zeta1);
    let gx = gamma_x(p, c.gamma);
    let c_x = p.pcx1 * p.lcx; // (24), (4.E11)
    let mut mu_x = (p.pdx1 + p.pdx2 * dfz)
        * (F::ONE + p.ppx3 * dpi + p.ppx4 * dpi * dpi)
        * (F::ONE - p.pdx3 * gx * gx)
        * c.lmux_star; // (26), (4.E13)
    if fz == F::ZERO {
        mu_x = F::ZERO;
    }
    let d_x = mu_x * fz * zeta1; // (25), (4.E12)
    let exp_arg = match p.version {
        // (28): exp(−pKx3·dfz) in the paper's appendix.
        Version::Delft96 => -p.pkx3 * dfz,
        _ => p.pkx3 * dfz, // (4.E15)
    };
    let k_xk = fz
        * (p.pkx1 + p.pkx2 * dfz)
        * M::exp(exp_arg)
        * (F::ONE + p.ppx1 * dpi + p.ppx2 * dpi * dpi)
        * p.lkx; // (28), (4.E15)
    let eps = F::from_f64(EPS);
    let b_x = k_xk / (c_x * d_x + eps * d_x.sign_nz()); // (29), (4.E16) with the signed ε
    let mut s_hx = (p.phx1 + p.phx2 * dfz) * p.lhx; // (30), (4.E17)
    let mut s_vx = fz * (p.pvx1 + p.pvx2 * dfz) * p.lvx * c.lmux_prime * zeta1; // (31), (4.E18)
    if c.low_speed {
        s_vx *= c.red_smooth;
        s_hx *= c.red_smooth;
    }
    let kappa_x = c.kappa + s_hx; // (23), (4.E10)
    let e_x =
        (p.pex1 + p.pex2 * dfz + p.pex3 * dfz * dfz) * (F::ONE - p.pex4 * kappa_x.sign()) * p.lex; // (27), (4.E14)
    let e_x = clip_e(e_x, c);
    let mut fx0 = magic_sin::<F, M>(b_x, c_x, d_x, e_x, kappa_x) + s_vx; // (22), (4.E9)
    if c.vx < F::ZERO && !c.transient {
        // Running backwards: mirror image (appendix, first paragraph), for steady-state slips
        // defined with κ = −1 locked in both directions. Slips from the transient model
        // (κ' = −Vsx/|Vx|) already carry the direction: a wheel locked while sliding backwards
        // has κ' = +1 and must get Fx > 0 (MFeval's dynamic modes flip κ for the same reason).
        fx0 = -fx0;
    }
    Fx0 { fx0, mu_x, k_xk }
}

/// Results of [`fy0`].
#[derive(Debug, Clone, Copy)]
pub struct Fy0<F> {
    /// Pure lateral force Fy0 \[N\] (32), (4.E19).
    pub fy0: F,
    /// μy \[-\] (37), (4.E23), signed as the file fits it.
    pub mu_y: F,
    /// Kyα \[N/rad\] (39), (4.E25).
    pub k_ya: F,
    /// SHy \[rad\] (41), (4.E27).
    pub s_hy: F,
    /// SVy \[N\] (42), (4.E29).
    pub s_vy: F,
    /// By \[1/rad\] (40), (4.E26).
    pub b_y: F,
    /// Cy \[-\] (35), (4.E21).
    pub c_y: F,
    /// ζ2 (turn slip, 1 without).
    pub zeta2: F,
}

/// Pure side-slip force, eqs. (32)–(42) / (4.E19)–(4.E30), at camber `gamma_star` (the
/// aligning torque needs Fy0 at γ = 0 too) and with or without turn slip.
pub fn fy0<F: Float, M: Backend<F>>(
    p: &Params<F>,
    c: &mut Conditioned<F>,
    gamma_star: F,
    turn_slip: bool,
) -> Fy0<F> {
    let (fz, dfz, dpi) = (c.fz, c.dfz, c.dpi);
    let fz0p = c.fz0_prime;
    let eps = F::from_f64(EPS);
    let spin = if turn_slip { c.turn } else { None };
    let (zeta2, zeta3) = match spin {
        Some(s) => (s.zeta2, s.zeta3),
        None => (F::ONE, F::ONE),
    };
    let mf6 = p.version.is_mf6();
    // γy: (34) γ·λγy for Delft 96 and MF 5.2; MF 6.x uses γ* with λKyγ in the camber terms.
    let g_y = if mf6 { gamma_star } else { gamma_star * p.lgay };
    let pky4 = if mf6 { p.pky4 } else { F::TWO }; // (39): the constant 2 before MF 6
    let k_ya = p.pky1
        * fz0p
        * (F::ONE + p.ppy1 * dpi)
        * (F::ONE - p.pky3 * g_y.abs())
        * M::sin(
            pky4 * M::atan((fz / fz0p) / ((p.pky2 + p.pky5 * g_y * g_y) * (F::ONE + p.ppy2 * dpi))),
        )
        * zeta3
        * p.lky; // (39), (4.E25)
    let k_ya_prime = k_ya + eps * k_ya.sign_nz(); // (4.E39)

    let (mut s_hy, mut s_vy) = match p.version {
        Version::Delft96 => {
            // (41), (42): λHy and λVy scale the camber terms too.
            let s_hy = (p.phy1 + p.phy2 * dfz + p.phy3 * g_y) * p.lhy;
            let s_vy =
                fz * (p.pvy1 + p.pvy2 * dfz + (p.pvy3 + p.pvy4 * dfz) * g_y) * p.lvy * c.lmuy_prime;
            (s_hy, s_vy)
        }
        Version::Mf52 => {
            // MF-Tyre 5.2 equation manual.
            let s_hy = (p.phy1 + p.phy2 * dfz) * p.lhy + p.phy3 * g_y;
            let s_vy = fz * (p.pvy1 + p.pvy2 * dfz) * p.lvy * c.lmuy_prime
                + fz * (p.pvy3 + p.pvy4 * dfz) * g_y * c.lmuy_prime;
            (s_hy, s_vy)
        }
        Version::Mf61 | Version::Mf62 => {
            let s_vyg = fz * (p.pvy3 + p.pvy4 * dfz) * g_y * p.lkyc * c.lmuy_prime * zeta2; // (4.E28)
            let k_yg0 = fz * (p.pky6 + p.pky7 * dfz) * (F::ONE + p.ppy5 * dpi) * p.lkyc; // (4.E30)
            let (zeta0, zeta4) = match spin {
                Some(_) => {
                    let s_hyp = super::turnslip::s_hyp::<F, M>(p, c, k_yg0);
                    (F::ZERO, F::ONE + s_hyp - s_vyg / k_ya_prime) // (4.83), (4.84)
                }
                None => (F::ONE, F::ONE),
            };
            let s_hy = (p.phy1 + p.phy2 * dfz) * p.lhy
                + ((k_yg0 * g_y - s_vyg) / k_ya_prime) * zeta0
                + zeta4
                - F::ONE; // (4.E27)
            let s_vy = fz * (p.pvy1 + p.pvy2 * dfz) * p.lvy * c.lmuy_prime * zeta2 + s_vyg; // (4.E29)
            (s_hy, s_vy)
        }
    };
    if c.low_speed {
        s_vy *= c.red_smooth;
        s_hy *= c.red_smooth;
    }
    let alpha_y = c.alpha_star + s_hy; // (33), (4.E20)
    let c_y = p.pcy1 * p.lcy; // (35), (4.E21)
    let mut mu_y = (p.pdy1 + p.pdy2 * dfz)
        * (F::ONE + p.ppy3 * dpi + p.ppy4 * dpi * dpi)
        * (F::ONE - p.pdy3 * g_y * g_y)
        * c.lmuy_star; // (37), (4.E23)
    let d_y = mu_y * fz * zeta2; // (36), (4.E22)
    let e_y = (p.pey1 + p.pey2 * dfz)
        * (F::ONE + p.pey5 * g_y * g_y - (p.pey3 + p.pey4 * g_y) * alpha_y.sign_nz())
        * p.ley; // (38), (4.E24)
    let e_y = clip_e(e_y, c);
    let b_y = k_ya / (c_y * d_y + eps * d_y.sign_nz()); // (40), (4.E26) with the signed ε
    let mut fy0 = magic_sin::<F, M>(b_y, c_y, d_y, e_y, alpha_y) + s_vy; // (32), (4.E19)
    if c.use_alpha_star && c.vx < F::ZERO {
        // With α* = tan(α)·sign(Vx) the force changes sign with Vx; undo it (MFeval, TNO).
        fy0 = -fy0;
    }
    if fz == F::ZERO {
        mu_y = F::ZERO;
    }
    Fy0 {
        fy0,
        mu_y,
        k_ya,
        s_hy,
        s_vy,
        b_y,
        c_y,
        zeta2,
    }
}

/// Factors of the pneumatic trail t and the residual torque Mzr at pure slip, from which the
/// combined-slip aligning torque is built.
#[derive(Debug, Clone, Copy)]
pub struct Mz0<F> {
    /// αr = α* + SHf (47), (4.E37) \[rad\].
    pub alpha_r: F,
    /// αt = α* + SHt (45), (4.E34) \[rad\].
    pub alpha_t: F,
    /// Kyα' = Kyα + ε·sign(Kyα) (4.E39) \[N/rad\].
    pub k_ya_prime: F,
    /// Bt (50), (A58).
    pub b_t: F,
    /// Ct (51), (4.E41).
    pub c_t: F,
    /// Dt \[m\] (52), (A60).
    pub d_t: F,
    /// Et (53), (4.E44).
    pub e_t: F,
    /// Br (55), (4.E45).
    pub b_r: F,
    /// Cr (4.E46): 1 without turn slip.
    pub c_r: F,
    /// Dr \[N·m\] (56), (4.E47).
    pub d_r: F,
}

/// Pneumatic trail and residual torque factors, eqs. (43)–(56) / (4.E31)–(4.E49).
///
/// RECONSTRUCTED (paper eqs. 43–56, damaged in the scan): from eqs. (7)–(11) of the body and
/// MF 5.2, which kept Delft Tyre 96's aligning torque. The equation numbers cited are the
/// paper's where its text is legible, else the MF 5.2/6.1 numbers.
pub fn mz0<F: Float, M: Backend<F>>(p: &Params<F>, c: &mut Conditioned<F>, fy0: &Fy0<F>) -> Mz0<F> {
    let fz = c.fz_low; // Dt, Dr use Fz raised to FZMIN (TNO limit handling)
    let (dfz, dpi) = (c.dfz, c.dpi);
    let r0 = p.unloaded_radius;
    let mf6 = p.version.is_mf6();
    // γz (49): γ·λγz before MF 6; MF 6 scales the camber torque with λKzγ in Dr.
    let (g_z, g_z_star) = if mf6 {
        (c.gamma, c.gamma_star)
    } else {
        (c.gamma * p.lgaz, c.gamma_star * p.lgaz)
    };
    let s_ht = p.qhz1 + p.qhz2 * dfz + (p.qhz3 + p.qhz4 * dfz) * g_z_star; // (54), (4.E35)
    let k_ya_prime = fy0.k_ya + F::from_f64(EPS) * fy0.k_ya.sign_nz(); // (4.E39)
    let s_hf = fy0.s_hy + fy0.s_vy / k_ya_prime; // (48), (4.E38)
    let alpha_r = c.alpha_star + s_hf; // (47), (4.E37)
    let alpha_t = c.alpha_star + s_ht; // (45), (4.E34)
    let zeta5 = c.turn.map_or(F::ONE, |t| t.zeta5);
    let fz0_for_dt = match p.version {
        Version::Delft96 => p.fnomin, // (52): R0/Fz0
        _ => c.fz0_prime,             // (A60): R0/Fz0'
    };
    // (A60): γ, not γ*, and QDZ3 without |·| (matches TNO; MFeval notes the book's (4.E43)
    // differs at negative camber).
    let d_t = (p.qdz1 + p.qdz2 * dfz)
        * (F::ONE - p.ppz1 * dpi)
        * (F::ONE + p.qdz3 * g_z + p.qdz4 * g_z * g_z)
        * fz
        * (r0 / fz0_for_dt)
        * p.ltr
        * zeta5; // (52), (A60)
    let b_t = (p.qbz1 + p.qbz2 * dfz + p.qbz3 * dfz * dfz)
        * (F::ONE + p.qbz4 * g_z + p.qbz5 * g_z.abs())
        * p.lky
        / c.lmuy_star; // (50), (A58)
    let c_t = p.qcz1; // (51), (4.E41)
    let e_t = (p.qez1 + p.qez2 * dfz + p.qez3 * dfz * dfz)
        * (F::ONE + (p.qez4 + p.qez5 * g_z_star) * F::FRAC_2_PI * M::atan(b_t * c_t * alpha_t)); // (53), (4.E44)
    let e_t = clip_e(e_t, c);

    let (zeta0, zeta2, zeta6, zeta7, zeta8) = match c.turn {
        Some(_) => {
            let g_yk =
                super::combined::fy::<F, M>(p, c, fy0.fy0, fy0.mu_y, c.gamma_star, fy0.zeta2).g_yk;
            super::turnslip::mz_zetas::<F, M>(p, c, fz, fy0.mu_y, g_yk)
        }
        None => (F::ONE, F::ONE, F::ONE, F::ONE, F::ONE),
    };
    let camber_torque = if mf6 {
        ((p.qdz8 + p.qdz9 * dfz) * (F::ONE + p.ppz2 * dpi)
            + (p.qdz10 + p.qdz11 * dfz) * g_z_star.abs())
            * g_z_star
            * p.lkzc
            * zeta0
    } else {
        (p.qdz8 + p.qdz9 * dfz) * g_z_star // (56)
    };
    let d_r = fz
        * r0
        * ((p.qdz6 + p.qdz7 * dfz) * p.lres * zeta2 + camber_torque)
        * c.lmuy_star
        * c.vx.sign()
        * c.cos_alpha_star
        + zeta8
        - F::ONE; // (56), (4.E47); the cos α of (46)/(72) is carried here
    let b_r = (p.qbz9 * p.lky / c.lmuy_star + p.qbz10 * fy0.b_y * fy0.c_y) * zeta6; // (55), (4.E45)
    let c_r = zeta7; // (4.E46)
    Mz0 {
        alpha_r,
        alpha_t,
        k_ya_prime,
        b_t,
        c_t,
        d_t,
        e_t,
        b_r,
        c_r,
        d_r,
    }
}
