//! The Magic Formula in fixed point, for cores without an FPU (Cortex-M0+/M3; feature `fixed`).
//!
//! ## Design: the same equations, a fixed-point scalar
//! Nothing here re-types a formula. [`Fix`], a saturating fixed-point number (the `fixed` crate's
//! `I32F32`), implements [`Float`], and [`FixMath`] implements [`Backend<Fix>`](crate::math::Backend) with
//! fixed-point kernels; then the generic [`mf::eval`] *is* the fixed-point
//! Magic Formula: `mf::eval::<Fix, FixMath>` (or [`eval`]) runs Delft 96, MF 5.2 and MF 6.1/6.2,
//! pure and combined slip, Fx, Fy, Mz, Mx, My, with limits, low speed and turn slip, because the
//! code that does so in `f32`/`f64` is the code that runs. A second, hand-scaled copy of the
//! equations would have to be kept in step with `mf` by hand, and a copy is a bug (style idiom 3).
//!
//! ## Q format, per quantity
//! One format, **Q31.32** (signed, 31 integer bits, 32 fraction bits: range ±2 147 483 648,
//! resolution 2⁻³² = 2.3e-10), holds every quantity the equations meet, with headroom:
//!
//! | quantity | unit | largest magnitude expected (largest in the oracle sweeps) | Q31.32 headroom | resolution, relative to a typical value |
//! |---|---|---|---|---|
//! | Fz, Fx, Fy, D, SV | N | 1e5: a truck tyre at 3·FNOMIN (1.9e4) | 2e4 | 2e-14 of 1e4 N |
//! | Kxκ, Kyα, Kyγ0 | N, N/rad | 2e6: truck (7.5e5) | 1e3 | 2e-15 of 1e5 |
//! | Mz, Mx, My, Dr | N·m | 2e4 (2e2) | 1e5 | 2e-13 of 1e3 N·m |
//! | vertical/carcass stiffness, pressure | N/m, Pa | 1e6 | 2e3 | 2e-16 of 1e6 |
//! | α, γ, κ, B·x, C·atan(·), E, μ, dfz, dpi | — | 1e3 (B·x at 90° slip) | 2e6 | 2e-10 absolute |
//! | smallest parameters (PVX1, QSY1.., RHX1) | — | 1e-5 | — | 2e-5 relative |
//! | ε of (4.E6a), (4.E16), … | — | 1e-6 | — | 4e-4 relative (4295 LSB) |
//!
//! Q31.32 is chosen over an `i32` format because the largest (stiffness, 2e6) and the smallest
//! (ε, 1e-6) quantities of one evaluation are 2e12 apart: no 32-bit format holds both, and mixing
//! formats per quantity would mean re-typing the equations with their shifts.
//!
//! ## Arithmetic: saturating, no panic
//! Every operation saturates (`saturating_add/sub/mul/div`); x/0 gives [`Fix::MAX`] or
//! [`Fix::MIN`] by the sign of x, √ of a negative number and ln of x ≤ 0 give [`Fix::MIN`].
//! [`Fix::MAX`] and [`Fix::MIN`] play the part of ±∞/NaN: [`Float::is_finite`] is false for them,
//! so an input that saturates is rejected like a non-finite float, and a result that saturates
//! makes `mf::eval` return `EvalError::Overflow` (as long as the saturated value reaches an output:
//! unlike NaN, a saturated value multiplied by 0 is 0).
//!
//! ## Kernels ([`FixMath`])
//! Polynomials, with the minimax coefficients of the fast `f32` kernels (one table,
//! `math::minimax`; fits by `tools/minimax.py`) and the same argument reductions done in Q31.32:
//! sin, cos, tan by k·π/2; atan by 1/x and (x − 1)/(x + 1); acos through asin and √; eˣ by
//! k·ln 2 and a shift; ln by the leading-one position and atanh; √ by the `fixed` crate's integer
//! square root. Errors measured in [`kernels`]' tests: within 3e-7 relative (the polynomial fits)
//! plus a few 2⁻³² absolute.
//!
//! ## Accuracy of the Magic Formula
//! Against the `f64` path over the inputs of all 71 MFeval oracle sweeps (9497 rows, every
//! version and mode): max |ΔFx|, |ΔFy| = 2.2e-7·FNOMIN, 1.8e-7 of the sweep's largest |F|
//! (issue 7 asks ≤ 0.5 %); |ΔMz| = 1.3e-7·FNOMIN·R0. Printed and asserted by
//! `cargo test -p gough-host --release --test backends -- --nocapture`.
//!
//! ## What this module leaves out
//! - Speed on a core without an FPU: a Q31.32 multiply is a 64×64-bit product and a divide a
//!   128/64-bit division, library calls on a Cortex-M0 (`__multi3`, `__divti3`), slower than
//!   soft-float `f32`. Counting instructions under QEMU is issue 7, item 3; reaching its
//!   ≤ 4 000-instruction target needs narrower `i32` formats per quantity on the hot path, which
//!   means re-typing the equations (the trade this module declines for now, see above).
//!   `mul` and `div` are out of line, which keeps `mf::eval::<Fix, _>` at about 14 kB of Thumb
//!   code instead of 210 kB.
//! - The relaxation filter and the friction estimator in fixed point (issue 7, item 2): they are
//!   generic over [`Float`] as well, so `Fix` is their fixed-point scalar too, but they are not
//!   measured against `f64` yet.

