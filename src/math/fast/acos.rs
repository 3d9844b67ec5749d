//! acos in `f32` through a minimax asin polynomial on [0, ½].
//!
//! |x| ≤ ½: acos x = π/2 − asin x. |x| > ½: with z = (1 − |x|)/2 (exact) and s = √z,
//! acos x = 2·asin s for x > 0 and π − 2·asin s for x < 0 (the half-angle identity, as Cephes
//! `asinf`/`acosf`), so the result near x = 1 keeps its relative accuracy. Coefficients: our own
//! Remez fit (`tools/minimax.py`, in `math::minimax`), relative error 9.4e-8 before rounding to
//! f32.

use super::sqrt::sqrt;
use crate::math::minimax::{P0, P1, P2, P3};
use core::f32::consts::{FRAC_PI_2, PI};

#[inline]
fn asin_poly(s: f32, z: f32) -> f32 {
    s + s * z * (P0 + z * (P1 + z * (P2 + z * P3)))
}

/// acos x \[rad\] for x in [−1, 1], result in [0, π]; max error 2.1e-7 relative on [−1, 1]
/// (see tests); acos 1 = 0, acos −1 = π (f32), acos ±0 = π/2; NaN and |x| > 1 → NaN (outside the
/// domain, as `libm::acosf`; the Magic Formula clamps the argument first, (4.104)).
#[inline]
pub fn acos(x: f32) -> f32 {
    if x.is_nan() {
        return x;
    }
    let ax = x.abs();
    if ax > 1.0 {
        return f32::NAN; // outside the domain (±∞ included)
    }
    if ax <= 0.5 {
        return FRAC_PI_2 - asin_poly(x, x * x);
    }
    let z = 0.5 * (1.0 - ax); // exact: 1 − ax by Sterbenz, ×½ exact
    let s = sqrt(z);
    let a = 2.0 * asin_poly(s, z);
    if x > 0.0 {
        a
    } else {
        PI - a
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::testutil::{edge_inputs, linspace, sweep, ulp_walk};
    use proptest::prelude::*;

    #[test]
    fn special_cases() {
        assert!(acos(f32::NAN).is_nan());
        assert!(acos(f32::INFINITY).is_nan());
        assert!(acos(f32::NEG_INFINITY).is_nan());
        assert!(acos(1.000_000_1).is_nan());
        assert!(acos(-1.000_000_1).is_nan());
        assert_eq!(acos(1.0), 0.0);
        assert_eq!(acos(-1.0), PI);
        assert_eq!(acos(0.0), FRAC_PI_2);
        assert_eq!(acos(-0.0), FRAC_PI_2);
        assert_eq!(acos(f32::from_bits(1)), FRAC_PI_2);
    }

    #[test]
    fn edges_are_sane() {
        for x in edge_inputs() {
            let y = acos(x);
            if x.abs() <= 1.0 {
                assert!((0.0..=PI).contains(&y), "acos({x:e}) = {y}");
            } else {
                assert!(y.is_nan(), "acos({x:e}) = {y}");
            }
        }
    }

    #[test]
    fn accuracy() {
        let e = sweep(
            "acos [-1,1]",
            acos,
            f64::acos,
            linspace(-1.0, 1.0, 2_000_001),
        );
        assert!(e.rel < 2.5e-7, "{e:?}");
        // The f32 just below 1, where acos is smallest and the half-angle form matters.
        let e = sweep(
            "acos [0.999,1] ulp walk",
            acos,
            f64::acos,
            ulp_walk(0.999, 1.0, 1),
        );
        assert!(e.rel < 2.5e-7, "{e:?}");
    }

    #[test]
    fn monotone() {
        let mut prev = PI;
        for x in linspace(-1.0, 1.0, 400_001) {
            let y = acos(x);
            assert!(y <= prev, "not monotone at {x}");
            prev = y;
        }
    }

    proptest! {
        #[test]
        fn vs_std(x in -1.0f32..=1.0) {
            let want = (x as f64).acos();
            prop_assert!((acos(x) as f64 - want).abs() <= 2.5e-7 * want.abs().max(1.0 / 1024.0));
        }
    }
}
