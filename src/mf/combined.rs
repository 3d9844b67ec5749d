//! Combined slip: Fx(κ, α), Fy(α, κ) by the weighting functions G of eq. (12), and the
//! aligning torque Mz of eq. (17).
//!
//! Paper eqs. (13)–(18) and (57)–(75); MF 5.2/6.1 (4.E50)–(4.E78) with (A54)–(A56) of
//! Besselink et al. (2010). Delft Tyre 96 has no curvature factor E in the weights ("the factor
//! E was not needed"), MF 5.2 adds REX/REY; the files of each version carry the matching keys,
//! and the absent ones are zero.

use super::limits::Conditioned;
use super::pure::{fy0, Fx0, Fy0, Mz0};
use super::{clip_e, cos_atan, magic_cos, Flags, Params, Version};
use crate::math::{Backend, Float};

/// G = cos[C·atan{B·x − E(B·x − atan B·x)}] / cos[C·atan{B·S − E(B·S − atan B·S)}], eqs. (14),
/// (4.E51)/(4.E52), (4.E59)/(4.E60), at x = slip + S. A vanishing denominator (only for C > 1
/// with a large shift S: outside any fitted tyre) returns G = 1 and flags [`Flags::GUARD`].
/// Without a shift (S = 0) the denominator is cos 0 = 1 exactly and is not evaluated.
fn weight<F: Float, M: Backend<F>>(b: F, c: F, e: F, s_h: F, x: F, flags: &mut Flags) -> F {
    if s_h == F::ZERO {
        return magic_cos::<F, M>(b, c, e, x);
    }
    let g0 = magic_cos::<F, M>(b, c, e, s_h);
    if g0.abs() < F::from_f64(1e-6) {
        flags.insert(Flags::GUARD);
        return F::ONE;
    }
    magic_cos::<F, M>(b, c, e, x) / g0
}

/// Combined-slip longitudinal force, (57)–(62) RECONSTRUCTED for Delft 96 (from eq. (12) and
/// MF 5.2), (4.E50)–(4.E57).
pub fn fx<F: Float, M: Backend<F>>(p: &Params<F>, c: &mut Conditioned<F>, fx0: F) -> F {
    let c_xa = p.rcx1; // (4.E55)
    let e_xa = clip_e(p.rex1 + p.rex2 * c.dfz, c); // (4.E56); 0 for Delft 96
    let s_hxa = p.rhx1; // (4.E57)
    let b_xa = (p.rbx1 + p.rbx3 * c.gamma_star * c.gamma_star)
        * cos_atan::<F, M>(p.rbx2 * c.kappa)
        * p.lxal; // (4.E54)
    let alpha_s = c.alpha_star + s_hxa; // (4.E53)
    let g_xa = weight::<F, M>(b_xa, c_xa, e_xa, s_hxa, alpha_s, &mut c.flags); // (4.E51), (4.E52)
    g_xa * fx0 // (4.E50)
}

/// Results of [`fy`].
#[derive(Debug, Clone, Copy)]
pub struct Fy<F> {
    /// Combined-slip lateral force Fy \[N\] (13), (4.E58).
    pub fy: F,
    /// Gyκ (14), (4.E59). It does not depend on Fy0, μy or ζ2: the aligning torque reuses it.
    pub g_yk: F,
    /// κ-induced side force SVyκ \[N\] (16), (4.E66).
    pub s_vyk: F,
    /// SVyκ per unit μy·ζ2 \[N\]: SVyκ = μy·ζ2·`s_vyk_per_mu` (with the low-speed reduction),
    /// so that the aligning torque gets SVyκ at another μy without the kernels again.
    pub s_vyk_per_mu: F,
}

