//! ln x in `f32`: x = 2ᵏ·m with m in [√½, √2), then ln m = 2·atanh s, s = (m − 1)/(m + 1).
//!
//! The atanh series in s² ≤ 0.0295 needs two coefficients for f32; the division costs one
//! instruction on an FPU (and is what musl's `logf` and Cephes do as well). Coefficients: our own
//! Remez fit (`tools/minimax.py`, in `math::minimax`), relative error 1.5e-7 before rounding to
//! f32. ln 2 is split in
//! two (12 + 24 bits) so that k·LN2_HI is exact.

use crate::math::minimax::{L0, L1};
use core::f32::consts::SQRT_2;

/// ln 2, leading 12 bits.
const LN2_HI: f32 = f32::from_bits(0x3f317000); // 0.693_115_234_375
/// ln 2 − LN2_HI rounded to f32; residual 1.6e-12.
const LN2_LO: f32 = f32::from_bits(0x3805fdf4); // 3.194_618_3e-5
/// 2²³, to bring subnormals into the normal range.
const TWO_23: f32 = 8_388_608.0;

/// ln x for x > 0; max error 3.6e-7 relative where |ln x| ≥ 2⁻¹⁰, 1.4e-10 absolute below (see
/// tests), subnormal x included; ln 1 = 0; ln ±0 = −∞; ln +∞ = +∞; NaN and x < 0 → NaN.
#[inline]
pub fn ln(x: f32) -> f32 {
    if x.is_nan() || x < 0.0 {
        return f32::NAN; // outside the domain (−∞ included)
    }
    if x == 0.0 {
        return f32::NEG_INFINITY; // ±0
    }
    if x.is_infinite() {
        return x;
    }
    let (mut bits, mut k) = (x.to_bits(), 0i32);
    if bits < 0x0080_0000 {
        bits = (x * TWO_23).to_bits(); // subnormal: scale up exactly
        k = -23;
    }
    k += ((bits >> 23) as i32) - 127;
    let mut m = f32::from_bits((bits & 0x007f_ffff) | 0x3f80_0000); // [1, 2)
    if m > SQRT_2 {
        m *= 0.5;
        k += 1;
    }
    let f = m - 1.0; // exact (Sterbenz)
    let s = f / (2.0 + f);
    let z = s * s;
    let l = s * (2.0 + z * (L0 + z * L1));
    let kf = k as f32;
    kf * LN2_HI + (l + kf * LN2_LO)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::testutil::{edge_inputs, linspace, logspace, sweep, ulp_walk};
    use proptest::prelude::*;

    #[test]
    fn special_cases() {
        assert!(ln(f32::NAN).is_nan());
        assert!(ln(-1.0).is_nan());
        assert!(ln(-f32::from_bits(1)).is_nan());
        assert!(ln(f32::NEG_INFINITY).is_nan());
        assert_eq!(ln(0.0), f32::NEG_INFINITY);
        assert_eq!(ln(-0.0), f32::NEG_INFINITY);
        assert_eq!(ln(f32::INFINITY), f32::INFINITY);
        assert_eq!(ln(1.0), 0.0);
        assert!((ln(2.0) - core::f32::consts::LN_2).abs() <= f32::EPSILON);
        let tiny = ln(f32::from_bits(1)) as f64;
        assert!((tiny - (f32::from_bits(1) as f64).ln()).abs() < 1e-5);
    }

    #[test]
    fn edges_are_sane() {
        for x in edge_inputs() {
            let y = ln(x);
            if x > 0.0 && x.is_finite() {
                let want = (x as f64).ln();
                assert!(
                    (y as f64 - want).abs() <= 4e-7 * want.abs().max(1.0 / 1024.0),
                    "ln({x:e})"
                );
            }
        }
    }

    #[test]
    fn accuracy() {
        let e = sweep(
            "ln [0.01,100]",
            ln,
            f64::ln,
            logspace(0.01, 100.0, 2_000_001),
        );
        assert!(e.rel < 4e-7 && e.abs < 2e-10, "{e:?}");
        let e = sweep("ln [0.5,2]", ln, f64::ln, linspace(0.5, 2.0, 2_000_001));
        assert!(e.rel < 4e-7 && e.abs < 2e-10, "{e:?}");
        let e = sweep(
            "ln [0.999,1.001] ulp walk",
            ln,
            f64::ln,
            ulp_walk(0.999, 1.001, 3),
        );
        assert!(e.abs < 2e-10, "{e:?}");
        let e = sweep(
            "ln full range",
            ln,
            f64::ln,
            logspace(1e-45, 3.4e38, 2_000_001),
        );
        assert!(e.rel < 4e-7, "{e:?}");
    }

    proptest! {
        #[test]
        fn vs_std(x in proptest::num::f32::POSITIVE | proptest::num::f32::SUBNORMAL) {
            prop_assume!(x > 0.0 && x.is_finite());
            let want = (x as f64).ln();
            prop_assert!((ln(x) as f64 - want).abs() <= 4e-7 * want.abs().max(1.0 / 1024.0));
        }
    }
}
