//! Lanes: `N` points in one value, so that the one generic Magic Formula evaluates several
//! points per instruction (issue 57). [`Lanes<f64, N>`] implements [`Real`] lane by lane; its
//! comparisons give a [`LaneMask`], its flags are one [`Flags`] per lane ([`LaneFlags`]), and
//! [`Lanewise`] is its backend: fdlibm's sin, cos, tan and atan polynomials behind reductions
//! that select by masks instead of branching (the kernels of 7567f2d, measured slower than
//! `libm` as a scalar path, which is what lanes need), `libm` for acos, exp and ln lane by lane.
//!
//! Every operation is a loop over `[f64; N]` that the compiler turns into vector instructions
//! where the target has them: `mf::eval_batch_lanes` compiles it inside
//! `#[target_feature(enable = "avx2,fma")]` (N = 4) and `"avx512f"` (N = 8) functions and picks
//! one at run time.
//!
//! ## What differs from a scalar
//! `PartialOrd` and `PartialEq` hold when they hold in *every* lane (so `x < y` is `x < y` for
//! values that are the same in every lane: the parameters; a branch on a parameter stays an
//! `if`). Branches on values go through [`Real::mask_lt`] and friends, [`Real::select`] and
//! [`super::choose`]. `is_finite` is "every lane finite".
//!
//! | kernel | reduction | polynomial | max error (tests below) |
//! |---|---|---|---|
//! | sin, cos | x = k·π/2 + r, \|r\| ≤ π/4, π/2 in two parts (k·π/2₁ exact for \|x\| ≤ 2²⁰); beyond 10⁶ or non-finite, `libm` | fdlibm's odd deg 13 / even deg 14 | ≤ 2 ulp where \|y\| ≥ 2⁻¹⁰; 3e-19·max(1, \|x\|) abs. below |
//! | tan | as sin; sin r/cos r, −cos r/sin r for odd k | (sin, cos) | ≤ 4 ulp |
//! | atan | (t − 1)/(t + 1) above tan π/8, −1/t above tan 3π/8 (one division) | fdlibm's odd deg 23 | ≤ 2 ulp, all x |
//! | √ | `f64::sqrt` with `std` (the vector instruction), `libm` lane by lane without | — | exact |
//! | acos, exp, ln | `libm`, lane by lane | — | ≤ 1 ulp |

// fdlibm's constants as fdlibm prints them (more digits than an f64 keeps).
#![allow(clippy::excessive_precision)]

use super::{Backend, Mask, Real};
use crate::mf::{FlagSet, Flags};
use core::cmp::Ordering;
use core::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// `N` values of `T`, computed lane by lane (`T` = `f64`).
#[derive(Clone, Copy, Debug)]
#[repr(transparent)]
pub struct Lanes<T, const N: usize>(pub [T; N]);

/// The result of comparing [`Lanes`]: all ones in a lane where the comparison holds, 0 where not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub struct LaneMask<const N: usize>(pub [u64; N]);

/// One [`Flags`] per lane.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(transparent)]
pub struct LaneFlags<const N: usize>(pub [Flags; N]);

impl<const N: usize> Default for LaneMask<N> {
    #[inline(always)]
    fn default() -> Self {
        LaneMask([0; N])
    }
}

impl<const N: usize> Default for LaneFlags<N> {
    #[inline(always)]
    fn default() -> Self {
        LaneFlags([Flags(0); N])
    }
}

impl<const N: usize> Default for Lanes<f64, N> {
    #[inline(always)]
    fn default() -> Self {
        Lanes([0.0; N])
    }
}

/// All ones where `c`, else 0.
#[inline(always)]
fn ones(c: bool) -> u64 {
    0u64.wrapping_sub(u64::from(c))
}

impl<const N: usize> Mask for LaneMask<N> {
    #[inline(always)]
    fn splat(b: bool) -> Self {
        LaneMask([ones(b); N])
    }
    #[inline(always)]
    fn all(self) -> bool {
        self.0.iter().fold(u64::MAX, |a, &m| a & m) != 0
    }
    #[inline(always)]
    fn any(self) -> bool {
        self.0.iter().fold(0, |a, &m| a | m) != 0
    }
    #[inline(always)]
    fn and(mut self, o: Self) -> Self {
        for (a, b) in self.0.iter_mut().zip(o.0) {
            *a &= b;
        }
        self
    }
    #[inline(always)]
    fn or(mut self, o: Self) -> Self {
        for (a, b) in self.0.iter_mut().zip(o.0) {
            *a |= b;
        }
        self
    }
    #[inline(always)]
    fn not(mut self) -> Self {
        for a in self.0.iter_mut() {
            *a = !*a;
        }
        self
    }
}

