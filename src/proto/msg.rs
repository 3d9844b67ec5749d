//! The messages and their encoding: `[PROTO_VERSION][MsgType][postcard body][CRC-32 LE]`.
//!
//! Every quantity is SI, angles in radians, forces and moments in ISO-W axes at the contact
//! point (x forward, y left, z up): α > 0 gives Fy < 0. Timestamps are the sender's clock in
//! microseconds as a `u32` (wraps after 71.6 min), sent as 4 fixed bytes (little endian) so that
//! they sit at fixed offsets. Floats are IEEE-754 `f32`, 4 bytes little endian; `Option<f32>`
//! is a tag byte (0 none, 1 some) followed by the value when present.

use super::crc::crc32;
use super::{Error, PROTO_VERSION};
use crate::mf::Output;
use crate::mu::{self, preview, State};
use crate::wheel;
use core::fmt;
use postcard::experimental::max_size::MaxSize;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// Bytes of `.tir` text per [`ParamChunk`].
pub const CHUNK_LEN: usize = 48;

/// Longest `.tir` text a device accepts for upload \[bytes\] (the largest sample file, MF 6.2,
/// is 26 341 bytes).
pub const MAX_TIR_LEN: usize = 32 * 1024;

/// The message type, the second byte of every encoded message. Host → device types are
/// below 0x80, device → host types above.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[repr(u8)]
pub enum MsgType {
    /// [`Msg::Measurement`]
    Measurement = 0x01,
    /// [`Msg::ParamBegin`]
    ParamBegin = 0x02,
    /// [`Msg::ParamChunk`]
    ParamChunk = 0x03,
    /// [`Msg::ParamCommit`]
    ParamCommit = 0x04,
    /// [`Msg::Settings`]
    Settings = 0x05,
    /// [`Msg::Command`]
    Command = 0x06,
    /// [`Msg::CompactMeasurement`]
    CompactMeasurement = 0x07,
    /// [`Msg::CompactBatch`]
    CompactBatch = 0x08,
    /// [`Msg::Forces`]
    Forces = 0x81,
    /// [`Msg::Estimate`]
    Estimate = 0x82,
    /// [`Msg::Status`]
    Status = 0x83,
    /// [`Msg::Ack`]
    Ack = 0x84,
    /// [`Msg::CompactResults`]
    CompactResults = 0x85,
}

impl MsgType {
    /// Every type, in code order.
    pub const ALL: [MsgType; 13] = [
        MsgType::Measurement,
        MsgType::ParamBegin,
        MsgType::ParamChunk,
        MsgType::ParamCommit,
        MsgType::Settings,
        MsgType::Command,
        MsgType::CompactMeasurement,
        MsgType::CompactBatch,
        MsgType::Forces,
        MsgType::Estimate,
        MsgType::Status,
        MsgType::Ack,
        MsgType::CompactResults,
    ];
    /// The type of a header byte, if known.
    pub fn from_u8(b: u8) -> Option<MsgType> {
        MsgType::ALL.iter().copied().find(|t| *t as u8 == b)
    }
    /// Name as in docs/protocol.md's table.
    pub const fn name(self) -> &'static str {
        match self {
            MsgType::Measurement => "Measurement",
            MsgType::ParamBegin => "ParamBegin",
            MsgType::ParamChunk => "ParamChunk",
            MsgType::ParamCommit => "ParamCommit",
            MsgType::Settings => "Settings",
            MsgType::Command => "Command",
            MsgType::CompactMeasurement => "CompactMeasurement",
            MsgType::Forces => "Forces",
            MsgType::Estimate => "Estimate",
            MsgType::Status => "Status",
            MsgType::Ack => "Ack",
            MsgType::CompactBatch => "CompactBatch",
            MsgType::CompactResults => "CompactResults",
        }
    }
}

/// Which wheel a sample or a result belongs to: [`crate::wheel::Wheel`], one byte, 0..=3.
pub use crate::wheel::Wheel;

