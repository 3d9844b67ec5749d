//! The float trait the equations are written against, and the math backends that supply the
//! transcendental kernels.
//!
//! Two traits, kept deliberately small:
//! - [`Real`]: arithmetic, a few constants and the exact (non-transcendental) operations that
//!   the Magic Formula needs (`abs`, `sign`, `min`/`max`, finiteness), and comparisons into
//!   masks with `select` for its value branches. [`Float`] is a `Real` whose masks are `bool`
//!   and whose flags are one `mf::Flags`: `f32` (device) and `f64` (host); [`Lanes`] is `N`
//!   values in lanes (the host's batch, `mf::eval_batch_lanes`).
//! - [`Backend`]: the transcendental kernels the equations call (`sin cos tan atan acos exp ln
//!   sqrt`), one line per function. The *type* chooses the backend:
//!   `mf::eval::<f32, math::Fast>`. Each kernel is listed with the equations that need it.
//!
//! ## Backends
//! Features make a backend available; the type chooses which one runs, so one binary can run
//! them side by side (`host-tests/tests/backends.rs` does, against f64).
//!
//! | backend | feature | f32 kernels | max error (measured; each kernel's doc) |
//! |---|---|---|---|
//! | [`Libm`] | always | the `libm` crate (musl port) | ≤ 1 ulp; the reference |
//! | `Fast` | `fast` | minimax polynomials, pure f32 (`math::fast`) | ≤ 4e-7 relative (issue 7 asks 2e-6) |
//! | `Micromath` | `micromath` | the `micromath` crate, wrapped (`math::micro`) | 1e-3 to 3e-2 absolute, ln 0.12, √ 6 % |
//! | [`Lanewise`] | always | — ([`Lanes`]`<f64, N>` only: fdlibm's sin, cos, tan, atan by masks; exp, ln, acos from `libm` lane by lane) | ≤ 2 ulp (tan 4) |
//!
//! Through the whole Magic Formula (`host-tests/tests/backends.rs`, all oracle sweeps): f32 with
//! `Fast` is as close to f64 as f32 with `Libm` (2e-6·FNOMIN); `Micromath` is 4e-2·FNOMIN off.
//!
//! The fixed-point path (feature `fixed`) implements [`Float`] and [`Backend`] for a fixed-point
//! type in `crate::fixed`.
//!
//! [`Libm`] is the reference backend (the `libm` crate: correctly rounded to within 1 ulp for
//! most functions).

use core::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

pub mod dual;
pub use dual::Dual;

pub mod lanes;
pub use lanes::{LaneFlags, LaneMask, Lanes, Lanewise};

#[cfg(any(feature = "fast", feature = "fixed"))]
pub(crate) mod minimax;

#[cfg(feature = "fast")]
pub mod fast;
#[cfg(feature = "fast")]
pub use fast::Fast;

#[cfg(feature = "micromath")]
pub mod micro;
#[cfg(feature = "micromath")]
pub use micro::Micromath;

#[cfg(all(test, any(feature = "fast", feature = "micromath")))]
pub(crate) mod testutil;