pub mod kernels;

pub use kernels::FixMath;

use crate::math::Float;
use crate::mf::{self, EvalError, Input, Options, Output, Params};
use core::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};
use fixed::types::{I32F32, U32F32};

/// A Q31.32 fixed-point real (the `fixed` crate's `I32F32`) with saturating arithmetic; the
/// scalar of the fixed-point Magic Formula (see the [module doc](self) for the format and why).
///
/// Units are those of the quantity it holds. [`Fix::MAX`] and [`Fix::MIN`] mark saturation and
/// count as "not finite".
#[derive(Clone, Copy, Default, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Fix(pub I32F32);

/// 2³², the weight of the integer part.
const SCALE: f64 = 4_294_967_296.0;

impl Fix {
    /// Largest value, 2³¹ − 2⁻³²; also the saturation marker for +∞.
    pub const MAX: Fix = Fix(I32F32::MAX);
    /// Smallest value, −2³¹; also the saturation marker for −∞ and NaN.
    pub const MIN: Fix = Fix(I32F32::MIN);
    /// The smallest positive value, 2⁻³².
    pub const DELTA: Fix = Fix(I32F32::DELTA);

    /// From the raw two's-complement bits (value = bits / 2³²).
    pub const fn from_bits(bits: i64) -> Fix {
        Fix(I32F32::from_bits(bits))
    }

    /// The raw bits (value = bits / 2³²).
    pub const fn to_bits(self) -> i64 {
        self.0.to_bits()
    }

    /// From an integer (exact).
    pub const fn from_int(n: i32) -> Fix {
        Fix::from_bits((n as i64) << 32)
    }

    /// From an `f64`, rounded to nearest, saturating; NaN gives [`Fix::MIN`]. A `const fn`, so
    /// constants cost nothing at run time (on a core without an FPU a run-time call is soft
    /// float).
    pub const fn from_f64_const(x: f64) -> Fix {
        if x.is_nan() {
            return Fix::MIN;
        }
        let s = x * SCALE;
        // `as` saturates at the i64 range.
        let bits = if s >= 0.0 {
            (s + 0.5) as i64
        } else {
            (s - 0.5) as i64
        };
        Fix::from_bits(bits)
    }

    /// From an `f32` (exact when in range and no finer than 2⁻³²), saturating; NaN → [`Fix::MIN`].
    pub fn from_f32(x: f32) -> Fix {
        Fix::from_f64_const(x as f64)
    }

    /// To `f32` (rounded to nearest).
    pub fn to_f32(self) -> f32 {
        self.to_f64_exact() as f32
    }

    /// To `f64`: exact for |x| < 2²¹ (53 significant bits), rounded above.
    pub fn to_f64_exact(self) -> f64 {
        self.to_bits() as f64 / SCALE
    }

