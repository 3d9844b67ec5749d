//! Host → device: one wheel's measured forces with what the vehicle knows of its motion
//! ([`Measurement`]), the same in scaled integers ([`CompactMeasurement`]), and one sample
//! instant of up to four wheels ([`CompactBatch`]); the wheel ([`Wheel`]).

use crate::wheel;
use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

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
pub(super) fn count_i16(x: f32, unit: f32) -> Option<i16> {
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
/// frames), answered by one [`CompactResults`](super::CompactResults). Four wheels at 1 kHz as one message per
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