/// One sample of one wheel's measured forces (from a force-sensing hub or bearing, or from a
/// vehicle observer), with what the vehicle knows of its motion.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Measurement {
    /// The wheel.
    pub wheel: Wheel,
    /// Sample time \[µs\], sender's clock, wrapping.
    #[serde(with = "postcard::fixint::le")]
    pub t_us: u32,
    /// Vertical load Fz \[N\], ≥ 0 in contact.
    pub fz: f32,
    /// Lateral force Fy \[N\], ISO-W.
    pub fy: f32,
    /// Aligning moment Mz \[N·m\], ISO-W.
    pub mz: f32,
    /// Longitudinal force Fx \[N\], ISO-W, if measured.
    pub fx: Option<f32>,
    /// Longitudinal speed of the wheel centre Vx \[m/s\], if known (default: the tyre's LONGVL).
    pub vx: Option<f32>,
    /// Wheel spin speed ω \[rad/s\], if known.
    pub omega: Option<f32>,
    /// Road-wheel steering angle δ \[rad\], positive to the left, if known.
    pub delta: Option<f32>,
    /// Slip angle α \[rad\], ISO-W, if the vehicle estimates it.
    pub alpha: Option<f32>,
    /// Longitudinal slip κ \[-\], if the vehicle estimates it.
    pub kappa: Option<f32>,
    /// Inclination (camber) angle γ \[rad\], if known (default 0).
    pub gamma: Option<f32>,
}

impl From<&Measurement> for wheel::Measurement<f32> {
    /// What the wheel's pipeline takes of a measurement (δ is not used).
    fn from(m: &Measurement) -> Self {
        wheel::Measurement {
            t_us: m.t_us,
            fz: m.fz,
            fy: m.fy,
            mz: m.mz,
            fx: m.fx,
            vx: m.vx,
            omega: m.omega,
            alpha: m.alpha,
            kappa: m.kappa,
            gamma: m.gamma,
        }
    }
}

/// A [`Measurement`] in scaled integers: 29 bytes encoded instead of 30 to 58, so 5 classic
/// frames instead of 6 to 10, and one 32-byte CAN FD frame on its own identifier
/// ([`super::id::COMPACT`]) instead of a 64-byte one. Every field is a fixed-width little-endian
/// integer at a fixed offset (postcard `fixint`), so the FD DBC shows it as physical signals.
///
/// | field | type | unit per count | range |
/// |---|---|---|---|
/// | `fz` | u16 | 0.5 N | 0 ..= 32 767.5 N |
/// | `fy`, `fx` | i16 | 1 N | ±32 767 N |
/// | `mz` | i16 | 0.1 N·m | ±3 276.7 N·m |
/// | `vx` | i16 | 0.01 m/s | ±327.67 m/s |
/// | `omega` | i16 | 0.01 rad/s | ±327.67 rad/s |
/// | `alpha`, `kappa`, `gamma` | i16 | 1e-4 rad (κ: 1e-4) | ±3.2767 |
///
/// Optional fields are absent when [`CompactMeasurement::ABSENT`] (`i16::MIN`). The steering
/// angle δ is not carried (the device's pipeline does not use it). [`CompactMeasurement::new`]
/// refuses a value outside its range or not finite (no silent clamp); values are rounded to the
/// nearest count, so the device sees the measurement within half a count.
#[derive(Serialize, Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CompactMeasurement {
    /// The wheel.
    pub wheel: Wheel,
    /// Sample time \[µs\], sender's clock, wrapping.
    #[serde(with = "postcard::fixint::le")]
    pub t_us: u32,
    /// Fz, Fy, Mz, Fx, Vx, ω, α, κ, γ in the scaled integers above ([`CompactWheel`], which a
    /// [`CompactBatch`] carries per wheel; postcard writes a nested struct's fields in place,
    /// so the bytes are those of the table).
    pub fields: CompactWheel,
}

// Fixed-width fields: the exact size (the derive would count them as varints).
impl MaxSize for CompactMeasurement {
    const POSTCARD_MAX_SIZE: usize = Wheel::POSTCARD_MAX_SIZE + 4 + CompactWheel::POSTCARD_MAX_SIZE;
}