impl<const N: usize> FlagSet<LaneMask<N>> for LaneFlags<N> {
    #[inline(always)]
    fn insert(&mut self, other: Flags) {
        for f in self.0.iter_mut() {
            f.0 |= other.0;
        }
    }
    #[inline(always)]
    fn set_if(&mut self, other: Flags, m: LaneMask<N>) {
        for (f, m) in self.0.iter_mut().zip(m.0) {
            // The mask's low 16 bits are all ones or all zeros.
            f.0 |= other.0 & (m as u16);
        }
    }
    #[inline(always)]
    fn merge(&mut self, other: Self) {
        for (f, o) in self.0.iter_mut().zip(other.0) {
            f.0 |= o.0;
        }
    }
}

/// `f` lane by lane.
#[inline(always)]
fn map<const N: usize>(mut a: [f64; N], f: impl Fn(f64) -> f64) -> [f64; N] {
    for x in a.iter_mut() {
        *x = f(*x);
    }
    a
}

/// `f` lane by lane over two operands.
#[inline(always)]
fn zip<const N: usize>(mut a: [f64; N], b: [f64; N], f: impl Fn(f64, f64) -> f64) -> [f64; N] {
    for (x, y) in a.iter_mut().zip(b) {
        *x = f(*x, y);
    }
    a
}

/// A comparison lane by lane.
#[inline(always)]
fn cmp<const N: usize>(a: [f64; N], b: [f64; N], f: impl Fn(f64, f64) -> bool) -> LaneMask<N> {
    let mut m = [0u64; N];
    for ((m, x), y) in m.iter_mut().zip(a).zip(b) {
        *m = ones(f(x, y));
    }
    LaneMask(m)
}

impl<const N: usize> Lanes<f64, N> {
    /// `x` in every lane.
    #[inline(always)]
    pub const fn splat(x: f64) -> Self {
        Lanes([x; N])
    }
}

macro_rules! lane_op {
    ($tr:ident, $f:ident, $atr:ident, $af:ident, $op:tt) => {
        impl<const N: usize> $tr for Lanes<f64, N> {
            type Output = Self;
            #[inline(always)]
            fn $f(self, o: Self) -> Self {
                Lanes(zip(self.0, o.0, |a, b| a $op b))
            }
        }
        impl<const N: usize> $atr for Lanes<f64, N> {
            #[inline(always)]
            fn $af(&mut self, o: Self) {
                *self = *self $op o;
            }
        }
    };
}
lane_op!(Add, add, AddAssign, add_assign, +);
lane_op!(Sub, sub, SubAssign, sub_assign, -);
lane_op!(Mul, mul, MulAssign, mul_assign, *);

impl<const N: usize> Div for Lanes<f64, N> {
    type Output = Self;
    #[inline(always)]
    fn div(self, o: Self) -> Self {
        Lanes(zip(self.0, o.0, |a, b| a / b))
    }
}

impl<const N: usize> Neg for Lanes<f64, N> {
    type Output = Self;
    #[inline(always)]
    fn neg(self) -> Self {
        Lanes(map(self.0, |a| -a))
    }
}

/// Equal in every lane.
impl<const N: usize> PartialEq for Lanes<f64, N> {
    #[inline(always)]
    fn eq(&self, o: &Self) -> bool {
        cmp(self.0, o.0, |a, b| a == b).all()
    }
}

/// An order where every lane has it (`None` where lanes disagree): the comparison operators
/// hold when they hold in every lane.
impl<const N: usize> PartialOrd for Lanes<f64, N> {
    #[inline(always)]
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        if self == o {
            Some(Ordering::Equal)
        } else if self < o {
            Some(Ordering::Less)
        } else if self > o {
            Some(Ordering::Greater)
        } else {
            None
        }
    }
    #[inline(always)]
    fn lt(&self, o: &Self) -> bool {
        cmp(self.0, o.0, |a, b| a < b).all()
    }
    #[inline(always)]
    fn le(&self, o: &Self) -> bool {
        cmp(self.0, o.0, |a, b| a <= b).all()
    }
    #[inline(always)]
    fn gt(&self, o: &Self) -> bool {
        cmp(self.0, o.0, |a, b| a > b).all()
    }
    #[inline(always)]
    fn ge(&self, o: &Self) -> bool {
        cmp(self.0, o.0, |a, b| a >= b).all()
    }
}

