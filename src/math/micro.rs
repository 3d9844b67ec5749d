//! `Micromath`: the `micromath` crate's approximations (feature `micromath`), wrapped so that
//! what a kernel promises holds: NaN, ±0, ±∞ and the domain ends are handled here, first; the
//! arithmetic in between is micromath's, unchanged, so the measured error is micromath's.
//!
//! Each kernel calls the trait method explicitly (`micromath::F32Ext::atan(x)`): with the trait in
//! scope, `x.atan()` resolves to std's inherent method on the host and silently measures std.
//!
//! What the wrappers repair (each is a test below):
//! - `atan(±∞)`, and atan of |x| > 1.8e19, is NaN in micromath (x² overflows, ∞/∞): the argument
//!   is clamped to ±1e18, where micromath's own result is already ±π/2 in f32.
//! - `acos` of |x| < 1e-19 is NaN in micromath (√(1 − x²)/x overflows into the same atan): π/2.
//! - `sqrt(−0)` is 2.7e19 and `sqrt(+0)` 8e-20 (bit trick on the sign bit), `sqrt(+∞)` 1.8e19:
//!   ±0 → ±0, +∞ → +∞.
//! - `exp`: NaN in → garbage out, `exp(88.72…)` trips a `debug_assert!` inside micromath, results
//!   below f32::MIN_POSITIVE come out with a wrong exponent: NaN → NaN, x > ln f32::MAX → +∞,
//!   x < ln f32::MIN_POSITIVE → +0 (flush to zero).
//! - `ln`: x < 0 → NaN, ±0 → −∞, +∞ → +∞, NaN → NaN (micromath returns finite numbers for all).
//! - `sin`, `cos`, `tan`: ±∞ → NaN; micromath floors x/2π through an `i32`, which saturates above
//!   |x| ≈ 1.3e10 and makes cos unbounded: beyond |x| = 1e9 the phase is taken as 0 (consecutive
//!   f32 there are 64 rad apart; the value is bounded, not meaningful). `tan` = sin/cos can
//!   divide by 0: ±f32::MAX instead of ±∞.
//!
//! Measured max errors (`cargo test -p gough --features micromath --lib math::micro --
//! --nocapture`, against f64 std at the same f32 input; "abs" absolute, "rel" relative):
//!
//! | kernel | micromath's doc | measured | where |
//! |---|---|---|---|
//! | sin, cos | 0.002 | 1.09e-3 abs | \|x\| ≤ 2π (2.3e-3 abs up to \|x\| = 1e4; relative error unbounded next to the zeros) |
//! | tan | 0.6 | 1.14e-3 abs, 0.88 % rel | \|x\| ≤ 0.5 (α in the Magic Formula); 1.0 % rel (0.14 abs) at x = 1.5 |
//! | atan | 0.002 (but `atan_norm`: 0.162° = 2.83e-3 rad) | **2.83e-3 abs** | all x: the 0.002 of the doc does not hold (its test compares without `abs`) |
//! | acos | — | 2.9e-2 abs | \[−1, 1\] (micromath's √ inside) |
//! | exp | — | 2.4e-3 rel | \[−10, 10\] |
//! | ln | — | 6.1e-5 abs on \[1, 10\]; **0.118 abs on (0, 1)** | x < 1 goes through micromath's `inv`, a bit trick up to 12 % off |
//! | sqrt | "~5 % average" | 6.1 % rel | all x > 0 |
//!
//! For `f64`, `Micromath` delegates to [`Libm`](super::Libm) (micromath is f32 only).

use micromath::F32Ext;

/// micromath's kernels behind the [`Backend`](super::Backend) trait (see the [module doc](self) for what is
/// wrapped and the measured errors). `mf::eval::<f32, Micromath>`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Micromath;

/// Beyond this |x| sin/cos/tan take the phase as 0 (micromath's floor saturates at 1.3e10).
const TRIG_MAX: f32 = 1.0e9;
/// micromath's atan is NaN once x² overflows (|x| > 1.8e19); at 1e18 it is ±π/2 already.
const ATAN_MAX: f32 = 1.0e18;
/// ln f32::MAX.
const EXP_MAX: f32 = 88.722_83;
/// ln f32::MIN_POSITIVE: below this micromath's result has a wrong exponent.
const EXP_MIN: f32 = -87.336_55;
/// Below this |x| acos x = π/2 to f32 precision; micromath's √(1−x²)/x overflows for |x| < 1e-19.
const ACOS_TINY: f32 = 1.0e-8;