/// `x / unit` rounded, if it is finite and fits an i16 other than `i16::MIN`.
fn count_i16(x: f32, unit: f32) -> Option<i16> {
    let c = libm::roundf(x / unit);
    if c.is_finite() && c > f32::from(i16::MIN) && c <= f32::from(i16::MAX) {
        Some(c as i16)
    } else {
        None
    }
}

impl CompactMeasurement {
    /// The count that marks an optional field as absent.
    pub const ABSENT: i16 = i16::MIN;
    /// Fz per count \[N\].
    pub const FZ: f32 = 0.5;
    /// Fx, Fy per count \[N\].
    pub const F: f32 = 1.0;
    /// Mz per count \[N·m\].
    pub const MZ: f32 = 0.1;
    /// Vx per count \[m/s\], ω per count \[rad/s\].
    pub const SPEED: f32 = 0.01;
    /// α, γ per count \[rad\], κ per count \[-\].
    pub const ANGLE: f32 = 1e-4;

    /// The compact form of `m`, or `None` when a value is not finite or out of range (then
    /// send the [`Measurement`]). δ is dropped.
    pub fn new(m: &Measurement) -> Option<CompactMeasurement> {
        let opt = |x: Option<f32>, unit: f32| match x {
            None => Some(Self::ABSENT),
            Some(v) => count_i16(v, unit),
        };
        let fz = libm::roundf(m.fz / Self::FZ);
        if !(fz.is_finite() && (0.0..=f32::from(u16::MAX)).contains(&fz)) {
            return None;
        }
        Some(CompactMeasurement {
            wheel: m.wheel,
            t_us: m.t_us,
            fields: CompactWheel {
                fz: fz as u16,
                fy: count_i16(m.fy, Self::F)?,
                mz: count_i16(m.mz, Self::MZ)?,
                fx: opt(m.fx, Self::F)?,
                vx: opt(m.vx, Self::SPEED)?,
                omega: opt(m.omega, Self::SPEED)?,
                alpha: opt(m.alpha, Self::ANGLE)?,
                kappa: opt(m.kappa, Self::ANGLE)?,
                gamma: opt(m.gamma, Self::ANGLE)?,
            },
        })
    }

    /// The measurement it stands for (δ absent). Device and host both use this.
    pub fn measurement(&self) -> Measurement {
        let opt = |c: i16, unit: f32| (c != Self::ABSENT).then(|| f32::from(c) * unit);
        let f = &self.fields;
        Measurement {
            wheel: self.wheel,
            t_us: self.t_us,
            fz: f32::from(f.fz) * Self::FZ,
            fy: f32::from(f.fy) * Self::F,
            mz: f32::from(f.mz) * Self::MZ,
            fx: opt(f.fx, Self::F),
            vx: opt(f.vx, Self::SPEED),
            omega: opt(f.omega, Self::SPEED),
            delta: None,
            alpha: opt(f.alpha, Self::ANGLE),
            kappa: opt(f.kappa, Self::ANGLE),
            gamma: opt(f.gamma, Self::ANGLE),
        }
    }
}

/// One wheel's measured fields in scaled integers: [`CompactMeasurement`]'s after its wheel and
/// time, and each wheel's in a [`CompactBatch`] (18 bytes, fixed-width little endian, in this
/// order; scales and the absent marker in [`CompactMeasurement`]'s table).
#[derive(Serialize, Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CompactWheel {
    /// Fz \[0.5 N\].
    #[serde(with = "postcard::fixint::le")]
    pub fz: u16,
    /// Fy \[N\].
    #[serde(with = "postcard::fixint::le")]
    pub fy: i16,
    /// Mz \[0.1 N·m\].
    #[serde(with = "postcard::fixint::le")]
    pub mz: i16,
    /// Fx \[N\] or [`CompactMeasurement::ABSENT`].
    #[serde(with = "postcard::fixint::le")]
    pub fx: i16,
    /// Vx \[0.01 m/s\] or absent.
    #[serde(with = "postcard::fixint::le")]
    pub vx: i16,
    /// ω \[0.01 rad/s\] or absent.
    #[serde(with = "postcard::fixint::le")]
    pub omega: i16,
    /// α \[1e-4 rad\] or absent.
    #[serde(with = "postcard::fixint::le")]
    pub alpha: i16,
    /// κ \[1e-4\] or absent.
    #[serde(with = "postcard::fixint::le")]
    pub kappa: i16,
    /// γ \[1e-4 rad\] or absent.
    #[serde(with = "postcard::fixint::le")]
    pub gamma: i16,
}

