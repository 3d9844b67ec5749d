//! Host → device requests: a tyre parameter upload ([`ParamBegin`], [`ParamChunk`],
//! [`ParamCommit`]), the settings ([`Settings`]) and commands ([`Command`]).

use super::AckCode;
use crate::mu::{self, preview};
use core::fmt;
use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

/// Bytes of `.tir` text per [`ParamChunk`].
pub const CHUNK_LEN: usize = 48;

/// Longest `.tir` text a device accepts for upload \[bytes\] (the largest sample file, MF 6.2,
/// is 26 341 bytes).
pub const MAX_TIR_LEN: usize = 32 * 1024;

/// Starts a tyre parameter upload: the `.tir` text that follows in [`ParamChunk`]s.
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParamBegin {
    /// Length of the text \[bytes\], ≤ [`MAX_TIR_LEN`].
    #[serde(with = "postcard::fixint::le")]
    pub len: u32,
    /// CRC-32 ([`crc32`](super::crc32)) of the whole text.
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
/// then replaces its parameter set. Answered by an [`Ack`](super::Ack).
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct ParamCommit {
    /// The hash of [`ParamBegin::hash`] again.
    #[serde(with = "postcard::fixint::le")]
    pub hash: u32,
}

/// Evaluation and estimator settings. Answered by an [`Ack`](super::Ack): [`AckCode::Ok`] when applied
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
    /// Friction μ \[-\] reported in [`State::Fallback`](crate::mu::State::Fallback) (on the `.tir` surface's scale);
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
    /// Send a [`Status`](super::Status).
    StatusRequest,
    /// End the session: the QEMU board sends a [`Status`](super::Status), logs its counters and exits with
    /// code 0; a real board answers [`AckCode::NotSupported`].
    Stop,
}