/// A real number as the equations compute with it: one value ([`Float`]: `f32` on the device,
/// `f64` on the host, `fixed::Fix` with the `fixed` feature) or several in lanes ([`Lanes`],
/// the host's batch).
///
/// Only what the equations use. Units are whatever the caller's quantity has.
pub trait Real:
    Copy
    + PartialOrd
    + PartialEq
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + MulAssign
    + core::fmt::Debug
    + Default
{
    /// 0
    const ZERO: Self;
    /// 1
    const ONE: Self;
    /// 2
    const TWO: Self;
    /// 1/2
    const HALF: Self;
    /// π
    const PI: Self;
    /// π/2
    const FRAC_PI_2: Self;
    /// 2/π (the normalisation of `atan` in (4.E44))
    const FRAC_2_PI: Self;

    /// What a comparison of two values gives: `bool` for a scalar, one flag per lane for
    /// [`Lanes`]. The formula's branches on a *value* (a sign, a clip, a guard) compare into a
    /// mask and [`select`](Real::select) or [`choose`]; branches on parameters stay `if`s
    /// (`PartialOrd`, which for lanes holds when it holds in every lane).
    type Mask: Mask;
    /// The flags of an evaluation ([`crate::mf::Flags`]; one set per lane for [`Lanes`]).
    type Flags: crate::mf::FlagSet<Self::Mask>;
    /// `self < o`, per lane.
    fn mask_lt(self, o: Self) -> Self::Mask;
    /// `self <= o`, per lane.
    fn mask_le(self, o: Self) -> Self::Mask;
    /// `self == o`, per lane.
    fn mask_eq(self, o: Self) -> Self::Mask;
    /// `self > o`, per lane.
    #[inline(always)]
    fn mask_gt(self, o: Self) -> Self::Mask {
        o.mask_lt(self)
    }
    /// `self >= o`, per lane.
    #[inline(always)]
    fn mask_ge(self, o: Self) -> Self::Mask {
        o.mask_le(self)
    }
    /// `a` where `m`, else `b` (per lane; for a scalar, `if m { a } else { b }`).
    fn select(m: Self::Mask, a: Self, b: Self) -> Self;
    /// Converts from `f64` (rounding to nearest for `f32`). Used for parameters and constants.
    fn from_f64(x: f64) -> Self;
    /// |x|
    fn abs(self) -> Self;
    /// `true` unless NaN or ±∞ (for `fixed::Fix`: unless saturated).
    fn is_finite(self) -> bool;
    /// `true` when every value [`is_finite`](Real::is_finite). The floats override it with
    /// one comparison for the whole slice (x − x is 0 for every finite x and NaN otherwise, so
    /// their sum is 0 exactly when all are finite) instead of one test and branch per value.
    #[inline]
    fn all_finite(xs: &[Self]) -> bool {
        xs.iter().all(|x| x.is_finite())
    }
    /// The larger of two values; NaN-free inputs assumed (callers check finiteness first).
    #[inline]
    fn max(self, other: Self) -> Self {
        if self > other {
            self
        } else {
            other
        }
    }
    /// The smaller of two values; NaN-free inputs assumed.
    #[inline]
    fn min(self, other: Self) -> Self {
        if self < other {
            self
        } else {
            other
        }
    }
    /// Mathematical sign: −1, 0 or +1 (MATLAB's `sign`, as the MF references use it).
    #[inline]
    fn sign(self) -> Self {
        if self > Self::ZERO {
            Self::ONE
        } else if self < Self::ZERO {
            -Self::ONE
        } else {
            Self::ZERO
        }
    }
    /// Sign that is +1 at zero: the "sign(x) with sign(0) = 1" used by the book's signed
    /// ε-guards ((4.E6a), (4.E16), (4.E26), (4.E39): "explained on page 177").
    #[inline]
    fn sign_nz(self) -> Self {
        if self < Self::ZERO {
            -Self::ONE
        } else {
            Self::ONE
        }
    }
    /// x²
    #[inline]
    fn sq(self) -> Self {
        self * self
    }
    /// Clamps to `[lo, hi]`; returns the value and whether it was changed (per lane).
    #[inline]
    fn clamp_flag(self, lo: Self, hi: Self) -> (Self, Self::Mask) {
        let (below, above) = (self.mask_lt(lo), self.mask_gt(hi));
        (
            Self::select(below, lo, Self::select(above, hi, self)),
            below.or(above),
        )
    }
}

/// One real scalar: `f32` on the device, `f64` on the host (and `fixed::Fix`, Q31.32, with the
/// `fixed` feature). A [`Real`] whose comparisons are `bool`s and whose flags are one
/// [`crate::mf::Flags`], with the conversions the rest of the crate needs.
pub trait Float: Real<Mask = bool, Flags = crate::mf::Flags> {
    /// Converts to `f64` (exact for `f32` and `f64`; `fixed::Fix` rounds beyond 2²¹).
    fn to_f64(self) -> f64;
    /// ⌊x⌋ as an index, clamped to `0..=max` (NaN and negative values give 0): a table cell
    /// from a position along a uniform grid, with no conversion through `f64`.
    fn floor_index(self, max: usize) -> usize;
    /// A small index as a value (exact for `i` < 2¹⁶): a grid position, with no conversion
    /// through `f64`.
    fn from_index(i: u16) -> Self;
    /// `us` microseconds in seconds. The floats divide by 10⁶ in their own precision
    /// (correctly rounded for `us` < 2²⁴ in `f32`, all `u32` in `f64`): no soft `f64` on a
    /// device whose FPU is single precision.
    #[inline]
    fn from_micros(us: u32) -> Self {
        Self::from_f64(f64::from(us) * 1e-6)
    }
}

