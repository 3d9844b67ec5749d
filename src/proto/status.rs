//! Device → host: the status report ([`Status`]) and the acknowledgement of a request
//! ([`Ack`], [`AckCode`]).

use crate::wheel;
use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

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
    /// [`PROTO_VERSION`](super::PROTO_VERSION) of the firmware.
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
    /// Measurements that got no [`Forces`](super::Forces) (no parameters, no slip, evaluation error).
    pub eval_errors: u32,
    /// Messages sent.
    pub tx_messages: u32,
    /// Deepest stack use since boot \[bytes\] (stack painting; 0 if not measured).
    pub stack_peak: u32,
    /// Authentication (v5): the MAC length (0: no key), epoch and last accepted counter, and
    /// the secured messages accepted and refused, by reason.
    pub auth: super::AuthStatus,
}

/// Result of a host → device request.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum AckCode {
    /// Done.
    Ok,
    /// The text's CRC-32 differs from the announced hash.
    BadHash,
    /// The announced length is 0 or above [`MAX_TIR_LEN`](super::MAX_TIR_LEN), or the chunks did not fill it.
    BadLength,
    /// A chunk's offset is not where the previous one ended.
    BadOffset,
    /// A chunk or commit came without a [`ParamBegin`](super::ParamBegin).
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
    /// A [`Settings`](super::Settings) field is out of range ([`Settings::wheelbase`](super::Settings::wheelbase)); the settings in use stay.
    BadSettings,
    /// A [`SetCalibration`](super::Msg::SetCalibration) the wheel's estimator refused (a value
    /// or σ not a valid number, or a value beyond its bound:
    /// [`CalibrationError`](crate::mu::calibration::CalibrationError)); its calibration stays.
    BadCalibration,
    /// (v5) The device has no key: it refuses every state-changing message
    /// ([`auth`](super::auth)); nothing changed.
    NoKey,
    /// (v5) A state-changing message that was not secured (no MAC); nothing changed.
    MacMissing,
    /// (v5) The MAC is wrong (another key, a forged or damaged message, another MAC length);
    /// nothing changed.
    BadMac,
    /// (v5) The freshness counter is not above the last accepted one (a replayed or reordered
    /// message), or too far above it; nothing changed.
    StaleFreshness,
}

impl From<wheel::Error> for AckCode {
    /// Why a measurement got no forces, as the device answers it.
    fn from(e: wheel::Error) -> AckCode {
        match e {
            wheel::Error::NoSlip => AckCode::NoSlip,
            wheel::Error::Tyre(_) => AckCode::EvalError,
        }
    }
}

/// Answer to a request ([`ParamBegin`](super::ParamBegin), [`ParamCommit`](super::ParamCommit), [`Settings`](super::Settings), [`Command`](super::Command)), to a
/// failed [`ParamChunk`](super::ParamChunk), and to a [`Measurement`](super::Measurement) that gives no [`Forces`](super::Forces).
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Ack {
    /// [`MsgType`](super::MsgType) byte of the request.
    pub of: u8,
    /// Sequence number of the request's frames.
    pub seq: u8,
    /// Result.
    pub code: AckCode,
}
