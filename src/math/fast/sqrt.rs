//! √x in `f32`: the FPU's `vsqrt.f32` on bare-metal Arm with a hard-float FPU, `libm::sqrtf`
//! elsewhere (an arch version and a generic fallback, always both — as `libm`'s own `sqrtf`).
//!
//! Why not simply `libm::sqrtf`: on `thumbv7em-none-eabihf` it takes the generic path (libm
//! selects an arch version only for x86 SSE2, aarch64 and wasm), a bit-by-bit integer loop,
//! although the Cortex-M4F has `VSQRT.F32` (one instruction, 14 cycles). `f32::sqrt` is not in
//! `core`, and Rust's `asm!` cannot name an `s` register on this target (the `sreg` class needs
//! the `vfp2` feature, which single-precision FPUs do not have and which is unstable to enable),
//! so the instruction sits in a three-instruction leaf function written with `global_asm!`,
//! called through the hard-float ABI (argument and result in `s0`).
//!
//! Both paths are correctly rounded IEEE square roots: √−0 = −0, √+∞ = +∞, √x = NaN for x < 0
//! and for NaN.

#[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
core::arch::global_asm!(
    ".section .text.gough_fast_vsqrtf,\"ax\",%progbits",
    ".globl gough_fast_vsqrtf",
    ".type gough_fast_vsqrtf,%function",
    // The assembler of a module-level block does not always see the target's FPU: name the
    // smallest FPU with VSQRT.F32 that every hard-float Cortex-M has (M4F's; M7 and M33 extend it).
    ".fpu fpv4-sp-d16",
    "gough_fast_vsqrtf:",
    "vsqrt.f32 s0, s0",
    "bx lr",
    ".size gough_fast_vsqrtf, . - gough_fast_vsqrtf",
);

#[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
extern "C" {
    /// `vsqrt.f32 s0, s0; bx lr` (above). AAPCS-VFP: x and the result in `s0`.
    fn gough_fast_vsqrtf(x: f32) -> f32;
}

/// √x; correctly rounded (`VSQRT.F32` on an Arm hard-float target, `libm::sqrtf` elsewhere);
/// √±0 = ±0, √+∞ = +∞, NaN for x < 0 and for NaN.
#[inline]
pub fn sqrt(x: f32) -> f32 {
    #[cfg(all(target_arch = "arm", target_abi = "eabihf", target_os = "none"))]
    {
        // SAFETY: `gough_fast_vsqrtf` is defined above; it reads s0, writes s0 and returns,
        // touching no memory and no callee-saved register, as the hard-float C ABI requires.
        unsafe { gough_fast_vsqrtf(x) }
    }
    #[cfg(not(all(target_arch = "arm", target_abi = "eabihf", target_os = "none")))]
    {
        libm::sqrtf(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::testutil::{logspace, sweep};
    use proptest::prelude::*;

    #[test]
    fn special_cases() {
        assert!(sqrt(f32::NAN).is_nan());
        assert!(sqrt(-1.0).is_nan());
        assert!(sqrt(f32::NEG_INFINITY).is_nan());
        assert_eq!(sqrt(f32::INFINITY), f32::INFINITY);
        assert_eq!(sqrt(0.0).to_bits(), 0.0f32.to_bits());
        assert_eq!(sqrt(-0.0).to_bits(), (-0.0f32).to_bits());
        assert_eq!(sqrt(4.0), 2.0);
        assert_eq!(
            sqrt(f32::from_bits(1)),
            2.0f32.powi(-75) * core::f32::consts::SQRT_2
        );
    }

    #[test]
    fn correctly_rounded() {
        let e = sweep("sqrt", sqrt, f64::sqrt, logspace(1e-45, 3.4e38, 1_000_001));
        assert!(e.rel <= f32::EPSILON as f64 / 2.0, "{e:?}");
    }

    proptest! {
        #[test]
        fn vs_std(x in proptest::num::f32::POSITIVE | proptest::num::f32::ZERO) {
            // Correctly rounded: the f32 nearest to the f64 root.
            prop_assert_eq!(sqrt(x), (x as f64).sqrt() as f32);
        }
    }
}
