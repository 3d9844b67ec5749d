//! Pure-slip Magic Formula: Fx0(κ), Fy0(α), and the pneumatic trail / residual torque factors.
//!
//! Paper (Delft Tyre 96) eqs. (22)–(56); MF 5.2/6.1 (4.E9)–(4.E49) with the TNO corrections
//! (A58), (A60) of Besselink et al. (2010). Version differences are coded where they occur:
//! - Delft 96: Kx = Fz(pKx1 + pKx2·dfz)·exp(−pKx3·dfz) (28) — note the minus sign; camber
//!   enters Fy through γy = γ·λγy in the shifts, and λHy, λVy scale the camber shifts too (41),
//!   (42); no μx camber term, no E in the combined-slip weights.
//! - MF 5.2: exp(+PKX3·dfz); SHy = (PHY1 + PHY2·dfz)·λHy + PHY3·γy; γx, γy, γz with λγ.
//! - MF 6.x: pressure terms; camber through Kyγ0 (4.E30) and the shift (4.E27); PKY4..7, PEY5.
//!
//! Each quantity is computed in one of three stages (see [`super::prepared`]): `*_load`
//! (Fz, γ, p, Vx and the scaling factors other than λμ: every exp/sin/atan of the load),
//! `*_mu` (the friction scalings λμx*, λμy*: arithmetic only) and `*_slip` (κ, α). The slip
//! stage is generic over the type `G` it computes in (the stored `F`, or dual numbers for
//! derivatives; [`Lift`]).

use super::limits::Cond;
use super::{clip_e, magic_sin, Params, Version, EPS};
use crate::math::{Backend, Lift, Mask, Real};

/// Results of [`fx0`].
#[cfg(test)]
#[derive(Debug, Clone, Copy)]
pub struct Fx0<F> {
    /// Pure longitudinal force Fx0 \[N\] (22), (4.E9).
    pub fx0: F,
    /// Kxκ \[N\] (28), (4.E15).
    pub k_xk: F,
}

/// γx: camber as Fx sees it — γ·λγx (MF 5.x), γ (MF 6.x, Delft 96 has no μx camber term).
fn gamma_x<F: Real>(p: &Params<F>, gamma: F) -> F {
    match p.version {
        Version::Mf52 => gamma * p.lgax,
        _ => gamma,
    }
}

/// Load stage of Fx0, eqs. (22)–(31) / (4.E9)–(4.E18): every factor free of κ and λμ.
#[derive(Debug, Clone, Copy, Default)]
pub struct Fx0Load<F> {
    /// μx / λμx* \[-\] (26), (4.E13).
    pub mu_x1: F,
    /// Cx (24), (4.E11).
    pub c_x: F,
    /// Kxκ \[N\] (28), (4.E15).
    pub k_xk: F,
    /// SHx (30), (4.E17), with the low-speed reduction.
    pub s_hx: F,
    /// SVx / (λμx'·ζ1) \[N\] (31), (4.E18).
    pub s_vx1: F,
    /// ζ1 (turn slip, 1 without).
    pub zeta1: F,
    /// pEx1 + pEx2·dfz + pEx3·dfz² of (27), (4.E14).
    pub e_x1: F,
    /// pEx4.
    pub pex4: F,
    /// λEx.
    pub lex: F,
}

