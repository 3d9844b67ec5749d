//! atan in `f32`: three-interval reduction, then a minimax odd polynomial on [0, tan π/8].
//!
//! Reduction (as Cephes `atanf`, S. L. Moshier): |x| > tan 3π/8 → π/2 + atan(−1/|x|);
//! |x| > tan π/8 → π/4 + atan((|x| − 1)/(|x| + 1)); at most one division. Coefficients: our own
//! Remez fit (`tools/minimax.py`, in `math::minimax`), relative error 2.2e-8 before rounding to
//! f32.

use crate::math::minimax::{A0, A1, A2, A3};
use core::f32::consts::{FRAC_PI_2, FRAC_PI_4};

/// tan 3π/8 = 1 + √2.
const TAN_3PI_8: f32 = f32::from_bits(0x401a827a); // 2.414_213_6
/// tan π/8 = √2 − 1.
const TAN_PI_8: f32 = f32::from_bits(0x3ed413cd); // 0.414_213_57

/// atan x \[rad\], in [−π/2, π/2] (±π/2 is f32's nearest to the limit, as `libm::atanf`); max
/// error 2.1e-7 relative for every finite x (see tests); odd; NaN → NaN; ±0 → ±0; ±∞ → ±π/2.
///
/// No early returns: NaN fails both comparisons and runs through the polynomial as NaN; a tiny
/// |x| (below 2⁻¹², where x²/3 < 2⁻²⁵) gives t + t·z·P = t after rounding, ±0 and subnormals
/// included (z underflows to 0), and `copysign` restores the sign of −0.
#[inline]
pub fn atan(x: f32) -> f32 {
    let ax = x.abs();
    let (base, t) = if ax > TAN_3PI_8 {
        (FRAC_PI_2, -1.0 / ax) // ±∞ gives t = −0: exactly π/2
    } else if ax > TAN_PI_8 {
        (FRAC_PI_4, (ax - 1.0) / (ax + 1.0))
    } else {
        (0.0, ax)
    };
    let z = t * t;
    let y = base + (t + t * z * (A0 + z * (A1 + z * (A2 + z * A3))));
    y.copysign(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::testutil::{edge_inputs, linspace, logspace, sweep, ulp_walk};
    use proptest::prelude::*;

    #[test]
    fn special_cases() {
        assert!(atan(f32::NAN).is_nan());
        assert_eq!(atan(f32::INFINITY), FRAC_PI_2);
        assert_eq!(atan(f32::NEG_INFINITY), -FRAC_PI_2);
        assert_eq!(atan(0.0).to_bits(), 0.0f32.to_bits());
        assert_eq!(atan(-0.0).to_bits(), (-0.0f32).to_bits());
        assert_eq!(atan(f32::from_bits(1)), f32::from_bits(1));
        assert_eq!(atan(f32::MAX), FRAC_PI_2);
        assert_eq!(atan(f32::MIN), -FRAC_PI_2);
        assert!((atan(1.0) - FRAC_PI_4).abs() <= f32::EPSILON * FRAC_PI_4);
        assert!((atan(-1.0) + FRAC_PI_4).abs() <= f32::EPSILON * FRAC_PI_4);
    }

    #[test]
    fn edges_are_sane() {
        for x in edge_inputs().into_iter().filter(|x| !x.is_nan()) {
            let y = atan(x);
            assert!(y.abs() <= FRAC_PI_2, "atan({x:e}) = {y}");
            let want = (x as f64).atan();
            assert!(
                (y as f64 - want).abs() <= 2.5e-7 * want.abs(),
                "atan({x:e}) = {y:e}"
            );
        }
    }

    #[test]
    fn accuracy() {
        let e = sweep(
            "atan [-10,10]",
            atan,
            f64::atan,
            linspace(-10.0, 10.0, 2_000_001),
        );
        assert!(e.rel < 2.5e-7, "{e:?}");
        let e = sweep(
            "atan [1e-6,1e6] log",
            atan,
            f64::atan,
            logspace(1e-6, 1e6, 2_000_001),
        );
        assert!(e.rel < 2.5e-7, "{e:?}");
        // Every 31st f32 across the reduction boundaries.
        let e = sweep(
            "atan [0.3,3] ulp walk",
            atan,
            f64::atan,
            ulp_walk(0.3, 3.0, 31),
        );
        assert!(e.rel < 2.5e-7, "{e:?}");
        assert!(e.abs == 0.0);
    }

    #[test]
    fn odd_and_monotone() {
        let mut prev = -FRAC_PI_2;
        for x in linspace(-50.0, 50.0, 400_001) {
            let y = atan(x);
            assert_eq!(atan(-x).to_bits(), (-y).to_bits(), "{x}");
            assert!(y >= prev, "not monotone at {x}");
            prev = y;
        }
    }

    proptest! {
        #[test]
        fn vs_std(x in proptest::num::f32::NORMAL | proptest::num::f32::SUBNORMAL | proptest::num::f32::ZERO) {
            let want = (x as f64).atan();
            let got = atan(x);
            prop_assert!(got.abs() <= FRAC_PI_2);
            prop_assert!((got as f64 - want).abs() <= 2.5e-7 * want.abs(), "{} vs {}", got, want);
        }
    }
}