/// A comparison's result ([`Real::Mask`]): `bool` for one value, a flag per lane for
/// [`Lanes`].
pub trait Mask: Copy + Default + core::fmt::Debug {
    /// `b` in every lane.
    fn splat(b: bool) -> Self;
    /// Every lane set (for `bool`: itself).
    fn all(self) -> bool;
    /// Some lane set (for `bool`: itself).
    fn any(self) -> bool;
    /// Lane-wise and.
    fn and(self, o: Self) -> Self;
    /// Lane-wise or.
    fn or(self, o: Self) -> Self;
    /// Lane-wise not.
    fn not(self) -> Self;
}

impl Mask for bool {
    #[inline(always)]
    fn splat(b: bool) -> bool {
        b
    }
    #[inline(always)]
    fn all(self) -> bool {
        self
    }
    #[inline(always)]
    fn any(self) -> bool {
        self
    }
    #[inline(always)]
    fn and(self, o: bool) -> bool {
        self && o
    }
    #[inline(always)]
    fn or(self, o: bool) -> bool {
        self || o
    }
    #[inline(always)]
    fn not(self) -> bool {
        !self
    }
}

/// `a()` where `m`, `b()` elsewhere: one side alone when every lane agrees (for a scalar,
/// always: `if m { a() } else { b() }`), both sides and a [`Real::select`] when lanes differ.
/// For a value branch whose sides are both finite for finite inputs.
#[inline(always)]
pub fn choose<F: Real>(m: F::Mask, a: impl FnOnce() -> F, b: impl FnOnce() -> F) -> F {
    if m.all() {
        a()
    } else if !m.any() {
        b()
    } else {
        F::select(m, a(), b())
    }
}

macro_rules! impl_float {
    ($t:ty, $pi:expr, $pi2:expr, $f2pi:expr) => {
        impl Real for $t {
            type Mask = bool;
            type Flags = crate::mf::Flags;
            #[inline(always)]
            fn mask_lt(self, o: Self) -> bool {
                self < o
            }
            #[inline(always)]
            fn mask_le(self, o: Self) -> bool {
                self <= o
            }
            #[inline(always)]
            fn mask_eq(self, o: Self) -> bool {
                self == o
            }
            #[inline(always)]
            fn select(m: bool, a: Self, b: Self) -> Self {
                if m {
                    a
                } else {
                    b
                }
            }
            /// The scalar form (an `if` chain), as before lanes existed.
            #[inline]
            fn clamp_flag(self, lo: Self, hi: Self) -> (Self, bool) {
                if self < lo {
                    (lo, true)
                } else if self > hi {
                    (hi, true)
                } else {
                    (self, false)
                }
            }
            const ZERO: Self = 0.0;
            const ONE: Self = 1.0;
            const TWO: Self = 2.0;
            const HALF: Self = 0.5;
            const PI: Self = $pi;
            const FRAC_PI_2: Self = $pi2;
            const FRAC_2_PI: Self = $f2pi;
            #[inline]
            fn from_f64(x: f64) -> Self {
                x as $t
            }
            #[inline]
            fn abs(self) -> Self {
                <$t>::from_bits(self.to_bits() & !(1 << (<$t>::BITS_MINUS_ONE)))
            }
            #[inline]
            fn is_finite(self) -> bool {
                <$t>::is_finite(self)
            }
            #[inline]
            fn all_finite(xs: &[Self]) -> bool {
                let mut acc: $t = 0.0;
                for &x in xs {
                    acc += x - x;
                }
                acc == 0.0
            }
        }
        impl Float for $t {
            #[inline]
            fn to_f64(self) -> f64 {
                self as f64
            }
            #[inline]
            fn floor_index(self, max: usize) -> usize {
                // `as` truncates towards zero (⌊x⌋ for x ≥ 0) and saturates: NaN and x < 0
                // give 0.
                (self as usize).min(max)
            }
            #[inline]
            fn from_index(i: u16) -> Self {
                <$t>::from(i)
            }
            #[inline]
            fn from_micros(us: u32) -> Self {
                us as $t / 1e6
            }
        }
    };
}

trait BitsMinusOne {
    const BITS_MINUS_ONE: u32;
}
impl BitsMinusOne for f32 {
    const BITS_MINUS_ONE: u32 = 31;
}
impl BitsMinusOne for f64 {
    const BITS_MINUS_ONE: u32 = 63;
}

impl_float!(
    f32,
    core::f32::consts::PI,
    core::f32::consts::FRAC_PI_2,
    core::f32::consts::FRAC_2_PI
);
impl_float!(
    f64,
    core::f64::consts::PI,
    core::f64::consts::FRAC_PI_2,
    core::f64::consts::FRAC_2_PI
);