/// [`Fx0Load`] of the conditioned load `c`.
#[inline(always)]
pub fn fx0_load<F: Real, M: Backend<F>>(p: &Params<F>, c: &Cond<F>) -> Fx0Load<F> {
    let (fz, dfz, dpi) = (c.fz, c.dfz, c.dpi);
    let zeta1 = c.turn.map_or(F::ONE, |t| t.zeta1);
    let gx = gamma_x(p, c.gamma);
    let c_x = p.pcx1 * p.lcx; // (24), (4.E11)
    let mu_x1 = (p.pdx1 + p.pdx2 * dfz)
        * (F::ONE + p.ppx3 * dpi + p.ppx4 * dpi * dpi)
        * (F::ONE - p.pdx3 * gx * gx); // (26), (4.E13) without λμx*
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
    let mut s_hx = (p.phx1 + p.phx2 * dfz) * p.lhx; // (30), (4.E17)
    if c.low_speed.any() {
        s_hx *= c.red_smooth;
    }
    Fx0Load {
        mu_x1,
        c_x,
        k_xk,
        s_hx,
        s_vx1: fz * (p.pvx1 + p.pvx2 * dfz) * p.lvx, // (31), (4.E18) without λμx'·ζ1
        zeta1,
        e_x1: p.pex1 + p.pex2 * dfz + p.pex3 * dfz * dfz,
        pex4: p.pex4,
        lex: p.lex,
    }
}

/// Friction stage of Fx0: the factors that scale with λμx.
#[derive(Debug, Clone, Copy, Default)]
pub struct Fx0Mu<G> {
    /// μx \[-\] (26), (4.E13).
    pub mu_x: G,
    /// Dx \[N\] (25), (4.E12).
    pub d_x: G,
    /// Bx (29), (4.E16).
    pub b_x: G,
    /// SVx \[N\] (31), (4.E18).
    pub s_vx: G,
}

/// [`Fx0Mu`] at λμx* = `lmux_star`, λμx' = `lmux_prime` (4.E7), (4.E8).
#[inline(always)]
pub fn fx0_mu<F: Real, G: Lift<F>>(
    l: &Fx0Load<F>,
    c: &Cond<F>,
    lmux_star: G,
    lmux_prime: G,
) -> Fx0Mu<G> {
    // Load-stage values (`F`) meet λμ (`G`) in mixed operations (`Lift<F>`).
    let mu_x = G::select(c.fz.mask_eq(F::ZERO), G::ZERO, lmux_star * l.mu_x1); // (26), (4.E13)
    let d_x = mu_x * c.fz * l.zeta1; // (25), (4.E12)
    let eps = F::from_f64(EPS) * d_x.value().sign_nz();
    let b_x = G::lift(l.k_xk) / (d_x * l.c_x + eps); // (29), (4.E16) with the signed ε
    let mut s_vx = lmux_prime * l.s_vx1 * l.zeta1; // (31), (4.E18)
    if c.low_speed.any() {
        s_vx = s_vx * c.red_smooth;
    }
    Fx0Mu {
        mu_x,
        d_x,
        b_x,
        s_vx,
    }
}

/// Slip stage of Fx0 at the conditioned κ: (22), (23), (27) / (4.E9), (4.E10), (4.E14).
#[inline(always)]
pub fn fx0_slip<F: Real, H: Lift<F>, G: Lift<F> + Lift<H>, M: Backend<G>>(
    l: &Fx0Load<F>,
    m: &Fx0Mu<H>,
    c: &Cond<F>,
    kappa: G,
    flags: &mut F::Flags,
) -> G {
    let kappa_x = kappa + l.s_hx; // (23), (4.E10)
                                  // Ex depends on κ through sign(κx) alone (derivative 0): computed in F.
    let sign_x = <G as Lift<F>>::value(kappa_x.sign());
    let e_x = l.e_x1 * (F::ONE - l.pex4 * sign_x) * l.lex; // (27), (4.E14)
    let e_x = clip_e(e_x, c.limits, flags);
    let mut fx0 = magic_sin::<G, M, H, F, H, F>(m.b_x, l.c_x, m.d_x, e_x, kappa_x) + m.s_vx; // (22), (4.E9)
    if !c.transient {
        // Running backwards: mirror image (appendix, first paragraph), for steady-state slips
        // defined with κ = −1 locked in both directions. Slips from the transient model
        // (κ' = −Vsx/|Vx|) already carry the direction: a wheel locked while sliding backwards
        // has κ' = +1 and must get Fx > 0 (MFeval's dynamic modes flip κ for the same reason).
        fx0 = G::select(c.vx.mask_lt(F::ZERO), -fx0, fx0);
    }
    fx0
}

