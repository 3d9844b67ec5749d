//! Both ways: one wheel's tyre calibration ([`CalibrationState`], the estimator's
//! [`crate::mu::calibration::Exported`] with the wheel). Device → host as
//! [`Msg::Calibration`](super::Msg::Calibration), reported at a low rate (the firmware: once a
//! second per wheel whose estimator runs), so that the host can store it; host → device as
//! [`Msg::SetCalibration`](super::Msg::SetCalibration), so that a device starts warm after
//! power-up (answered by an [`Ack`](super::Ack): [`AckCode::Ok`](super::AckCode::Ok) when the
//! wheel's estimator took it, [`AckCode::BadCalibration`](super::AckCode::BadCalibration) when
//! it refused it, nothing changed, [`AckCode::NoParams`](super::AckCode::NoParams) when no
//! estimator runs on that wheel).

use super::Wheel;
use crate::mu::calibration::{Exported, PROPERTIES};
use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

/// One wheel's calibration: 37 body bytes, fixed-width little endian, in this order.
///
/// | bytes | field | meaning |
/// |---|---|---|
/// | 0 | `wheel` | 0 FL, 1 FR, 2 RL, 3 RR |
/// | 1..17 | `value` | 4 × f32: trail scale, trail-shape scale, trail shift \[rad\], Kxκ scale (scales: 1 = the file) |
/// | 17..33 | `sigma` | 4 × f32: their σ (of a scale's logarithm: relative; of the shift: rad) |
/// | 33..37 | `batches` | u32: batches that moved the calibration |
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CalibrationState {
    /// The wheel.
    pub wheel: Wheel,
    /// Values, by [`crate::mu::calibration::Property`] index.
    pub value: [f32; PROPERTIES],
    /// Their σ.
    pub sigma: [f32; PROPERTIES],
    /// Batches that moved it (saturating).
    #[serde(with = "postcard::fixint::le")]
    pub batches: u32,
}

impl CalibrationState {
    /// Wheel `wheel`'s calibration `e`.
    pub fn new(wheel: Wheel, e: &Exported) -> CalibrationState {
        CalibrationState {
            wheel,
            value: e.value,
            sigma: e.sigma,
            batches: e.batches,
        }
    }

    /// The calibration it carries (checked only where it is imported,
    /// [`crate::mu::Bank::import_calibration`]).
    pub fn exported(&self) -> Exported {
        Exported {
            value: self.value,
            sigma: self.sigma,
            batches: self.batches,
        }
    }
}
