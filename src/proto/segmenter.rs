//! Message → frames.
//!
//! Every frame on one identifier has the same length ([`Mtu::frame_len`]): the last frame of a
//! message (and a single frame) is padded with 0x00. A DBC file gives each identifier one data
//! length, and strict decoders (cantools) reject frames of another length.

use super::frame::{Frame, FrameRepr, Position};
use super::{id, Error, Msg, Signer, Verifier, MAX_MSG_LEN};
use postcard::experimental::max_size::MaxSize;

/// Largest frame of the bus.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Mtu {
    /// Classic CAN: 8 data bytes.
    Classic,
    /// CAN FD: 64 data bytes.
    Fd,
}

impl Mtu {
    /// Data bytes per frame.
    pub const fn bytes(self) -> usize {
        match self {
            Mtu::Classic => 8,
            Mtu::Fd => 64,
        }
    }

    /// Length of every frame on identifier `cid` \[bytes\]: each identifier has one fixed
    /// data length (as bus tools and DBC files expect), and a frame that carries fewer message
    /// bytes is padded with 0x00 (receivers ignore padding after the announced length).
    /// Classic CAN: 8 on every identifier. CAN FD: 32 on [`id::RESULT`] and [`id::COMPACT`] (a
    /// whole [`Msg::Forces`], [`Msg::Estimate`] or [`Msg::CompactMeasurement`] fits one frame),
    /// 48 on [`id::BATCH`] (a [`Msg::CompactBatch`], 83 bytes, in two frames), 64 on the others
    /// (a [`Msg::CompactResults`] fits one).
    pub const fn frame_len(self, cid: u16) -> usize {
        match self {
            Mtu::Classic => 8,
            Mtu::Fd => {
                if cid == id::RESULT || cid == id::COMPACT {
                    32
                } else if cid == id::BATCH {
                    48
                } else {
                    64
                }
            }
        }
    }
}

// A `CompactMeasurement` is 29 bytes encoded, one 32-byte frame; postcard's `MaxSize` counts its
// fixed-width fields as varints (2 bytes more per i16), so that bound is checked by a test
// (`proto::tests::compact_measurement`), not here.
const _: () = assert!(
    3 + 2 + super::Forces::POSTCARD_MAX_SIZE + 4 <= Mtu::Fd.frame_len(id::RESULT)
        && 3 + 2 + super::Estimate::POSTCARD_MAX_SIZE + 4 <= Mtu::Fd.frame_len(id::RESULT)
);

// A whole `CompactResults` in one 64-byte frame; a `CompactBatch` in two 48-byte frames.
const _: () = assert!(
    3 + 2 + super::CompactResults::POSTCARD_MAX_SIZE + 4 <= Mtu::Fd.frame_len(id::BATCH_RESULT)
        && 3 + 2 + super::CompactBatch::POSTCARD_MAX_SIZE + 4
            <= 2 * Mtu::Fd.frame_len(id::BATCH) - 2
        && 3 + 2 + super::CompactBatch::POSTCARD_MAX_SIZE + 4 > Mtu::Fd.frame_len(id::BATCH)
);

/// The smallest valid CAN FD data length ≥ `n` (n ≤ 64).
pub const fn fd_len(n: usize) -> usize {
    match n {
        0..=8 => n,
        9..=12 => 12,
        13..=16 => 16,
        17..=20 => 20,
        21..=24 => 24,
        25..=32 => 32,
        33..=48 => 48,
        _ => 64,
    }
}

/// Cuts one encoded message into frames: `new`, then `next_frame` until `None`.
#[derive(Debug, Clone)]
pub struct Segmenter {
    buf: [u8; MAX_MSG_LEN],
    len: usize,
    pos: usize,
    index: u8,
    seq: u8,
    frame_len: usize,
}

impl Segmenter {
    /// Encodes `msg` with sequence number `seq` (the sender increments it per message and
    /// identifier).
    pub fn new(msg: &Msg, seq: u8, mtu: Mtu) -> Result<Segmenter, Error> {
        let mut buf = [0u8; MAX_MSG_LEN];
        let len = msg.encode(&mut buf)?;
        Ok(Segmenter::of(buf, len, seq, mtu, id::of(msg.msg_type())))
    }

    /// Encodes `msg` secured by `signer` with its next freshness value ([`super::auth`]), with
    /// sequence number `seq`.
    pub fn sealed(msg: &Msg, seq: u8, mtu: Mtu, signer: &mut Signer) -> Result<Segmenter, Error> {
        let cid = id::of(msg.msg_type());
        let mut buf = [0u8; MAX_MSG_LEN];
        let len = signer.seal(cid, msg, &mut buf)?;
        Ok(Segmenter::of(buf, len, seq, mtu, cid))
    }

    /// Encodes `msg`, sent by the device, as its [`Verifier`] secures it ([`Verifier::seal`]:
    /// secured under [`super::Policy::All`], else plain), with sequence number `seq`.
    pub fn device(msg: &Msg, seq: u8, mtu: Mtu, v: &mut Verifier) -> Result<Segmenter, Error> {
        let cid = id::of(msg.msg_type());
        let mut buf = [0u8; MAX_MSG_LEN];
        let len = v.seal(cid, msg, &mut buf)?;
        Ok(Segmenter::of(buf, len, seq, mtu, cid))
    }

    fn of(buf: [u8; MAX_MSG_LEN], len: usize, seq: u8, mtu: Mtu, cid: u16) -> Segmenter {
        Segmenter {
            buf,
            len,
            pos: 0,
            index: 0,
            seq,
            frame_len: mtu.frame_len(cid),
        }
    }

    /// The encoded message.
    pub fn encoded(&self) -> &[u8] {
        self.buf.get(..self.len).unwrap_or(&[])
    }

    /// Length of each of its frames \[bytes\] ([`Mtu::frame_len`]).
    pub fn frame_len(&self) -> usize {
        self.frame_len
    }

    /// Number of frames the message takes.
    pub fn frame_count(&self) -> usize {
        let m = self.frame_len;
        let first = m - 3;
        if self.len <= first {
            1
        } else {
            1 + (self.len - first).div_ceil(m - 2)
        }
    }

    /// Writes the next frame into `out` and returns it, or `None` when all are out.
    pub fn next_frame<'b>(&mut self, out: &'b mut [u8; 64]) -> Option<&'b [u8]> {
        if self.pos >= self.len {
            return None;
        }
        let first = self.pos == 0;
        let header = if first { 3 } else { 2 };
        // Message bytes per frame: the identifier's frame length less the header.
        let room = self.frame_len - header;
        let n = (self.len - self.pos).min(room);
        let last = self.pos + n == self.len;
        let repr = FrameRepr {
            seq: self.seq,
            pos: if first {
                Position::First {
                    total_len: u8::try_from(self.len).unwrap_or(u8::MAX),
                }
            } else {
                Position::Next { index: self.index }
            },
            last,
        };
        let frame_len = self.frame_len.max(repr.buffer_len(n));
        let fb = out.get_mut(..frame_len)?;
        fb.fill(0);
        let mut f = Frame::new_unchecked(&mut *fb);
        repr.emit(&mut f);
        f.payload_mut()
            .get_mut(..n)?
            .copy_from_slice(self.buf.get(self.pos..self.pos + n)?);
        self.pos += n;
        self.index = self.index.saturating_add(1);
        out.get(..frame_len)
    }
}