// Fixed-width fields: the exact size (the derive would count them as varints).
impl MaxSize for CompactWheel {
    const POSTCARD_MAX_SIZE: usize = 18;
}

/// One sample instant of up to four wheels in scaled integers (type 0x08, identifier
/// [`super::id::BATCH`]): 77 body bytes, 83 encoded, two 48-byte CAN FD frames (14 classic
/// frames), answered by one [`CompactResults`]. Four wheels at 1 kHz as one message per
/// millisecond each way instead of four plus eight.
///
/// | bytes | field | meaning |
/// |---|---|---|
/// | 0..4 | `t_us` | u32 LE: the sample time of every wheel in the batch \[µs\] |
/// | 4 | `present` | bit i set: wheel i (0 FL, 1 FR, 2 RL, 3 RR) is in the batch; bits 4–7 are 0 |
/// | 5 + 18 i .. | `wheels[i]` | [`CompactWheel`]: Fz u16 \[0.5 N\], Fy i16 \[N\], Mz i16 \[0.1 N·m\], Fx i16 \[N\], Vx i16 \[0.01 m/s\], ω i16 \[0.01 rad/s\], α i16 \[1e-4 rad\], κ i16 \[1e-4\], γ i16 \[1e-4 rad\] |
///
/// Scales, ranges and the absent marker (−32 768) are [`CompactMeasurement`]'s; a wheel not
/// present is sent as zeros and ignored. [`CompactBatch::new`] refuses (never clamps) a value
/// out of range or not finite, as [`CompactMeasurement::new`] does.
#[derive(Serialize, Deserialize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CompactBatch {
    /// Sample time \[µs\] of every wheel in the batch, sender's clock, wrapping.
    #[serde(with = "postcard::fixint::le")]
    pub t_us: u32,
    /// Bit i: wheel i is present.
    pub present: u8,
    /// The wheels, by index (0 FL, 1 FR, 2 RL, 3 RR).
    pub wheels: [CompactWheel; 4],
}

impl MaxSize for CompactBatch {
    const POSTCARD_MAX_SIZE: usize = 4 + 1 + 4 * CompactWheel::POSTCARD_MAX_SIZE;
}

impl CompactBatch {
    /// The batch of `t_us` holding `ms` (at most one per wheel; each at its own wheel's slot,
    /// its own `t_us` replaced by the batch's), or `None` when a value is not finite or out of
    /// range, or a wheel comes twice. δ is dropped.
    pub fn new(t_us: u32, ms: &[Measurement]) -> Option<CompactBatch> {
        let mut b = CompactBatch {
            t_us,
            ..CompactBatch::default()
        };
        for m in ms {
            let bit = 1u8 << m.wheel.index();
            if b.present & bit != 0 {
                return None;
            }
            b.present |= bit;
            *b.wheels.get_mut(m.wheel.index())? = CompactMeasurement::new(m)?.fields;
        }
        Some(b)
    }

    /// The measurements it stands for, by wheel index (`None`: not present), each with the
    /// batch's `t_us` and δ absent. Device and host both use this.
    pub fn measurements(&self) -> [Option<Measurement>; 4] {
        let mut out = [None; 4];
        for ((o, w), wheel) in out.iter_mut().zip(self.wheels.iter()).zip(Wheel::ALL) {
            if self.present & (1 << wheel.index()) != 0 {
                let c = CompactMeasurement {
                    wheel,
                    t_us: self.t_us,
                    fields: *w,
                };
                *o = Some(c.measurement());
            }
        }
        out
    }
}