/// `a` where `m`, else `b`, by the bits.
#[inline(always)]
fn blend(m: u64, a: f64, b: f64) -> f64 {
    f64::from_bits((a.to_bits() & m) | (b.to_bits() & !m))
}

const SIGN: u64 = 1 << 63;

impl<const N: usize> Real for Lanes<f64, N> {
    type Mask = LaneMask<N>;
    type Flags = LaneFlags<N>;
    const ZERO: Self = Lanes([0.0; N]);
    const ONE: Self = Lanes([1.0; N]);
    const TWO: Self = Lanes([2.0; N]);
    const HALF: Self = Lanes([0.5; N]);
    const PI: Self = Lanes([core::f64::consts::PI; N]);
    const FRAC_PI_2: Self = Lanes([core::f64::consts::FRAC_PI_2; N]);
    const FRAC_2_PI: Self = Lanes([core::f64::consts::FRAC_2_PI; N]);

    #[inline(always)]
    fn mask_lt(self, o: Self) -> LaneMask<N> {
        cmp(self.0, o.0, |a, b| a < b)
    }
    #[inline(always)]
    fn mask_le(self, o: Self) -> LaneMask<N> {
        cmp(self.0, o.0, |a, b| a <= b)
    }
    #[inline(always)]
    fn mask_eq(self, o: Self) -> LaneMask<N> {
        cmp(self.0, o.0, |a, b| a == b)
    }
    #[inline(always)]
    fn select(m: LaneMask<N>, a: Self, b: Self) -> Self {
        let mut r = b.0;
        for ((r, m), a) in r.iter_mut().zip(m.0).zip(a.0) {
            *r = blend(m, a, *r);
        }
        Lanes(r)
    }
    #[inline(always)]
    fn from_f64(x: f64) -> Self {
        Lanes([x; N])
    }
    #[inline(always)]
    fn abs(self) -> Self {
        Lanes(map(self.0, |a| f64::from_bits(a.to_bits() & !SIGN)))
    }
    /// Every lane finite.
    #[inline(always)]
    fn is_finite(self) -> bool {
        <f64 as Real>::all_finite(&self.0)
    }
    #[inline(always)]
    fn all_finite(xs: &[Self]) -> bool {
        let mut acc = [0.0f64; N];
        for x in xs {
            for (a, v) in acc.iter_mut().zip(x.0) {
                // v − v: 0 for finite v, NaN otherwise (as `f64`'s own `all_finite`).
                #[allow(clippy::eq_op)]
                {
                    *a += v - v;
                }
            }
        }
        acc.iter().fold(0.0, |s, &a| s + a) == 0.0
    }
    #[inline(always)]
    fn max(self, o: Self) -> Self {
        Lanes(zip(self.0, o.0, |a, b| if a > b { a } else { b }))
    }
    #[inline(always)]
    fn min(self, o: Self) -> Self {
        Lanes(zip(self.0, o.0, |a, b| if a < b { a } else { b }))
    }
    #[inline(always)]
    fn sign(self) -> Self {
        Lanes(map(self.0, |a| {
            // ±1 with a's sign where a ≠ 0, 0 at ±0 (NaN gives ±1: callers check finiteness).
            let one = f64::from_bits(1.0f64.to_bits() | (a.to_bits() & SIGN));
            blend(ones(a == 0.0), 0.0, one)
        }))
    }
    #[inline(always)]
    fn sign_nz(self) -> Self {
        Lanes(map(self.0, |a| blend(ones(a < 0.0), -1.0, 1.0)))
    }
}

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
const AT0: f64 = 3.333_333_333_333_293_180_27e-1;
const AT1: f64 = -1.999_999_999_987_648_324_76e-1;
const AT2: f64 = 1.428_571_427_250_346_637_11e-1;
const AT3: f64 = -1.111_111_040_546_235_578_80e-1;
const AT4: f64 = 9.090_887_133_436_506_561_96e-2;
const AT5: f64 = -7.691_876_205_044_829_994_95e-2;
const AT6: f64 = 6.661_073_137_387_531_206_69e-2;
const AT7: f64 = -5.833_570_133_790_573_486_45e-2;
const AT8: f64 = 4.976_877_994_615_932_360_17e-2;
const AT9: f64 = -3.653_157_274_421_691_552_70e-2;
const AT10: f64 = 1.628_582_011_536_578_236_23e-2;
/// 2/π.
const INV_PIO2: f64 = core::f64::consts::FRAC_2_PI;
/// π/2's first 33 bits: k·PIO2_1 is exact for |k| < 2²⁰.
const PIO2_1: f64 = 1.570_796_326_734_125_614_17;
/// π/2 − PIO2_1.
const PIO2_1T: f64 = 6.077_100_506_506_192_249_32e-11;
/// 1.5·2⁵²: adding it rounds x·2/π to an integer k whose low bits are the sum's low mantissa
/// bits (two's complement for k < 0), and subtracting it gives k as a float (|k| < 2⁵¹).
const TO_INT: f64 = 1.5 / f64::EPSILON;
/// Above this |x| the two-part reduction is no longer exact: `libm` reduces (never in the
/// Magic Formula's ranges).
const REDUCE_MAX: f64 = 1.0e6;
/// tan(π/8) = √2 − 1.
const TAN_PI_8: f64 = 0.414_213_562_373_095_03;
/// tan(3π/8) = √2 + 1.
const TAN_3PI_8: f64 = 2.414_213_562_373_095;
/// π/4 in two parts (atan(1): fdlibm's atanhi\[1\], atanlo\[1\]).
const PIO4_HI: f64 = core::f64::consts::FRAC_PI_4;
const PIO4_LO: f64 = 3.061_616_997_868_383_017_93e-17;
/// π/2 in two parts (fdlibm's atanhi\[3\], atanlo\[3\]).
const PIO2_HI: f64 = core::f64::consts::FRAC_PI_2;
const PIO2_LO: f64 = 6.123_233_995_736_766_035_87e-17;