/// Combined-slip lateral force, eqs. (13)–(16), (63)–(68), (4.E58)–(4.E67), given Fy0 and μy
/// at camber `gamma_star`.
pub fn fy<F: Float, M: Backend<F>>(
    p: &Params<F>,
    c: &mut Conditioned<F>,
    fy0: F,
    mu_y: F,
    gamma_star: F,
    zeta2: F,
) -> Fy<F> {
    let dfz = c.dfz;
    // (68), (4.E67) DVyκ = μy·Fz·(rVy1 + rVy2·dfz + rVy3·γ*)·cos(atan(rVy4·α*))·ζ2, and
    // (16), (4.E66) SVyκ = DVyκ·sin(rVy5·atan(rVy6·κ))·λVyκ, computed per unit μy·ζ2 (and not
    // at all for a file without the κ-induced side force).
    let r_vy = p.rvy1 + p.rvy2 * dfz + p.rvy3 * gamma_star;
    let mut s_vyk_per_mu = if r_vy == F::ZERO {
        F::ZERO
    } else {
        c.fz * r_vy
            * cos_atan::<F, M>(p.rvy4 * c.alpha_star)
            * M::sin(p.rvy5 * M::atan(p.rvy6 * c.kappa))
            * p.lvyka
    };
    if c.low_speed {
        s_vyk_per_mu *= c.red_smooth;
    }
    let s_vyk = mu_y * zeta2 * s_vyk_per_mu;
    let s_hyk = p.rhy1 + p.rhy2 * dfz; // (4.E65); RHY2 from MF 5.2 on
    let e_yk = clip_e(p.rey1 + p.rey2 * dfz, c); // (4.E64); 0 for Delft 96
    let c_yk = p.rcy1; // (4.E63)
    let b_yk = (p.rby1 + p.rby4 * gamma_star * gamma_star)
        * cos_atan::<F, M>(p.rby2 * (c.alpha_star - p.rby3))
        * p.lyka; // (15), (4.E62)
    let kappa_s = c.kappa + s_hyk; // (4.E61)
    let g_yk = weight::<F, M>(b_yk, c_yk, e_yk, s_hyk, kappa_s, &mut c.flags); // (14), (4.E59), (4.E60)
    Fy {
        fy: g_yk * fy0 + s_vyk, // (13), (4.E58)
        g_yk,
        s_vyk,
        s_vyk_per_mu,
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

impl<F: Float> Arm<F> {
    /// The coefficients of `p`.
    pub fn from_params(p: &Params<F>) -> Self {
        Arm {
            r0: p.unloaded_radius,
            fz0: p.fnomin,
            ssz: [p.ssz1, p.ssz2, p.ssz3, p.ssz4],
            ls: p.ls,
        }
    }

    /// s \[m\] at lateral force `fy` \[N\], normalised load increment `dfz` and camber `gamma`
    /// \[rad\]: s = R0·(ssz1 + ssz2·Fy/Fz0 + (ssz3 + ssz4·dfz)·γ)·λs (73), (A56) — Fy/Fz0 and γ,
    /// not Fz0' and γ*, as the paper and TNO.
    pub fn s(&self, fy: F, dfz: F, gamma: F) -> F {
        let [s1, s2, s3, s4] = self.ssz;
        self.r0 * (s1 + s2 * (fy / self.fz0) + (s3 + s4 * dfz) * gamma) * self.ls
    }

    /// [`Arm::s`] of the tyre as mounted: a mirrored tyre's arm is the mirror of the file's,
    /// −s(−Fy, dfz, −γ), as `mf::eval` computes it for a wheel on the other side.
    pub fn s_mounted(&self, mirrored: bool, fy: F, dfz: F, gamma: F) -> F {
        if mirrored {
            -self.s(-fy, dfz, -gamma)
        } else {
            self.s(fy, dfz, gamma)
        }
    }
}

/// Results of [`mz`].
#[derive(Debug, Clone, Copy)]
pub struct Mz<F> {
    /// Aligning torque Mz \[N·m\] (17), (69), (4.E71).
    pub mz: F,
    /// Pneumatic trail t \[m\] (70), (4.E73).
    pub t: F,
    /// Residual torque Mzr \[N·m\] (72), (4.E75).
    pub m_zr: F,
}

/// Combined-slip aligning torque, eqs. (17), (18), (69)–(75) / (4.E71)–(4.E78), (A54)–(A56).
// DIFFERS FROM MFeval: MFeval multiplies t by λFz0 (LFZO), which no published equation has;
// we follow the equations (every bundled file has LFZO = 1, so the oracle cannot tell).
pub fn mz<F: Float, M: Backend<F>>(
    p: &Params<F>,
    c: &mut Conditioned<F>,
    fx0: &Fx0<F>,
    fy0_full: &Fy0<F>,
    m: &Mz0<F>,
    fx: F,
    fy_c: &Fy<F>,
) -> Mz<F> {
    let kappa = c.kappa;
    // (18), (74), (75), (A54), (A55): equivalent slip angles with (Kxκ/Kyα')²κ².
    let kk = (fx0.k_xk / m.k_ya_prime) * kappa;
    let kk2 = kk * kk;
    let tan_r = M::tan(m.alpha_r);
    let tan_t = M::tan(m.alpha_t);
    let alpha_r_eq = M::atan(M::sqrt(tan_r * tan_r + kk2)) * m.alpha_r.sign(); // (75), (A54)
    let alpha_t_eq = M::atan(M::sqrt(tan_t * tan_t + kk2)) * m.alpha_t.sign(); // (74), (A55)
                                                                               // (73), (A56): s with Fy/Fz0 and γ (not Fz0', γ*), as the paper and TNO.
    let s = Arm::from_params(p).s(fy_c.fy, c.dfz, c.gamma);
    // (72), (4.E75); Cr = 1 without turn slip, and cos(atan x) = 1/√(1 + x²) exactly.
    let mut m_zr = if m.c_r == F::ONE {
        m.d_r * cos_atan::<F, M>(m.b_r * alpha_r_eq)
    } else {
        m.d_r * M::cos(m.c_r * M::atan(m.b_r * alpha_r_eq))
    };

    // F'y (4.E74): Fy at γ = 0 (MF 6.x); the weighting Gyκ keeps the actual γ* (TNO, MFeval).
    // At γ* = 0 that is the Fy0 already computed (the common case on a car: no extra cost).
    let (fy0_g0, mu_y_g0) = if c.gamma_star == F::ZERO {
        (fy0_full.fy0, fy0_full.mu_y)
    } else {
        let f = fy0::<F, M>(p, c, F::ZERO, c.turn.is_some());
        (f.fy0, f.mu_y)
    };
    // The weight and the κ-induced shift of F'y are taken without the turn-slip ζ2 (MFeval's
    // `internalParams_sub0`): Gyκ is Fy's own (it depends on neither Fy0, μy nor ζ2), SVyκ is
    // Fy's per unit μy at μy(γ = 0).
    let fy_prime = fy_c.g_yk * fy0_g0; // (4.E74)
    let s_vyk_sub = mu_y_g0 * fy_c.s_vyk_per_mu;

    let mut t =
        m.d_t * super::magic_cos::<F, M>(m.b_t, m.c_t, m.e_t, alpha_t_eq) * c.cos_alpha_prime; // (70), (4.E73)
    if c.low_speed {
        t *= c.red_smooth;
        m_zr *= c.red_smooth;
    }
    let mz = match p.version {
        // (69)–(71) and MF 5.2: Mz = −t·(Fy − SVyκ) + Mzr + s·Fx.
        // RECONSTRUCTED (69): the scan reads "s·Fz"; eq. (17) of the body has s·Fx.
        Version::Delft96 | Version::Mf52 => -t * (fy_c.fy - s_vyk_sub) + m_zr + s * fx,
        // (4.E71), (4.E72): Mz = −t·F'y + Mzr + s·Fx.
        Version::Mf61 | Version::Mf62 => -t * fy_prime + m_zr + s * fx,
    };
    Mz { mz, t, m_zr }
}
