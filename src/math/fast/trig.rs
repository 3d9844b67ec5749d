//! sin, cos, tan in `f32`: Cody–Waite reduction by π/2, then minimax polynomials on [−π/4, π/4].
//!
//! Polynomials: sin r = r + r³·P(r²) (deg 7), cos r = 1 − r²/2 + r⁴·Q(r²) (deg 6), tan r = r +
//! r³·T(r²) (deg 11); coefficients in `math::minimax`, from our own Remez fits
//! (`tools/minimax.py`, which also prints the π/2 split below with its bit patterns).
//! For sin and cos of |x| ≤ 8 (every Magic Formula argument) the reduction takes two parts of
//! π/2 (a 20-bit head, exact times |k| ≤ 5, and the rest), which leaves r accurate to its own
//! rounding there (`reduce_short`). Otherwise, and always for tan (next to its poles tan = −1/r
//! needs r to 1e-13 of π/2), the reduction splits π/2 into four parts; the first three have 8 significant
//! bits, so k·PIO2_1, k·PIO2_2 and k·PIO2_3 are exact for |k| < 2¹⁶ and the subtractions that
//! cancel are exact (Sterbenz); what is left is |k|·5e-17 from the truncated π/2 and the
//! rounding of r. (With three parts, |k|·5e-14 was 1.2e-6 of tan next to π/2 and 3e-6 of
//! tan next to 3π/2: not enough for the 2e-6 target.)
//! Beyond |x| = [`REDUCE_MAX`] the products are no longer exact: r is clamped to [−π/4, π/4], so
//! the result stays in [−1, 1] (tan finite) but carries no accuracy. The Magic Formula's
//! arguments are below 2π.

use crate::math::minimax::{C0, C1, S0, S1, S2, T0, T1, T2, T3, T4};
use core::f32::consts::{FRAC_2_PI, FRAC_PI_4};

/// π/2, leading 8 bits (`tools/minimax.py`).
const PIO2_1: f32 = f32::from_bits(0x3fc90000); // 1.570_312_5
/// π/2 − PIO2_1, leading 8 bits.
const PIO2_2: f32 = f32::from_bits(0x39fd0000); // 4.825_592_041_015_625e-4
/// π/2 − PIO2_1 − PIO2_2, leading 8 bits.
const PIO2_3: f32 = f32::from_bits(0x35aa0000); // 1.266_598_701_477_050_8e-6
/// π/2 − PIO2_1 − PIO2_2 − PIO2_3 rounded to f32; residual −5.0e-17.
const PIO2_4: f32 = f32::from_bits(0x30885a31); // 9.920_936e-10

/// Largest |x| whose reduction is exact to |k|·5e-17 (|k| < 2¹⁶ keeps k·PIO2_1..3 exact).
pub const REDUCE_MAX: f32 = 1.0e5;

/// π/2 truncated to 20 significant bits, ⌊π/2·2¹⁹⌋/2¹⁹, for the short reduction: k·PIO2_HI is
/// exact for |k| < 16.
const PIO2_HI: f32 = f32::from_bits(0x3fc90fd0); // 1.570_795_059_204_101_6
/// π/2 − PIO2_HI rounded to f32; residual 5.2e-14 (python3: `math.pi/2 - 823549/2**19`).
const PIO2_LO: f32 = f32::from_bits(0x35aa2217); // 1.267_590_8e-6
/// Up to this |x| (|k| ≤ 5) the short reduction is used: every argument of the Magic Formula.
const SHORT: f32 = 8.0;
/// 1.5·2²³: (y + ROUND) − ROUND rounds |y| < 2²² to the nearest integer (ties to even).
const ROUND: f32 = 12_582_912.0;

/// x = k·π/2 + r for sin and cos with |x| ≤ [`SHORT`]; returns (r, k mod 4).
///
/// Two parts of π/2: x − k·PIO2_HI is exact (k·PIO2_HI has at most 23 bits; Sterbenz), and
/// k·PIO2_LO is off by |k|·5.2e-14 plus its rounding (4e-13), far below the 2⁻¹⁰·2e-7 that sin
/// and cos need where their relative error is promised; k comes from the rounding constant,
/// without a conversion to an integer and back. Beyond, [`reduce`]. (tan always takes
/// [`reduce`]: next to its poles, tan = −1/r needs r to 1e-13 relative to π/2.)
#[inline]
fn reduce_short(x: f32) -> (f32, u32) {
    let kf = (x * FRAC_2_PI + ROUND) - ROUND;
    let r = (x - kf * PIO2_HI) - kf * PIO2_LO;
    (r, (kf as i32 & 3) as u32)
}

