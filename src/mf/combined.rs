//! Combined slip: Fx(κ, α), Fy(α, κ) by the weighting functions G of eq. (12), and the
//! aligning torque Mz of eq. (17).
//!
//! Paper eqs. (13)–(18) and (57)–(75); MF 5.2/6.1 (4.E50)–(4.E78) with (A54)–(A56) of
//! Besselink et al. (2010). Delft Tyre 96 has no curvature factor E in the weights ("the factor
//! E was not needed"), MF 5.2 adds REX/REY; the files of each version carry the matching keys,
//! and the absent ones are zero.

use super::limits::Cond;
use super::FlagSet;
use super::{clip_e, cos_atan, magic_cos, Flags, Params};
use crate::math::{Backend, Lift, Mask, Real};

/// G = cos[C·atan{B·x − E(B·x − atan B·x)}] / cos[C·atan{B·S − E(B·S − atan B·S)}], eqs. (14),
/// (4.E51)/(4.E52), (4.E59)/(4.E60), at x = slip + S. A vanishing denominator (only for C > 1
/// with a large shift S: outside any fitted tyre) returns G = 1 and flags [`Flags::GUARD`].
/// Without a shift (S = 0) the denominator is cos 0 = 1 exactly and is not evaluated.
///
/// Computed in the slips' type `G`; C, E and S are load-stage values (`F`).
#[inline(always)]
fn weight<F: Real, G: Lift<F>, M: Backend<G>>(
    b: G,
    c: F,
    e: F,
    s_h: F,
    x: G,
    flags: &mut F::Flags,
) -> G {
    // S = 0 in every lane; where only some lanes have it, their G0 is cos 0 = 1 exactly.
    if s_h.mask_eq(F::ZERO).all() {
        return magic_cos::<G, M, G, F, F>(b, c, e, x);
    }
    // The denominator's B·S taken as S·B (the same product): S is the load-stage value.
    let g0 = magic_cos::<G, M, F, F, F>(s_h, c, e, b);
    let vanished = g0.abs().mask_lt(G::from_f64(1e-6));
    flags.set_if(Flags::GUARD, vanished);
    if vanished.all() {
        return G::ONE;
    }
    G::select(
        vanished,
        G::ONE,
        magic_cos::<G, M, G, F, F>(b, c, e, x) / g0,
    )
}

/// Load stage of the combined-slip Fx and Fy, (57)–(68) / (4.E50)–(4.E67): the weights'
/// factors free of κ and α.
#[derive(Debug, Clone, Copy, Default)]
pub struct WeightsLoad<F> {
    /// Cxα (4.E55).
    pub c_xa: F,
    /// Exα (4.E56), clipped; 0 for Delft 96.
    pub e_xa: F,
    /// SHxα (4.E57).
    pub s_hxa: F,
    /// rBx1 + rBx3·γ*² of Bxα (4.E54).
    pub b_xa1: F,
    /// rBx2.
    pub rbx2: F,
    /// λxα.
    pub lxal: F,
    /// Fz·(rVy1 + rVy2·dfz + rVy3·γ*) of DVyκ (68), (4.E67) per μy·ζ2.
    pub d_vyk1: F,
    /// rVy1 + rVy2·dfz + rVy3·γ* is 0 (in every lane): no κ-induced side force. (A lane where
    /// it is 0 gets SVyκ = 0 from the formula too: DVyκ = 0.)
    pub no_vyk: bool,
    /// rVy4, rVy5, rVy6.
    pub rvy4: F,
    /// rVy5.
    pub rvy5: F,
    /// rVy6.
    pub rvy6: F,
    /// λVyκ.
    pub lvyka: F,
    /// SHyκ (4.E65).
    pub s_hyk: F,
    /// Eyκ (4.E64), clipped; 0 for Delft 96.
    pub e_yk: F,
    /// Cyκ (4.E63).
    pub c_yk: F,
    /// rBy1 + rBy4·γ*² of Byκ (15), (4.E62).
    pub b_yk1: F,
    /// rBy2.
    pub rby2: F,
    /// rBy3.
    pub rby3: F,
    /// λyκ.
    pub lyka: F,
}

