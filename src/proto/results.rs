//! Device → host: one wheel's predicted forces ([`Forces`]) and friction estimate
//! ([`Estimate`]), and the four wheels' answer to a batch in scaled integers
//! ([`CompactResults`]).

use super::measurement::count_i16;
use super::Wheel;
use crate::mf::Output;
use crate::mu::{self, State};
use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

/// One wheel's results in a [`CompactResults`]: 12 bytes, fixed-width little endian, in this
/// order.
///
/// | field | type | per count | range | not available |
/// |---|---|---|---|---|
/// | `fx`, `fy` | i16 | 1 N | ±32 767 N | −32 768 |
/// | `mz` | i16 | 0.1 N·m | ±3 276.7 N·m | −32 768 |
/// | `mu`, `sigma` | u16 | 1e-4 | 0 ..= 6.5534 | 65 535 |
/// | `mu_min` | u8 | 0.01, rounded **down** (stays a lower bound) | 0 ..= 2.54 | 255 |
/// | `status` | u8 | bits 0–1 state (0 Identifiable, 1 NotIdentifiable, 2 Fallback, 3 no estimate), bit 2 change, bit 3 MF flags non-zero (an input clipped or regularised), bit 4 wheel present, bit 5 model mismatch ([`Estimate::mismatch`], v4); bits 6–7 are 0 | | |
///
/// "Not available" marks a value the device has not got (no forces: no parameters, no slip or
/// an evaluation error, counted in `Status::eval_errors`; no estimate: μ, σ, μ_min) or cannot
/// represent (out of range or not finite): the device sends it rather than a clamped value
/// ([`CompactWheelResult::or_na`]). [`CompactWheelResult::new`] refuses such values instead.
#[derive(Serialize, Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CompactWheelResult {
    /// Predicted Fx \[N\] or [`CompactWheelResult::NA_I16`].
    #[serde(with = "postcard::fixint::le")]
    pub fx: i16,
    /// Predicted Fy \[N\] or not available.
    #[serde(with = "postcard::fixint::le")]
    pub fy: i16,
    /// Predicted Mz \[0.1 N·m\] or not available.
    #[serde(with = "postcard::fixint::le")]
    pub mz: i16,
    /// μ \[1e-4\] or [`CompactWheelResult::NA_U16`].
    #[serde(with = "postcard::fixint::le")]
    pub mu: u16,
    /// σ of μ \[1e-4\] or not available.
    #[serde(with = "postcard::fixint::le")]
    pub sigma: u16,
    /// μ_min \[0.01\], rounded down, or [`CompactWheelResult::NA_U8`].
    pub mu_min: u8,
    /// State (bits 0–1), change (bit 2), MF flags non-zero (bit 3), present (bit 4), mismatch
    /// (bit 5).
    pub status: u8,
}

impl MaxSize for CompactWheelResult {
    const POSTCARD_MAX_SIZE: usize = 12;
}

/// `x / unit` rounded, if finite and in `0 ..= u16::MAX − 1`.
fn count_u16(x: f32, unit: f32) -> Option<u16> {
    let c = libm::roundf(x / unit);
    (c.is_finite() && c >= 0.0 && c < f32::from(u16::MAX)).then_some(c as u16)
}

/// `x / unit` rounded down, if finite and in `0 ..= u8::MAX − 1`.
fn count_u8_floor(x: f32, unit: f32) -> Option<u8> {
    // A small tolerance so that 0.3 (0.29999…/0.01 = 29.99…) is 30, not 29.
    let c = libm::floorf(x / unit + 1e-3);
    (c.is_finite() && c >= 0.0 && c < f32::from(u8::MAX)).then_some(c as u8)
}

impl CompactWheelResult {
    /// Not available (i16 fields).
    pub const NA_I16: i16 = i16::MIN;
    /// Not available (u16 fields).
    pub const NA_U16: u16 = u16::MAX;
    /// Not available (u8 fields).
    pub const NA_U8: u8 = u8::MAX;
    /// Fx, Fy per count \[N\].
    pub const F: f32 = 1.0;
    /// Mz per count \[N·m\].
    pub const MZ: f32 = 0.1;
    /// μ, σ per count.
    pub const MU: f32 = 1e-4;
    /// μ_min per count.
    pub const MU_MIN: f32 = 0.01;
    /// Status: the state bits.
    pub const STATE_MASK: u8 = 0b11;
    /// Status state value: no estimate.
    pub const NO_ESTIMATE: u8 = 3;
    /// Status: change of surface.
    pub const CHANGE: u8 = 1 << 2;
    /// Status: the Magic Formula clipped or regularised an input (`Forces::flags` ≠ 0).
    pub const MF_FLAGS: u8 = 1 << 3;
    /// Status: the wheel is present.
    pub const PRESENT: u8 = 1 << 4;
    /// Status: the calibrated model does not explain the data ([`Estimate::mismatch`]).
    pub const MISMATCH: u8 = 1 << 5;