/// x = k·π/2 + r, four parts of π/2; returns (r, k mod 4). Callers handle NaN and ±∞ before.
#[inline]
fn reduce(x: f32) -> (f32, u32) {
    // round(x·2/π); `as` saturates, and |x| ≤ REDUCE_MAX keeps |k| < 2¹⁶ anyway.
    let k = (x * FRAC_2_PI + 0.5f32.copysign(x)) as i32;
    let kf = k as f32;
    let mut r = (((x - kf * PIO2_1) - kf * PIO2_2) - kf * PIO2_3) - kf * PIO2_4;
    if x.abs() > REDUCE_MAX {
        // Inexact reduction: keep r in the polynomial's range so the result stays bounded.
        r = r.clamp(-FRAC_PI_4, FRAC_PI_4);
    }
    (r, (k & 3) as u32)
}

#[inline]
fn tan_poly(r: f32) -> f32 {
    let z = r * r;
    r + r * z * (T0 + z * (T1 + z * (T2 + z * (T3 + z * T4))))
}

#[inline]
fn sin_poly(r: f32) -> f32 {
    let z = r * r;
    r + r * z * (S0 + z * (S1 + z * S2))
}

#[inline]
fn cos_poly(r: f32) -> f32 {
    let z = r * r;
    (1.0 - 0.5 * z) + z * z * (C0 + z * C1)
}

/// sin x \[x in rad\]; max error 2.1e-7 relative for |x| ≤ 1e5 where |sin x| ≥ 2⁻¹⁰, 5.5e-11
/// absolute below (see tests); odd; NaN and ±∞ → NaN; ±0 → ±0; in [−1, 1] for every finite x
/// (not accurate beyond |x| = 1e5, see the module doc).
///
/// Every argument of the Magic Formula is within |x| ≤ 8 (`SHORT`), so that path comes first:
/// there a tiny x (|x| < 2⁻¹²) gives k = 0, r = x and r + r³·P rounds to x, subnormals kept,
/// the result an early return would give; only −0 needs its own test (−0 + 0 is +0). NaN and
/// ±∞ fail `|x| ≤ SHORT` and are caught on the long path.
#[inline]
pub fn sin(x: f32) -> f32 {
    let (r, q) = if x.abs() <= SHORT {
        if x == 0.0 {
            return x; // keeps the sign of ±0
        }
        reduce_short(x)
    } else if x.is_nan() || x.is_infinite() {
        return f32::NAN; // sin ±∞ is undefined
    } else {
        reduce(x)
    };
    match q {
        0 => sin_poly(r),
        1 => cos_poly(r),
        2 => -sin_poly(r),
        _ => -cos_poly(r),
    }
}

/// cos x \[x in rad\]; max error 2.1e-7 relative for |x| ≤ 2π (2.3e-7 up to 1e5) where
/// |cos x| ≥ 2⁻¹⁰, 5.3e-11 absolute below (see tests); even; NaN and ±∞ → NaN; cos ±0 = 1; in [−1, 1] for every finite
/// x (not accurate beyond |x| = 1e5, see the module doc).
///
/// As [`sin`]: the short path first; a tiny x gives r = x and (1 − r²/2) + r⁴·Q rounds to 1.
#[inline]
pub fn cos(x: f32) -> f32 {
    let (r, q) = if x.abs() <= SHORT {
        reduce_short(x)
    } else if x.is_nan() || x.is_infinite() {
        return f32::NAN; // cos ±∞ is undefined
    } else {
        reduce(x)
    };
    match q {
        0 => cos_poly(r),
        1 => -sin_poly(r),
        2 => -cos_poly(r),
        _ => sin_poly(r),
    }
}

/// (sin x, cos x), bit for bit [`sin`] and [`cos`]: on the short path (0 < |x| ≤ 8, every
/// Magic Formula argument) one reduction for both; elsewhere the two kernels.
#[inline]
pub fn sin_cos(x: f32) -> (f32, f32) {
    if x.abs() <= SHORT && x != 0.0 {
        let (r, q) = reduce_short(x);
        let (s, c) = (sin_poly(r), cos_poly(r));
        match q {
            0 => (s, c),
            1 => (c, -s),
            2 => (-s, -c),
            _ => (-c, s),
        }
    } else {
        (sin(x), cos(x))
    }
}

