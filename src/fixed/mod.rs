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
//! (ε, 1e-6) quantities of one evaluation are 2e12 apart in SI units: no 32-bit format holds
//! both, and mixing formats per quantity would mean re-typing the equations with their shifts.
//! A change of units does it without re-typing (forces in kN, pressures in kPa, ε rounded up to
//! one LSB): an unmerged experiment (docs/decisions.md, commit 6f2cbad) ran the same equations in
//! Q15.16 within 8.2e-4 of the peak force over the oracle sweeps.
//!
//! ## Arithmetic: saturating, no panic
//! Every operation saturates (`saturating_add/sub/mul/div`); x/0 gives [`Fix::MAX`] or
//! [`Fix::MIN`] by the sign of x, √ of a negative number and ln of x ≤ 0 give [`Fix::MIN`].
//! [`Fix::MAX`] and [`Fix::MIN`] play the part of ±∞/NaN: [`Real::is_finite`] is false for them,
//! so an input that saturates is rejected like a non-finite float, and a result that saturates
//! makes `mf::eval` return `EvalError::Overflow` (as long as the saturated value reaches an output:
//! unlike NaN, a saturated value multiplied by 0 is 0).
//!
//! The product and the quotient are the `fixed` crate's `saturating_mul`/`saturating_div` bit
//! for bit (⌊a·b⌋ and a/b rounded towards zero, at 2⁻³²; tests against it on random and edge
//! bit patterns), computed without its `i128` arithmetic, which a 32-bit core runs as library
//! calls (`__multi3`, `__divti3`; on the Cortex-M0 over nine tenths of an evaluation): the
//! product from the 32-bit words' partial products that are not zero (four 16×16-bit `muls` each
//! on ARMv6-M, which has no 32×32→64 multiply; two where a high word is below 2¹⁶), the
//! quotient by two 3-by-2-word steps with the divisor's reciprocal (Möller–Granlund; the
//! reciprocal from a 128-entry table and two Newton steps, no divide instruction). The square
//! root, also `fixed`'s bit for bit, from a table of 1/√, two Newton steps, one Heron step with
//! that quotient and an exact check of the square. On the Cortex-M0 (no `clz` either: leading
//! zeros by binary search) that took the combined evaluation down by about 8×, and the kernels'
//! polynomials in Q0.31 (below) further (the M0 bench's figures: docs/backends.md, measured by
//! `cargo xtask firmware --m0`).
//!
//! ## Kernels ([`FixMath`])
//! Polynomials, with the minimax coefficients of the fast `f32` kernels (one table,
//! `math::minimax`; fits by `tools/minimax.py`) and the same argument reductions done in Q31.32:
//! sin, cos, tan by k·π/2; atan by 1/x and (x − 1)/(x + 1); acos through asin and √; eˣ by
//! k·ln 2 and a shift; ln by the leading-one position and atanh; √ exact to the last bit (rounded
//! down, as the `fixed` crate's: `Fix::sqrt`). The sin, cos, tan, atan and exp polynomials run
//! in Q0.31 after their reductions (|r| < 1): one 32×32→64-bit product per step instead of a
//! Q31.32 product, the leading term (r, 1) added in Q31.32. Errors measured in [`kernels`]'
//! tests: within 3e-7 relative (the polynomial fits) plus a few 2⁻³² absolute.
//!
//! ## Accuracy of the Magic Formula
//! Against the `f64` path over the inputs of all 71 MFeval oracle sweeps (9497 rows, every
//! version and mode): max |ΔFx|, |ΔFy| = 2.2e-7·FNOMIN, 1.8e-7 of the sweep's largest |F|
//! (the target: ≤ 0.5 %); |ΔMz| = 1.3e-7·FNOMIN·R0. Printed and asserted by
//! `cargo test -p gough-host --release --test backends -- --nocapture`.
//!
//! ## What this module leaves out
//! - The target of ≤ 4 000 instructions per combined evaluation on a Cortex-M0 (measured in
//!   docs/backends.md, well above it): about 260 products and 35 quotients of 64-bit values per
//!   evaluation remain, and the operation count of a Q15.16 experiment (237 products, 25
//!   quotients, 40 kernel calls) puts MF 6.1 above 4,000 in any fixed-point format. `mul` and `div` are out of
//!   line, which keeps `mf::eval::<Fix, _>` at about 14 kB of Thumb code instead of 210 kB.