/// One wheel's results in a [`CompactResults`]: 12 bytes, fixed-width little endian, in this
/// order.
///
/// | field | type | per count | range | not available |
/// |---|---|---|---|---|
/// | `fx`, `fy` | i16 | 1 N | ±32 767 N | −32 768 |
/// | `mz` | i16 | 0.1 N·m | ±3 276.7 N·m | −32 768 |
/// | `mu`, `sigma` | u16 | 1e-4 | 0 ..= 6.5534 | 65 535 |
/// | `mu_min` | u8 | 0.01, rounded **down** (stays a lower bound) | 0 ..= 2.54 | 255 |
/// | `status` | u8 | bits 0–1 state (0 Identifiable, 1 NotIdentifiable, 2 Fallback, 3 no estimate), bit 2 change, bit 3 MF flags non-zero (an input clipped or regularised), bit 4 wheel present; bits 5–7 are 0 | | |
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
    /// State (bits 0–1), change (bit 2), MF flags non-zero (bit 3), present (bit 4).
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
        Self::PRESENT | state | change | flags
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
}

/// The four wheels' results answering one [`CompactBatch`] (type 0x85, identifier
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

/// Starts a tyre parameter upload: the `.tir` text that follows in [`ParamChunk`]s.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParamBegin {
    /// Length of the text \[bytes\], ≤ [`MAX_TIR_LEN`].
    #[serde(with = "postcard::fixint::le")]
    pub len: u32,
    /// CRC-32 ([`crc32`]) of the whole text.
    #[serde(with = "postcard::fixint::le")]
    pub hash: u32,
}

/// Up to `N` bytes (postcard: a length byte, then the bytes).
#[derive(Clone, Copy)]
pub struct Bytes<const N: usize> {
    len: u8,
    buf: [u8; N],
}

impl<const N: usize> Bytes<N> {
    const OK: () = assert!(N < 128, "the length must fit one varint byte");
    /// A copy of `data`, or `None` when it is longer than `N`.
    pub fn new(data: &[u8]) -> Option<Self> {
        let () = Self::OK;
        let mut buf = [0u8; N];
        buf.get_mut(..data.len())?.copy_from_slice(data);
        Some(Bytes {
            len: u8::try_from(data.len()).ok()?,
            buf,
        })
    }
    /// The bytes.
    pub fn as_slice(&self) -> &[u8] {
        self.buf.get(..usize::from(self.len)).unwrap_or(&[])
    }
}

impl<const N: usize> PartialEq for Bytes<N> {
    fn eq(&self, other: &Self) -> bool {
        self.as_slice() == other.as_slice()
    }
}
impl<const N: usize> Eq for Bytes<N> {}

impl<const N: usize> fmt::Debug for Bytes<N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Bytes({:02x?})", self.as_slice())
    }
}

#[cfg(feature = "defmt")]
impl<const N: usize> defmt::Format for Bytes<N> {
    fn format(&self, f: defmt::Formatter<'_>) {
        defmt::write!(f, "Bytes({=[u8]:x})", self.as_slice())
    }
}

impl<const N: usize> MaxSize for Bytes<N> {
    const POSTCARD_MAX_SIZE: usize = N + 1;
}

impl<const N: usize> Serialize for Bytes<N> {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_bytes(self.as_slice())
    }
}

impl<'de, const N: usize> Deserialize<'de> for Bytes<N> {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<const N: usize>;
        impl<'de, const N: usize> serde::de::Visitor<'de> for V<N> {
            type Value = Bytes<N>;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "at most {N} bytes")
            }
            fn visit_bytes<E: serde::de::Error>(self, v: &[u8]) -> Result<Bytes<N>, E> {
                Bytes::new(v).ok_or_else(|| E::invalid_length(v.len(), &self))
            }
        }
        d.deserialize_bytes(V::<N>)
    }
}

/// A piece of the `.tir` text announced by [`ParamBegin`].
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParamChunk {
    /// Offset of the first byte in the text \[bytes\]; chunks are sent in order.
    #[serde(with = "postcard::fixint::le")]
    pub offset: u32,
    /// Up to [`CHUNK_LEN`] bytes of text.
    pub data: Bytes<CHUNK_LEN>,
}

/// Ends an upload: the device checks length and hash, parses and validates the text, and only
/// then replaces its parameter set. Answered by an [`Ack`].
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParamCommit {
    /// The hash of [`ParamBegin::hash`] again.
    #[serde(with = "postcard::fixint::le")]
    pub hash: u32,
}

