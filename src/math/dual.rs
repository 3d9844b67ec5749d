//! Forward-mode dual numbers: a value and its partial derivatives along `N` directions,
//! carried through the same generic Magic Formula code as `f32`/`f64`.
//!
//! [`Dual<F, N>`] implements [`Float`], and every backend `M: Backend<F>` is also a
//! `Backend<Dual<F, N>>` (each kernel's value is `M`'s, its derivative the kernel's analytic
//! derivative evaluated with `M`): so `mf`'s slip stage, instantiated with `Dual<f32, 2>`,
//! gives Fx, Fy, Mz and their derivatives in κ and α with nothing written twice.
//!
//! Comparisons (`<`, `==`, `sign`, the clamps) look at the value only: at a kink (a sign
//! switch, a clip) the derivative is the one-sided derivative of the branch taken, and a clipped
//! value is a constant (derivative 0). √ at 0 and acos at ±1, whose derivatives are infinite,
//! get the derivative 0 (their callers' kinks): never NaN from finite input.

use super::{Backend, Float, Lift, Real};
use core::cmp::Ordering;
use core::ops::{Add, AddAssign, Div, Mul, MulAssign, Neg, Sub, SubAssign};

/// x + Σ dᵢ·εᵢ with εᵢ·εⱼ = 0: a value and its derivatives along `N` directions.
#[derive(Debug, Clone, Copy)]
pub struct Dual<F, const N: usize> {
    /// The value.
    pub v: F,
    /// ∂/∂ of each direction.
    pub d: [F; N],
}

impl<F: Float, const N: usize> Dual<F, N> {
    /// A constant (all derivatives 0).
    #[inline]
    pub fn cst(v: F) -> Self {
        Dual { v, d: [F::ZERO; N] }
    }
    /// The variable of direction `i`: value `v`, derivative 1 along `i` (0 along the others;
    /// `i ≥ N` gives a constant).
    #[inline]
    pub fn var(v: F, i: usize) -> Self {
        let mut d = [F::ZERO; N];
        if let Some(x) = d.get_mut(i) {
            *x = F::ONE;
        }
        Dual { v, d }
    }
    /// ∂/∂ direction `i` (0 for `i ≥ N`).
    #[inline]
    pub fn der(&self, i: usize) -> F {
        self.d.get(i).copied().unwrap_or(F::ZERO)
    }
    /// f(x) with f(x.v) = `v` and f'(x.v) = `slope`: the chain rule.
    #[inline]
    fn chain(self, v: F, slope: F) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x *= slope;
        }
        Dual { v, d }
    }
}

impl<F: Float, const N: usize> Default for Dual<F, N> {
    fn default() -> Self {
        Self::cst(F::ZERO)
    }
}

impl<F: Float, const N: usize> PartialEq for Dual<F, N> {
    /// Compares the values (the branches of the code depend on values only).
    fn eq(&self, other: &Self) -> bool {
        self.v == other.v
    }
}

impl<F: Float, const N: usize> PartialOrd for Dual<F, N> {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        self.v.partial_cmp(&other.v)
    }
}

impl<F: Float, const N: usize> Add for Dual<F, N> {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        let mut d = self.d;
        for (x, y) in d.iter_mut().zip(o.d.iter()) {
            *x += *y;
        }
        Dual { v: self.v + o.v, d }
    }
}

impl<F: Float, const N: usize> Sub for Dual<F, N> {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        let mut d = self.d;
        for (x, y) in d.iter_mut().zip(o.d.iter()) {
            *x -= *y;
        }
        Dual { v: self.v - o.v, d }
    }
}

impl<F: Float, const N: usize> Mul for Dual<F, N> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        let mut d = self.d;
        for (x, y) in d.iter_mut().zip(o.d.iter()) {
            *x = *x * o.v + self.v * *y;
        }
        Dual { v: self.v * o.v, d }
    }
}

impl<F: Float, const N: usize> Div for Dual<F, N> {
    type Output = Self;
    #[inline]
    fn div(self, o: Self) -> Self {
        let q = self.v / o.v;
        let mut d = self.d;
        for (x, y) in d.iter_mut().zip(o.d.iter()) {
            *x = (*x - q * *y) / o.v;
        }
        Dual { v: q, d }
    }
}

impl<F: Float, const N: usize> Neg for Dual<F, N> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x = -*x;
        }
        Dual { v: -self.v, d }
    }
}

