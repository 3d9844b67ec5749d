//! Frames → messages, one [`Reassembler`] per CAN identifier.
//!
//! Survives any frame sequence: lost, duplicated, reordered, truncated, garbage. What it does:
//! - a frame whose header does not parse is dropped alone; a message being assembled goes on;
//! - a frame identical to the previous accepted frame is a duplicate: ignored and counted;
//! - a well-formed frame that does not continue the pending message (other sequence number,
//!   unexpected index) drops the pending message ([`Error::OutOfOrder`]); a first frame then
//!   starts a new one, any other frame is dropped too;
//! - a message whose next frame is later than [`FRAME_TIMEOUT_MS`] is dropped ([`Error::Timeout`]);
//! - a complete message is delivered only if its length, CRC, version, type and body check;
//!   nothing is ever delivered from a partial or damaged message.
//!
//! Every drop increments one counter of [`Counters`].

use super::frame::{Frame, FrameRepr, Position};
use super::{Error, Msg, FRAME_TIMEOUT_MS};
use postcard::experimental::max_size::MaxSize;
use serde::{Deserialize, Serialize};

/// What the receiver has seen. Counters wrap at 2³².
#[derive(Serialize, Deserialize, MaxSize, Debug, Clone, Copy, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Counters {
    /// Frames fed.
    pub frames: u32,
    /// Messages delivered.
    pub messages: u32,
    /// Duplicate frames ignored.
    pub duplicates: u32,
    /// Drops: [`Error::Truncated`].
    pub truncated: u32,
    /// Drops: [`Error::BadHeader`].
    pub bad_header: u32,
    /// Drops: [`Error::BadCrc`].
    pub bad_crc: u32,
    /// Drops: [`Error::OutOfOrder`].
    pub out_of_order: u32,
    /// Drops: [`Error::Overflow`].
    pub overflow: u32,
    /// Drops: [`Error::Timeout`].
    pub timeout: u32,
    /// Drops: [`Error::Version`], [`Error::UnknownType`], [`Error::Decode`].
    pub decode: u32,
}

impl Counters {
    /// Counts one drop.
    pub fn count(&mut self, e: Error) {
        let c = match e {
            Error::Truncated => &mut self.truncated,
            Error::BadHeader => &mut self.bad_header,
            Error::BadCrc => &mut self.bad_crc,
            Error::OutOfOrder => &mut self.out_of_order,
            Error::Overflow => &mut self.overflow,
            Error::Timeout => &mut self.timeout,
            Error::Version | Error::UnknownType | Error::Decode => &mut self.decode,
        };
        *c = c.wrapping_add(1);
    }
    /// All drops.
    pub fn dropped(&self) -> u32 {
        [
            self.truncated,
            self.bad_header,
            self.bad_crc,
            self.out_of_order,
            self.overflow,
            self.timeout,
            self.decode,
        ]
        .iter()
        .fold(0u32, |a, &b| a.wrapping_add(b))
    }
    /// Element-wise sum (several receivers into one report).
    pub fn add(&mut self, o: &Counters) {
        self.frames = self.frames.wrapping_add(o.frames);
        self.messages = self.messages.wrapping_add(o.messages);
        self.duplicates = self.duplicates.wrapping_add(o.duplicates);
        self.truncated = self.truncated.wrapping_add(o.truncated);
        self.bad_header = self.bad_header.wrapping_add(o.bad_header);
        self.bad_crc = self.bad_crc.wrapping_add(o.bad_crc);
        self.out_of_order = self.out_of_order.wrapping_add(o.out_of_order);
        self.overflow = self.overflow.wrapping_add(o.overflow);
        self.timeout = self.timeout.wrapping_add(o.timeout);
        self.decode = self.decode.wrapping_add(o.decode);
    }
}

/// Result of feeding one frame.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Feed {
    /// Accepted (or ignored as a duplicate); the message is not complete.
    Pending,
    /// A message is complete and valid.
    Done(Msg),
    /// Something was dropped (counted); see the module doc for what.
    Dropped(Error),
}

#[derive(Debug, Clone, Copy)]
struct Partial {
    seq: u8,
    next_index: u8,
    total: usize,
    got: usize,
    last_ms: u32,
}

/// Reassembles the messages of one CAN identifier into a buffer of `N` bytes.
#[derive(Debug, Clone)]
pub struct Reassembler<const N: usize> {
    buf: [u8; N],
    pending: Option<Partial>,
    prev: [u8; 64],
    prev_len: usize,
    done_len: usize,
    counters: Counters,
}

impl<const N: usize> Default for Reassembler<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Reassembler<N> {
    /// Longest message it can hold \[bytes\].
    pub const CAPACITY: usize = N;

