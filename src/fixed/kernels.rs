//! [`FixMath`]: the transcendental kernels of the Magic Formula in Q31.32.
//!
//! The polynomials are those of the fast `f32` kernels (coefficients in `math::minimax`, our own
//! Remez fits, `tools/minimax.py`); the argument reductions are redone in fixed point, where the
//! constants π/2, ln 2, … carry 32 fraction bits (error ≤ 2⁻³³), and the sin, cos, tan, atan
//! and exp polynomials, whose reduced arguments lie below 1, run in Q0.31 (`to_q31`,
//! `mul31`). Every operation saturates
//! (see [`Fix`]); no kernel panics for any input. Errors are measured by the tests below against
//! `f64` std at the same (Q31.32) input and stated on each function.

use super::Fix;
use crate::math::minimax::{
    A0, A1, A2, A3, C0, C1, E0, E1, E2, E3, L0, L1, P0, P1, P2, P3, S0, S1, S2, T0, T1, T2, T3, T4,
};
use crate::math::{Backend, Real};

/// A Q31.32 constant from an `f64` (compile time).
const fn q(x: f64) -> Fix {
    Fix::from_f64_const(x)
}

/// A Q31.32 constant from a shared `f32` coefficient (exact: the coefficients have 24 bits).
const fn c(x: f32) -> Fix {
    Fix::from_f64_const(x as f64)
}

const FRAC_PI_2: Fix = q(core::f64::consts::FRAC_PI_2);
const FRAC_PI_4: Fix = q(core::f64::consts::FRAC_PI_4);
const FRAC_2_PI: Fix = q(core::f64::consts::FRAC_2_PI);
const PI: Fix = q(core::f64::consts::PI);
const LN_2: Fix = q(core::f64::consts::LN_2);
const LOG2_E: Fix = q(core::f64::consts::LOG2_E);
const SQRT_2: Fix = q(core::f64::consts::SQRT_2);
const FRAC_1_SQRT_2: Fix = q(core::f64::consts::FRAC_1_SQRT_2);
/// tan 3π/8 = 1 + √2 and tan π/8 = √2 − 1: the atan reduction points.
const TAN_3PI_8: Fix = q(2.414_213_562_373_095);
const TAN_PI_8: Fix = q(0.414_213_562_373_095_1);
/// ln 2³¹: above this eˣ saturates.
const EXP_MAX: Fix = q(21.487_562_597_358_306);
/// ln 2⁻³³: below this eˣ rounds to 0.
const EXP_MIN: Fix = q(-22.873_856_958_478_2);

/// A value |x| < 1 in Q0.31 (x·2³¹ in an `i32`, rounded down; clamped to ±(1 − 2⁻³¹)): the
/// format of the sin, cos, tan, atan and exp polynomials, whose arguments are reduced below 1 —
/// one 32×32→64-bit product per step ([`mul31`]) instead of a Q31.32 product, which needs up to
/// four and tests for saturation. The kernels add the polynomial's leading term (r, 1) in
/// Q31.32, so that only the smaller rest has to fit Q0.31.
#[inline(always)]
fn to_q31(x: Fix) -> i32 {
    (x.to_bits() >> 1).clamp(-(i32::MAX as i64), i32::MAX as i64) as i32
}

/// A Q0.31 value as Q31.32 (exact).
#[inline(always)]
fn from_q31(y: i32) -> Fix {
    Fix::from_bits((y as i64) << 1)
}

/// a·b in Q0.31, rounded to nearest (ties away from zero); |a|, |b| < 1 (neither is −1: see
/// [`to_q31`]).
#[inline(always)]
fn mul31(a: i32, b: i32) -> i32 {
    let p = super::wide_mul(a.unsigned_abs(), b.unsigned_abs());
    let m = ((p + (1 << 30)) >> 31) as i32; // p < 2⁶²: m < 2³¹
    if (a ^ b) < 0 {
        -m
    } else {
        m
    }
}

/// A Q0.31 constant from a shared `f32` coefficient (|x| < 1), rounded (compile time).
const fn c31(x: f32) -> i32 {
    let v = x as f64 * 2_147_483_648.0;
    (if v >= 0.0 { v + 0.5 } else { v - 0.5 }) as i32
}

/// The Q31.32 kernels behind [`Backend<Fix>`]: `mf::eval::<Fix, FixMath>`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct FixMath;

