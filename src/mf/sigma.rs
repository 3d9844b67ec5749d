//! Relaxation lengths σx, σy of the steady state, the inputs of the transient model.
//!
//! MF 6.x: σ = |K/C| with the carcass stiffnesses Cx, Cy (Besselink et al. 2010, eqs. 17–19).
//! MF 5.2 / Delft 96: the PTX/PTY formulas of the MF-Tyre 5.2 manual. A file without the needed
//! keys gives 0 ("not available"), never a division by zero.

use super::limits::Cond;
use super::Params;
use crate::math::{choose, Backend, Real};

/// (σx, σy) \[m\].
#[inline(always)]
pub fn sigma<F: Real, M: Backend<F>>(p: &Params<F>, c: &Cond<F>, k_xk: F, k_ya: F) -> (F, F) {
    let dfz = c.dfz;
    if p.version.is_mf6() {
        let dpi = c.dpi;
        let c_x = p.longitudinal_stiffness
            * (F::ONE + p.pcfx1 * dfz + p.pcfx2 * dfz * dfz)
            * (F::ONE + p.pcfx3 * dpi); // eq. (17)
        let c_y = p.lateral_stiffness
            * (F::ONE + p.pcfy1 * dfz + p.pcfy2 * dfz * dfz)
            * (F::ONE + p.pcfy3 * dpi); // eq. (18)
        let sx = choose::<F>(c_x.mask_eq(F::ZERO), || F::ZERO, || (k_xk / c_x).abs()); // eq. (19)
        let sy = choose::<F>(c_y.mask_eq(F::ZERO), || F::ZERO, || (k_ya / c_y).abs()); // eq. (19)
        (sx, sy)
    } else {
        let (r0, fz0, fz) = (p.unloaded_radius, p.fnomin, c.fz);
        let sx = (p.ptx1 + p.ptx2 * dfz) * M::exp(-p.ptx3 * dfz) * p.lsgkp * r0 * fz / fz0;
        let pty_fzn = p.pty2 * c.fz0_prime;
        let sy = if pty_fzn != F::ZERO {
            p.pty1
                * M::sin(F::TWO * M::atan(fz / pty_fzn))
                * (F::ONE - p.pky3 * c.gamma.abs())
                * r0
                * p.lfzo
                * p.lsgal
        } else {
            F::ZERO
        };
        (sx, sy)
    }
}