pub mod kernels;

pub use kernels::FixMath;

use crate::math::{Float, Real};
use crate::mf::{self, EvalError, Input, Options, Output, Params};
use core::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};
use fixed::types::I32F32;

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

    /// √x for x ≥ 0, rounded down to the last bit (⌊√(bits·2³²)⌋, as the `fixed` crate's
    /// `sqrt`, with a table and Newton steps instead of a bit at a time); x < 0 → [`Fix::MIN`].
    pub fn sqrt(self) -> Fix {
        let x = self.to_bits();
        if x < 0 {
            return Fix::MIN;
        }
        Fix::from_bits(sqrt_bits(x as u64) as i64)
    }
}

/// ⌊√(x·2³²)⌋ for x < 2⁶³ (the square root of a Q31.32 bit pattern, < 2⁴⁸). The `fixed`
/// crate's square root finds it a bit at a time with 64-bit operations (about 1,500
/// instructions on the Cortex-M0); here: 1/√ of the normalised top word from a table and two
/// Newton steps (products only) to about 27 bits, one Heron step with a quotient
/// ([`div_bits`]) to within 1, then the exact floor by comparing the square.
#[inline(never)]
fn sqrt_bits(x: u64) -> u64 {
    if x == 0 {
        return 0;
    }
    // N = x·2³² < 2⁹⁵. Normalise by an even shift 2k: M = N·2²ᵏ in [2⁹⁴, 2⁹⁶); its top word
    // `mt` in [2³⁰, 2³²), t = mt/2³² in [¼, 1).
    let len = 96 - lz64(x); // bit length of N
    let k = (96 - len) / 2;
    let shift = 2 * k; // of N, < 64 + 32
    let mt = if shift >= 32 {
        (x << (shift - 32)) as u32
    } else {
        (x >> (32 - shift)) as u32
    };
    // r ≈ 1/√t in Q2.30, from the table (t's top 7 bits), then r ← r·(3 − t·r²)/2 twice.
    let mut r = RSQRT_TABLE
        .get(((mt >> 25) as usize).wrapping_sub(32))
        .copied()
        .unwrap_or(1 << 30);
    for _ in 0..2 {
        let r2 = (wide_mul(r, r) >> 30).min(u32::MAX as u64) as u32; // r², Q2.30
        let tr2 = (wide_mul(mt, r2) >> 32) as u32; // t·r², Q2.30, ≈ 1
        let e = (3u32 << 30).saturating_sub(tr2); // 3 − t·r², Q2.30
        r = (wide_mul(r, e) >> 31).min(u32::MAX as u64) as u32;
    }
    // √M ≈ t·r·2⁴⁸ (t·r in Q2.62); √N = √M/2ᵏ.
    let s0 = ((wide_mul(mt, r) >> 14) >> k).max(1);
    // Heron: ⌊(s0 + ⌊N/s0⌋)/2⌋ ≥ ⌊√N⌋, and within 1 of it from 27 correct bits.
    let q = div_bits(x as i64, s0 as i64) as u64;
    let mut s = (s0 + q) / 2;
    // The floor: lower s while s² > N (s < 2⁴⁸: s² from its 32-bit words). Heron from 27 bits
    // leaves at most 1 to go; bounded all the same (the tests check the floor exactly).
    for _ in 0..3 {
        if !square_exceeds(s, x) {
            break;
        }
        s -= 1;
    }
    s
}

