//! `Fast64`: `f64` kernels for the host's Magic Formula — sin, cos, tan and atan without a
//! branch on their argument's range, so that a call costs a few dozen arithmetic instructions
//! and a batch loop can keep its lanes in step.
//!
//! The `libm` crate's sin, cos, tan and atan are exact to within 1 ulp but choose between four
//! or five argument ranges by branches that the Magic Formula's inputs take at random: measured
//! with `perf` on `cargo bench --bench mf_eval` (MF 6.1, f64), they were two thirds of a
//! combined evaluation (atan 35 %, cos 12 %, sin 11 %, tan 3 %). These take the same polynomials
//! (fdlibm's, as the `libm` crate has them: `k_sin`, `k_cos`, `atan`) behind reductions that
//! select with masks instead of branching:
//!
//! | kernel | reduction | polynomial | max error (the tests below, asserted with margin) |
//! |---|---|---|---|
//! | [`sin`], [`cos`], [`sin_cos`] | x = k·π/2 + r, \|r\| ≤ π/4, π/2 in two parts (exact k·π/2₁ for \|x\| ≤ 2²⁰); beyond, `libm` | fdlibm's odd deg 13 / even deg 14 | ≤ 2 ulp where \|y\| ≥ 2⁻¹⁰; 3e-19·max(1, \|x\|) abs. below |
//! | [`tan`] | as sin; sin r/cos r, −cos r/sin r for odd k | (sin, cos) | ≤ 4 ulp |
//! | [`atan`] | 1/\|x\| above 1, (t − 1)/(t + 1) above tan π/8 | fdlibm's odd deg 23 | ≤ 2 ulp, all x |
//!
//! acos, exp, ln and √ are `libm`'s (one or two calls per evaluation). NaN gives NaN, ±∞ the
//! limits (atan ±π/2; sin, cos, tan NaN), −0 keeps its sign.
//!
//! Through the whole Magic Formula the results are within 1e-12·FNOMIN of [`Libm`]'s
//! (`host-tests/tests/oracle.rs`, the batch test, every oracle point): the budget a fast `f64`
//! path has is 1e-9·FNOMIN.

use super::Libm;

// fdlibm's polynomials, as the `libm` crate (0.2) has them (k_sin.rs, k_cos.rs, atan.rs).
const S1: f64 = -1.666_666_666_666_663_243_48e-1;
const S2: f64 = 8.333_333_333_322_489_461_24e-3;
const S3: f64 = -1.984_126_982_985_794_931_34e-4;
const S4: f64 = 2.755_731_370_707_006_767_89e-6;
const S5: f64 = -2.505_076_025_340_686_341_95e-8;
const S6: f64 = 1.589_690_995_211_550_102_21e-10;
const C1: f64 = 4.166_666_666_666_660_190_37e-2;
const C2: f64 = -1.388_888_888_887_410_957_49e-3;
const C3: f64 = 2.480_158_728_947_672_941_78e-5;
const C4: f64 = -2.755_731_435_139_066_330_35e-7;
const C5: f64 = 2.087_572_321_298_174_827_90e-9;
const C6: f64 = -1.135_964_755_778_819_482_65e-11;
const AT: [f64; 11] = [
    3.333_333_333_333_293_180_27e-1,
    -1.999_999_999_987_648_324_76e-1,
    1.428_571_427_250_346_637_11e-1,
    -1.111_111_040_546_235_578_80e-1,
    9.090_887_133_436_506_561_96e-2,
    -7.691_876_205_044_829_994_95e-2,
    6.661_073_137_387_531_206_69e-2,
    -5.833_570_133_790_573_486_45e-2,
    4.976_877_994_615_932_360_17e-2,
    -3.653_157_274_421_691_552_70e-2,
    1.628_582_011_536_578_236_23e-2,
];
/// 2/π.
const INV_PIO2: f64 = 6.366_197_723_675_813_824_33e-1;
/// π/2's first 33 bits: k·PIO2_1 is exact for |k| < 2²⁰.
const PIO2_1: f64 = 1.570_796_326_734_125_614_17;
/// π/2 − PIO2_1.
const PIO2_1T: f64 = 6.077_100_506_506_192_249_32e-11;
/// 1.5·2⁵²: adding and subtracting it rounds to an integer (|x| < 2⁵¹).
const TO_INT: f64 = 1.5 / f64::EPSILON;
/// Above this |x| the two-part reduction is no longer exact: `libm` reduces (never in the
/// Magic Formula's ranges).
const REDUCE_MAX: f64 = 1.0e6;
/// tan(π/8) = √2 − 1.
const TAN_PI_8: f64 = 0.414_213_562_373_095_03;
/// π/4 in two parts (atan(1): fdlibm's atanhi\[1\], atanlo\[1\]).
const PIO4_HI: f64 = 7.853_981_633_974_482_789_99e-1;
const PIO4_LO: f64 = 3.061_616_997_868_383_017_93e-17;
/// π/2 in two parts (fdlibm's atanhi\[3\], atanlo\[3\]).
const PIO2_HI: f64 = 1.570_796_326_794_896_558_00;
const PIO2_LO: f64 = 6.123_233_995_736_766_035_87e-17;