    /// Integer part, rounded towards −∞ (`floor`), as an `i64`.
    pub const fn floor_int(self) -> i64 {
        self.to_bits() >> 32
    }

    /// √x for x ≥ 0 (the `fixed` crate's integer square root, exact to the last bit); x < 0 →
    /// [`Fix::MIN`].
    pub fn sqrt(self) -> Fix {
        if self.to_bits() < 0 {
            return Fix::MIN;
        }
        // Non-negative: reinterpret as unsigned Q32.32; √ of ≤ 2³¹ fits back.
        let r = U32F32::from_bits(self.to_bits() as u64).sqrt();
        Fix::from_bits(r.to_bits() as i64)
    }
}

impl core::fmt::Debug for Fix {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        core::fmt::Debug::fmt(&self.0, f)
    }
}

impl core::fmt::Display for Fix {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        core::fmt::Display::fmt(&self.0, f)
    }
}

impl Add for Fix {
    type Output = Fix;
    #[inline]
    fn add(self, rhs: Fix) -> Fix {
        Fix(self.0.saturating_add(rhs.0))
    }
}

impl Sub for Fix {
    type Output = Fix;
    #[inline]
    fn sub(self, rhs: Fix) -> Fix {
        Fix(self.0.saturating_sub(rhs.0))
    }
}

impl Mul for Fix {
    type Output = Fix;
    /// Out of line on purpose: the 64×64-bit product with its saturation checks is large, and
    /// inlined at every `*` of the equations it made `mf::eval` 210 kB of Thumb code.
    #[inline(never)]
    fn mul(self, rhs: Fix) -> Fix {
        Fix(self.0.saturating_mul(rhs.0))
    }
}

impl Div for Fix {
    type Output = Fix;
    /// Saturating; x/0 is [`Fix::MAX`] for x ≥ 0 and [`Fix::MIN`] for x < 0 (no panic). Out of
    /// line, as `mul`.
    #[inline(never)]
    fn div(self, rhs: Fix) -> Fix {
        if rhs.to_bits() == 0 {
            return if self.to_bits() < 0 {
                Fix::MIN
            } else {
                Fix::MAX
            };
        }
        Fix(self.0.saturating_div(rhs.0))
    }
}

impl Neg for Fix {
    type Output = Fix;
    #[inline]
    fn neg(self) -> Fix {
        Fix(self.0.saturating_neg())
    }
}

impl AddAssign for Fix {
    #[inline]
    fn add_assign(&mut self, rhs: Fix) {
        *self = *self + rhs;
    }
}

impl SubAssign for Fix {
    #[inline]
    fn sub_assign(&mut self, rhs: Fix) {
        *self = *self - rhs;
    }
}

impl MulAssign for Fix {
    #[inline]
    fn mul_assign(&mut self, rhs: Fix) {
        *self = *self * rhs;
    }
}

impl Float for Fix {
    const ZERO: Fix = Fix::from_int(0);
    const ONE: Fix = Fix::from_int(1);
    const TWO: Fix = Fix::from_int(2);
    const HALF: Fix = Fix::from_bits(1 << 31);
    const PI: Fix = Fix::from_f64_const(core::f64::consts::PI);
    const FRAC_PI_2: Fix = Fix::from_f64_const(core::f64::consts::FRAC_PI_2);
    const FRAC_2_PI: Fix = Fix::from_f64_const(core::f64::consts::FRAC_2_PI);

    /// Rounded to nearest, saturating; NaN → [`Fix::MIN`]. `#[inline(always)]`: the equations
    /// call it with constants (ε), which then fold at compile time.
    #[inline(always)]
    fn from_f64(x: f64) -> Fix {
        Fix::from_f64_const(x)
    }
    /// Exact for |x| < 2²¹; rounded above (the trait's "exact" holds for the floats only).
    #[inline]
    fn to_f64(self) -> f64 {
        self.to_f64_exact()
    }
    #[inline]
    fn floor_index(self, max: usize) -> usize {
        let k = self.floor_int();
        if k <= 0 {
            0
        } else {
            usize::try_from(k).map_or(max, |k| k.min(max))
        }
    }
    #[inline]
    fn from_index(i: u16) -> Fix {
        Fix::from_int(i32::from(i))
    }
    #[inline]
    fn abs(self) -> Fix {
        Fix(self.0.saturating_abs())
    }
    /// `false` for the saturation markers [`Fix::MAX`] and [`Fix::MIN`].
    #[inline]
    fn is_finite(self) -> bool {
        self != Fix::MAX && self != Fix::MIN
    }
}