/// A [`Float`] that a value of `F` converts into: `F` itself (the identity, free) and
/// [`Dual<F, N>`] (a constant). The Magic Formula's slip stage reads its load-stage values
/// (stored as `F`) through it, so that one generic body computes in `F` or in dual numbers.
///
/// The mixed operations `Self ∘ F` are what the slip stage uses where one side is a load-stage
/// value: for `F` itself they are `F`'s own; for a dual number they skip the derivative
/// arithmetic of the constant side (x·c is N + 1 products, where lifting c first made
/// 2N + 1 products and N sums).
pub trait Lift<F: Real>:
    Real<Mask = F::Mask, Flags = F::Flags>
    + Add<F, Output = Self>
    + Sub<F, Output = Self>
    + Mul<F, Output = Self>
    + Div<F, Output = Self>
{
    /// `x` as a `Self` (for a dual number: a constant).
    fn lift(x: F) -> Self;
    /// The value of `self` as an `F` (a dual number's value without its derivatives): for a
    /// quantity whose derivative is 0 by construction (a sign, a clipped constant).
    fn value(self) -> F;
}

impl<F: Real> Lift<F> for F {
    #[inline]
    fn lift(x: F) -> F {
        x
    }
    #[inline]
    fn value(self) -> F {
        self
    }
}

/// The transcendental kernels of the Magic Formula, chosen by type.
///
/// Every function takes and returns the same scalar type. Angles in radians.
pub trait Backend<F: Real> {
    /// sin x — the sine Magic Formula (4.E9), (4.E19); turn-slip shifts (4.80).
    fn sin(x: F) -> F;
    /// cos x — the cosine Magic Formula (4.E33), (4.E36), weighting functions (4.E51), (4.E59).
    fn cos(x: F) -> F;
    /// tan x — `alpha_star` (4.E3) and the equivalent slip angles (A54), (A55).
    fn tan(x: F) -> F;
    /// atan x, result in (−π/2, π/2) — every Magic Formula argument.
    fn atan(x: F) -> F;
    /// acos x for x in [−1, 1], result in [0, π] — `alpha_prime` (4.E6).
    fn acos(x: F) -> F;
    /// eˣ — longitudinal slip stiffness (4.E15).
    fn exp(x: F) -> F;
    /// ln x for x > 0 — the powers of rolling resistance (A48) as exp(q·ln x).
    fn ln(x: F) -> F;
    /// √x for x ≥ 0 — equivalent slip angles (A54), (A55), turn slip (4.77).
    fn sqrt(x: F) -> F;
    /// (sin x, cos x), equal to [`Backend::sin`] and [`Backend::cos`] — a dual number's sine or
    /// cosine needs both. A backend may share the argument reduction (`Fast` does).
    #[inline]
    fn sin_cos(x: F) -> (F, F) {
        (Self::sin(x), Self::cos(x))
    }
}

/// Reference backend: the `libm` crate (Rust port of musl's libm).
///
/// Accuracy: within 1 ulp for the functions used here (musl's documentation). On a Cortex-M4F,
/// the single-precision trigonometric functions go through `f64` internally (soft float) and are
/// slow; they are the accuracy reference, not the fast path.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Libm;

/// Implements [`Backend<F>`] for a backend by delegating each kernel to a function of the same
/// signature (`impl_backend!(Type, f32, { sin => path::to::sin, ... })`, or `impl_backend!(Type,
/// f32, in_scope)` for functions named like the kernels where it is invoked); the compiler
/// checks that every kernel of the trait is named.
macro_rules! impl_backend {
    ($backend:ty, $f:ty, in_scope) => {
        $crate::math::impl_backend!($backend, $f, {
            sin => sin,
            cos => cos,
            tan => tan,
            atan => atan,
            acos => acos,
            exp => exp,
            ln => ln,
            sqrt => sqrt,
        });
    };
    ($backend:ty, $f:ty, { $($name:ident => $fun:expr),* $(,)? }) => {
        impl $crate::math::Backend<$f> for $backend {
            $(
                #[inline]
                fn $name(x: $f) -> $f {
                    ($fun)(x)
                }
            )*
        }
    };
}
#[cfg(any(feature = "fast", feature = "micromath"))]
pub(crate) use impl_backend;