/// x = k·π/2 + r with |r| ≤ π/4; returns (r, k mod 4). Exact to |k|·2⁻³³ + 2⁻³²; beyond
/// |x| ≈ 1e9 (k·π/2 saturates) r is clamped to ±π/4 wherever it leaves [−1, 1], so results
/// stay bounded and r always fits the polynomials' Q0.31.
#[inline]
fn reduce(x: Fix) -> (Fix, u32) {
    let k = (x * FRAC_2_PI + Fix::HALF).floor_int();
    let kf = Fix::from_bits(k.saturating_mul(1 << 32));
    let mut r = x - kf * FRAC_PI_2;
    if r >= Fix::ONE || r <= -Fix::ONE {
        r = if r > Fix::ZERO { FRAC_PI_4 } else { -FRAC_PI_4 };
    }
    (r, (k & 3) as u32)
}

/// sin r for |r| < 1 (reduced: ≤ π/4): r + (the rest in Q0.31).
#[inline]
fn sin_poly(r: Fix) -> Fix {
    let q = to_q31(r);
    let z = mul31(q, q);
    let p = c31(S0) + mul31(z, c31(S1) + mul31(z, c31(S2)));
    r + from_q31(mul31(q, mul31(z, p)))
}

/// cos r for |r| < 1 (reduced: ≤ π/4): 1 + (the rest in Q0.31).
#[inline]
fn cos_poly(r: Fix) -> Fix {
    let r = to_q31(r);
    let z = mul31(r, r);
    let q = c31(C0) + mul31(z, c31(C1));
    Fix::ONE + from_q31(mul31(mul31(z, z), q) - ((z + 1) >> 1))
}

#[inline]
fn asin_poly(s: Fix, z: Fix) -> Fix {
    s + s * z * (c(P0) + z * (c(P1) + z * (c(P2) + z * c(P3))))
}

/// sin x \[rad\]; error ≤ 2.3e-9 + 1e-7·|sin x| for |x| ≤ 2π (see tests), in [−1, 1] for all x.
pub fn sin(x: Fix) -> Fix {
    let (r, k) = reduce(x);
    match k {
        0 => sin_poly(r),
        1 => cos_poly(r),
        2 => -sin_poly(r),
        _ => -cos_poly(r),
    }
}

/// cos x \[rad\]; error ≤ 2.3e-9 + 1e-7·|cos x| for |x| ≤ 2π (see tests), in [−1, 1] for all x.
pub fn cos(x: Fix) -> Fix {
    let (r, k) = reduce(x);
    match k {
        0 => cos_poly(r),
        1 => -sin_poly(r),
        2 => -cos_poly(r),
        _ => sin_poly(r),
    }
}

/// tan x \[rad\]; error ≤ 3e-7 relative + 4e-9 for |x| ≤ 1.5 (see tests); saturates at the poles.
pub fn tan(x: Fix) -> Fix {
    let (r, k) = reduce(x);
    // r + (the rest in Q0.31: below 0.56 for |r| < 1).
    let q = to_q31(r);
    let z = mul31(q, q);
    let p = c31(T0)
        + mul31(
            z,
            c31(T1) + mul31(z, c31(T2) + mul31(z, c31(T3) + mul31(z, c31(T4)))),
        );
    let t = r + from_q31(mul31(q, mul31(z, p)));
    if k & 1 == 0 {
        t
    } else if t == Fix::ZERO {
        Fix::MIN // on a pole: the saturation marker
    } else {
        -(Fix::ONE / t)
    }
}

/// atan x \[rad\], in [−π/2, π/2]; error ≤ 2e-7 relative + 1e-9 for all x (see tests); odd.
pub fn atan(x: Fix) -> Fix {
    let ax = x.abs();
    let (base, t) = if ax > TAN_3PI_8 {
        (FRAC_PI_2, -(Fix::ONE / ax))
    } else if ax > TAN_PI_8 {
        (FRAC_PI_4, (ax - Fix::ONE) / (ax + Fix::ONE))
    } else {
        (Fix::ZERO, ax)
    };
    // |t| ≤ tan π/8: t + (the rest in Q0.31).
    let q = to_q31(t);
    let z = mul31(q, q);
    let p = c31(A0) + mul31(z, c31(A1) + mul31(z, c31(A2) + mul31(z, c31(A3))));
    let y = base + (t + from_q31(mul31(q, mul31(z, p))));
    if x < Fix::ZERO {
        -y
    } else {
        y
    }
}

/// acos x \[rad\] for x in [−1, 1], in [0, π]; error ≤ 2e-7 relative + 2e-9 (see tests);
/// |x| > 1 → [`Fix::MIN`] (outside the domain: the Magic Formula clamps first, (4.104)).
pub fn acos(x: Fix) -> Fix {
    let ax = x.abs();
    if ax > Fix::ONE {
        return Fix::MIN;
    }
    if ax <= Fix::HALF {
        return FRAC_PI_2 - asin_poly(x, x * x);
    }
    // s = √((1 − |x|)/2) as √(1 − |x|)/√2: halving first would drop the last bit of 1 − |x|,
    // which near |x| = 1 (where acos is steep) costs 7e-8.
    let w = Fix::ONE - ax; // exact
    let s = w.sqrt() * FRAC_1_SQRT_2;
    let a = Fix::TWO * asin_poly(s, w * Fix::HALF);
    if x > Fix::ZERO {
        a
    } else {
        PI - a
    }
}