/// s² > x·2³² for s < 2⁴⁸.
#[inline(always)]
fn square_exceeds(s: u64, x: u64) -> bool {
    let (sh, sl) = ((s >> 32) as u32, s as u32);
    let sq = wide_mul(sl, sl) as u128
        + ((wide_mul(sh, sl) as u128) << 33)
        + ((wide_mul(sh, sh) as u128) << 64);
    sq > (x as u128) << 32
}

/// 1/√t in Q2.30 at the middle of each interval of t = k/128 … (k + 1)/128, k = 32…127 (t's
/// top 7 bits), to within a few units of 2⁻³⁰ (found by bisection in integers).
// Evaluated at compile time: an index out of range would fail the build, not panic.
#[allow(clippy::indexing_slicing)]
const RSQRT_TABLE: [u32; 96] = {
    let mut t = [0u32; 96];
    let mut i = 0;
    while i < 96 {
        // 1/√u for u = (2k + 1)/256 by bisection on y² · u = 1 (no floating point in const
        // context needed: integers, y in Q2.30).
        let num = 2 * (32 + i as u64) + 1; // u = num/256
        let (mut lo, mut hi) = (1u64 << 30, 1u64 << 31);
        while hi - lo > 1 {
            let mid = (lo + hi) / 2;
            // mid² · num / 256 ≤ 2⁶⁰ ?
            if (mid * mid / 256) * num <= 1 << 60 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        t[i] = lo as u32;
        i += 1;
    }
    t
};

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

/// The full product of two 32-bit words. On ARMv6-M (Cortex-M0/M0+), which has no `umull`, from
/// four 16×16-bit products with `muls` (the compiler would call `__aeabi_lmul`, a 64×64-bit
/// multiply); elsewhere one instruction. ARMv6-M is told apart by its lack of 32-bit atomics
/// (target features are not visible to `cfg` on stable Rust); the older Arm cores that also
/// lack them take the same path, correct if slower.
#[inline(always)]
fn wide_mul(a: u32, b: u32) -> u64 {
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    {
        wide_mul_halves(a, b)
    }
    #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
    {
        a as u64 * b as u64
    }
}

/// `x.leading_zeros()`. ARMv6-M has no `clz` instruction, and the library routine the compiler
/// calls for it took about 70 instructions per 64-bit count on the Cortex-M0 (in a combined
/// evaluation's profile): here a binary search, about 40; elsewhere the instruction.
#[inline(always)]
pub(crate) fn lz64(x: u64) -> u32 {
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    {
        lz64_search(x)
    }
    #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
    {
        x.leading_zeros()
    }
}

/// [`lz64`] by binary search over the bits (ARMv6-M's; compiled everywhere, so that the host
/// tests it).
#[inline(always)]
#[cfg_attr(
    not(any(test, all(target_arch = "arm", not(target_has_atomic = "32")))),
    allow(dead_code)
)]
fn lz64_search(x: u64) -> u32 {
    let (mut w, mut n) = if x >> 32 == 0 {
        (x as u32, 32)
    } else {
        ((x >> 32) as u32, 0)
    };
    if w == 0 {
        return 64;
    }
    if w >> 16 == 0 {
        n += 16;
        w <<= 16;
    }
    if w >> 24 == 0 {
        n += 8;
        w <<= 8;
    }
    if w >> 28 == 0 {
        n += 4;
        w <<= 4;
    }
    if w >> 30 == 0 {
        n += 2;
        w <<= 2;
    }
    if w >> 31 == 0 {
        n += 1;
    }
    n
}

/// h·w where h is the high word of a Q31.32 magnitude, usually below 2¹⁶ (|value| < 65536):
/// on ARMv6-M then two 16×16-bit `muls` instead of [`wide_mul`]'s four; elsewhere
/// [`wide_mul`], one instruction (a test there would only cost).
#[inline(always)]
fn wide_mul_high(h: u32, w: u32) -> u64 {
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    {
        if h >> 16 == 0 {
            wide_mul_short_halves(h, w)
        } else {
            wide_mul(h, w)
        }
    }
    #[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
    {
        wide_mul(h, w)
    }
}

