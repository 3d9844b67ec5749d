//! The messages and their encoding: `[PROTO_VERSION][MsgType][postcard body][CRC-32 LE]`.
//! [`Msg`] is every message; their bodies are defined by direction: measurements
//! ([`super::measurement`]) and requests ([`super::requests`]) host → device, results
//! ([`super::results`]) and the status and acknowledgements ([`super::status`]) device → host.
//!
//! Every quantity is SI, angles in radians, forces and moments in ISO-W axes at the contact
//! point (x forward, y left, z up): α > 0 gives Fy < 0. Timestamps are the sender's clock in
//! microseconds as a `u32` (wraps after 71.6 min), sent as 4 fixed bytes (little endian) so that
//! they sit at fixed offsets. Floats are IEEE-754 `f32`, 4 bytes little endian; `Option<f32>`
//! is a tag byte (0 none, 1 some) followed by the value when present.

use super::auth::{Trailer, COUNTER_LEN, MAC_LEN_MAX, MAC_LEN_MIN, SECURED};
use super::crc::crc32;
use super::{
    Ack, CalibrationState, Command, CompactBatch, CompactMeasurement, CompactResults, Estimate,
    Forces, Measurement, ParamBegin, ParamChunk, ParamCommit, Settings, Status,
};
use super::{Error, PROTO_VERSION};
use postcard::experimental::max_size::MaxSize;
use serde::de::DeserializeOwned;

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
    /// [`Msg::SetCalibration`]
    SetCalibration = 0x09,
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
    /// [`Msg::Calibration`]
    Calibration = 0x86,
}

impl MsgType {
    /// Every type, in code order.
    pub const ALL: [MsgType; 15] = [
        MsgType::Measurement,
        MsgType::ParamBegin,
        MsgType::ParamChunk,
        MsgType::ParamCommit,
        MsgType::Settings,
        MsgType::Command,
        MsgType::CompactMeasurement,
        MsgType::CompactBatch,
        MsgType::SetCalibration,
        MsgType::Forces,
        MsgType::Estimate,
        MsgType::Status,
        MsgType::Ack,
        MsgType::CompactResults,
        MsgType::Calibration,
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
            MsgType::SetCalibration => "SetCalibration",
            MsgType::Calibration => "Calibration",
        }
    }
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
    /// Host → device: start a wheel's estimator from this calibration (warm start).
    SetCalibration(CalibrationState),
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
    /// Device → host: a wheel's calibration, at a low rate.
    Calibration(CalibrationState),
}

/// Decodes a postcard body at the start of `b`: the value and the bytes left after it.
fn body<T: DeserializeOwned>(b: &[u8], wrap: fn(T) -> Msg) -> Result<(Msg, &[u8]), Error> {
    postcard::take_from_bytes::<T>(b)
        .map(|(v, rest)| (wrap(v), rest))
        .map_err(|_| Error::Decode)
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
            Msg::SetCalibration(_) => MsgType::SetCalibration,
            Msg::Calibration(_) => MsgType::Calibration,
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
            Msg::SetCalibration(m) => postcard::to_slice(m, rest),
            Msg::Calibration(m) => postcard::to_slice(m, rest),
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
    /// CRC (skipped when fuzzing, so the fuzzer reaches the body), version, type, body. A secured
    /// message ([`super::auth`]) decodes to its message; its MAC is not checked here
    /// ([`super::auth::Verifier::open`] does).
    pub fn decode(bytes: &[u8]) -> Result<Msg, Error> {
        Msg::decode_secured(bytes).map(|(m, _)| m)
    }

    /// As [`Msg::decode`], and the trailer (counter and MAC) when the message is secured (the
    /// type byte's bit [`SECURED`]): after the body exactly 4 counter bytes and a MAC of
    /// [`MAC_LEN_MIN`]`..=`[`MAC_LEN_MAX`] bytes, else [`Error::Decode`].
    pub fn decode_secured(bytes: &[u8]) -> Result<(Msg, Option<Trailer<'_>>), Error> {
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
        let (msg, rest) = match MsgType::from_u8(t & !SECURED).ok_or(Error::UnknownType)? {
            MsgType::Measurement => body(b, Msg::Measurement),
            MsgType::ParamBegin => body(b, Msg::ParamBegin),
            MsgType::ParamChunk => body(b, Msg::ParamChunk),
            MsgType::ParamCommit => body(b, Msg::ParamCommit),
            MsgType::Settings => body(b, Msg::Settings),
            MsgType::Command => body(b, Msg::Command),
            MsgType::CompactMeasurement => body(b, Msg::CompactMeasurement),
            MsgType::CompactBatch => body(b, Msg::CompactBatch),
            MsgType::CompactResults => body(b, Msg::CompactResults),
            MsgType::SetCalibration => body(b, Msg::SetCalibration),
            MsgType::Calibration => body(b, Msg::Calibration),
            MsgType::Forces => body(b, Msg::Forces),
            MsgType::Estimate => body(b, Msg::Estimate),
            MsgType::Status => body(b, Msg::Status),
            MsgType::Ack => body(b, Msg::Ack),
        }?;
        if t & SECURED == 0 {
            return if rest.is_empty() {
                Ok((msg, None))
            } else {
                Err(Error::Decode)
            };
        }
        let (counter, mac) = rest.split_at_checked(COUNTER_LEN).ok_or(Error::Decode)?;
        if !(usize::from(MAC_LEN_MIN)..=usize::from(MAC_LEN_MAX)).contains(&mac.len()) {
            return Err(Error::Decode);
        }
        let data_len = data.len().saturating_sub(mac.len());
        let trailer = Trailer {
            data: data.get(..data_len).ok_or(Error::Decode)?,
            counter: u32::from_le_bytes(counter.try_into().map_err(|_| Error::Decode)?),
            mac,
        };
        Ok((msg, Some(trailer)))
    }
}