/// (sin r, cos r, k mod 4) with x = k·π/2 + r, |r| ≤ π/4 (meaningful for |x| ≤ [`REDUCE_MAX`]).
#[inline(always)]
fn reduced(x: f64) -> (f64, f64, u64) {
    let shifted = x * INV_PIO2 + TO_INT;
    let k = shifted - TO_INT;
    let r = (x - k * PIO2_1) - k * PIO2_1T;
    let z = r * r;
    let w = z * z;
    // fdlibm's k_sin (y = 0): r + r·z·(S1 + z·(S2 + …)); r = ±0 stays ±0.
    let sp = S2 + z * (S3 + z * S4) + z * w * (S5 + z * S6);
    let s = blend(ones(r == 0.0), r, r + z * r * (S1 + z * sp));
    // fdlibm's k_cos (y = 0), with the rounding of 1 − z/2 kept apart.
    let hz = 0.5 * z;
    let one_m = 1.0 - hz;
    let poly = z * (C1 + z * (C2 + z * C3)) + w * w * (C4 + z * (C5 + z * C6));
    let c = one_m + (((1.0 - one_m) - hz) + z * poly);
    (s, c, shifted.to_bits() & 3)
}

/// sin x for |x| ≤ [`REDUCE_MAX`]: k mod 4 = 0: s, 1: c, 2: −s, 3: −c.
#[inline(always)]
fn sin_core(x: f64) -> f64 {
    let (s, c, q) = reduced(x);
    let v = blend(ones(q & 1 != 0), c, s);
    f64::from_bits(v.to_bits() ^ ((q & 2) << 62))
}

/// cos x for |x| ≤ [`REDUCE_MAX`]: k mod 4 = 0: c, 1: −s, 2: −c, 3: s.
#[inline(always)]
fn cos_core(x: f64) -> f64 {
    let (s, c, q) = reduced(x);
    let v = blend(ones(q & 1 != 0), s, c);
    f64::from_bits(v.to_bits() ^ (((q + 1) & 2) << 62))
}

/// tan x for |x| ≤ [`REDUCE_MAX`]: even k: sin r / cos r; odd k: −cos r / sin r.
#[inline(always)]
fn tan_core(x: f64) -> f64 {
    let (s, c, q) = reduced(x);
    let odd = ones(q & 1 != 0);
    let num = blend(odd, -c, s);
    num / blend(odd, s, c)
}