/// h·w for h < 2¹⁶ from two 16×16-bit products ([`wide_mul_high`]'s on ARMv6-M; compiled
/// everywhere, so that the host tests it): both fit 32 bits.
#[inline(always)]
#[cfg_attr(
    not(any(test, all(target_arch = "arm", not(target_has_atomic = "32")))),
    allow(dead_code)
)]
fn wide_mul_short_halves(h: u32, w: u32) -> u64 {
    let lo = h * (w & 0xffff);
    let hi = h * (w >> 16);
    ((hi as u64) << 16) + lo as u64
}

/// [`wide_mul`] from 16-bit halves (ARMv6-M's; compiled everywhere, so that the host tests it).
#[inline(always)]
#[cfg_attr(
    not(any(test, all(target_arch = "arm", not(target_has_atomic = "32")))),
    allow(dead_code)
)]
fn wide_mul_halves(a: u32, b: u32) -> u64 {
    let (a0, a1) = (a & 0xffff, a >> 16);
    let (b0, b1) = (b & 0xffff, b >> 16);
    // Each 16×16-bit product fits 32 bits; the two middle ones may carry out of their sum.
    let (mid, carry) = (a1 * b0).overflowing_add(a0 * b1);
    let (lo, c) = (a0 * b0).overflowing_add(mid << 16);
    let hi = a1 * b1 + (mid >> 16) + ((carry as u32) << 16) + c as u32;
    ((hi as u64) << 32) | lo as u64
}

/// ⌊a·b / 2³²⌋ of two Q31.32 bit patterns, saturated to the `i64` range (to `i64::MIN` when the
/// operands' signs differ, else `i64::MAX`): bit for bit the `fixed` crate's
/// `I32F32::saturating_mul`, which forms the product in `i128` — a library call per product on
/// a core without a 64-bit multiply (`__multi3`). Here: the magnitudes' 32-bit words, the
/// partial products that are not zero (a value below 1 has no high word), ⌊·⌋ as ⌈·⌉ of the
/// magnitude when the result is negative.
#[inline(always)]
fn mul_bits(a: i64, b: i64) -> i64 {
    let neg = (a < 0) != (b < 0);
    let (ua, ub) = (a.unsigned_abs(), b.unsigned_abs());
    let (ah, al) = ((ua >> 32) as u32, ua as u32);
    let (bh, bl) = ((ub >> 32) as u32, ub as u32);
    // ua·ub / 2³² = ah·bh·2³² + ah·bl + al·bh + al·bl / 2³²: its integer part in `acc`, any
    // part at or above 2⁶⁴ is an overflow (a saturated result).
    let ll = wide_mul(al, bl);
    let mut acc = ll >> 32;
    let mut over = false;
    if ah != 0 {
        let (x, c) = acc.overflowing_add(wide_mul_high(ah, bl));
        acc = x;
        over |= c;
        if bh != 0 {
            let hh = wide_mul_high(ah, bh);
            let (x, c) = acc.overflowing_add(hh << 32);
            acc = x;
            over |= c | (hh >> 32 != 0);
        }
    }
    if bh != 0 {
        let (x, c) = acc.overflowing_add(wide_mul_high(bh, al));
        acc = x;
        over |= c;
    }
    if neg {
        // ⌊−x⌋ = −⌈x⌉: round the magnitude up when the low word is not 0.
        let (m, c) = acc.overflowing_add(u64::from(ll as u32 != 0));
        if over || c || m > 1 << 63 {
            i64::MIN
        } else {
            m.wrapping_neg() as i64
        }
    } else if over || acc > i64::MAX as u64 {
        i64::MAX
    } else {
        acc as i64
    }
}