/// eˣ; error ≤ 2e-7 relative + 2⁻³² (see tests); saturates to [`Fix::MAX`] above ln 2³¹ ≈ 21.49;
/// 0 below ln 2⁻³³.
pub fn exp(x: Fix) -> Fix {
    if x > EXP_MAX {
        return Fix::MAX;
    }
    if x < EXP_MIN {
        return Fix::ZERO;
    }
    let k = (x * LOG2_E + Fix::HALF).floor_int(); // −33..=31
    let r = x - Fix::from_int(k as i32) * LN_2;
    // |r| ≤ ln 2/2 (and a few 2⁻³²): 1 + r + (the rest in Q0.31).
    let h = to_q31(r);
    let q = c31(E0) + mul31(h, c31(E1) + mul31(h, c31(E2) + mul31(h, c31(E3))));
    let p = Fix::ONE + (r + from_q31(mul31(mul31(h, h), q)));
    let bits = p.to_bits(); // p in (0.7, 1.42)
    if k >= 0 {
        let k = k as u32;
        if bits > (i64::MAX >> k) {
            Fix::MAX
        } else {
            Fix::from_bits(bits << k)
        }
    } else {
        let s = (-k) as u32; // 1..=33
        Fix::from_bits((bits + (1 << (s - 1))) >> s) // rounded
    }
}

/// ln x for x > 0; error ≤ 2e-7 relative + 2e-9 (see tests); x ≤ 0 → [`Fix::MIN`] (−∞).
pub fn ln(x: Fix) -> Fix {
    let bits = x.to_bits();
    if bits <= 0 {
        return Fix::MIN;
    }
    // x = 2ᵏ·m with m in [1, 2): the leading one at bit 32 + k.
    let mut k = 31 - super::lz64(bits as u64) as i32; // −32..=30
    let mut m = if k >= 0 {
        Fix::from_bits(bits >> k)
    } else {
        Fix::from_bits(bits << (-k))
    };
    if m > SQRT_2 {
        m = Fix::from_bits(m.to_bits() >> 1);
        k += 1;
    }
    let f = m - Fix::ONE;
    let s = f / (Fix::TWO + f);
    let z = s * s;
    let l = s * (Fix::TWO + z * (c(L0) + z * c(L1)));
    Fix::from_int(k) * LN_2 + l
}