/// atan x, in (−π/2, π/2), every x (±∞ → ±π/2, NaN → NaN, −0 → −0). One division: |x| = t is
/// reduced to |u| ≤ tan π/8 (< 7/16, fdlibm's polynomial range) by
/// - t ≤ tan π/8: u = t, atan t = atan u;
/// - t ≤ tan 3π/8: u = (t − 1)/(t + 1), atan t = π/4 + atan u;
/// - above: u = −1/t, atan t = π/2 + atan u (1/∞ = 0: π/2 at ∞).
#[inline(always)]
fn atan_lane(x: f64) -> f64 {
    let t = f64::from_bits(x.to_bits() & !SIGN);
    let mid = ones(t > TAN_PI_8);
    let big = ones(t > TAN_3PI_8);
    let num = blend(big, -1.0, blend(mid, t - 1.0, t));
    let den = blend(big, t, blend(mid, t + 1.0, 1.0));
    let u = num / den;
    let z = u * u;
    let w = z * z;
    let s1 = z * (AT0 + w * (AT2 + w * (AT4 + w * (AT6 + w * (AT8 + w * AT10)))));
    let s2 = w * (AT1 + w * (AT3 + w * (AT5 + w * (AT7 + w * AT9))));
    let hi = blend(big, PIO2_HI, blend(mid, PIO4_HI, 0.0));
    let lo = blend(big, PIO2_LO, blend(mid, PIO4_LO, 0.0));
    // fdlibm: atanhi − ((u·(s1 + s2) − atanlo) − u).
    let a = hi - ((u * (s1 + s2) - lo) - u);
    // The sign of x (−0 stays −0; NaN stays NaN).
    f64::from_bits(a.to_bits() | (x.to_bits() & SIGN))
}

/// `core` lane by lane; the lanes beyond [`REDUCE_MAX`] (or not finite) again through `far`
/// (a branch taken only when some lane is out there: never in the Magic Formula's ranges).
#[inline(always)]
fn reduced_kernel<const N: usize>(
    x: [f64; N],
    core: impl Fn(f64) -> f64,
    far: fn(f64) -> f64,
) -> [f64; N] {
    let r = map(x, core);
    // Not `a.abs() > m`: NaN is out too.
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    let out = cmp(x, [REDUCE_MAX; N], |a, m| !(a.abs() <= m));
    if !out.any() {
        return r;
    }
    let mut r = r;
    for ((r, x), o) in r.iter_mut().zip(x).zip(out.0) {
        if o != 0 {
            *r = far(x);
        }
    }
    r
}

/// The backend of [`Lanes`]: the kernels of the [module doc](self), lane by lane.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Lanewise;