/// Implements [`Backend<f64>`] for an `f32` backend by delegating to [`Libm`] (the fast
/// backends have no `f64` kernels of their own).
#[cfg(any(feature = "fast", feature = "micromath"))]
macro_rules! f64_via_libm {
    ($backend:ty) => {
        $crate::math::impl_backend!($backend, f64, {
            sin => <$crate::math::Libm as $crate::math::Backend<f64>>::sin,
            cos => <$crate::math::Libm as $crate::math::Backend<f64>>::cos,
            tan => <$crate::math::Libm as $crate::math::Backend<f64>>::tan,
            atan => <$crate::math::Libm as $crate::math::Backend<f64>>::atan,
            acos => <$crate::math::Libm as $crate::math::Backend<f64>>::acos,
            exp => <$crate::math::Libm as $crate::math::Backend<f64>>::exp,
            ln => <$crate::math::Libm as $crate::math::Backend<f64>>::ln,
            sqrt => <$crate::math::Libm as $crate::math::Backend<f64>>::sqrt,
        });
    };
}
#[cfg(any(feature = "fast", feature = "micromath"))]
pub(crate) use f64_via_libm;

impl_backend!(Libm, f32, {
    sin => libm::sinf,
    cos => libm::cosf,
    tan => libm::tanf,
    atan => libm::atanf,
    acos => libm::acosf,
    exp => libm::expf,
    ln => libm::logf,
    sqrt => libm::sqrtf,
});

impl_backend!(Libm, f64, {
    sin => libm::sin,
    cos => libm::cos,
    tan => libm::tan,
    atan => libm::atan,
    acos => libm::acos,
    exp => libm::exp,
    ln => libm::log,
    sqrt => libm::sqrt,
});

#[cfg(test)]
mod tests {
    use super::*;

    /// `from_micros` in `f32` is the nearest `f32` to us/10⁶ (below 2²⁴ µs), as the doc says;
    /// in `f64` it divides (the host's figures did not move when it replaced `us * 1e-6`).
    #[test]
    fn micros_are_correctly_rounded() {
        let exact = |us: u32| f64::from(us) / 1e6;
        for us in (0..20_000).chain((0..16_777_216).step_by(9_973)) {
            let x = <f32 as Float>::from_micros(us);
            let e = exact(us);
            let err = |y: f32| (f64::from(y) - e).abs();
            for n in [
                f32::from_bits(x.to_bits() + 1),
                f32::from_bits(x.to_bits().saturating_sub(1)),
            ] {
                assert!(
                    err(x) <= err(n),
                    "{us} µs: {x} is not the nearest f32 to {e}"
                );
            }
            assert_eq!(<f64 as Float>::from_micros(us), e);
        }
    }

    #[test]
    fn sign_conventions() {
        assert_eq!(0.0f64.sign(), 0.0);
        assert_eq!((-0.0f64).sign(), 0.0);
        assert_eq!(0.0f64.sign_nz(), 1.0);
        assert_eq!((-2.0f32).sign_nz(), -1.0);
        assert_eq!((-2.5f32).abs(), 2.5);
        assert_eq!((-0.0f64).abs().to_bits(), 0);
    }

    #[test]
    fn clamp_reports() {
        assert_eq!(3.0f64.clamp_flag(0.0, 1.0), (1.0, true));
        assert_eq!(0.5f64.clamp_flag(0.0, 1.0), (0.5, false));
        assert_eq!((-1.0f32).clamp_flag(0.0, 1.0), (0.0, true));
    }

    /// The one-comparison override agrees with a test per value, at the extremes of the range
    /// too (x − x = 0 for ±MAX: no overflow), for f32 and f64.
    #[test]
    fn all_finite_is_every_is_finite() {
        fn check<F: Float>(vals: &[F]) {
            for a in vals {
                for b in vals {
                    let xs = [*a, F::ONE, *b];
                    assert_eq!(
                        F::all_finite(&xs),
                        xs.iter().all(|x| x.is_finite()),
                        "{xs:?}"
                    );
                }
            }
            assert!(F::all_finite(&[]));
        }
        check(&[
            0.0f32,
            -0.0,
            f32::MAX,
            f32::MIN,
            f32::MIN_POSITIVE,
            f32::from_bits(1),
            1e30,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
        ]);
        check(&[
            0.0f64,
            f64::MAX,
            f64::MIN,
            f64::from_bits(1),
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ]);
    }

    #[test]
    fn libm_matches_std() {
        for &x in &[-3.0f64, -0.5, 0.0, 0.25, 1.0, 7.0] {
            assert!((<Libm as Backend<f64>>::atan(x) - x.atan()).abs() < 1e-15);
            assert!((<Libm as Backend<f64>>::sin(x) - x.sin()).abs() < 1e-15);
            assert!((<Libm as Backend<f32>>::cos(x as f32) - (x as f32).cos()).abs() < 1e-6);
        }
    }
}