    /// An empty reassembler.
    pub const fn new() -> Self {
        Reassembler {
            buf: [0; N],
            pending: None,
            prev: [0; 64],
            prev_len: 0,
            done_len: 0,
            counters: Counters {
                frames: 0,
                messages: 0,
                duplicates: 0,
                truncated: 0,
                bad_header: 0,
                bad_crc: 0,
                out_of_order: 0,
                overflow: 0,
                timeout: 0,
                decode: 0,
            },
        }
    }

    /// What it has seen.
    pub const fn counters(&self) -> &Counters {
        &self.counters
    }

    /// The encoded bytes of the message the last [`Feed::Done`] delivered (for
    /// [`Verifier::open`](super::Verifier::open)); empty after any other result.
    pub fn last(&self) -> &[u8] {
        self.buf.get(..self.done_len).unwrap_or(&[])
    }

    /// `true` while a message is partly received.
    pub const fn is_pending(&self) -> bool {
        self.pending.is_some()
    }

    /// Drops a pending message whose last frame is older than [`FRAME_TIMEOUT_MS`] at
    /// `now_ms` (a wrapping millisecond clock); returns the drop, if any.
    pub fn poll(&mut self, now_ms: u32) -> Option<Error> {
        let p = self.pending?;
        if now_ms.wrapping_sub(p.last_ms) > FRAME_TIMEOUT_MS {
            Some(self.abort(Error::Timeout))
        } else {
            None
        }
    }

    fn abort(&mut self, e: Error) -> Error {
        self.pending = None;
        self.counters.count(e);
        e
    }

    fn reject(&mut self, e: Error) -> Feed {
        self.counters.count(e);
        Feed::Dropped(e)
    }

    /// Feeds one frame's payload (`data`: 2..=64 bytes) received at `now_ms`.
    pub fn feed(&mut self, data: &[u8], now_ms: u32) -> Feed {
        self.counters.frames = self.counters.frames.wrapping_add(1);
        self.done_len = 0;
        let _ = self.poll(now_ms);
        let frame = Frame::new_unchecked(data);
        let repr = match FrameRepr::parse(&frame) {
            Ok(r) => r,
            Err(e) => return self.reject(e),
        };
        if self.prev_len > 0 && self.prev.get(..self.prev_len) == Some(data) {
            self.counters.duplicates = self.counters.duplicates.wrapping_add(1);
            return Feed::Pending;
        }
        let payload = frame.payload();
        let mut p = match (repr.pos, self.pending) {
            (Position::First { total_len }, pending) => {
                if pending.is_some() {
                    let _ = self.abort(Error::OutOfOrder);
                }
                let total = usize::from(total_len);
                if total > N {
                    return self.reject(Error::Overflow);
                }
                Partial {
                    seq: repr.seq,
                    next_index: 0,
                    total,
                    got: 0,
                    last_ms: now_ms,
                }
            }
            (Position::Next { index }, Some(p)) if p.seq == repr.seq && p.next_index == index => p,
            (Position::Next { .. }, Some(_)) => {
                let _ = self.abort(Error::OutOfOrder);
                return self.reject(Error::OutOfOrder);
            }
            (Position::Next { .. }, None) => return self.reject(Error::OutOfOrder),
        };
        // Copy what belongs to the message; a last frame may carry padding beyond it.
        let room = p.total.saturating_sub(p.got);
        if payload.len() > room && !repr.last {
            self.pending = None;
            return self.reject(Error::BadHeader);
        }
        let n = payload.len().min(room);
        let end = p.got.saturating_add(n);
        match (self.buf.get_mut(p.got..end), payload.get(..n)) {
            (Some(dst), Some(src)) => dst.copy_from_slice(src),
            _ => {
                self.pending = None;
                return self.reject(Error::Overflow);
            }
        }
        p.got = end;
        p.last_ms = now_ms;
        p.next_index = p.next_index.saturating_add(1);
        if let Some(dst) = self.prev.get_mut(..data.len()) {
            dst.copy_from_slice(data);
            self.prev_len = data.len();
        }
        if !repr.last {
            if p.got >= p.total || p.next_index > super::frame::field::INDEX {
                self.pending = None;
                return self.reject(Error::BadHeader);
            }
            self.pending = Some(p);
            return Feed::Pending;
        }
        self.pending = None;
        if p.got < p.total {
            return self.reject(Error::Truncated);
        }
        match Msg::decode(self.buf.get(..p.total).unwrap_or(&[])) {
            Ok(m) => {
                self.counters.messages = self.counters.messages.wrapping_add(1);
                self.done_len = p.total;
                Feed::Done(m)
            }
            Err(e) => self.reject(e),
        }
    }
}