/// a·2³² / b of two Q31.32 bit patterns, rounded towards zero and saturated as [`mul_bits`];
/// b ≠ 0: bit for bit `I32F32::saturating_div` (an `i128` division, `__divti3`, on a 32-bit
/// core). The magnitudes are divided with 32-bit words as the digits: the divisor normalised
/// (top bit set), its reciprocal computed once, and the two words of the quotient each by one
/// 3-by-2-word step with that reciprocal (N. Möller, T. Granlund, "Improved division by
/// invariant integers", IEEE Trans. Computers 60(2), 2011, algorithms 5 and 6): a few 32×32-bit
/// products ([`wide_mul`]) per word instead of a loop over the quotient's bits.
#[inline(always)]
fn div_bits(a: i64, b: i64) -> i64 {
    let neg = (a < 0) != (b < 0);
    let (ua, d) = (a.unsigned_abs(), b.unsigned_abs());
    // The dividend ua·2³² (96 bits); the quotient fits 64 bits iff its part above 2⁶⁴, ua/2³²,
    // is below d.
    let q = if (ua >> 32) >= d {
        None
    } else {
        let s = lz64(d);
        let dn = d << s;
        let (d1, d0) = ((dn >> 32) as u32, dn as u32);
        // ua·2³²·2ˢ < 2⁶⁴·dn < 2¹²⁸: nothing shifted out.
        let n = (ua as u128) << (32 + s);
        let v = reciprocal_3by2(d1, d0);
        let (q1, r) = div_3by2((n >> 96) as u32, (n >> 64) as u32, (n >> 32) as u32, dn, v);
        let (q0, _) = div_3by2((r >> 32) as u32, r as u32, n as u32, dn, v);
        Some(((q1 as u64) << 32) | q0 as u64)
    };
    match q {
        Some(q) if neg && q <= 1 << 63 => q.wrapping_neg() as i64,
        Some(q) if !neg && q <= i64::MAX as u64 => q as i64,
        _ if neg => i64::MIN,
        _ => i64::MAX,
    }
}

/// ⌊(β³ − 1)/d⌋ − β for a normalised two-word divisor d = d1·β + d0 (β = 2³², d1 ≥ 2³¹):
/// Möller–Granlund algorithm 6, from the one-word reciprocal ⌊(β² − 1)/d1⌋ − β.
#[inline(always)]
fn reciprocal_3by2(d1: u32, d0: u32) -> u32 {
    let mut v = reciprocal_word(d1);
    let mut p = d1.wrapping_mul(v).wrapping_add(d0);
    if p < d0 {
        v = v.wrapping_sub(1);
        if p >= d1 {
            v = v.wrapping_sub(1);
            p = p.wrapping_sub(d1);
        }
        p = p.wrapping_sub(d1);
    }
    let t = wide_mul(v, d0);
    let (t1, t0) = ((t >> 32) as u32, t as u32);
    let (p, carry) = p.overflowing_add(t1);
    if carry {
        v = v.wrapping_sub(1);
        if ((p as u64) << 32 | t0 as u64) >= ((d1 as u64) << 32 | d0 as u64) {
            v = v.wrapping_sub(1);
        }
    }
    v
}