#[inline]
fn trig_arg(x: f32) -> f32 {
    if x.abs() > TRIG_MAX {
        0.0
    } else {
        x
    }
}

/// sin x via micromath (cos(x − π/2), parabola + correction); 1.1e-3 absolute for |x| ≤ 2π;
/// NaN, ±∞ → NaN; in [−1, 1].
#[inline]
pub fn sin(x: f32) -> f32 {
    if !x.is_finite() {
        return f32::NAN;
    }
    F32Ext::sin(trig_arg(x))
}

/// cos x via micromath; 1.1e-3 absolute for |x| ≤ 2π; NaN, ±∞ → NaN; in [−1, 1].
#[inline]
pub fn cos(x: f32) -> f32 {
    if !x.is_finite() {
        return f32::NAN;
    }
    F32Ext::cos(trig_arg(x))
}

/// tan x via micromath (sin/cos); see the module doc for its error; NaN, ±∞ → NaN; finite for
/// finite x.
#[inline]
pub fn tan(x: f32) -> f32 {
    if !x.is_finite() {
        return f32::NAN;
    }
    let t = F32Ext::tan(trig_arg(x));
    if t.is_finite() {
        t
    } else {
        f32::MAX.copysign(t) // cos came out 0: the pole, as far as micromath can tell
    }
}

/// atan x via micromath (Rajan et al. rational form); 2.83e-3 absolute (not the 0.002 of
/// micromath's doc); NaN → NaN, ±∞ → ±π/2.
#[inline]
pub fn atan(x: f32) -> f32 {
    if x.is_nan() {
        return x;
    }
    F32Ext::atan(x.clamp(-ATAN_MAX, ATAN_MAX))
}

/// acos x via micromath (atan(√(1−x²)/x)) for x in [−1, 1]; 2.9e-2 absolute; result in [0, π];
/// acos ±1 = 0, π exactly; NaN and |x| > 1 → NaN.
#[inline]
pub fn acos(x: f32) -> f32 {
    if x.is_nan() || x.abs() > 1.0 {
        return f32::NAN;
    }
    if x.abs() < ACOS_TINY {
        return core::f32::consts::FRAC_PI_2;
    }
    // The domain ends exactly (micromath's √0 is 8e-20, not 0).
    if x == 1.0 {
        return 0.0;
    }
    if x == -1.0 {
        return core::f32::consts::PI;
    }
    F32Ext::acos(x)
}

/// eˣ via micromath (2ᵏ·Taylor); 2.4e-3 relative on [−10, 10]; NaN → NaN, overflow → +∞, results
/// below f32::MIN_POSITIVE → +0.
#[inline]
pub fn exp(x: f32) -> f32 {
    if x.is_nan() {
        return x;
    }
    if x > EXP_MAX {
        return f32::INFINITY;
    }
    if x < EXP_MIN {
        return 0.0;
    }
    F32Ext::exp(x)
}

/// ln x via micromath for x > 0; 6.1e-5 absolute on [1, 10], 0.118 absolute on (0, 1); ln ±0 =
/// −∞, ln +∞ = +∞, NaN and x < 0 → NaN.
#[inline]
pub fn ln(x: f32) -> f32 {
    if x.is_nan() || x < 0.0 {
        return f32::NAN;
    }
    if x == 0.0 {
        return f32::NEG_INFINITY;
    }
    if x.is_infinite() {
        return x;
    }
    F32Ext::ln(x)
}

/// √x via micromath (exponent halving bit trick, no Newton step: 6 % off); √±0 = ±0, √+∞ = +∞,
/// NaN and x < 0 → NaN.
#[inline]
pub fn sqrt(x: f32) -> f32 {
    if x.is_nan() || x < 0.0 {
        return f32::NAN;
    }
    if x == 0.0 || x.is_infinite() {
        return x;
    }
    F32Ext::sqrt(x)
}

// The kernels above, by name.
crate::math::impl_backend!(Micromath, f32, in_scope);

