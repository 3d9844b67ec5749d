//! `Fast`: pure-`f32` minimax kernels for the Magic Formula on an FPU microcontroller (feature
//! `fast`).
//!
//! `libm`'s single-precision `sinf`, `cosf`, `tanf`, `atanf`, `expf`, `logf` compute through
//! `f64` or long tables; on a Cortex-M4F (single-precision FPU only) the `f64` part is soft float.
//! These kernels stay in `f32`: a Cody–Waite argument reduction, then a low-degree polynomial
//! whose coefficients are our own minimax (Remez) fits, made by `tools/minimax.py` (the script
//! prints every constant below with its bit pattern; rerun it to check them). Each kernel:
//! the special cases (NaN, ±0, ±∞, domain ends), the reduction, the polynomial. sin, cos, tan
//! and atan take the Magic Formula's arguments (|x| ≤ 8, |α| < π/4, any atan) on a path with one
//! comparison (sin: two, for −0): there the special cases either cannot occur or come out right
//! through the polynomial, and the others are caught on the long path — the same results, bit for
//! bit, as testing them first (compared once on all 2³² inputs when the paths were reordered,
//! with a scratch program outside the repository; the tests here check accuracy and the special
//! cases).
//!
//! | kernel | reduction | polynomial | max error (measured by the tests in each file) |
//! |---|---|---|---|
//! | [`sin`], [`cos`] | x = k·π/2 + r, \|r\| ≤ π/4: 2-part π/2 up to \|x\| = 8, 4-part beyond | odd deg 7 / even deg 6 | 2.1e-7 rel. (\|x\| ≤ 2π; 2.3e-7 up to 1e5) where \|y\| ≥ 2⁻¹⁰, 5.5e-11 abs. below |
//! | [`tan`] | as sin; odd k: −1/tan r | odd deg 11 | 4.0e-7 rel. (\|x\| ≤ 2π, poles' neighbours included) |
//! | [`atan`] | 1/x above tan 3π/8, (x−1)/(x+1) above tan π/8 | odd deg 9 | 2.1e-7 rel., all x |
//! | [`acos`] | asin(√((1−\|x\|)/2)) above \|x\| = ½ | odd deg 9 (asin) | 2.1e-7 rel. on \[−1, 1\] |
//! | [`exp`] | x = k·ln 2 + r, 2-part ln 2 | 1 + r + r²·P₃(r) | 1.9e-7 rel. on \[−87.3, 88.7\]; subnormal results ±2⁻¹⁴⁹ |
//! | [`ln`] | x = 2ᵏ·m, m ∈ \[√½, √2), s = (m−1)/(m+1) | 2s + s³·P₁(s²) | 3.6e-7 rel. where \|y\| ≥ 2⁻¹⁰, 1.4e-10 abs. below; subnormal x included |
//! | [`sqrt`] | — | `vsqrt.f32` on an Arm FPU, else `libm::sqrtf` | correctly rounded |
//!
//! All within the 2e-6 of issue 7. The figures are printed by
//! `cargo test -p gough --features fast --lib math::fast -- --nocapture` (each sweep prints its
//! maximum; sweeps of 1–2 million points plus ulp-by-ulp walks where the reductions switch) and
//! are asserted with a small margin.
//! "rel." is |y − y₆₄|/|y₆₄| against `f64` std at the same `f32` input; where the true value is
//! near zero only the absolute error is meaningful (e.g. cos near π/2, where the reduction
//! error, not the polynomial, dominates), and the table gives both.
//!
//! Outside the ranges above, the kernels stay *sane*: finite and bounded for finite input
//! (sin/cos in \[−1, 1\] for any finite x even where the reduction is no longer exact, |x| > 1e5;
//! tan finite; exp overflows to +∞ only above ln(f32::MAX), as it must). Which ranges the Magic
//! Formula uses: atan of any real (B·x grows with slip), sin/cos of C·atan(·) (|·| < C·π/2 ≤ 2π),
//! of α, γ and π·Vx/VXLOW; tan of |α| < π/2; acos on \[−1, 1\]; exp of small arguments
//! (PKX3·dfz, q·ln x); ln of Fz/Fz0 and p/p0 (positive, O(1)); sqrt of non-negatives.
//!
//! For `f64`, `Fast` delegates to [`Libm`](super::Libm): the host has a double-precision FPU and
//! the `f64` path is the accuracy reference, so nothing is gained by approximating there.

mod acos;
mod atan;
mod exp;
mod ln;
mod sqrt;
mod trig;

pub use acos::acos;
pub use atan::atan;
pub use exp::exp;
pub use ln::ln;
pub use sqrt::sqrt;
pub use trig::{cos, sin, sin_cos, tan};

/// The fast pure-`f32` backend (see the [module doc](self) for methods and measured errors).
///
/// `mf::eval::<f32, Fast>` runs the Magic Formula on these kernels; `mf::eval::<f64, Fast>` is the
/// same as with [`Libm`](super::Libm).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Fast;

// The kernels above, by name (and sin, cos with one reduction for dual numbers).
impl crate::math::Backend<f32> for Fast {
    #[inline]
    fn sin(x: f32) -> f32 {
        sin(x)
    }
    #[inline]
    fn cos(x: f32) -> f32 {
        cos(x)
    }
    #[inline]
    fn tan(x: f32) -> f32 {
        tan(x)
    }
    #[inline]
    fn atan(x: f32) -> f32 {
        atan(x)
    }
    #[inline]
    fn acos(x: f32) -> f32 {
        acos(x)
    }
    #[inline]
    fn exp(x: f32) -> f32 {
        exp(x)
    }
    #[inline]
    fn ln(x: f32) -> f32 {
        ln(x)
    }
    #[inline]
    fn sqrt(x: f32) -> f32 {
        sqrt(x)
    }
    #[inline]
    fn sin_cos(x: f32) -> (f32, f32) {
        sin_cos(x)
    }
}

// `f64`: delegates each kernel to `Libm` (see the module doc).
crate::math::f64_via_libm!(Fast);