/// [`WeightsLoad`] of the conditioned load `c`.
#[inline(always)]
pub fn weights_load<F: Real>(p: &Params<F>, c: &mut Cond<F>) -> WeightsLoad<F> {
    let (dfz, g) = (c.dfz, c.gamma_star);
    let r_vy = p.rvy1 + p.rvy2 * dfz + p.rvy3 * g;
    WeightsLoad {
        c_xa: p.rcx1,                                                // (4.E55)
        e_xa: clip_e(p.rex1 + p.rex2 * dfz, c.limits, &mut c.flags), // (4.E56); 0 for Delft 96
        s_hxa: p.rhx1,                                               // (4.E57)
        b_xa1: p.rbx1 + p.rbx3 * g * g,
        rbx2: p.rbx2,
        lxal: p.lxal,
        d_vyk1: c.fz * r_vy,
        no_vyk: r_vy.mask_eq(F::ZERO).all(),
        rvy4: p.rvy4,
        rvy5: p.rvy5,
        rvy6: p.rvy6,
        lvyka: p.lvyka,
        s_hyk: p.rhy1 + p.rhy2 * dfz, // (4.E65); RHY2 from MF 5.2 on
        e_yk: clip_e(p.rey1 + p.rey2 * dfz, c.limits, &mut c.flags), // (4.E64); 0 for Delft 96
        c_yk: p.rcy1,                 // (4.E63)
        b_yk1: p.rby1 + p.rby4 * g * g,
        rby2: p.rby2,
        rby3: p.rby3,
        lyka: p.lyka,
    }
}

/// Combined-slip longitudinal force, (57)–(62) RECONSTRUCTED for Delft 96 (from eq. (12) and
/// MF 5.2), (4.E50)–(4.E57): the slip stage, given Fx0.
#[inline(always)]
pub fn fx_slip<F: Real, G: Lift<F>, M: Backend<G>>(
    w: &WeightsLoad<F>,
    kappa: G,
    alpha_star: G,
    fx0: G,
    flags: &mut F::Flags,
) -> G {
    let b_xa = cos_atan::<G, M>(kappa * w.rbx2) * w.b_xa1 * w.lxal; // (4.E54)
    let alpha_s = alpha_star + w.s_hxa; // (4.E53)
    let g_xa = weight::<F, G, M>(b_xa, w.c_xa, w.e_xa, w.s_hxa, alpha_s, flags); // (4.E51), (4.E52)
    g_xa * fx0 // (4.E50)
}

/// Results of [`fy_slip`].
#[derive(Debug, Clone, Copy)]
pub struct Fy<F> {
    /// Combined-slip lateral force Fy \[N\] (13), (4.E58).
    pub fy: F,
    /// Gyκ (14), (4.E59). It does not depend on Fy0, μy or ζ2: the aligning torque reuses it.
    pub g_yk: F,
    /// SVyκ \[N\] (16), (4.E66), with the low-speed reduction: what MF 5.2's aligning torque
    /// takes off Fy.
    pub s_vyk: F,
}

/// Gyκ (14), (4.E59), (4.E60), with Byκ (15), (4.E62) and κS (4.E61): depends on neither Fy0
/// nor μy.
#[inline(always)]
pub fn g_yk<F: Real, G: Lift<F>, M: Backend<G>>(
    w: &WeightsLoad<F>,
    kappa: G,
    alpha_star: G,
    flags: &mut F::Flags,
) -> G {
    let b_yk = cos_atan::<G, M>((alpha_star - w.rby3) * w.rby2) * w.b_yk1 * w.lyka; // (15), (4.E62)
    let kappa_s = kappa + w.s_hyk; // (4.E61)
    weight::<F, G, M>(b_yk, w.c_yk, w.e_yk, w.s_hyk, kappa_s, flags) // (14), (4.E59), (4.E60)
}