// `f64`: delegates each kernel to `Libm` (micromath has no `f64` kernels).
crate::math::f64_via_libm!(Micromath);

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::testutil::{edge_inputs, linspace, logspace, sweep, Errors};
    use core::f32::consts::{FRAC_PI_2, PI};
    use core::f64::consts::PI as PI64;
    use proptest::prelude::*;

    /// The host's std methods are not what we test: a wrong dispatch would show as ~0 error.
    #[test]
    fn calls_micromath_not_std() {
        assert!((atan(0.5) - 0.5f32.atan()).abs() > 1e-5);
        assert!((sqrt(2.0) - core::f32::consts::SQRT_2).abs() > 1e-3);
    }

    #[test]
    fn special_cases() {
        for f in [sin, cos, tan, atan, acos, exp, ln, sqrt] {
            assert!(f(f32::NAN).is_nan());
        }
        for f in [sin, cos, tan] {
            assert!(f(f32::INFINITY).is_nan());
            assert!(f(f32::NEG_INFINITY).is_nan());
        }
        assert_eq!(atan(f32::INFINITY), FRAC_PI_2);
        assert_eq!(atan(f32::NEG_INFINITY), -FRAC_PI_2);
        assert_eq!(atan(f32::MAX), FRAC_PI_2);
        assert_eq!(atan(0.0), 0.0);
        assert_eq!(acos(1.0), 0.0);
        assert_eq!(acos(-1.0), PI);
        assert_eq!(acos(0.0), FRAC_PI_2);
        assert_eq!(acos(1e-30), FRAC_PI_2);
        assert!(acos(1.5).is_nan() && acos(-1.5).is_nan() && acos(f32::INFINITY).is_nan());
        assert_eq!(exp(0.0), 1.0);
        assert_eq!(exp(f32::INFINITY), f32::INFINITY);
        assert_eq!(exp(f32::NEG_INFINITY), 0.0);
        assert_eq!(exp(100.0), f32::INFINITY);
        assert_eq!(exp(-100.0), 0.0);
        assert!(exp(EXP_MAX).is_finite());
        assert!(exp(EXP_MIN) >= f32::MIN_POSITIVE * 0.9);
        assert_eq!(ln(1.0), 0.0);
        assert_eq!(ln(0.0), f32::NEG_INFINITY);
        assert_eq!(ln(-0.0), f32::NEG_INFINITY);
        assert_eq!(ln(f32::INFINITY), f32::INFINITY);
        assert!(ln(-1.0).is_nan());
        assert_eq!(sqrt(0.0).to_bits(), 0.0f32.to_bits());
        assert_eq!(sqrt(-0.0).to_bits(), (-0.0f32).to_bits());
        assert_eq!(sqrt(f32::INFINITY), f32::INFINITY);
        assert!(sqrt(-1.0).is_nan());
    }

    #[test]
    fn edges_are_sane() {
        for x in edge_inputs().into_iter().filter(|x| x.is_finite()) {
            assert!(sin(x).abs() <= 1.0 && cos(x).abs() <= 1.0, "sin/cos({x:e})");
            assert!(tan(x).is_finite(), "tan({x:e})");
            assert!(atan(x).abs() <= FRAC_PI_2, "atan({x:e}) = {}", atan(x));
            assert!(!exp(x).is_nan() && exp(x) >= 0.0, "exp({x:e})");
            if x > 0.0 {
                assert!(ln(x).is_finite() && sqrt(x).is_finite(), "ln/sqrt({x:e})");
            }
            if x.abs() <= 1.0 {
                assert!((0.0..=PI).contains(&acos(x)), "acos({x:e}) = {}", acos(x));
            }
        }
    }

    fn check(
        bad: &mut std::vec::Vec<std::string::String>,
        name: &str,
        e: Errors,
        abs: f64,
        rel: f64,
    ) {
        if !(e.abs_all <= abs && e.rel <= rel) {
            bad.push(std::format!("{name}: {e:?}"));
        }
    }

    /// The measured maxima of the module doc's table (each bound is the figure rounded up).
    #[test]
    fn measured_errors() {
        let two_pi = 2.0 * PI64;
        let mut bad = std::vec::Vec::new();
        let bad = &mut bad;
        let e = sweep(
            "micromath sin |x|<=2pi",
            sin,
            f64::sin,
            linspace(-two_pi, two_pi, 400_001),
        );
        check(bad, "sin", e, 1.1e-3, f64::INFINITY);
        let e = sweep(
            "micromath cos |x|<=2pi",
            cos,
            f64::cos,
            linspace(-two_pi, two_pi, 400_001),
        );
        check(bad, "cos", e, 1.1e-3, f64::INFINITY);
        let e = sweep(
            "micromath sin |x|<=1e4",
            sin,
            f64::sin,
            linspace(-1e4, 1e4, 400_001),
        );
        check(bad, "sin 1e4", e, 2.4e-3, f64::INFINITY);
        let e = sweep(
            "micromath tan |x|<=0.5",
            tan,
            f64::tan,
            linspace(-0.5, 0.5, 400_001),
        );
        check(bad, "tan", e, 1.2e-3, f64::INFINITY);
        let e = sweep(
            "micromath tan 0.1<=x<=0.5",
            tan,
            f64::tan,
            linspace(0.1, 0.5, 400_001),
        );
        check(bad, "tan rel", e, 1.2e-3, 9e-3);
        let e = sweep("micromath tan 1.5", tan, f64::tan, linspace(1.49, 1.5, 11));
        check(bad, "tan 1.5", e, 0.15, 0.011);
        let e = sweep(
            "micromath atan [-10,10]",
            atan,
            f64::atan,
            linspace(-10.0, 10.0, 400_001),
        );
        check(bad, "atan", e, 2.9e-3, f64::INFINITY);
        let e = sweep(
            "micromath atan log",
            atan,
            f64::atan,
            logspace(1e-6, 1e30, 400_001),
        );
        check(bad, "atan log", e, 2.9e-3, f64::INFINITY);
        let e = sweep(
            "micromath acos [-1,1]",
            acos,
            f64::acos,
            linspace(-1.0, 1.0, 400_001),
        );
        check(bad, "acos", e, 0.03, f64::INFINITY);
        let e = sweep(
            "micromath exp [-10,10]",
            exp,
            f64::exp,
            linspace(-10.0, 10.0, 400_001),
        );
        check(bad, "exp", e, f64::INFINITY, 2.4e-3);
        let e = sweep(
            "micromath ln [1,10]",
            ln,
            f64::ln,
            linspace(1.0, 10.0, 400_001),
        );
        check(bad, "ln >= 1", e, 7e-5, f64::INFINITY);
        let e = sweep(
            "micromath ln (0,1)",
            ln,
            f64::ln,
            logspace(1e-6, 1.0, 400_001),
        );
        check(bad, "ln < 1", e, 0.12, f64::INFINITY);
        let e = sweep(
            "micromath sqrt",
            sqrt,
            f64::sqrt,
            logspace(1e-30, 1e30, 400_001),
        );
        check(bad, "sqrt", e, f64::INFINITY, 0.062);
        assert!(bad.is_empty(), "{bad:#?}");
    }

    proptest! {
        #[test]
        fn bounded_for_any_finite(x in proptest::num::f32::NORMAL | proptest::num::f32::SUBNORMAL | proptest::num::f32::ZERO) {
            prop_assert!(sin(x).abs() <= 1.0);
            prop_assert!(cos(x).abs() <= 1.0);
            prop_assert!(tan(x).is_finite());
            prop_assert!(atan(x).abs() <= FRAC_PI_2);
            prop_assert!(exp(x) >= 0.0);
            prop_assert!(x <= 0.0 || (ln(x).is_finite() && sqrt(x).is_finite()));
        }

        #[test]
        fn vs_std(x in -6.3f32..6.3) {
            let xs = x as f64;
            prop_assert!((sin(x) as f64 - xs.sin()).abs() <= 1.1e-3);
            prop_assert!((cos(x) as f64 - xs.cos()).abs() <= 1.1e-3);
            prop_assert!((atan(x) as f64 - xs.atan()).abs() <= 2.9e-3);
            prop_assert!(((exp(x) as f64 - xs.exp()) / xs.exp()).abs() <= 2.4e-3);
        }

        #[test]
        fn tan_vs_std(x in -0.5f32..0.5) {
            prop_assert!((tan(x) as f64 - (x as f64).tan()).abs() <= 1.2e-3);
        }

        #[test]
        fn acos_ln_sqrt_vs_std(x in 0.0f32..=1.0) {
            let xs = x as f64;
            prop_assert!((acos(x) as f64 - xs.acos()).abs() <= 0.03);
            prop_assert!((acos(-x) as f64 - (-xs).acos()).abs() <= 0.03);
            prop_assert!(x == 0.0 || ((sqrt(x) as f64 - xs.sqrt()) / xs.sqrt()).abs() <= 0.062);
            prop_assert!(x == 0.0 || (ln(x) as f64 - xs.ln()).abs() <= 0.12);
        }
    }
}