/// Evaluation and estimator settings. Answered by an [`Ack`]: [`AckCode::Ok`] when applied
/// (the estimators restart: they forget what they learnt), [`AckCode::BadSettings`] when a
/// field is out of range (nothing changes).
///
/// Protocol v3 replaced v2's `window` and `min_utilisation` (settings of an earlier estimator
/// that the bank never used) by `wheelbase`.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Settings {
    /// Clip inputs to the `.tir` ranges (`mf::Options::limits`).
    pub limits: bool,
    /// Friction μ \[-\] reported in [`State::Fallback`] (on the `.tir` surface's scale);
    /// the bank's prior. A value that is not a positive number keeps the bank's default prior.
    pub fallback_mu: f32,
    /// The car's wheelbase \[m\] for the front-to-rear preview (`mu::preview`: each rear wheel's
    /// estimator is told what the front wheel on its side read when it gets there); `0`: none,
    /// every wheel estimates alone. Otherwise a positive finite number (else
    /// [`AckCode::BadSettings`]).
    pub wheelbase: f32,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            limits: true,
            fallback_mu: 0.3,
            wheelbase: 0.0,
        }
    }
}

impl Settings {
    /// The estimator's settings these give: the bank's defaults with the prior `mu_prior` =
    /// `fallback_mu` when it is a positive number.
    pub fn estimator_config(&self) -> mu::Config<f32> {
        let mut c = mu::Config::default();
        if self.fallback_mu.is_finite() && self.fallback_mu > 0.0 {
            c.mu_prior = self.fallback_mu;
        }
        c
    }

    /// The front-to-rear preview these give: none for wheelbase `0`, the preview over the
    /// wheelbase (default weight) for a positive finite one, `Err(AckCode::BadSettings)` for
    /// anything else ([`Settings::wheelbase`]).
    pub fn preview(&self) -> Result<Option<preview::Config<f32>>, AckCode> {
        Ok(self.wheelbase()?.map(preview::Config::with_wheelbase))
    }

    /// The wheelbase of the preview: `Ok(None)` for `0` (none), `Ok(Some(l))` for a positive
    /// finite `l`, `Err(AckCode::BadSettings)` for anything else (negative, NaN, ±∞).
    pub fn wheelbase(&self) -> Result<Option<f32>, AckCode> {
        let l = self.wheelbase;
        if l == 0.0 {
            Ok(None)
        } else if l.is_finite() && l > 0.0 {
            Ok(Some(l))
        } else {
            Err(AckCode::BadSettings)
        }
    }
}

/// A command.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// Restart the device (counters, settings and uploaded parameters are lost).
    Reset,
    /// Send a [`Status`].
    StatusRequest,
    /// End the session: the QEMU board sends a [`Status`], logs its counters and exits with
    /// code 0; a real board answers [`AckCode::NotSupported`].
    Stop,
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
/// Fields after `state` were added in protocol v2 (`mu_min`, `change`).
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
    /// prior [`Settings::fallback_mu`].
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
        }
    }
}

/// Where the device's parameter set came from.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum ParamSource {
    /// None loaded: measurements are answered with [`AckCode::NoParams`].
    None,
    /// Built into the firmware.
    Bundled,
    /// Uploaded and committed.
    Uploaded,
}

/// Device status and diagnostics.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Status {
    /// Firmware version (major, minor, patch).
    pub firmware: [u8; 3],
    /// [`PROTO_VERSION`] of the firmware.
    pub proto: u8,
    /// Where the parameter set came from.
    pub source: ParamSource,
    /// CRC-32 of the `.tir` text in use (0 when none).
    #[serde(with = "postcard::fixint::le")]
    pub param_hash: u32,
    /// Time since boot \[ms\].
    pub uptime_ms: u32,
    /// Frames and messages received, and drops by reason, over all receive identifiers.
    pub rx: super::Counters,
    /// Transport errors below the frames: malformed SLCAN lines, receive overruns.
    pub link_errors: u32,
    /// Measurements that got no [`Forces`] (no parameters, no slip, evaluation error).
    pub eval_errors: u32,
    /// Messages sent.
    pub tx_messages: u32,
    /// Deepest stack use since boot \[bytes\] (stack painting; 0 if not measured).
    pub stack_peak: u32,
}