impl<const N: usize> Backend<Lanes<f64, N>> for Lanewise {
    #[inline(always)]
    fn sin(x: Lanes<f64, N>) -> Lanes<f64, N> {
        Lanes(reduced_kernel(x.0, sin_core, libm::sin))
    }
    #[inline(always)]
    fn cos(x: Lanes<f64, N>) -> Lanes<f64, N> {
        Lanes(reduced_kernel(x.0, cos_core, libm::cos))
    }
    #[inline(always)]
    fn tan(x: Lanes<f64, N>) -> Lanes<f64, N> {
        Lanes(reduced_kernel(x.0, tan_core, libm::tan))
    }
    #[inline(always)]
    fn atan(x: Lanes<f64, N>) -> Lanes<f64, N> {
        Lanes(map(x.0, atan_lane))
    }
    #[inline(always)]
    fn acos(x: Lanes<f64, N>) -> Lanes<f64, N> {
        Lanes(map(x.0, libm::acos))
    }
    #[inline(always)]
    fn exp(x: Lanes<f64, N>) -> Lanes<f64, N> {
        Lanes(map(x.0, libm::exp))
    }
    #[inline(always)]
    fn ln(x: Lanes<f64, N>) -> Lanes<f64, N> {
        Lanes(map(x.0, libm::log))
    }
    #[inline(always)]
    fn sqrt(x: Lanes<f64, N>) -> Lanes<f64, N> {
        #[cfg(feature = "std")]
        {
            Lanes(map(x.0, f64::sqrt))
        }
        #[cfg(not(feature = "std"))]
        {
            Lanes(map(x.0, libm::sqrt))
        }
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

    /// A deterministic sweep: a uniform grid and an LCG's points.
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

    /// One kernel over lanes of 4 (the last chunk padded with its own first value).
    fn lanes(xs: &[f64], f: fn(Lanes<f64, 4>) -> Lanes<f64, 4>) -> Vec<f64> {
        let mut out = Vec::new();
        for c in xs.chunks(4) {
            let mut a = [c[0]; 4];
            a[..c.len()].copy_from_slice(c);
            out.extend_from_slice(&f(Lanes(a)).0[..c.len()]);
        }
        out
    }

    type B = Lanewise;

    #[test]
    fn atan_within_2_ulp() {
        let mut xs = points(-4.0, 4.0, 200_000);
        for e in -300..=300 {
            for m in [1.0, 1.234_567, 3.3, 7.9] {
                let x = m * 10f64.powi(e);
                xs.push(x);
                xs.push(-x);
            }
        }
        let got = lanes(&xs, <B as Backend<Lanes<f64, 4>>>::atan);
        let worst = xs
            .iter()
            .zip(&got)
            .map(|(&x, &g)| ulps(g, x.atan()))
            .fold(0.0, f64::max);
        assert!(worst < 2.5, "{worst}");
        let special = [f64::INFINITY, f64::NEG_INFINITY, -0.0, f64::NAN];
        let a = <B as Backend<Lanes<f64, 4>>>::atan(Lanes(special)).0;
        assert_eq!(a[0], core::f64::consts::FRAC_PI_2);
        assert_eq!(a[1], -core::f64::consts::FRAC_PI_2);
        assert_eq!(a[2].to_bits(), (-0.0f64).to_bits());
        assert!(a[3].is_nan());
    }

    #[test]
    fn sin_cos_tan_within_budget() {
        let mut xs = points(-8.0, 8.0, 200_000);
        xs.extend(points(-2.0e5, 2.0e5, 50_000));
        xs.extend([1.0e300, -3.0e7, 0.0, -0.0]);
        let s = lanes(&xs, <B as Backend<Lanes<f64, 4>>>::sin);
        let c = lanes(&xs, <B as Backend<Lanes<f64, 4>>>::cos);
        let t = lanes(&xs, <B as Backend<Lanes<f64, 4>>>::tan);
        let (mut ws, mut wc, mut wt, mut abs) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for (i, &x) in xs.iter().enumerate() {
            for (got, want, worst) in [(s[i], x.sin(), &mut ws), (c[i], x.cos(), &mut wc)] {
                if want.abs() >= 1.0 / 1024.0 {
                    *worst = worst.max(ulps(got, want));
                } else {
                    abs = abs.max((got - want).abs() / x.abs().max(1.0));
                }
            }
            let rt = x.tan();
            if rt.abs() >= 1.0 / 1024.0 && rt.abs() <= 1.0e3 {
                wt = wt.max(ulps(t[i], rt));
            }
        }
        assert!(ws <= 2.0 && wc <= 2.0, "{ws} {wc}");
        assert!(wt <= 4.0, "{wt}");
        assert!(abs <= 3e-19, "{abs}");
        let far = <B as Backend<Lanes<f64, 4>>>::sin(Lanes([1.0e300, 0.5, f64::NAN, -0.0])).0;
        assert_eq!(far[0], libm::sin(1.0e300));
        assert_eq!(far[1], libm::sin(0.5));
        assert!(far[2].is_nan());
        assert_eq!(far[3].to_bits(), (-0.0f64).to_bits());
    }

    #[test]
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    fn masks_select_and_flags_are_per_lane() {
        let a = Lanes([1.0, -2.0, 0.0, 5.0]);
        let b = Lanes::<f64, 4>::splat(0.0);
        let m = a.mask_lt(b);
        assert_eq!(m.0, [0, u64::MAX, 0, 0]);
        assert!(m.any() && !m.all());
        assert_eq!(Lanes::select(m, b, a).0, [1.0, 0.0, 0.0, 5.0]);
        assert_eq!(a.sign().0, [1.0, -1.0, 0.0, 1.0]);
        assert_eq!(a.sign_nz().0, [1.0, -1.0, 1.0, 1.0]);
        let (c, f) = a.clamp_flag(Lanes::splat(-1.0), Lanes::splat(2.0));
        assert_eq!(c.0, [1.0, -1.0, 0.0, 2.0]);
        assert_eq!(f.0, [0, u64::MAX, 0, u64::MAX]);
        let mut flags = LaneFlags::<4>::default();
        flags.set_if(Flags::ALPHA, f);
        flags.insert(Flags::REVERSE);
        assert_eq!(
            flags.0.map(|f| f.0),
            [
                Flags::REVERSE.0,
                Flags::REVERSE.0 | Flags::ALPHA.0,
                Flags::REVERSE.0,
                Flags::REVERSE.0 | Flags::ALPHA.0
            ]
        );
        // The operators hold when they hold in every lane.
        assert!(!(a < b) && !(a > b) && a != b);
        assert!(Lanes::<f64, 4>::splat(1.0) > b);
        assert!(!Lanes([1.0, f64::NAN, 0.0, 0.0]).is_finite());
    }
}