/// ⌊(β² − 1)/d⌋ − β for a normalised word d ≥ 2³¹ (β = 2³²; the quotient lies in [β, 2β), so
/// the result fits a word), without a divide instruction: 8 bits from a table, two Newton steps
/// X ← X + X·(β² − d·X)/β² on X ≈ β²/d (each 2 products of words), then the exact quotient by
/// stepping while (β + v)·d overshoots β² − 1 or (β + v + 1)·d does not (the two Newton steps
/// leave at most 3 to go; every one of the 2³¹ divisors is checked by the ignored test
/// `reciprocal_word_every_divisor`, about 15 s: `cargo test --release -p gough --features fixed
/// --lib -- --ignored reciprocal_word`). `u64` division here
/// would be a library call on a core without one (`__aeabi_uldivmod`, about 500 instructions
/// on the Cortex-M0).
#[inline(always)]
fn reciprocal_word(d: u32) -> u32 {
    // X − β = y: the table gives y/2¹⁶ at the middle of d's interval of 2²⁴.
    let i = ((d >> 24) & 0x7f) as usize;
    let mut y = (RECIP_TABLE.get(i).copied().unwrap_or(0) as u64) << 16;
    for _ in 0..2 {
        // e = β² − d·X, |e| < 2⁵⁷: d·X = d·y + d·β mod β², read as signed.
        let e = (0u64)
            .wrapping_sub(wide_mul(d, y as u32).wrapping_add((d as u64) << 32))
            .wrapping_sub(if y >> 32 != 0 { (d as u64) << 32 } else { 0 }) as i64;
        let (neg, ue) = (e < 0, e.unsigned_abs());
        let eh = (ue >> 32) as u32;
        // X·|e|/β² = |e|/β + y·|e|/β², to within 2 units.
        let c = eh as u64
            + (wide_mul(y.min(u32::MAX as u64) as u32, eh) >> 32)
            + (((ue as u32) as u64) >> 31);
        y = if neg {
            y.saturating_sub(c)
        } else {
            (y + c).min(1 << 32)
        };
    }
    let mut v = y.min(u32::MAX as u64) as u32;
    // P = (β + v)·d, 65 bits: (over β², low 64 bits).
    let (mut lo, mut over) = ((d as u64) << 32).overflowing_add(wide_mul(v, d));
    while over {
        v = v.wrapping_sub(1);
        let (l, borrow) = lo.overflowing_sub(d as u64);
        lo = l;
        over = !borrow;
    }
    while let (l, false) = lo.overflowing_add(d as u64) {
        v = v.wrapping_add(1);
        lo = l;
    }
    v
}

/// ⌊2²⁴/(k + ½)⌋ − 2¹⁶ for k = 128…255, the top 8 bits of a normalised word d: (β²/d − β)/2¹⁶
/// at the middle of each interval of d (to within 2⁻⁸ relative).
// Evaluated at compile time: an index out of range would fail the build, not panic.
#[allow(clippy::indexing_slicing)]
const RECIP_TABLE: [u16; 128] = {
    let mut t = [0u16; 128];
    let mut i = 0;
    while i < 128 {
        let k2 = 2 * (128 + i as u64) + 1; // 2·(k + ½)
        t[i] = ((1u64 << 25) / k2 - (1 << 16)) as u16;
        i += 1;
    }
    t
};

/// One quotient word of (u2·β² + u1·β + u0) / d and the remainder, for a normalised two-word d
/// with reciprocal `v` ([`reciprocal_3by2`]) and u2·β + u1 < d: Möller–Granlund algorithm 5.
#[inline(always)]
fn div_3by2(u2: u32, u1: u32, u0: u32, d: u64, v: u32) -> (u32, u64) {
    let (d1, d0) = ((d >> 32) as u32, d as u32);
    let q = wide_mul(v, u2).wrapping_add(((u2 as u64) << 32) | u1 as u64);
    let (mut q1, q0) = ((q >> 32) as u32, q as u32);
    let r1 = u1.wrapping_sub(q1.wrapping_mul(d1));
    let mut r = (((r1 as u64) << 32) | u0 as u64)
        .wrapping_sub(wide_mul(d0, q1))
        .wrapping_sub(d);
    q1 = q1.wrapping_add(1);
    if (r >> 32) as u32 >= q0 {
        q1 = q1.wrapping_sub(1);
        r = r.wrapping_add(d);
    }
    if r >= d {
        q1 = q1.wrapping_add(1);
        r -= d;
    }
    (q1, r)
}