/// Pure longitudinal slip force, eqs. (22)–(31) / (4.E9)–(4.E18), at the conditioned `c`: the
/// three stages in a row (`mf::eval` runs them staged; the tests check the pure-slip identities
/// with this).
#[cfg(test)]
pub fn fx0<F: Real, M: Backend<F>>(p: &Params<F>, c: &mut Cond<F>) -> Fx0<F> {
    let l = fx0_load::<F, M>(p, c);
    let m = fx0_mu::<F, F>(&l, c, c.lmux_star, c.lmux_prime);
    let mut flags = c.flags;
    let fx0 = fx0_slip::<F, F, F, M>(&l, &m, c, c.kappa, &mut flags);
    c.flags = flags;
    Fx0 { fx0, k_xk: l.k_xk }
}

/// Results of [`fy0`].
#[cfg(test)]
#[derive(Debug, Clone, Copy)]
pub struct Fy0<F> {
    /// Pure lateral force Fy0 \[N\] (32), (4.E19).
    pub fy0: F,
    /// Kyα \[N/rad\] (39), (4.E25).
    pub k_ya: F,
    /// SHy \[rad\] (41), (4.E27).
    pub s_hy: F,
}

/// Load stage of Fy0, eqs. (32)–(42) / (4.E19)–(4.E30), at one camber: every factor free of
/// α and λμ.
#[derive(Debug, Clone, Copy, Default)]
pub struct Fy0Load<F> {
    /// Kyα \[N/rad\] (39), (4.E25).
    pub k_ya: F,
    /// Kyα' = Kyα + ε·sign(Kyα) (4.E39).
    pub k_ya_prime: F,
    /// μy / λμy* (37), (4.E23).
    pub mu_y1: F,
    /// Cy (35), (4.E21).
    pub c_y: F,
    /// ζ2 (turn slip, 1 without).
    pub zeta2: F,
    /// SVy's term that scales with λμy' (and ζ2) \[N\] (42), (4.E29).
    pub s_vy1: F,
    /// SVy's camber term per λμy' (MF 5.2), SVyγ per λμy'·ζ2 (MF 6.x, (4.E28)) \[N\].
    pub s_vyg1: F,
    /// SHy without the SVyγ terms (41), (4.E27).
    pub s_hy1: F,
    /// Kyγ0·γ* (4.E30) (MF 6.x).
    pub k_yg: F,
    /// ζ0 (turn slip; 1 without).
    pub zeta0: F,
    /// SHyp (4.80) (turn slip; 0 without).
    pub s_hyp: F,
    /// Turn slip on.
    pub turn: bool,
    /// pEy1 + pEy2·dfz of (38), (4.E24).
    pub e_y1: F,
    /// 1 + pEy5·γ*².
    pub e_y2: F,
    /// pEy3 + pEy4·γ*.
    pub e_y3: F,
    /// λEy.
    pub ley: F,
}

