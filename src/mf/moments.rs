//! Overturning moment Mx and rolling resistance moment My.
//!
//! Not part of the paper's appendix (Delft Tyre 96 gives Fx, Fy, Mz); Delft 96 and MF 5.2 files
//! carry QSX1..3 and QSY1..4 for the MF-Tyre 5.2 forms, MF 6.x files the full forms:
//! - Mx: Besselink et al. (2010) (A47) extended by the QSX12..14 terms of MF-Tyre 6.1.2 (as in
//!   TNO's manual and MFeval's eq. (49)); with QSX4..14 = 0 it is the MF 5.2 form.
//! - My: (A48) for MF 6.x (Fz0 in front, load and pressure powers), the MF 5.2 form otherwise;
//!   with the low-speed and reverse handling of the TNO solver.

use super::limits::Cond;
use super::{Params, Version};
use crate::math::{choose, Backend, Mask, Real};

/// Load used by the moments: below FZMIN it fades as Fz·(Fz/FZMIN)^n (n = 2 for Mx, 1 for My),
/// so the moments vanish smoothly at lift-off (TNO solver behaviour, as MFeval reproduces it).
#[inline(always)]
fn low_load<F: Real>(fz: F, fzmin: F, power2: bool) -> F {
    if fzmin > F::ZERO {
        choose::<F>(
            fz.mask_lt(fzmin),
            || {
                let r = fz / fzmin;
                if power2 {
                    fz * r * r
                } else {
                    fz * r
                }
            },
            || fz,
        )
    } else {
        fz
    }
}

/// Overturning moment Mx \[N·m\], (A47) + MF 6.1.2 terms.
#[inline(always)]
pub fn mx<F: Real, M: Backend<F>>(p: &Params<F>, c: &Cond<F>, fy: F) -> F {
    let fz = low_load(c.fz, p.fzmin, true);
    let (g, fz0, r0) = (c.gamma, p.fnomin, p.unloaded_radius);
    let fy_n = fy / fz0;
    r0 * fz
        * p.lmx
        * (p.qsx1 * p.lvmx - p.qsx2 * g * (F::ONE + p.ppmx1 * c.dpi) - p.qsx12 * g * g.abs()
            + p.qsx3 * fy_n
            + p.qsx4
                * M::cos(p.qsx5 * M::atan((p.qsx6 * fz / fz0) * (p.qsx6 * fz / fz0)))
                * M::sin(p.qsx7 * g + p.qsx8 * M::atan(p.qsx9 * fy_n))
            + p.qsx10 * M::atan(p.qsx11 * fz / fz0) * g)
        + r0 * fy * p.lmx * (p.qsx13 + p.qsx14 * g.abs())
}

/// x^y for x ≥ 0 as exp(y·ln x); 0^y = 0 for y > 0 and 1 for y = 0. 1^y and x^0 are 1
/// without the kernels (what exp(y·ln x) gives there: ln 1 = 0, exp 0 = 1): the pressure power
/// at p = NOMPRES, the usual case, costs nothing.
#[inline(always)]
fn pow<F: Real, M: Backend<F>>(x: F, y: F) -> F {
    // y is a parameter (the same in every lane), x a value.
    if y == F::ZERO {
        return F::ONE;
    }
    choose::<F>(
        x.mask_le(F::ZERO),
        || F::ZERO,
        || choose::<F>(x.mask_eq(F::ONE), || F::ONE, || M::exp(y * M::ln(x))),
    )
}

/// Rolling resistance moment My \[N·m\], (A48) for MF 6.x, MF 5.2 form otherwise; `kappa_u` is
/// κ as given.
#[inline(always)]
pub fn my<F: Real, M: Backend<F>>(p: &Params<F>, c: &Cond<F>, fx: F, kappa_u: F) -> F {
    let fz = low_load(c.fz_u, p.fzmin, false);
    let (fz0, r0, v0) = (p.fnomin, p.unloaded_radius, p.longvl);
    let vx = c.vx;
    let v_n = vx / v0;
    let v4 = v_n * v_n * v_n * v_n;
    let base = p.qsy1 + p.qsy2 * (fx / fz0) + p.qsy3 * v_n.abs() + p.qsy4 * v4;
    let mut my = match p.version {
        Version::Mf61 | Version::Mf62 => {
            -r0 * fz0
                * p.lmy
                * (base + (p.qsy5 + p.qsy6 * (fz / fz0)) * c.gamma * c.gamma)
                * (pow::<F, M>(fz / fz0, p.qsy7) * pow::<F, M>(c.p / p.nompres, p.qsy8))
        } // (A48)
        Version::Delft96 | Version::Mf52 => -r0 * fz * p.lmy * base,
    };
    my = F::select(vx.mask_lt(F::ZERO), -my, my); // rolling backwards
    let stopped = vx.mask_eq(F::ZERO);
    if stopped.all() {
        return F::ZERO;
    }
    // Near a locked wheel (κ → −1) the wheel hardly rotates and My fades out: sin of a linear
    // ramp from 0 at κ = −1 to π/2 at κ = VXLOW/|Vx| − 1; below the window My reverses (the
    // wheel spins backwards). TNO solver behaviour as MFeval reproduces it.
    let kappa = kappa_u;
    let high = p.vxlow / vx.abs() - F::ONE;
    let low = -F::ONE - p.vxlow - high;
    let window = kappa.mask_ge(low).and(kappa.mask_le(high));
    if window.any() {
        let ramp = F::FRAC_PI_2 * (kappa + F::ONE) / (high + F::ONE);
        my = F::select(window, my * M::sin(ramp), my);
    }
    my = F::select(kappa.mask_lt(low), -my, my);
    // Vx = 0: no rolling resistance (in a lane that stopped among lanes that roll).
    F::select(stopped, F::ZERO, my)
}