/// The Magic Formula in fixed point: [`mf::eval`]`::<Fix, FixMath>`.
///
/// Parameters come from a float set with [`Params::cast`] (`p64.cast::<Fix>()`); inputs and
/// outputs in the units of [`Input`] and [`Output`]. Never panics; a result that saturates is
/// `Err(EvalError::Overflow)`, a saturated input `Err(EvalError::NonFinite)`.
pub fn eval(p: &Params<Fix>, input: &Input<Fix>, opts: &Options) -> Result<Output<Fix>, EvalError> {
    mf::eval::<Fix, FixMath>(p, input, opts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn constants_and_conversions() {
        assert_eq!(Fix::ONE.to_bits(), 1 << 32);
        assert_eq!(Fix::HALF.to_f64(), 0.5);
        assert!((Fix::PI.to_f64() - core::f64::consts::PI).abs() <= 1.2e-10);
        assert_eq!(Fix::from_f64(-2.5).to_f64(), -2.5);
        assert_eq!(Fix::from_f64(1e30), Fix::MAX);
        assert_eq!(Fix::from_f64(-1e30), Fix::MIN);
        assert_eq!(Fix::from_f64(f64::NAN), Fix::MIN);
        assert_eq!(Fix::from_f64(1e-6).to_bits(), 4295);
        assert_eq!(Fix::from_int(-3).floor_int(), -3);
        assert_eq!(Fix::from_f64(-2.5).floor_int(), -3);
        assert_eq!(Fix::from_f32(0.1).to_f32(), 0.1);
    }

    #[test]
    fn saturating_arithmetic_never_panics() {
        let (max, min, one) = (Fix::MAX, Fix::MIN, Fix::ONE);
        assert_eq!(max + one, max);
        assert_eq!(min - one, min);
        assert_eq!(max * max, max);
        assert_eq!(max * min, min);
        assert_eq!(-min, max);
        assert_eq!(min.abs(), max);
        assert_eq!(one / Fix::ZERO, max);
        assert_eq!(-one / Fix::ZERO, min);
        assert_eq!(Fix::ZERO / Fix::ZERO, max);
        assert_eq!(max / Fix::DELTA, max);
        assert!(!max.is_finite() && !min.is_finite() && one.is_finite());
        assert_eq!(Fix::from_int(-4).sqrt(), min);
        assert_eq!(Fix::from_int(4).sqrt(), Fix::TWO);
        assert_eq!(max.sqrt().floor_int(), 46_340);
    }

    proptest! {
        #[test]
        fn ops_match_f64(a in -4.0e4f64..4.0e4, b in -4.0e4f64..4.0e4) {
            let (fa, fb) = (Fix::from_f64(a), Fix::from_f64(b));
            let (a, b) = (fa.to_f64(), fb.to_f64()); // the values Fix holds
            let lsb = 1.0 / SCALE;
            prop_assert!(((fa + fb).to_f64() - (a + b)).abs() <= lsb);
            prop_assert!(((fa - fb).to_f64() - (a - b)).abs() <= lsb);
            prop_assert!(((fa * fb).to_f64() - a * b).abs() <= 2.0 * lsb + 1e-15 * (a * b).abs());
            if b.abs() > 1e-3 {
                prop_assert!(((fa / fb).to_f64() - a / b).abs() <= 2.0 * lsb + 1e-15 * (a / b).abs());
            }
        }

        #[test]
        fn any_bits_any_op_no_panic(a in any::<i64>(), b in any::<i64>()) {
            let (fa, fb) = (Fix::from_bits(a), Fix::from_bits(b));
            let _ = (fa + fb, fa - fb, fa * fb, fa / fb, -fa, fa.abs(), fa.sqrt());
        }
    }
}