/// Combined-slip lateral force, eqs. (13)–(16), (63)–(68), (4.E58)–(4.E67): the slip stage,
/// given Fy0, μy (of the friction stage, `H`) and ζ2.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
pub fn fy_slip<F: Real, H: Lift<F>, G: Lift<F> + Lift<H>, M: Backend<G>>(
    w: &WeightsLoad<F>,
    c: &Cond<F>,
    (kappa, alpha_star): (G, G),
    fy0: G,
    mu_y: H,
    zeta2: F,
    flags: &mut F::Flags,
) -> Fy<G> {
    // (68), (4.E67) DVyκ = μy·Fz·(rVy1 + rVy2·dfz + rVy3·γ*)·cos(atan(rVy4·α*))·ζ2, and
    // (16), (4.E66) SVyκ = DVyκ·sin(rVy5·atan(rVy6·κ))·λVyκ, computed per unit μy·ζ2 (and not
    // at all for a file without the κ-induced side force).
    let mut s_vyk_per_mu = if w.no_vyk {
        G::ZERO
    } else {
        cos_atan::<G, M>(alpha_star * w.rvy4)
            * w.d_vyk1
            * M::sin(M::atan(kappa * w.rvy6) * w.rvy5)
            * w.lvyka
    };
    if c.low_speed.any() {
        s_vyk_per_mu = s_vyk_per_mu * c.red_smooth;
    }
    let s_vyk = s_vyk_per_mu * (mu_y * zeta2);
    let g_yk = g_yk::<F, G, M>(w, kappa, alpha_star, flags);
    Fy {
        fy: g_yk * fy0 + s_vyk, // (13), (4.E58)
        g_yk,
        s_vyk,
    }
}

/// The moment arm s of Fx in the aligning torque, eq. (73) / (A56): its coefficients, copied
/// out of a parameter set so that an estimator can carry them without the whole set.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Arm<F> {
    /// R0 \[m\].
    pub r0: F,
    /// Fz0 \[N\].
    pub fz0: F,
    /// SSZ1..SSZ4 \[-\].
    pub ssz: [F; 4],
    /// λs \[-\].
    pub ls: F,
}

impl<F: Real> Arm<F> {
    /// The coefficients of `p`.
    pub fn from_params(p: &Params<F>) -> Self {
        Arm {
            r0: p.unloaded_radius,
            fz0: p.fnomin,
            ssz: [p.ssz1, p.ssz2, p.ssz3, p.ssz4],
            ls: p.ls,
        }
    }

    /// s \[m\] at lateral force `fy` \[N\] (a dual number carries ∂s/∂Fy), normalised load
    /// increment `dfz` and camber `gamma` \[rad\]: s = R0·(ssz1 + ssz2·Fy/Fz0 + (ssz3 +
    /// ssz4·dfz)·γ)·λs (73), (A56) — Fy/Fz0 and γ, not Fz0' and γ*, as the paper and TNO.
    #[inline(always)]
    pub fn s_at<G: Lift<F>>(&self, fy: G, dfz: F, gamma: F) -> G {
        let [s1, s2, s3, s4] = self.ssz;
        (fy / self.fz0 * s2 + s1 + (s3 + s4 * dfz) * gamma) * self.r0 * self.ls
    }
}

/// Results of [`mz_slip`].
#[derive(Debug, Clone, Copy)]
pub struct Mz<F> {
    /// Aligning torque Mz \[N·m\] (17), (69), (4.E71).
    pub mz: F,
    /// Pneumatic trail t \[m\] (70), (4.E73).
    pub t: F,
    /// Residual torque Mzr \[N·m\] (72), (4.E75).
    pub m_zr: F,
}