/// Result of a host → device request.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AckCode {
    /// Done.
    Ok,
    /// The text's CRC-32 differs from the announced hash.
    BadHash,
    /// The announced length is 0 or above [`MAX_TIR_LEN`], or the chunks did not fill it.
    BadLength,
    /// A chunk's offset is not where the previous one ended.
    BadOffset,
    /// A chunk or commit came without a [`ParamBegin`].
    NotInUpload,
    /// The text is not a valid `.tir` file; the line of the first error (0: the file as a
    /// whole). The previous parameter set stays in use.
    TirError {
        /// 1-based line.
        line: u32,
    },
    /// A measurement came before any parameter set.
    NoParams,
    /// A measurement carried neither α nor κ: no forces to predict.
    NoSlip,
    /// The Magic Formula rejected the sample (non-finite input).
    EvalError,
    /// This board does not do that.
    NotSupported,
    /// A [`Settings`] field is out of range ([`Settings::wheelbase`]); the settings in use stay.
    BadSettings,
}

impl From<wheel::Error> for AckCode {
    /// Why a measurement got no forces, as the device answers it.
    fn from(e: wheel::Error) -> AckCode {
        match e {
            wheel::Error::NoSlip => AckCode::NoSlip,
            wheel::Error::Step(_) | wheel::Error::Eval(_) => AckCode::EvalError,
        }
    }
}

/// Answer to a request ([`ParamBegin`], [`ParamCommit`], [`Settings`], [`Command`]), to a
/// failed [`ParamChunk`], and to a [`Measurement`] that gives no [`Forces`].
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ack {
    /// [`MsgType`] byte of the request.
    pub of: u8,
    /// Sequence number of the request's frames.
    pub seq: u8,
    /// Result.
    pub code: AckCode,
}

/// Every message of the protocol.
#[derive(MaxSize, Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Msg {
    /// Host → device: a per-wheel sample.
    Measurement(Measurement),
    /// Host → device: start a parameter upload.
    ParamBegin(ParamBegin),
    /// Host → device: a piece of the parameter text.
    ParamChunk(ParamChunk),
    /// Host → device: check and use the uploaded parameters.
    ParamCommit(ParamCommit),
    /// Host → device: evaluation and estimator settings.
    Settings(Settings),
    /// Host → device: reset, status request, stop.
    Command(Command),
    /// Host → device: a per-wheel sample in scaled integers.
    CompactMeasurement(CompactMeasurement),
    /// Host → device: one sample instant of up to four wheels in scaled integers.
    CompactBatch(CompactBatch),
    /// Device → host: predicted forces.
    Forces(Forces),
    /// Device → host: friction estimate.
    Estimate(Estimate),
    /// Device → host: status and counters.
    Status(Status),
    /// Device → host: acknowledgement.
    Ack(Ack),
    /// Device → host: the four wheels' forces and estimates answering a [`CompactBatch`].
    CompactResults(CompactResults),
}

fn body<T: DeserializeOwned>(b: &[u8]) -> Result<T, Error> {
    match postcard::take_from_bytes::<T>(b) {
        Ok((v, [])) => Ok(v),
        _ => Err(Error::Decode),
    }
}

impl Msg {
    /// The message's type byte.
    pub const fn msg_type(&self) -> MsgType {
        match self {
            Msg::Measurement(_) => MsgType::Measurement,
            Msg::ParamBegin(_) => MsgType::ParamBegin,
            Msg::ParamChunk(_) => MsgType::ParamChunk,
            Msg::ParamCommit(_) => MsgType::ParamCommit,
            Msg::Settings(_) => MsgType::Settings,
            Msg::Command(_) => MsgType::Command,
            Msg::CompactMeasurement(_) => MsgType::CompactMeasurement,
            Msg::CompactBatch(_) => MsgType::CompactBatch,
            Msg::CompactResults(_) => MsgType::CompactResults,
            Msg::Forces(_) => MsgType::Forces,
            Msg::Estimate(_) => MsgType::Estimate,
            Msg::Status(_) => MsgType::Status,
            Msg::Ack(_) => MsgType::Ack,
        }
    }

