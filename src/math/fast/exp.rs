//! eˣ in `f32`: x = k·ln 2 + r with |r| ≤ ln2/2, eʳ by a minimax polynomial, 2ᵏ through the
//! exponent bits.
//!
//! ln 2 is split in two (12 + 24 bits, `tools/minimax.py`) so that k·LN2_HI is exact for every k
//! the kernel meets (|k| ≤ 150). Coefficients: our own Remez fit (`math::minimax`), relative
//! error 1.1e-7 before rounding to f32.

use crate::math::minimax::{E0, E1, E2, E3};
use core::f32::consts::LOG2_E;

/// ln 2, leading 12 bits.
const LN2_HI: f32 = f32::from_bits(0x3f317000); // 0.693_115_234_375
/// ln 2 − LN2_HI rounded to f32; residual 1.6e-12.
const LN2_LO: f32 = f32::from_bits(0x3805fdf4); // 3.194_618_3e-5
/// Largest x with eˣ ≤ f32::MAX (ln f32::MAX = 88.722839…).
const X_MAX: f32 = f32::from_bits(0x42b17217); // 88.722_83
/// Below this eˣ < 2⁻¹⁵⁰ rounds to 0 (ln 2⁻¹⁵⁰ = −103.972077…).
const X_MIN: f32 = f32::from_bits(0xc2cff1b4); // -103.972_08

/// 2ᵏ as an f32, for −126 ≤ k ≤ 127.
#[inline]
fn pow2(k: i32) -> f32 {
    f32::from_bits(((k + 127) as u32) << 23)
}

/// eˣ; max error 1.9e-7 relative for x in [−87.3, 88.7] (normal results; see tests), subnormal
/// results within 2e-7·eˣ + 2⁻¹⁴⁹; NaN → NaN; +∞ and x > ln f32::MAX → +∞ (overflow); −∞ and
/// x < ln 2⁻¹⁵⁰ → +0; e^±0 = 1.
#[inline]
pub fn exp(x: f32) -> f32 {
    if x.is_nan() {
        return x;
    }
    if x > X_MAX {
        return f32::INFINITY; // overflow (+∞ included)
    }
    if x < X_MIN {
        return 0.0; // underflow (−∞ included)
    }
    // round(x/ln 2); |x·log2 e| ≤ 150 here.
    let k = (x * LOG2_E + 0.5f32.copysign(x)) as i32;
    let kf = k as f32;
    let r = (x - kf * LN2_HI) - kf * LN2_LO;
    let p = 1.0 + (r + r * r * (E0 + r * (E1 + r * (E2 + r * E3))));
    if k > 127 {
        p * pow2(127) * 2.0 // k = 128 only: x ≤ X_MAX keeps the product finite
    } else if k >= -126 {
        p * pow2(k)
    } else {
        p * pow2(k + 64) * pow2(-64) // subnormal result: one rounding, in the last product
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::testutil::{edge_inputs, linspace, sweep};
    use proptest::prelude::*;

    #[test]
    fn special_cases() {
        assert!(exp(f32::NAN).is_nan());
        assert_eq!(exp(f32::INFINITY), f32::INFINITY);
        assert_eq!(exp(f32::NEG_INFINITY), 0.0);
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(-0.0), 1.0);
        assert_eq!(exp(f32::from_bits(1)), 1.0);
        assert_eq!(exp(-f32::from_bits(1)), 1.0);
        assert_eq!(exp(89.0), f32::INFINITY);
        assert!(exp(X_MAX).is_finite());
        assert!(exp(X_MAX) > 3.4e38);
        assert_eq!(exp(-104.0), 0.0);
        // The smallest subnormal, 2⁻¹⁴⁹, at x = ln 2⁻¹⁴⁹.
        assert_eq!(exp(-103.278_93), f32::from_bits(1));
        assert!(((exp(1.0) - core::f32::consts::E) / core::f32::consts::E).abs() <= 2e-7);
    }

    #[test]
    fn edges_are_sane() {
        for x in edge_inputs().into_iter().filter(|x| !x.is_nan()) {
            let y = exp(x);
            assert!(y >= 0.0, "exp({x:e}) = {y}");
            let want = (x as f64).exp();
            if want < f32::MAX as f64 && want > f32::MIN_POSITIVE as f64 {
                assert!(
                    ((y as f64 - want) / want).abs() < 2e-7,
                    "exp({x:e}) = {y:e}"
                );
            }
        }
    }

    #[test]
    fn accuracy() {
        let e = sweep(
            "exp [-10,10]",
            exp,
            f64::exp,
            linspace(-10.0, 10.0, 2_000_001),
        );
        assert!(e.rel < 2e-7, "{e:?}");
        let e = sweep(
            "exp [-87.3,88.7]",
            exp,
            f64::exp,
            linspace(-87.3, 88.72, 2_000_001),
        );
        assert!(e.rel < 2e-7, "{e:?}");
        // Subnormal results: the polynomial's 2e-7 plus the rounding to the subnormal grid (2⁻¹⁴⁹).
        for x in linspace(-103.9, -87.4, 100_001) {
            let (got, want) = (exp(x) as f64, (x as f64).exp());
            let tol = 2e-7 * want + f32::from_bits(1) as f64;
            assert!((got - want).abs() <= tol, "exp({x:e})");
        }
    }

    proptest! {
        #[test]
        fn vs_std(x in -87.0f32..88.0) {
            let want = (x as f64).exp();
            prop_assert!(((exp(x) as f64 - want) / want).abs() <= 2e-7);
        }

        #[test]
        fn sane_for_any(x in proptest::num::f32::ANY) {
            let y = exp(x);
            prop_assert!(x.is_nan() == y.is_nan());
            prop_assert!(x.is_nan() || y >= 0.0);
        }
    }
}
