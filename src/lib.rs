//! # gough — Pacejka tyre models and road-friction estimation for ABS/ESC microcontrollers
//!
//! `no_std`, no heap, generic over `f32` (device) and `f64` (host).
//!
//! ## Conventions (stated once, used everywhere)
//! - **Units**: SI — N, N·m, m, rad, Pa, s. Angles are radians in every API, file and message.
//! - **Axes**: ISO-W (TYDEX W) at the contact point, as in TNO/ADAMS `.tir` files: x forward
//!   along the wheel heading, z up, y to the left. With ISO-W a positive slip angle α gives a
//!   negative lateral force Fy and (below the peak) a positive aligning torque Mz; a positive
//!   longitudinal slip κ (driving) gives a positive Fx. κ = −1 is a locked wheel.
//! - **Names** follow the paper (H. B. Pacejka, *The tyre as a vehicle component*, 1996) and the
//!   MF 6.1 references, spelled out in snake_case: `fz0_prime`, `dfz`, `k_ya`, `mu_y`, `b_y`.
//!
//! ## Modules
//! - [`math`] — the float trait and the math backend ([`math::Libm`] by default).
//! - [`mf`] — the Magic Formula: Delft Tyre 96, MF 5.2, MF 6.1/6.2; pure and combined slip.
//! - [`tir`] — `.tir` text → [`mf::Params`], without allocation.
//! - [`proto`] — the CAN protocol: messages (postcard), segmentation, CRC, SLCAN, DBC; the wire
//!   only (the messages convert to and from the domain's types).
//! - [`relax`] — transient slip through relaxation lengths, paper eqs. (19)–(21).
//! - [`mu`] — the road-friction estimator ([`mu::bank`]: μ from Fy, Mz, Fz and, when given, Fx,
//!   κ, Vx, γ — never α).
//! - [`wheel`] — a car's wheels: their positions ([`wheel::Wheel`]), each one's per-sample
//!   pipeline ([`wheel::Corner`]: transient filter → Magic Formula → estimator) and the four of
//!   a [`wheel::Car`], as the firmware runs them.
//!
//! ## Guarantees
//! The core never panics (no `unwrap`, no unchecked indexing; see the crate-level lints) and
//! never returns NaN for finite input: non-finite input is an error value, and every input that
//! was clipped or regularised is flagged in the result.
#![no_std]
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

#[cfg(any(test, feature = "std"))]
extern crate std;

#[cfg(feature = "fixed")]
pub mod fixed;
pub mod math;
pub mod mf;
pub mod mu;
pub mod proto;
pub mod relax;
pub mod tir;
pub mod wheel;