impl<F: Float, const N: usize> AddAssign for Dual<F, N> {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl<F: Float, const N: usize> SubAssign for Dual<F, N> {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}
impl<F: Float, const N: usize> MulAssign for Dual<F, N> {
    #[inline]
    fn mul_assign(&mut self, o: Self) {
        *self = *self * o;
    }
}

impl<F: Float, const N: usize> Real for Dual<F, N> {
    type Mask = F::Mask;
    type Flags = F::Flags;
    /// Compares the values (the derivatives do not order).
    #[inline(always)]
    fn mask_lt(self, o: Self) -> F::Mask {
        self.v.mask_lt(o.v)
    }
    #[inline(always)]
    fn mask_le(self, o: Self) -> F::Mask {
        self.v.mask_le(o.v)
    }
    #[inline(always)]
    fn mask_eq(self, o: Self) -> F::Mask {
        self.v.mask_eq(o.v)
    }
    #[inline(always)]
    fn select(m: F::Mask, a: Self, b: Self) -> Self {
        let mut d = b.d;
        for (x, y) in d.iter_mut().zip(a.d) {
            *x = F::select(m, y, *x);
        }
        Dual {
            v: F::select(m, a.v, b.v),
            d,
        }
    }
    const ZERO: Self = Dual {
        v: F::ZERO,
        d: [F::ZERO; N],
    };
    const ONE: Self = Dual {
        v: F::ONE,
        d: [F::ZERO; N],
    };
    const TWO: Self = Dual {
        v: F::TWO,
        d: [F::ZERO; N],
    };
    const HALF: Self = Dual {
        v: F::HALF,
        d: [F::ZERO; N],
    };
    const PI: Self = Dual {
        v: F::PI,
        d: [F::ZERO; N],
    };
    const FRAC_PI_2: Self = Dual {
        v: F::FRAC_PI_2,
        d: [F::ZERO; N],
    };
    const FRAC_2_PI: Self = Dual {
        v: F::FRAC_2_PI,
        d: [F::ZERO; N],
    };
    #[inline]
    fn from_f64(x: f64) -> Self {
        Self::cst(F::from_f64(x))
    }
    #[inline]
    fn abs(self) -> Self {
        if self.v < F::ZERO {
            -self
        } else {
            self
        }
    }
    #[inline]
    fn is_finite(self) -> bool {
        self.v.is_finite() && F::all_finite(&self.d)
    }
    /// Every value and derivative finite, without a branch per element (`F`'s own
    /// [`Real::all_finite`] on each derivative array).
    #[inline]
    fn all_finite(xs: &[Self]) -> bool {
        xs.iter()
            .fold(true, |ok, x| ok & x.v.is_finite() & F::all_finite(&x.d))
    }
    #[inline]
    fn sign(self) -> Self {
        Self::cst(self.v.sign())
    }
    #[inline]
    fn sign_nz(self) -> Self {
        Self::cst(self.v.sign_nz())
    }
}

impl<F: Float, const N: usize> Float for Dual<F, N> {
    #[inline]
    fn to_f64(self) -> f64 {
        self.v.to_f64()
    }
    #[inline]
    fn floor_index(self, max: usize) -> usize {
        self.v.floor_index(max)
    }
    #[inline]
    fn from_index(i: u16) -> Self {
        Self::cst(F::from_index(i))
    }
}

impl<F: Float, const N: usize> Lift<F> for Dual<F, N> {
    #[inline]
    fn lift(x: F) -> Self {
        Self::cst(x)
    }
    #[inline]
    fn value(self) -> F {
        self.v
    }
}

// Mixed operations with a constant `F` (derivative 0): the derivative lanes are scaled or
// kept, never multiplied by the constant's zero lanes.
impl<F: Float, const N: usize> Add<F> for Dual<F, N> {
    type Output = Self;
    #[inline]
    fn add(self, c: F) -> Self {
        Dual {
            v: self.v + c,
            d: self.d,
        }
    }
}

impl<F: Float, const N: usize> Sub<F> for Dual<F, N> {
    type Output = Self;
    #[inline]
    fn sub(self, c: F) -> Self {
        Dual {
            v: self.v - c,
            d: self.d,
        }
    }
}

impl<F: Float, const N: usize> Mul<F> for Dual<F, N> {
    type Output = Self;
    #[inline]
    fn mul(self, c: F) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x *= c;
        }
        Dual { v: self.v * c, d }
    }
}

impl<F: Float, const N: usize> Div<F> for Dual<F, N> {
    type Output = Self;
    #[inline]
    fn div(self, c: F) -> Self {
        let mut d = self.d;
        for x in d.iter_mut() {
            *x = *x / c;
        }
        Dual { v: self.v / c, d }
    }
}