impl Backend<Fix> for FixMath {
    #[inline]
    fn sin(x: Fix) -> Fix {
        sin(x)
    }
    #[inline]
    fn cos(x: Fix) -> Fix {
        cos(x)
    }
    #[inline]
    fn tan(x: Fix) -> Fix {
        tan(x)
    }
    #[inline]
    fn atan(x: Fix) -> Fix {
        atan(x)
    }
    #[inline]
    fn acos(x: Fix) -> Fix {
        acos(x)
    }
    #[inline]
    fn exp(x: Fix) -> Fix {
        exp(x)
    }
    #[inline]
    fn ln(x: Fix) -> Fix {
        ln(x)
    }
    #[inline]
    fn sqrt(x: Fix) -> Fix {
        x.sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Float;
    use core::f64::consts::PI as PI64;
    use proptest::prelude::*;

    /// Max of |got − want| / (abs + rel·|want|) over `xs`: ≤ 1 means within the stated bound.
    fn sweep(
        name: &str,
        f: impl Fn(Fix) -> Fix,
        reference: impl Fn(f64) -> f64,
        xs: impl Iterator<Item = f64>,
        abs: f64,
        rel: f64,
    ) {
        let (mut worst, mut at, mut max_abs) = (0.0f64, 0.0f64, 0.0f64);
        for x in xs {
            let fx = Fix::from_f64(x);
            let want = reference(fx.to_f64());
            let err = (f(fx).to_f64() - want).abs();
            max_abs = max_abs.max(err);
            let r = err / (abs + rel * want.abs());
            if r > worst {
                (worst, at) = (r, x);
            }
        }
        std::println!(
            "fixed {name}: max abs error {max_abs:.2e}, worst/bound {worst:.2} at {at:e}"
        );
        assert!(worst <= 1.0, "{name}: {worst} of the bound at {at}");
    }

    fn lin(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f64> {
        (0..n).map(move |i| lo + (hi - lo) * i as f64 / (n - 1) as f64)
    }

    fn log(lo: f64, hi: f64, n: usize) -> impl Iterator<Item = f64> {
        lin(lo.ln(), hi.ln(), n).map(f64::exp)
    }

    #[test]
    fn accuracy() {
        let tp = 2.0 * PI64;
        sweep("sin", sin, f64::sin, lin(-tp, tp, 400_001), 2.3e-9, 1e-7);
        sweep("cos", cos, f64::cos, lin(-tp, tp, 400_001), 2.3e-9, 1e-7);
        sweep("tan", tan, f64::tan, lin(-1.5, 1.5, 400_001), 4e-9, 3e-7);
        sweep(
            "atan",
            atan,
            f64::atan,
            lin(-20.0, 20.0, 400_001),
            1e-9,
            2e-7,
        );
        sweep(
            "atan log",
            atan,
            f64::atan,
            log(1e-9, 2e9, 400_001),
            1e-9,
            2e-7,
        );
        sweep("acos", acos, f64::acos, lin(-1.0, 1.0, 400_001), 2e-9, 2e-7);
        sweep(
            "exp",
            exp,
            f64::exp,
            lin(-22.0, 21.4, 400_001),
            2.4e-10,
            2e-7,
        );
        sweep("ln", ln, f64::ln, log(1e-9, 2e9, 400_001), 2e-9, 2e-7);
        sweep(
            "sqrt",
            Fix::sqrt,
            f64::sqrt,
            log(1e-9, 2e9, 400_001),
            2.4e-10,
            1e-15,
        );
    }

    #[test]
    fn special_points() {
        assert_eq!(sin(Fix::ZERO), Fix::ZERO);
        assert_eq!(cos(Fix::ZERO), Fix::ONE);
        assert_eq!(atan(Fix::ZERO), Fix::ZERO);
        assert_eq!(exp(Fix::ZERO), Fix::ONE);
        assert_eq!(ln(Fix::ONE), Fix::ZERO);
        assert_eq!(acos(Fix::ONE), Fix::ZERO);
        assert_eq!(acos(-Fix::ONE), PI);
        assert_eq!(acos(Fix::from_int(2)), Fix::MIN);
        assert_eq!(ln(Fix::ZERO), Fix::MIN);
        assert_eq!(ln(-Fix::ONE), Fix::MIN);
        assert_eq!(exp(Fix::from_int(30)), Fix::MAX);
        assert_eq!(exp(Fix::from_int(-30)), Fix::ZERO);
        assert!((atan(Fix::MAX).to_f64() - core::f64::consts::FRAC_PI_2).abs() < 1e-9);
        assert!((atan(Fix::MIN).to_f64() + core::f64::consts::FRAC_PI_2).abs() < 1e-9);
    }

    proptest! {
        /// Any Q31.32 input: no panic, sin/cos bounded, atan within ±π/2.
        #[test]
        fn sane_for_any_bits(bits in any::<i64>()) {
            let x = Fix::from_bits(bits);
            prop_assert!(sin(x).abs() <= Fix::ONE && cos(x).abs() <= Fix::ONE);
            prop_assert!(atan(x).abs() <= FRAC_PI_2 + Fix::DELTA);
            let _ = (tan(x), acos(x), exp(x), ln(x), x.sqrt());
        }

        #[test]
        fn vs_std(x in -6.0f64..6.0) {
            let fx = Fix::from_f64(x);
            let xs = fx.to_f64();
            prop_assert!((sin(fx).to_f64() - xs.sin()).abs() <= 2.3e-9 + 1e-7 * xs.sin().abs());
            prop_assert!((atan(fx).to_f64() - xs.atan()).abs() <= 1e-9 + 2e-7 * xs.atan().abs());
            prop_assert!((exp(fx).to_f64() - xs.exp()).abs() <= 2.4e-10 + 2e-7 * xs.exp());
            prop_assert!((cos(fx).to_f64() - xs.cos()).abs() <= 2.3e-9 + 1e-7 * xs.cos().abs());
        }

        #[test]
        fn vs_std_domains(x in -1.0f64..=1.0, y in 1e-6f64..1e6, t in -1.5f64..1.5) {
            let (fx, fy, ft) = (Fix::from_f64(x), Fix::from_f64(y), Fix::from_f64(t));
            let (x, y, t) = (fx.to_f64(), fy.to_f64(), ft.to_f64());
            prop_assert!((acos(fx).to_f64() - x.acos()).abs() <= 2e-9 + 2e-7 * x.acos());
            prop_assert!((ln(fy).to_f64() - y.ln()).abs() <= 2e-9 + 2e-7 * y.ln().abs());
            prop_assert!((fy.sqrt().to_f64() - y.sqrt()).abs() <= 2.4e-10);
            prop_assert!((tan(ft).to_f64() - t.tan()).abs() <= 4e-9 + 3e-7 * t.tan().abs());
        }
    }
}