/// What the combined-slip aligning torque takes from the slip stage's earlier results (in the
/// slips' type `G`) and from the friction stage (`H`).
#[derive(Debug, Clone, Copy)]
pub struct MzIn<G, H> {
    /// κ (conditioned).
    pub kappa: G,
    /// αt = α* + SHt (45), (4.E34) \[rad\].
    pub alpha_t: G,
    /// αr = α* + SHf (47), (4.E37) \[rad\].
    pub alpha_r: G,
    /// Bt (50), (A58).
    pub b_t: H,
    /// Et (53), (4.E44).
    pub e_t: G,
    /// Dr (56), (4.E47) \[N·m\].
    pub d_r: G,
    /// Br (55), (4.E45).
    pub b_r: H,
    /// cos α' (4.E6).
    pub cos_alpha_prime: G,
    /// Combined Fx \[N\].
    pub fx: G,
    /// Combined Fy \[N\].
    pub fy: G,
    /// F'y (4.E74) (MF 6.x) or the Fy − SVyκ of MF 5.2 and Delft 96 \[N\].
    pub fy_arm: G,
}

/// The aligning torque's load-stage factors.
#[derive(Debug, Clone, Copy, Default)]
pub struct MzLoad<F> {
    /// Kxκ/Kyα' of (A54), (A55).
    pub k_ratio: F,
    /// Dt \[m\] (52), (A60).
    pub d_t: F,
    /// Ct (51), (4.E41).
    pub c_t: F,
    /// Cr (4.E46).
    pub c_r: F,
    /// The arm s of Fx (73), (A56).
    pub arm: Arm<F>,
}

/// Combined-slip aligning torque, eqs. (17), (18), (69)–(75) / (4.E71)–(4.E78), (A54)–(A56):
/// the slip stage.
// DIFFERS FROM MFeval: MFeval multiplies t by λFz0 (LFZO), which no published equation has;
// we follow the equations (every bundled file has LFZO = 1, so the oracle cannot tell).
#[inline(always)]
pub fn mz_slip<F: Real, H: Lift<F>, G: Lift<F> + Lift<H>, M: Backend<G>>(
    l: &MzLoad<F>,
    c: &Cond<F>,
    m: &MzIn<G, H>,
) -> Mz<G> {
    // (18), (74), (75), (A54), (A55): equivalent slip angles with (Kxκ/Kyα')²κ².
    let kk = m.kappa * l.k_ratio;
    let kk2 = kk * kk;
    let tan_r = M::tan(m.alpha_r);
    let tan_t = M::tan(m.alpha_t);
    let alpha_r_eq = M::atan(M::sqrt(tan_r * tan_r + kk2)) * m.alpha_r.sign(); // (75), (A54)
    let alpha_t_eq = M::atan(M::sqrt(tan_t * tan_t + kk2)) * m.alpha_t.sign(); // (74), (A55)
                                                                               // (73), (A56): s with Fy/Fz0 and γ (not Fz0', γ*), as the paper and TNO.
    let s = l.arm.s_at::<G>(m.fy, c.dfz, c.gamma);
    // (72), (4.E75); Cr = 1 without turn slip, and cos(atan x) = 1/√(1 + x²) exactly.
    let mut m_zr = if l.c_r.mask_eq(F::ONE).all() {
        m.d_r * cos_atan::<G, M>(alpha_r_eq * m.b_r)
    } else {
        m.d_r * M::cos(M::atan(alpha_r_eq * m.b_r) * l.c_r)
    };
    let mut t =
        magic_cos::<G, M, H, F, G>(m.b_t, l.c_t, m.e_t, alpha_t_eq) * l.d_t * m.cos_alpha_prime; // (70), (4.E73)
    if c.low_speed.any() {
        t = t * c.red_smooth;
        m_zr = m_zr * c.red_smooth;
    }
    // (69)–(71) and MF 5.2: Mz = −t·(Fy − SVyκ) + Mzr + s·Fx; RECONSTRUCTED (69): the scan
    // reads "s·Fz"; eq. (17) of the body has s·Fx. (4.E71), (4.E72): Mz = −t·F'y + Mzr + s·Fx.
    let mz = -t * m.fy_arm + m_zr + s * m.fx;
    Mz { mz, t, m_zr }
}