/// [`Fy0Load`] at camber `gamma_star` (the aligning torque needs Fy0 at γ = 0 too), with or
/// without turn slip.
#[inline(always)]
pub fn fy0_load<F: Real, M: Backend<F>>(
    p: &Params<F>,
    c: &mut Cond<F>,
    gamma_star: F,
    turn_slip: bool,
) -> Fy0Load<F> {
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

    let (mut zeta0, mut s_hyp, mut k_yg) = (F::ONE, F::ZERO, F::ZERO);
    let (s_hy1, s_vy1, s_vyg1) = match p.version {
        Version::Delft96 => {
            // (41), (42): λHy and λVy scale the camber terms too.
            let s_hy = (p.phy1 + p.phy2 * dfz + p.phy3 * g_y) * p.lhy;
            let s_vy = fz * (p.pvy1 + p.pvy2 * dfz + (p.pvy3 + p.pvy4 * dfz) * g_y) * p.lvy;
            (s_hy, s_vy, F::ZERO)
        }
        Version::Mf52 => {
            // MF-Tyre 5.2 equation manual.
            let s_hy = (p.phy1 + p.phy2 * dfz) * p.lhy + p.phy3 * g_y;
            (
                s_hy,
                fz * (p.pvy1 + p.pvy2 * dfz) * p.lvy,
                fz * (p.pvy3 + p.pvy4 * dfz) * g_y,
            )
        }
        Version::Mf61 | Version::Mf62 => {
            let s_vyg1 = fz * (p.pvy3 + p.pvy4 * dfz) * g_y * p.lkyc; // (4.E28) per λμy'·ζ2
            let k_yg0 = fz * (p.pky6 + p.pky7 * dfz) * (F::ONE + p.ppy5 * dpi) * p.lkyc; // (4.E30)
            k_yg = k_yg0 * g_y;
            if spin.is_some() {
                zeta0 = F::ZERO; // (4.83)
                s_hyp = super::turnslip::s_hyp::<F, M>(p, c, k_yg0);
            }
            let s_hy1 = (p.phy1 + p.phy2 * dfz) * p.lhy;
            (s_hy1, fz * (p.pvy1 + p.pvy2 * dfz) * p.lvy, s_vyg1)
        }
    };
    Fy0Load {
        k_ya,
        k_ya_prime,
        mu_y1: (p.pdy1 + p.pdy2 * dfz)
            * (F::ONE + p.ppy3 * dpi + p.ppy4 * dpi * dpi)
            * (F::ONE - p.pdy3 * g_y * g_y), // (37), (4.E23) without λμy*
        c_y: p.pcy1 * p.lcy, // (35), (4.E21)
        zeta2,
        s_vy1,
        s_vyg1,
        s_hy1,
        k_yg,
        zeta0,
        s_hyp,
        turn: spin.is_some(),
        e_y1: p.pey1 + p.pey2 * dfz,
        e_y2: F::ONE + p.pey5 * g_y * g_y,
        e_y3: p.pey3 + p.pey4 * g_y,
        ley: p.ley,
    }
}

/// Friction stage of Fy0: the factors that scale with λμy.
#[derive(Debug, Clone, Copy, Default)]
pub struct Fy0Mu<G> {
    /// μy \[-\] (37), (4.E23), signed as the file fits it.
    pub mu_y: G,
    /// Dy \[N\] (36), (4.E22).
    pub d_y: G,
    /// By (40), (4.E26).
    pub b_y: G,
    /// SHy \[rad\] (41), (4.E27).
    pub s_hy: G,
    /// SVy \[N\] (42), (4.E29).
    pub s_vy: G,
}

/// [`Fy0Mu`] at λμy* = `lmuy_star`, λμy' = `lmuy_prime` (4.E7), (4.E8).
#[inline(always)]
pub fn fy0_mu<F: Real, G: Lift<F>>(
    l: &Fy0Load<F>,
    c: &Cond<F>,
    lmuy_star: G,
    lmuy_prime: G,
) -> Fy0Mu<G> {
    // Load-stage values (`F`) meet λμ (`G`) in mixed operations (`Lift<F>`).
    let f = |x: F| G::lift(x);
    let zeta2 = l.zeta2;
    let (mut s_hy, mut s_vy) = match c.version {
        // (41), (42).
        Version::Delft96 => (f(l.s_hy1), lmuy_prime * l.s_vy1),
        Version::Mf52 => (f(l.s_hy1), lmuy_prime * l.s_vy1 + lmuy_prime * l.s_vyg1),
        Version::Mf61 | Version::Mf62 => {
            let k_ya_prime = l.k_ya_prime;
            let s_vyg = lmuy_prime * l.s_vyg1 * zeta2; // (4.E28)
            let zeta4 = if l.turn {
                G::ONE + f(l.s_hyp) - s_vyg / k_ya_prime // (4.84)
            } else {
                G::ONE
            };
            let s_hy = f(l.s_hy1) + ((f(l.k_yg) - s_vyg) / k_ya_prime) * l.zeta0 + zeta4 - G::ONE; // (4.E27)
            let s_vy = lmuy_prime * l.s_vy1 * zeta2 + s_vyg; // (4.E29)
            (s_hy, s_vy)
        }
    };
    if c.low_speed.any() {
        s_vy = s_vy * c.red_smooth;
        s_hy = s_hy * c.red_smooth;
    }
    let mu_y = lmuy_star * l.mu_y1; // (37), (4.E23)
    let d_y = mu_y * c.fz * zeta2; // (36), (4.E22)
    let eps = F::from_f64(EPS) * d_y.value().sign_nz();
    let b_y = f(l.k_ya) / (d_y * l.c_y + eps); // (40), (4.E26) with the signed ε
    Fy0Mu {
        mu_y: G::select(c.fz.mask_eq(F::ZERO), G::ZERO, mu_y),
        d_y,
        b_y,
        s_hy,
        s_vy,
    }
}