/// tan x \[x in rad\]; max error 4.0e-7 relative for |x| ≤ 2π, next to the poles too (see
/// tests); odd; NaN and ±∞ → NaN; ±0 → ±0; finite for every finite x (±f32::MAX if the reduced argument is exactly 0 at a
/// pole; not accurate beyond |x| = 1e5).
///
/// Below |x| = π/4 (where the reduction rounds k to 0 and returns r = x: the same test) the
/// polynomial is all: every slip angle of the Magic Formula takes that path, with no other
/// test (a tiny x gives r + r³·T = x after rounding, ±0 and subnormals kept). NaN and ±∞ fail
/// it and are caught on the long path.
#[inline]
pub fn tan(x: f32) -> f32 {
    if x.abs() * FRAC_2_PI + 0.5 < 1.0 {
        return tan_poly(x);
    }
    if x.is_nan() || x.is_infinite() {
        return f32::NAN; // tan ±∞ is undefined
    }
    let (r, q) = reduce(x);
    let t = tan_poly(r);
    if q & 1 == 0 {
        t
    } else if t == 0.0 {
        // Exactly on a pole as far as f32 can tell: the largest finite value, signed as −1/t.
        -f32::MAX.copysign(t)
    } else {
        -1.0 / t // tan(r + π/2) = −1/tan r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::testutil::{edge_inputs, linspace, sweep, ulp_walk};
    use core::f64::consts::PI;
    use proptest::prelude::*;

    const TWO_PI: f64 = 2.0 * PI;

    #[test]
    fn special_cases() {
        for f in [sin, cos, tan] {
            assert!(f(f32::NAN).is_nan());
            assert!(f(f32::INFINITY).is_nan());
            assert!(f(f32::NEG_INFINITY).is_nan());
        }
        assert_eq!(sin(0.0).to_bits(), 0.0f32.to_bits());
        assert_eq!(sin(-0.0).to_bits(), (-0.0f32).to_bits());
        assert_eq!(tan(-0.0).to_bits(), (-0.0f32).to_bits());
        assert_eq!(cos(0.0), 1.0);
        assert_eq!(cos(-0.0), 1.0);
        let sub = f32::from_bits(1);
        assert_eq!(sin(sub), sub);
        assert_eq!(tan(-sub), -sub);
        assert_eq!(cos(sub), 1.0);
        assert_eq!(sin(1.0e-30), 1.0e-30);
    }

    #[test]
    fn edges_are_sane() {
        for x in edge_inputs() {
            if !x.is_finite() {
                continue;
            }
            let (s, c, t) = (sin(x), cos(x), tan(x));
            assert!((-1.0..=1.0).contains(&s), "sin({x:e}) = {s}");
            assert!((-1.0..=1.0).contains(&c), "cos({x:e}) = {c}");
            assert!(t.is_finite(), "tan({x:e}) = {t}");
            if x.abs() <= REDUCE_MAX {
                let xs = x as f64;
                assert!((s as f64 - xs.sin()).abs() < 2e-7, "sin({x:e})");
                assert!((c as f64 - xs.cos()).abs() < 2e-7, "cos({x:e})");
            }
        }
    }

    /// sin_cos is sin and cos, bit for bit, on both paths and at the special values.
    #[test]
    fn sin_cos_is_sin_and_cos() {
        for x in linspace(-20.0, 20.0, 400_001).chain(edge_inputs()) {
            let (s, c) = sin_cos(x);
            assert_eq!(s.to_bits(), sin(x).to_bits(), "sin {x:e}");
            assert_eq!(c.to_bits(), cos(x).to_bits(), "cos {x:e}");
        }
    }

    #[test]
    fn symmetry() {
        for x in linspace(0.0, 20.0, 20_001) {
            assert_eq!(sin(-x).to_bits(), (-sin(x)).to_bits(), "{x}");
            assert_eq!(cos(-x), cos(x), "{x}");
            assert_eq!(tan(-x).to_bits(), (-tan(x)).to_bits(), "{x}");
        }
    }

    #[test]
    fn sin_accuracy() {
        let e = sweep(
            "sin |x|<=2pi",
            sin,
            f64::sin,
            linspace(-TWO_PI, TWO_PI, 2_000_001),
        );
        assert!(e.rel < 2.5e-7 && e.abs < 1e-10, "{e:?}");
        let e = sweep("sin [0,1] ulp walk", sin, f64::sin, ulp_walk(1e-4, 1.0, 97));
        assert!(e.rel < 2.5e-7, "{e:?}");
        let e = sweep(
            "sin |x|<=1e5",
            sin,
            f64::sin,
            linspace(-1e5, 1e5, 1_000_001),
        );
        assert!(e.rel < 2.5e-7 && e.abs < 1e-10, "{e:?}");
    }

    #[test]
    fn cos_accuracy() {
        let e = sweep(
            "cos |x|<=2pi",
            cos,
            f64::cos,
            linspace(-TWO_PI, TWO_PI, 2_000_001),
        );
        assert!(e.rel < 2.5e-7 && e.abs < 1e-10, "{e:?}");
        let e = sweep(
            "cos |x|<=1e5",
            cos,
            f64::cos,
            linspace(-1e5, 1e5, 1_000_001),
        );
        assert!(e.rel < 2.5e-7 && e.abs < 1e-10, "{e:?}");
        // Next to the zeros of cos the output is the reduced argument itself.
        let h = core::f32::consts::FRAC_PI_2;
        for x in [
            h,
            f32::from_bits(h.to_bits() - 1),
            f32::from_bits(h.to_bits() + 1),
        ] {
            let (got, want) = (cos(x) as f64, (x as f64).cos());
            assert!(
                (got - want).abs() < 1e-13,
                "cos({x:e}) = {got:e}, want {want:e}"
            );
        }
    }

    /// The short reduction (|x| ≤ SHORT) keeps r accurate to its own rounding: at the zeros of
    /// sin and cos up to 8 (k ≤ 5) the output is the reduced argument, within 1e-12 absolute,
    /// and sin and cos stay within 2.5e-7 relative across the switch to the long reduction.
    #[test]
    fn short_reduction_is_exact_enough() {
        for k in 1..=5 {
            let z = k as f32 * core::f32::consts::FRAC_PI_2;
            for x in [
                z,
                f32::from_bits(z.to_bits() - 1),
                f32::from_bits(z.to_bits() + 1),
            ] {
                assert!(x.abs() <= SHORT);
                for (f, g) in [
                    (sin as fn(f32) -> f32, f64::sin as fn(f64) -> f64),
                    (cos, f64::cos),
                ] {
                    let (got, want) = (f(x) as f64, g(x as f64));
                    assert!(
                        (got - want).abs() < 1e-12,
                        "k {k}: {got:e} vs {want:e} at {x:e}"
                    );
                }
            }
        }
        for (name, f, g) in [
            ("sin", sin as fn(f32) -> f32, f64::sin as fn(f64) -> f64),
            ("cos", cos, f64::cos),
        ] {
            let e = sweep(name, f, g, ulp_walk(SHORT * 0.999, SHORT * 1.001, 1));
            assert!(e.rel < 2.5e-7, "{name} across SHORT: {e:?}");
        }
    }

    #[test]
    fn tan_accuracy() {
        let e = sweep(
            "tan |x|<=1.57",
            tan,
            f64::tan,
            linspace(-1.57, 1.57, 2_000_001),
        );
        assert!(e.rel < 5e-7, "{e:?}");
        let e = sweep(
            "tan |x|<=2pi",
            tan,
            f64::tan,
            linspace(-TWO_PI, TWO_PI, 1_000_001),
        );
        assert!(e.rel < 5e-7, "{e:?}");
        // Across π/4, where tan leaves its polynomial-only path for the reduction: every f32.
        let q = core::f32::consts::FRAC_PI_4;
        let e = sweep(
            "tan across pi/4",
            tan,
            f64::tan,
            ulp_walk(q * 0.999, q * 1.001, 1),
        );
        assert!(e.rel < 5e-7 && e.rel > 0.0, "{e:?}");
        let neg = ulp_walk(q * 0.999, q * 1.001, 1).map(|x| -x);
        let e = sweep("tan across -pi/4", tan, f64::tan, neg);
        assert!(e.rel < 5e-7 && e.rel > 0.0, "{e:?}");
        // The f32 next to π/2: tan is −2.3e7 / +2.3e7 on either side; r ≈ 4e-8 there.
        let h = core::f32::consts::FRAC_PI_2;
        let e = sweep("tan next to pi/2", tan, f64::tan, ulp_walk(h - 1e-4, h, 1));
        assert!(e.rel < 5e-7, "{e:?}");
    }

    proptest! {
        #[test]
        fn sin_cos_vs_std(x in -100.0f32..100.0) {
            let xs = x as f64;
            prop_assert!((sin(x) as f64 - xs.sin()).abs() <= 2.5e-7 * xs.sin().abs().max(1.0 / 1024.0));
            prop_assert!((cos(x) as f64 - xs.cos()).abs() <= 2.5e-7 * xs.cos().abs().max(1.0 / 1024.0));
        }

        #[test]
        fn tan_vs_std(x in -1.5706f32..1.5706) {
            let want = (x as f64).tan();
            prop_assert!((tan(x) as f64 - want).abs() <= 5e-7 * want.abs().max(1.0 / 1024.0));
        }

        #[test]
        fn bounded_for_any_finite(x in proptest::num::f32::NORMAL | proptest::num::f32::SUBNORMAL | proptest::num::f32::ZERO) {
            prop_assert!(sin(x).abs() <= 1.0);
            prop_assert!(cos(x).abs() <= 1.0);
            prop_assert!(tan(x).is_finite());
        }
    }
}