/// Every backend of `F` is a backend of `Dual<F, N>`: the value from `M`'s kernel, the
/// derivative from the kernel's analytic derivative (with `M`'s kernels).
impl<F: Float, M: Backend<F>, const N: usize> Backend<Dual<F, N>> for M {
    #[inline]
    fn sin(x: Dual<F, N>) -> Dual<F, N> {
        let (s, c) = M::sin_cos(x.v);
        x.chain(s, c)
    }
    #[inline]
    fn cos(x: Dual<F, N>) -> Dual<F, N> {
        let (s, c) = M::sin_cos(x.v);
        x.chain(c, -s)
    }
    #[inline]
    fn tan(x: Dual<F, N>) -> Dual<F, N> {
        let t = M::tan(x.v);
        x.chain(t, F::ONE + t * t)
    }
    #[inline]
    fn atan(x: Dual<F, N>) -> Dual<F, N> {
        x.chain(M::atan(x.v), F::ONE / (F::ONE + x.v * x.v))
    }
    #[inline]
    fn acos(x: Dual<F, N>) -> Dual<F, N> {
        let r = F::ONE - x.v * x.v;
        let slope = if r > F::ZERO {
            -F::ONE / M::sqrt(r)
        } else {
            F::ZERO
        };
        x.chain(M::acos(x.v), slope)
    }
    #[inline]
    fn exp(x: Dual<F, N>) -> Dual<F, N> {
        let e = M::exp(x.v);
        x.chain(e, e)
    }
    #[inline]
    fn ln(x: Dual<F, N>) -> Dual<F, N> {
        let slope = if x.v > F::ZERO { F::ONE / x.v } else { F::ZERO };
        x.chain(M::ln(x.v), slope)
    }
    #[inline]
    fn sqrt(x: Dual<F, N>) -> Dual<F, N> {
        let s = M::sqrt(x.v);
        let slope = if s > F::ZERO { F::HALF / s } else { F::ZERO };
        x.chain(s, slope)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Libm;

    type D = Dual<f64, 2>;

    /// Each kernel's derivative equals a central difference of the kernel.
    #[test]
    fn kernels_differentiate() {
        let h = 1e-6;
        let check = |f: fn(D) -> D, g: fn(f64) -> f64, x: f64| {
            let y = f(D::var(x, 0));
            let fd = (g(x + h) - g(x - h)) / (2.0 * h);
            assert_eq!(y.v, g(x));
            assert!(
                (y.der(0) - fd).abs() < 1e-6 * fd.abs().max(1.0),
                "{x}: {} vs {fd}",
                y.der(0)
            );
            assert_eq!(y.der(1), 0.0);
        };
        for x in [0.1, 0.4, 0.9, 1.7] {
            check(<Libm as Backend<D>>::sin, libm::sin, x);
            check(<Libm as Backend<D>>::cos, libm::cos, x);
            check(<Libm as Backend<D>>::tan, libm::tan, x * 0.5);
            check(<Libm as Backend<D>>::atan, libm::atan, x);
            check(<Libm as Backend<D>>::acos, libm::acos, x * 0.5);
            check(<Libm as Backend<D>>::exp, libm::exp, x);
            check(<Libm as Backend<D>>::ln, libm::log, x);
            check(<Libm as Backend<D>>::sqrt, libm::sqrt, x);
        }
    }

    /// Product and quotient rules along two directions.
    #[test]
    fn arithmetic() {
        let x = D::var(3.0, 0);
        let y = D::var(2.0, 1);
        let z = (x * y - x / y + -x) * D::cst(2.0);
        assert_eq!(z.v, 2.0 * (6.0 - 1.5 - 3.0));
        assert!((z.der(0) - 2.0 * (2.0 - 0.5 - 1.0)).abs() < 1e-15);
        assert!((z.der(1) - 2.0 * (3.0 + 3.0 / 4.0)).abs() < 1e-15);
        assert_eq!(z.der(5), 0.0);
    }

    /// √ at 0 has the derivative 0, not ∞ (its callers' kink), and comparisons look at values.
    #[test]
    fn kinks_stay_finite() {
        let s = <Libm as Backend<D>>::sqrt(D::var(0.0, 0));
        assert!(s.is_finite() && s.der(0) == 0.0);
        assert!(D::var(1.0, 0) == D::cst(1.0));
        assert!(D::var(-1.0, 1).abs().der(1) == -1.0);
        assert!(!D::var(f64::NAN, 0).is_finite());
    }
}