impl Mul for Fix {
    type Output = Fix;
    /// Saturating, ⌊a·b⌋ to the last bit (as `fixed`'s `saturating_mul`). Out of line on
    /// purpose: inlined at every `*` of the equations, a 64×64-bit product with its saturation
    /// checks made `mf::eval` 210 kB of Thumb code.
    #[inline(never)]
    fn mul(self, rhs: Fix) -> Fix {
        Fix::from_bits(mul_bits(self.to_bits(), rhs.to_bits()))
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
        Fix::from_bits(div_bits(self.to_bits(), rhs.to_bits()))
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

impl Real for Fix {
    type Mask = bool;
    type Flags = crate::mf::Flags;
    #[inline(always)]
    fn mask_lt(self, o: Fix) -> bool {
        self < o
    }
    #[inline(always)]
    fn mask_le(self, o: Fix) -> bool {
        self <= o
    }
    #[inline(always)]
    fn mask_eq(self, o: Fix) -> bool {
        self == o
    }
    #[inline(always)]
    fn select(m: bool, a: Fix, b: Fix) -> Fix {
        if m {
            a
        } else {
            b
        }
    }
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

impl Float for Fix {
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
    use fixed::types::U32F32;
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

    /// [`mul_bits`] and [`div_bits`] against the `fixed` crate on the edges: 0, ±1 LSB, ±1,
    /// powers of two about the saturation limits, `i64::MIN`/`MAX` and their neighbours.
    #[test]
    fn mul_div_edges_are_fixed_bit_for_bit() {
        let mut v = std::vec![
            0i64,
            1,
            -1,
            2,
            -2,
            3,
            i64::MAX,
            i64::MIN,
            i64::MAX - 1,
            i64::MIN + 1
        ];
        for k in 0..63 {
            for x in [1i64 << k, (1i64 << k) - 1, (1i64 << k) + 1] {
                v.extend([x, -x]);
            }
        }
        v.extend([
            0xffff_ffff,
            0x1_0000_0000,
            0xffff_0000_ffff,
            0x7fff_ffff_ffff_0000,
        ]);
        for &x in &v {
            for &y in &v {
                let (fx, fy) = (I32F32::from_bits(x), I32F32::from_bits(y));
                assert_eq!(mul_bits(x, y), fx.saturating_mul(fy).to_bits(), "{x} * {y}");
                if y != 0 {
                    assert_eq!(div_bits(x, y), fx.saturating_div(fy).to_bits(), "{x} / {y}");
                }
            }
        }
        // The square root at the ends of the range, of each table interval, and at squares.
        let mut xs = std::vec![0u64, 1, 2, 3, 4, i64::MAX as u64, (i64::MAX - 1) as u64];
        for b in 0..63 {
            xs.extend([1u64 << b, (1u64 << b) - 1, (1u64 << b) + 1]);
        }
        for q in [1u64, 2, 3, 65535, 65536, 1 << 20, (1 << 31) - 1] {
            let sq = q * q; // x·2³² = (q·2¹⁶)² → x = q²
            xs.extend([sq, sq - 1, sq + 1]);
        }
        for x in xs {
            assert_eq!(sqrt_bits(x), U32F32::from_bits(x).sqrt().to_bits(), "√{x}");
        }
        // Leading zeros of 0, of every power of two and its neighbours.
        assert_eq!(lz64_search(0), 64);
        for b in 0..64 {
            for x in [1u64 << b, (1u64 << b) | 1, ((1u64 << b) - 1) | (1 << b)] {
                assert_eq!(lz64_search(x), x.leading_zeros(), "{x}");
            }
        }
        // The one-word reciprocal at its ends and at every table interval's ends.
        let mut ds = std::vec![1u32 << 31, u32::MAX];
        for k in 128u32..256 {
            ds.extend([k << 24, (k << 24) | 0xff_ffff, (k << 24) | 0x80_0000]);
        }
        for d in ds {
            assert_eq!(
                reciprocal_word(d) as u64,
                u64::MAX / d as u64 - (1 << 32),
                "{d}"
            );
        }
        // ARMv6-M's product from 16-bit halves, whatever the host: all-ones and carries.
        for (a, b) in [
            (u32::MAX, u32::MAX),
            (0xffff, 0xffff_0000),
            (0x8000_8000, u32::MAX),
            (0, 7),
        ] {
            assert_eq!(wide_mul_halves(a, b), a as u64 * b as u64, "{a} * {b}");
            let h = a >> 16;
            assert_eq!(
                wide_mul_short_halves(h, b),
                h as u64 * b as u64,
                "{h} * {b}"
            );
        }
    }

    /// [`reciprocal_word`] for every normalised divisor (2³¹ of them; run with `--ignored`).
    #[test]
    #[ignore = "2³¹ divisors: about 15 s in release, minutes in debug"]
    fn reciprocal_word_every_divisor() {
        for d in (1u32 << 31)..=u32::MAX {
            assert_eq!(
                reciprocal_word(d) as u64,
                u64::MAX / d as u64 - (1 << 32),
                "{d}"
            );
        }
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

        /// The word-wise product and the shift-and-subtract quotient are the `fixed` crate's
        /// saturating ones bit for bit: random bit patterns, and values of every magnitude
        /// (a random mantissa at a random scale, so that high words are often zero).
        #[test]
        fn mul_div_are_fixed_bit_for_bit(
            a in any::<i64>(), b in any::<i64>(),
            sa in 0u32..63, sb in 0u32..63,
        ) {
            for (x, y) in [(a, b), (a >> sa, b >> sb), (a >> sa, b), (a, b >> sb)] {
                let (fx, fy) = (I32F32::from_bits(x), I32F32::from_bits(y));
                prop_assert_eq!(mul_bits(x, y), fx.saturating_mul(fy).to_bits(), "{} * {}", x, y);
                if y != 0 {
                    prop_assert_eq!(div_bits(x, y), fx.saturating_div(fy).to_bits(), "{} / {}", x, y);
                }
            }
        }

        /// The square root is `fixed`'s bit for bit, and the floor: s² ≤ x·2³² < (s + 1)².
        #[test]
        fn sqrt_is_fixed_bit_for_bit(x in 0i64..i64::MAX, sh in 0u32..63) {
            for x in [x, x >> sh] {
                let s = sqrt_bits(x as u64);
                prop_assert_eq!(s, U32F32::from_bits(x as u64).sqrt().to_bits(), "√{}", x);
                let n = (x as u128) << 32;
                prop_assert!((s as u128) * (s as u128) <= n && (s as u128 + 1) * (s as u128 + 1) > n);
            }
        }

        #[test]
        fn reciprocal_word_is_the_quotient(d in (1u32 << 31)..=u32::MAX) {
            prop_assert_eq!(reciprocal_word(d) as u64, u64::MAX / d as u64 - (1 << 32));
        }

        #[test]
        fn lz64_search_is_leading_zeros(x in any::<u64>(), sh in 0u32..64) {
            prop_assert_eq!(lz64_search(x >> sh), (x >> sh).leading_zeros());
        }

        #[test]
        fn wide_mul_halves_is_the_product(a in any::<u32>(), b in any::<u32>(), h in 0u32..1 << 16) {
            prop_assert_eq!(wide_mul_halves(a, b), a as u64 * b as u64);
            prop_assert_eq!(wide_mul_short_halves(h, b), h as u64 * b as u64);
        }

        #[test]
        fn any_bits_any_op_no_panic(a in any::<i64>(), b in any::<i64>()) {
            let (fa, fb) = (Fix::from_bits(a), Fix::from_bits(b));
            let _ = (fa + fb, fa - fb, fa * fb, fa / fb, -fa, fa.abs(), fa.sqrt());
        }
    }
}
