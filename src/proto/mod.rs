//! The CAN protocol between a vehicle (or a log replayer) and a gough device: messages, their
//! encoding, segmentation over classic CAN (8-byte frames) and CAN FD (64-byte frames), and the
//! SLCAN text transport used where there is no CAN controller (QEMU).
//!
//! One definition, used unchanged by the firmware and the host tools.
//!
//! ## Layers
//! 1. [`Msg`] ([`msg`]; the bodies in [`measurement`], [`requests`], [`results`], [`status`]):
//!    the messages, SI units, radians, ISO-W axes. A message is encoded as
//!    `[PROTO_VERSION][type][postcard body][CRC-32 LE]` ([`Msg::encode`], [`Msg::decode`]); the
//!    header's `type` byte is [`MsgType`], the body is the variant's struct in
//!    [postcard](https://postcard.jamesmunns.com/wire-format), the CRC ([`crc32`]) covers header
//!    and body.
//! 2. Segmentation ([`frame`], [`Segmenter`], [`Reassembler`]): an encoded message is cut into
//!    CAN frames, each starting with a 2-byte header (first/last flags, frame index, message
//!    sequence number); the first frame adds the message length. Frames of one message are sent
//!    back to back on one CAN identifier ([`id`]); a receiver keeps one [`Reassembler`] per
//!    identifier.
//! 3. Transport: any `embedded_can` driver ([`link`]), or SLCAN (Lawicel) text over a UART or
//!    TCP socket ([`slcan`]).
//!
//! ## Why not ISO-TP (ISO 15765-2)
//! ISO-TP is point-to-point with a flow-control handshake: a receiver must answer each first
//! frame before the sender may continue. Our traffic is periodic streaming (four wheels at
//! 1 kHz) that bus monitors read passively, and a handshake per measurement would add a round
//! trip to every sample. ISO-TP also carries no checksum (it trusts CAN's CRC, which a gateway
//! or a UART bridge does not extend end to end), and its 4-bit frame counter cannot tell a lost
//! run of 16 frames. So each message here carries a CRC-32, a frame index (6 bits), a message
//! sequence number (8 bits) and the total length, and needs no answer frames.
//!
//! ## What this module leaves out
//! Retransmission (a lost message is counted and dropped; the application's acknowledgements
//! and status requests are the recovery path) and CAN FD on the SLCAN transport (Lawicel
//! SLCAN has no FD frames; FD segmentation is exercised by the unit tests and fuzzers).

pub mod auth;
pub mod calibration;
pub mod crc;
pub mod dbc;
pub mod frame;
pub mod link;
pub mod measurement;
pub mod msg;
pub mod reassembler;
pub mod requests;
pub mod results;
pub mod segmenter;
pub mod slcan;
pub mod status;

pub use auth::{AuthStatus, Key, MacLen, Policy, Signer, Verifier};
pub use calibration::CalibrationState;
pub use crc::crc32;
pub use frame::{Frame, FrameRepr, Position};
pub use measurement::*;
pub use msg::*;
pub use reassembler::{Counters, Feed, Reassembler};
pub use requests::*;
pub use results::*;
pub use segmenter::{Mtu, Segmenter};
pub use status::*;

use core::fmt;
use postcard::experimental::max_size::MaxSize;

/// Protocol version, the first byte of every encoded message. A receiver drops messages of
/// another version ([`Error::Version`]).
pub const PROTO_VERSION: u8 = 5;

/// Longest encoded message \[bytes\]: header (2) + the largest postcard body + the longest
/// trailer of a secured message ([`auth::TRAILER_MAX`]) + CRC (4). It fits the one-byte length
/// field of the first frame.
pub const MAX_MSG_LEN: usize = 2 + Msg::POSTCARD_MAX_SIZE + auth::TRAILER_MAX + 4;
const _: () = assert!(MAX_MSG_LEN <= u8::MAX as usize);

/// Receive buffer that holds any message: `Reassembler<MSG_BUF>`.
pub const MSG_BUF: usize = MAX_MSG_LEN;
const _: () =
    assert!(Msg::POSTCARD_MAX_SIZE + 6 + auth::TRAILER_MAX <= Reassembler::<MSG_BUF>::CAPACITY);

/// A partially received message is dropped when its next frame is this late \[ms\].
pub const FRAME_TIMEOUT_MS: u32 = 50;