    /// Encodes into `out` as `[PROTO_VERSION][type][body][CRC-32 LE]`; returns the length.
    /// [`Error::Overflow`] if `out` is too short (a buffer of [`super::MAX_MSG_LEN`] never is).
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, Error> {
        let (head, rest) = out.split_at_mut_checked(2).ok_or(Error::Overflow)?;
        head.copy_from_slice(&[PROTO_VERSION, self.msg_type() as u8]);
        let n = match self {
            Msg::Measurement(m) => postcard::to_slice(m, rest),
            Msg::ParamBegin(m) => postcard::to_slice(m, rest),
            Msg::ParamChunk(m) => postcard::to_slice(m, rest),
            Msg::ParamCommit(m) => postcard::to_slice(m, rest),
            Msg::Settings(m) => postcard::to_slice(m, rest),
            Msg::Command(m) => postcard::to_slice(m, rest),
            Msg::CompactMeasurement(m) => postcard::to_slice(m, rest),
            Msg::CompactBatch(m) => postcard::to_slice(m, rest),
            Msg::CompactResults(m) => postcard::to_slice(m, rest),
            Msg::Forces(m) => postcard::to_slice(m, rest),
            Msg::Estimate(m) => postcard::to_slice(m, rest),
            Msg::Status(m) => postcard::to_slice(m, rest),
            Msg::Ack(m) => postcard::to_slice(m, rest),
        }
        .map_err(|_| Error::Overflow)?
        .len();
        let end = n.checked_add(2).ok_or(Error::Overflow)?;
        let crc = crc32(out.get(..end).ok_or(Error::Overflow)?);
        out.get_mut(end..end.saturating_add(4))
            .filter(|s| s.len() == 4)
            .ok_or(Error::Overflow)?
            .copy_from_slice(&crc.to_le_bytes());
        Ok(end.saturating_add(4))
    }

    /// Decodes one whole encoded message (exactly; no bytes over). Checks, in order: length,
    /// CRC (skipped when fuzzing, so the fuzzer reaches the body), version, type, body.
    pub fn decode(bytes: &[u8]) -> Result<Msg, Error> {
        let split = bytes.len().checked_sub(4).ok_or(Error::Truncated)?;
        let (data, crc) = bytes.split_at_checked(split).ok_or(Error::Truncated)?;
        let (head, b) = data.split_at_checked(2).ok_or(Error::Truncated)?;
        let crc = u32::from_le_bytes(crc.try_into().map_err(|_| Error::Truncated)?);
        if !cfg!(fuzzing) && crc32(data) != crc {
            return Err(Error::BadCrc);
        }
        let (&version, &t) = (
            head.first().ok_or(Error::Truncated)?,
            head.get(1).ok_or(Error::Truncated)?,
        );
        if version != PROTO_VERSION {
            return Err(Error::Version);
        }
        Ok(match MsgType::from_u8(t).ok_or(Error::UnknownType)? {
            MsgType::Measurement => Msg::Measurement(body(b)?),
            MsgType::ParamBegin => Msg::ParamBegin(body(b)?),
            MsgType::ParamChunk => Msg::ParamChunk(body(b)?),
            MsgType::ParamCommit => Msg::ParamCommit(body(b)?),
            MsgType::Settings => Msg::Settings(body(b)?),
            MsgType::Command => Msg::Command(body(b)?),
            MsgType::CompactMeasurement => Msg::CompactMeasurement(body(b)?),
            MsgType::CompactBatch => Msg::CompactBatch(body(b)?),
            MsgType::CompactResults => Msg::CompactResults(body(b)?),
            MsgType::Forces => Msg::Forces(body(b)?),
            MsgType::Estimate => Msg::Estimate(body(b)?),
            MsgType::Status => Msg::Status(body(b)?),
            MsgType::Ack => Msg::Ack(body(b)?),
        })
    }
}