/// `a` where `c`, else `b`: a mask, not a branch.
#[inline(always)]
fn select(c: bool, a: f64, b: f64) -> f64 {
    let m = 0u64.wrapping_sub(u64::from(c));
    f64::from_bits((a.to_bits() & m) | (b.to_bits() & !m))
}

/// `x` with its sign flipped where `c`.
#[inline(always)]
fn neg_if(c: bool, x: f64) -> f64 {
    f64::from_bits(x.to_bits() ^ (u64::from(c) << 63))
}

/// (sin r, cos r, k mod 4) with x = k·π/2 + r, |r| ≤ π/4 (|x| ≤ [`REDUCE_MAX`]).
#[inline(always)]
fn reduced(x: f64) -> (f64, f64, u64) {
    let k = (x * INV_PIO2 + TO_INT) - TO_INT;
    let r = (x - k * PIO2_1) - k * PIO2_1T;
    let z = r * r;
    let w = z * z;
    // fdlibm's k_sin (y = 0): r + r·z·(S1 + z·(S2 + …)); r = ±0 stays ±0.
    let sp = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    let s = select(r == 0.0, r, r + z * r * (S1 + z * sp));
    // fdlibm's k_cos (y = 0), with the rounding of 1 − z/2 kept apart.
    let hz = 0.5 * z;
    let one_m = 1.0 - hz;
    let poly = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let c = one_m + (((1.0 - one_m) - hz) + z * poly);
    // k as an integer: exact (|k| < 2²⁰); two's complement keeps k mod 4 for negative k.
    let q = (k as i64 as u64) & 3;
    (s, c, q)
}

/// sin x.
#[inline]
pub fn sin(x: f64) -> f64 {
    if !(x.abs() <= REDUCE_MAX) {
        return libm::sin(x);
    }
    let (s, c, q) = reduced(x);
    // k mod 4 = 0: s, 1: c, 2: −s, 3: −c.
    neg_if(q & 2 != 0, select(q & 1 != 0, c, s))
}

/// cos x.
#[inline]
pub fn cos(x: f64) -> f64 {
    if !(x.abs() <= REDUCE_MAX) {
        return libm::cos(x);
    }
    let (s, c, q) = reduced(x);
    // k mod 4 = 0: c, 1: −s, 2: −c, 3: s.
    neg_if((q + 1) & 2 != 0, select(q & 1 != 0, s, c))
}

/// (sin x, cos x), one reduction.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    if !(x.abs() <= REDUCE_MAX) {
        return (libm::sin(x), libm::cos(x));
    }
    let (s, c, q) = reduced(x);
    let odd = q & 1 != 0;
    (
        neg_if(q & 2 != 0, select(odd, c, s)),
        neg_if((q + 1) & 2 != 0, select(odd, s, c)),
    )
}

/// tan x.
#[inline]
pub fn tan(x: f64) -> f64 {
    if !(x.abs() <= REDUCE_MAX) {
        return libm::tan(x);
    }
    let (s, c, q) = reduced(x);
    // even k: sin r / cos r; odd k: −cos r / sin r.
    let odd = q & 1 != 0;
    neg_if(odd, select(odd, c, s)) / select(odd, s, c)
}

/// atan x, in (−π/2, π/2).
#[inline]
pub fn atan(x: f64) -> f64 {
    let ax = x.abs();
    let big = ax > 1.0;
    // atan|x| = π/2 − atan(1/|x|) above 1 (1/∞ = 0: ±π/2 at ±∞).
    let t = select(big, 1.0 / ax, ax);
    // atan t = π/4 + atan((t − 1)/(t + 1)) above tan π/8: |u| ≤ tan π/8 < 7/16, fdlibm's range.
    let mid = t > TAN_PI_8;
    let u = select(mid, (t - 1.0) / (t + 1.0), t);
    let z = u * u;
    let w = z * z;
    let s1 = z * (AT[0] + w * (AT[2] + w * (AT[4] + w * (AT[6] + w * (AT[8] + w * AT[10])))));
    let s2 = w * (AT[1] + w * (AT[3] + w * (AT[5] + w * (AT[7] + w * AT[9]))));
    let hi = select(mid, PIO4_HI, 0.0);
    let lo = select(mid, PIO4_LO, 0.0);
    // fdlibm: atanhi − ((u·(s1 + s2) − atanlo) − u).
    let a = hi - ((u * (s1 + s2) - lo) - u);
    let a = select(big, PIO2_HI - (a - PIO2_LO), a);
    // The sign of x (−0 stays −0; NaN stays NaN).
    f64::from_bits(a.to_bits() | (x.to_bits() & (1 << 63)))
}