/// Slip stage of Fy0 at α*: (32), (33), (38) / (4.E19), (4.E20), (4.E24).
#[inline(always)]
pub fn fy0_slip<F: Real, H: Lift<F>, G: Lift<F> + Lift<H>, M: Backend<G>>(
    l: &Fy0Load<F>,
    m: &Fy0Mu<H>,
    c: &Cond<F>,
    alpha_star: G,
    flags: &mut F::Flags,
) -> G {
    let alpha_y = alpha_star + m.s_hy; // (33), (4.E20)
                                       // Ey depends on α through sign(αy) alone (derivative 0): computed in F.
    let sign_y = <G as Lift<F>>::value(alpha_y.sign_nz());
    let e_y = l.e_y1 * (l.e_y2 - l.e_y3 * sign_y) * l.ley; // (38), (4.E24)
    let e_y = clip_e(e_y, c.limits, flags);
    let mut fy0 = magic_sin::<G, M, H, F, H, F>(m.b_y, l.c_y, m.d_y, e_y, alpha_y) + m.s_vy; // (32), (4.E19)
    if c.use_alpha_star {
        // With α* = tan(α)·sign(Vx) the force changes sign with Vx; undo it (MFeval, TNO).
        fy0 = G::select(c.vx.mask_lt(F::ZERO), -fy0, fy0);
    }
    fy0
}

/// Pure side-slip force, eqs. (32)–(42) / (4.E19)–(4.E30), at the conditioned `c` and camber
/// `gamma_star`: the three stages in a row (as [`fx0`]).
#[cfg(test)]
pub fn fy0<F: Real, M: Backend<F>>(
    p: &Params<F>,
    c: &mut Cond<F>,
    gamma_star: F,
    turn_slip: bool,
) -> Fy0<F> {
    let l = fy0_load::<F, M>(p, c, gamma_star, turn_slip);
    let m = fy0_mu::<F, F>(&l, c, c.lmuy_star, c.lmuy_prime);
    let mut flags = c.flags;
    let fy0 = fy0_slip::<F, F, F, M>(&l, &m, c, c.alpha_star, &mut flags);
    c.flags = flags;
    Fy0 {
        fy0,
        k_ya: l.k_ya,
        s_hy: m.s_hy,
    }
}