    fn status(forces: Option<&Forces>, estimate: Option<&Estimate>) -> u8 {
        let state = estimate.map_or(Self::NO_ESTIMATE, |e| e.state as u8);
        let change = if estimate.is_some_and(|e| e.change) {
            Self::CHANGE
        } else {
            0
        };
        let flags = if forces.is_some_and(|f| f.flags != 0) {
            Self::MF_FLAGS
        } else {
            0
        };
        let mismatch = if estimate.is_some_and(|e| e.mismatch) {
            Self::MISMATCH
        } else {
            0
        };
        Self::PRESENT | state | change | flags | mismatch
    }

    /// A present wheel's results, or `None` when a value is out of range or not finite (no
    /// clamp). Absent forces or estimate are sent as not available.
    pub fn new(forces: Option<&Forces>, estimate: Option<&Estimate>) -> Option<Self> {
        let (fx, fy, mz) = match forces {
            None => (Self::NA_I16, Self::NA_I16, Self::NA_I16),
            Some(f) => (
                count_i16(f.fx, Self::F)?,
                count_i16(f.fy, Self::F)?,
                count_i16(f.mz, Self::MZ)?,
            ),
        };
        let (mu, sigma, mu_min) = match estimate {
            None => (Self::NA_U16, Self::NA_U16, Self::NA_U8),
            Some(e) => (
                count_u16(e.mu, Self::MU)?,
                count_u16(e.sigma, Self::MU)?,
                count_u8_floor(e.mu_min, Self::MU_MIN)?,
            ),
        };
        Some(CompactWheelResult {
            fx,
            fy,
            mz,
            mu,
            sigma,
            mu_min,
            status: Self::status(forces, estimate),
        })
    }

    /// What the device sends: as [`CompactWheelResult::new`], but each value it cannot
    /// represent (out of range or not finite) is sent as not available, never clamped.
    pub fn or_na(forces: Option<&Forces>, estimate: Option<&Estimate>) -> Self {
        let i = |x: Option<f32>, unit| x.and_then(|v| count_i16(v, unit)).unwrap_or(Self::NA_I16);
        let u = |x: Option<f32>| {
            x.and_then(|v| count_u16(v, Self::MU))
                .unwrap_or(Self::NA_U16)
        };
        CompactWheelResult {
            fx: i(forces.map(|f| f.fx), Self::F),
            fy: i(forces.map(|f| f.fy), Self::F),
            mz: i(forces.map(|f| f.mz), Self::MZ),
            mu: u(estimate.map(|e| e.mu)),
            sigma: u(estimate.map(|e| e.sigma)),
            mu_min: estimate
                .and_then(|e| count_u8_floor(e.mu_min, Self::MU_MIN))
                .unwrap_or(Self::NA_U8),
            status: Self::status(forces, estimate),
        }
    }

    /// Whether the wheel is present.
    pub fn present(&self) -> bool {
        self.status & Self::PRESENT != 0
    }
    /// Fx \[N\], if available.
    pub fn fx(&self) -> Option<f32> {
        (self.fx != Self::NA_I16).then(|| f32::from(self.fx) * Self::F)
    }
    /// Fy \[N\], if available.
    pub fn fy(&self) -> Option<f32> {
        (self.fy != Self::NA_I16).then(|| f32::from(self.fy) * Self::F)
    }
    /// Mz \[N·m\], if available.
    pub fn mz(&self) -> Option<f32> {
        (self.mz != Self::NA_I16).then(|| f32::from(self.mz) * Self::MZ)
    }
    /// μ, if available.
    pub fn mu(&self) -> Option<f32> {
        (self.mu != Self::NA_U16).then(|| f32::from(self.mu) * Self::MU)
    }
    /// σ, if available.
    pub fn sigma(&self) -> Option<f32> {
        (self.sigma != Self::NA_U16).then(|| f32::from(self.sigma) * Self::MU)
    }
    /// μ_min, if available.
    pub fn mu_min(&self) -> Option<f32> {
        (self.mu_min != Self::NA_U8).then(|| f32::from(self.mu_min) * Self::MU_MIN)
    }
    /// The estimate's state (`None`: no estimate).
    pub fn state(&self) -> Option<State> {
        match self.status & Self::STATE_MASK {
            0 => Some(State::Identifiable),
            1 => Some(State::NotIdentifiable),
            2 => Some(State::Fallback),
            _ => None,
        }
    }
    /// The change-of-surface flag.
    pub fn change(&self) -> bool {
        self.status & Self::CHANGE != 0
    }
    /// The model-mismatch flag.
    pub fn mismatch(&self) -> bool {
        self.status & Self::MISMATCH != 0
    }
}