/// The host's fast `f64` backend (see the [module doc](self)): sin, cos, tan, atan here; acos,
/// exp, ln, √ from `libm`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Fast64;

impl super::Backend<f64> for Fast64 {
    #[inline]
    fn sin(x: f64) -> f64 {
        sin(x)
    }
    #[inline]
    fn cos(x: f64) -> f64 {
        cos(x)
    }
    #[inline]
    fn tan(x: f64) -> f64 {
        tan(x)
    }
    #[inline]
    fn atan(x: f64) -> f64 {
        atan(x)
    }
    #[inline]
    fn acos(x: f64) -> f64 {
        <Libm as super::Backend<f64>>::acos(x)
    }
    #[inline]
    fn exp(x: f64) -> f64 {
        <Libm as super::Backend<f64>>::exp(x)
    }
    #[inline]
    fn ln(x: f64) -> f64 {
        <Libm as super::Backend<f64>>::ln(x)
    }
    #[inline]
    fn sqrt(x: f64) -> f64 {
        <Libm as super::Backend<f64>>::sqrt(x)
    }
    #[inline]
    fn sin_cos(x: f64) -> (f64, f64) {
        sin_cos(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    /// Error in ulp of the reference `want` (its spacing at |want|, at least the smallest normal's).
    fn ulps(got: f64, want: f64) -> f64 {
        let spacing = f64::from_bits(want.abs().max(f64::MIN_POSITIVE).to_bits() + 1)
            - want.abs().max(f64::MIN_POSITIVE);
        (got - want).abs() / spacing
    }

    /// A deterministic sweep: a uniform grid, a geometric one, and an LCG's points.
    fn points(lo: f64, hi: f64, n: usize) -> Vec<f64> {
        let mut v: Vec<f64> = (0..=n)
            .map(|i| lo + (hi - lo) * i as f64 / n as f64)
            .collect();
        let mut s = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..n {
            s = s
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            v.push(lo + (hi - lo) * ((s >> 11) as f64 / (1u64 << 53) as f64));
        }
        v
    }

    #[test]
    fn atan_within_2_ulp() {
        let mut xs = points(-4.0, 4.0, 400_000);
        for e in -300..=300 {
            for m in [1.0, 1.234_567, 3.3, 7.9] {
                let x = m * 10f64.powi(e);
                xs.push(x);
                xs.push(-x);
            }
        }
        let mut worst = 0.0f64;
        for &x in &xs {
            let e = ulps(atan(x), x.atan());
            worst = worst.max(e);
        }
        std::println!("atan: max {worst:.2} ulp over {} points", xs.len());
        assert!(worst < 2.5, "{worst}");
        assert_eq!(atan(f64::INFINITY), core::f64::consts::FRAC_PI_2);
        assert_eq!(atan(f64::NEG_INFINITY), -core::f64::consts::FRAC_PI_2);
        assert!(atan(f64::NAN).is_nan());
        assert_eq!(atan(-0.0).to_bits(), (-0.0f64).to_bits());
        assert_eq!(atan(0.0).to_bits(), 0);
    }

    #[test]
    fn sin_cos_tan_within_budget() {
        let mut xs = points(-8.0, 8.0, 400_000);
        xs.extend(points(-2.0e5, 2.0e5, 100_000));
        let (mut ws, mut wc, mut wt, mut abs) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for &x in &xs {
            let (s, c) = sin_cos(x);
            assert_eq!(
                (s.to_bits(), c.to_bits()),
                (sin(x).to_bits(), cos(x).to_bits())
            );
            let (rs, rc) = (x.sin(), x.cos());
            for (got, want, worst) in [(s, rs, &mut ws), (c, rc, &mut wc)] {
                if want.abs() >= 1.0 / 1024.0 {
                    *worst = worst.max(ulps(got, want));
                } else {
                    abs = abs.max((got - want).abs() / x.abs().max(1.0));
                }
            }
            let rt = x.tan();
            if rt.abs() >= 1.0 / 1024.0 && rt.abs() <= 1.0e3 {
                wt = wt.max(ulps(tan(x), rt));
            }
        }
        std::println!(
            "sin {ws:.2} ulp, cos {wc:.2} ulp, tan {wt:.2} ulp, near zeros {abs:.1e}·max(1, |x|) abs., {} points",
            xs.len()
        );
        assert!(ws <= 2.0 && wc <= 2.0, "{ws} {wc}");
        assert!(wt <= 4.0, "{wt}");
        assert!(abs <= 3e-19, "{abs}");
        for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(sin(x).is_nan() && cos(x).is_nan() && tan(x).is_nan());
        }
        assert_eq!(sin(-0.0).to_bits(), (-0.0f64).to_bits());
        assert_eq!(cos(0.0), 1.0);
        assert_eq!(sin(1.0e300), libm::sin(1.0e300));
    }
}