/// Load stage of the pneumatic trail t and the residual torque Mzr, eqs. (43)–(56) /
/// (4.E31)–(4.E49).
///
/// RECONSTRUCTED (paper eqs. 43–56, damaged in the scan): from eqs. (7)–(11) of the body and
/// MF 5.2, which kept Delft Tyre 96's aligning torque. The equation numbers cited are the
/// paper's where its text is legible, else the MF 5.2/6.1 numbers.
#[derive(Debug, Clone, Copy, Default)]
pub struct Mz0Load<F> {
    /// SHt \[rad\] (54), (4.E35).
    pub s_ht: F,
    /// Dt \[m\] (52), (A60).
    pub d_t: F,
    /// Bt·λμy* (50), (A58).
    pub b_t1: F,
    /// Ct (51), (4.E41).
    pub c_t: F,
    /// qEz1 + qEz2·dfz + qEz3·dfz² of (53), (4.E44).
    pub e_t1: F,
    /// (qEz4 + qEz5·γz*)·2/π of (53), (4.E44).
    pub e_t2: F,
    /// Fz·R0·(…) of Dr (56), (4.E47), before λμy*, sign(Vx) and cos α*.
    pub d_r1: F,
    /// ζ8 of Dr (4.E47) (turn slip; 1 without).
    pub zeta8: F,
    /// qBz9·λKy of Br (55), (4.E45).
    pub b_r1: F,
    /// qBz10 of Br.
    pub qbz10: F,
    /// ζ6 of Br (turn slip; 1 without).
    pub zeta6: F,
    /// Cr (4.E46): 1 without turn slip.
    pub c_r: F,
}

/// [`Mz0Load`] of the conditioned load `c`; with turn slip, `turn_g_yk` is (μy, Gyκ) at the
/// slips of `c`, which the turn-slip factors (4.92)–(4.104) need.
#[inline(always)]
pub fn mz0_load<F: Real, M: Backend<F>>(
    p: &Params<F>,
    c: &mut Cond<F>,
    turn_g_yk: Option<(F, F)>,
) -> Mz0Load<F> {
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
    let b_t1 = (p.qbz1 + p.qbz2 * dfz + p.qbz3 * dfz * dfz)
        * (F::ONE + p.qbz4 * g_z + p.qbz5 * g_z.abs())
        * p.lky; // (50), (A58) without 1/λμy*
    let (zeta0, zeta2, zeta6, zeta7, zeta8) = match turn_g_yk {
        Some((mu_y, g_yk)) => super::turnslip::mz_zetas::<F, M>(p, c, fz, mu_y, g_yk),
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
    Mz0Load {
        s_ht,
        d_t,
        b_t1,
        c_t: p.qcz1, // (51), (4.E41)
        e_t1: p.qez1 + p.qez2 * dfz + p.qez3 * dfz * dfz,
        e_t2: (p.qez4 + p.qez5 * g_z_star) * F::FRAC_2_PI,
        d_r1: fz * r0 * ((p.qdz6 + p.qdz7 * dfz) * p.lres * zeta2 + camber_torque), // (56), (4.E47)
        zeta8,
        b_r1: p.qbz9 * p.lky,
        qbz10: p.qbz10,
        zeta6,
        c_r: zeta7, // (4.E46)
    }
}

/// Friction stage of t and Mzr.
#[derive(Debug, Clone, Copy, Default)]
pub struct Mz0Mu<G> {
    /// Bt (50), (A58).
    pub b_t: G,
    /// The factor of cos α* in Dr \[N·m\] (56), (4.E47).
    pub d_r1: G,
    /// Br (55), (4.E45).
    pub b_r: G,
    /// SHf = SHy + SVy/Kyα' \[rad\] (48), (4.E38).
    pub s_hf: G,
}

/// [`Mz0Mu`] at λμy* = `lmuy_star`, with Fy0's friction stage `fy`.
#[inline(always)]
pub fn mz0_mu<F: Real, G: Lift<F>>(
    l: &Mz0Load<F>,
    fy_l: &Fy0Load<F>,
    fy: &Fy0Mu<G>,
    c: &Cond<F>,
    lmuy_star: G,
) -> Mz0Mu<G> {
    let f = |x: F| G::lift(x);
    Mz0Mu {
        b_t: f(l.b_t1) / lmuy_star,             // (50), (A58)
        d_r1: lmuy_star * l.d_r1 * c.vx.sign(), // (56), (4.E47)
        b_r: (f(l.b_r1) / lmuy_star + fy.b_y * l.qbz10 * fy_l.c_y) * l.zeta6, // (55), (4.E45)
        s_hf: fy.s_hy + fy.s_vy / fy_l.k_ya_prime, // (48), (4.E38)
    }
}
