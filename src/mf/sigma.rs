//! Relaxation lengths σx, σy of the steady state, the inputs of the transient model.
//!
//! MF 6.x: σ = |K/C| with the carcass stiffnesses Cx, Cy (Besselink et al. 2010, eqs. 17–19).
//! MF 5.2 / Delft 96: the PTX/PTY formulas of the MF-Tyre 5.2 manual. A file without the needed
//! keys gives 0 ("not available"), never a division by zero.

use super::limits::Cond;
use super::prepared::{Then, View};
use super::{EvalError, Input, Options, Params};
use crate::math::{choose, Backend, Float, Real};

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

/// The relaxation lengths (σx, σy) \[m\] of [`super::eval`] at `input` under `opts`, without its
/// slip stage (the forces and moments): `mf::eval`'s `sigma_x`, `sigma_y` to the bit, from the
/// same load stage (with turn slip on, the load parts at the point's slips, as `eval` has them).
/// For a caller that needs σ at a row before it evaluates the forces along a transient (the
/// gap diagnosis's sim: one σ per row, the forces at the filter's slips).
///
/// Errors: those of `eval`'s checks (non-finite input, pressure ≤ 0, turn slip without its
/// coefficients); [`EvalError::Overflow`] when σ itself is not finite. No contact (Fz ≤ 0):
/// (0, 0), as `eval` gives.
pub fn relaxation_lengths<F: Float, M: Backend<F>>(
    p: &Params<F>,
    input: &Input<F>,
    opts: &Options,
) -> Result<(F, F), EvalError> {
    if opts.turn_slip && !super::turnslip::available(p) {
        return Err(EvalError::TurnSlipUnavailable);
    }
    super::limits::check_finite(input)?;
    let (c, mirrored, turn) = super::prepared::for_eval::<F, M>(p, input, opts)?;
    /// σ at the load stage's view (`prepared::stages`'s continuation, as `mf::eval`'s).
    struct Sigmas<'a, F, M> {
        p: &'a Params<F>,
        backend: core::marker::PhantomData<M>,
    }
    impl<F: Float, M: Backend<F>> Then<F> for Sigmas<'_, F, M> {
        type Out = Result<(F, F), EvalError>;
        fn then(self, prep: View<'_, F>) -> Self::Out {
            if !prep.contact {
                return Ok((F::ZERO, F::ZERO));
            }
            let (sx, sy) = sigma::<F, M>(self.p, prep.c, prep.fx0.k_xk, prep.fy0.k_ya);
            if sx.is_finite() && sy.is_finite() {
                Ok((sx, sy))
            } else {
                Err(EvalError::Overflow)
            }
        }
    }
    let k = Sigmas::<F, M> {
        p,
        backend: core::marker::PhantomData,
    };
    super::prepared::stages::<F, M, _>(p, c, mirrored, turn, k)
}