/// CAN identifiers (11-bit, standard). Lower identifiers win arbitration: measurements first.
///
/// | id | direction | carries |
/// |---|---|---|
/// | `0x300` | host → device | [`Msg::Measurement`] |
/// | `0x301` | host → device | [`Msg::ParamBegin`], [`Msg::ParamChunk`], [`Msg::ParamCommit`], [`Msg::Settings`], [`Msg::Command`], [`Msg::SetCalibration`] |
/// | `0x302` | host → device | [`Msg::CompactMeasurement`] |
/// | `0x310` | device → host | [`Msg::Forces`], [`Msg::Estimate`] |
/// | `0x311` | device → host | [`Msg::Status`], [`Msg::Ack`], [`Msg::Calibration`] |
/// | `0x303` | host → device | [`Msg::CompactBatch`] |
/// | `0x312` | device → host | [`Msg::CompactResults`] |
pub mod id {
    /// Measurements, host → device.
    pub const MEASUREMENT: u16 = 0x300;
    /// Configuration and commands, host → device.
    pub const CONFIG: u16 = 0x301;
    /// Compact measurements, host → device (its own identifier: one frame length per
    /// identifier, 32 bytes on CAN FD).
    pub const COMPACT: u16 = 0x302;
    /// Four-wheel batches of compact measurements, host → device (48-byte frames on CAN FD:
    /// two per batch).
    pub const BATCH: u16 = 0x303;
    /// Four-wheel results, device → host (one 64-byte CAN FD frame per message).
    pub const BATCH_RESULT: u16 = 0x312;
    /// Results (predicted forces, friction estimates), device → host.
    pub const RESULT: u16 = 0x310;
    /// Status and acknowledgements, device → host.
    pub const STATUS: u16 = 0x311;
    /// Every identifier with its name and direction, in the order of the table above.
    pub const ALL: [(u16, &str, &str); 7] = [
        (MEASUREMENT, "GOUGH_MEASUREMENT", "host to device"),
        (CONFIG, "GOUGH_CONFIG", "host to device"),
        (COMPACT, "GOUGH_COMPACT", "host to device"),
        (RESULT, "GOUGH_RESULT", "device to host"),
        (STATUS, "GOUGH_STATUS", "device to host"),
        (BATCH, "GOUGH_BATCH", "host to device"),
        (BATCH_RESULT, "GOUGH_BATCH_RESULT", "device to host"),
    ];
    /// The identifier a message travels on.
    pub const fn of(t: super::MsgType) -> u16 {
        use super::MsgType as T;
        match t {
            T::Measurement => MEASUREMENT,
            T::CompactMeasurement => COMPACT,
            T::ParamBegin
            | T::ParamChunk
            | T::ParamCommit
            | T::Settings
            | T::Command
            | T::SetCalibration => CONFIG,
            T::Forces | T::Estimate => RESULT,
            T::Status | T::Ack | T::Calibration => STATUS,
            T::CompactBatch => BATCH,
            T::CompactResults => BATCH_RESULT,
        }
    }
}

/// Why a frame or a message was dropped. Every drop is counted in [`Counters`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Error {
    /// A frame shorter than its header, a message shorter than header + CRC, or a last frame
    /// that ends before the announced length.
    Truncated,
    /// A frame header that no sender emits (first frame with a non-zero index or a length
    /// below the minimum, or a frame with more bytes than the message has left).
    BadHeader,
    /// The message's CRC-32 does not match.
    BadCrc,
    /// A frame of another message, or with an unexpected index, arrived while a message was
    /// being assembled (lost or reordered frames); or a continuation without a first frame.
    OutOfOrder,
    /// The announced length exceeds the receive buffer, or an output buffer is too small.
    Overflow,
    /// The next frame of a message came later than [`FRAME_TIMEOUT_MS`].
    Timeout,
    /// The message was encoded for another [`PROTO_VERSION`].
    Version,
    /// The header's message type is not a [`MsgType`].
    UnknownType,
    /// The postcard body is malformed, holds an invalid value, or leaves bytes over.
    Decode,
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Error::Truncated => "truncated frame or message",
            Error::BadHeader => "malformed frame header",
            Error::BadCrc => "CRC mismatch",
            Error::OutOfOrder => "frame out of order",
            Error::Overflow => "message too long for the buffer",
            Error::Timeout => "message timed out between frames",
            Error::Version => "unsupported protocol version",
            Error::UnknownType => "unknown message type",
            Error::Decode => "malformed message body",
        })
    }
}

impl core::error::Error for Error {}

#[cfg(test)]
mod tests;