/// The four wheels' results answering one [`CompactBatch`](super::CompactBatch) (type 0x85, identifier
/// [`super::id::BATCH_RESULT`]): 52 body bytes, 58 encoded, one 64-byte CAN FD frame (10
/// classic frames). Instead of a [`Forces`] and an [`Estimate`] per wheel.
///
/// | bytes | field | meaning |
/// |---|---|---|
/// | 0..4 | `t_us` | u32 LE: the batch's sample time \[µs\] |
/// | 4 + 12 i .. | `wheels[i]` | [`CompactWheelResult`] of wheel i (0 FL, 1 FR, 2 RL, 3 RR): Fx, Fy i16 \[N\], Mz i16 \[0.1 N·m\], μ, σ u16 \[1e-4\], μ_min u8 \[0.01, rounded down\], status u8 |
///
/// A wheel not in the batch is all zeros (status bit 4 clear). `Forces::flags` are reduced to
/// one bit (status bit 3).
#[derive(Serialize, Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CompactResults {
    /// The batch's sample time \[µs\].
    #[serde(with = "postcard::fixint::le")]
    pub t_us: u32,
    /// The wheels, by index.
    pub wheels: [CompactWheelResult; 4],
}

impl MaxSize for CompactResults {
    const POSTCARD_MAX_SIZE: usize = 4 + 4 * CompactWheelResult::POSTCARD_MAX_SIZE;
}

/// Predicted steady-state forces of one wheel, from the Magic Formula at the sample's Fz and
/// the α, κ, γ it carried.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Forces {
    /// The wheel.
    pub wheel: Wheel,
    /// Time of the sample this answers \[µs\].
    #[serde(with = "postcard::fixint::le")]
    pub t_us: u32,
    /// Longitudinal force Fx \[N\], ISO-W.
    pub fx: f32,
    /// Lateral force Fy \[N\], ISO-W.
    pub fy: f32,
    /// Aligning moment Mz \[N·m\], ISO-W.
    pub mz: f32,
    /// `mf::Flags` bits: what was clipped or regularised.
    #[serde(with = "postcard::fixint::le")]
    pub flags: u16,
}

impl Forces {
    /// The forces of wheel `wheel` at sample time `t_us`: Fx, Fy, Mz and the flags of a Magic
    /// Formula evaluation.
    pub fn new(wheel: Wheel, t_us: u32, o: &Output<f32>) -> Forces {
        Forces {
            wheel,
            t_us,
            fx: o.fx,
            fy: o.fy,
            mz: o.mz,
            flags: o.flags.0,
        }
    }
}

/// Road friction estimate of one wheel, sent after each measurement once the estimator runs.
///
/// Fields after `state` were added in protocol v2 (`mu_min`, `change`) and v4 (`mismatch`).
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Estimate {
    /// The wheel.
    pub wheel: Wheel,
    /// Time of the sample the estimate includes \[µs\].
    #[serde(with = "postcard::fixint::le")]
    pub t_us: u32,
    /// Peak friction μ \[-\], on the scale of the `.tir` file's surface.
    pub mu: f32,
    /// Standard deviation of μ \[-\] by the estimator's own account (the confidence).
    pub sigma: f32,
    /// How to read μ (the estimator's [`State`], one byte: 0, 1, 2); in `Fallback` μ is the
    /// prior [`Settings::fallback_mu`](super::Settings::fallback_mu).
    pub state: State,
    /// The lowest μ \[-\] the evidence has not excluded: a lower bound on the road's friction a
    /// controller may rely on in any state (the lowest hypothesis, 0.1, when nothing is
    /// excluded).
    pub mu_min: f32,
    /// Change of surface: set on the one estimate at which the estimator declared it (an
    /// identifiable μ that moved by more than 0.1 + 2σ from the last identifiable value, the
    /// bank's `change_min`); clear on every other. It is not repeated: a receiver that misses
    /// that one estimate sees the new μ only.
    pub change: bool,
    /// The calibrated model does not explain the data (the estimator's mismatch indication,
    /// [`crate::mu::Estimate::mismatch`]): read μ with care, the tyre is not what the
    /// calibration says. Protocol v4.
    pub mismatch: bool,
}

impl Estimate {
    /// The estimate `e` of wheel `wheel` after the sample of time `t_us`.
    pub fn new(wheel: Wheel, t_us: u32, e: &mu::Estimate<f32>) -> Estimate {
        Estimate {
            wheel,
            t_us,
            mu: e.mu,
            sigma: e.sigma,
            state: e.state,
            mu_min: e.mu_min,
            change: e.change,
            mismatch: e.mismatch,
        }
    }

    /// The estimate it carries.
    pub fn estimate(&self) -> mu::Estimate<f32> {
        mu::Estimate {
            mu: self.mu,
            sigma: self.sigma,
            state: self.state,
            mu_min: self.mu_min,
            change: self.change,
            mismatch: self.mismatch,
        }
    }
}
