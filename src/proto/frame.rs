//! One CAN frame's payload: a view ([`Frame`]) and its header as a value ([`FrameRepr`]).
//!
//! ```text
//! byte 0   bit 7 FIRST, bit 6 LAST, bits 5..0 frame index (0 in a first frame)
//! byte 1   message sequence number (the sender counts messages per identifier, wrapping)
//! byte 2   first frame only: total message length in bytes (header + body + CRC), 6..=255
//! then     message bytes; a last frame may be padded (CAN FD lengths) and the padding is ignored
//! ```

use super::Error;

/// Byte positions of the header fields.
pub mod field {
    /// Flags and frame index.
    pub const FLAGS: usize = 0;
    /// Message sequence number.
    pub const SEQ: usize = 1;
    /// Total message length (first frames only).
    pub const LEN: usize = 2;
    /// Start of the message bytes in a first frame.
    pub const FIRST_PAYLOAD: usize = 3;
    /// Start of the message bytes in other frames.
    pub const NEXT_PAYLOAD: usize = 2;
    /// Flag: first frame of a message.
    pub const F_FIRST: u8 = 0x80;
    /// Flag: last frame of a message.
    pub const F_LAST: u8 = 0x40;
    /// Mask of the frame index.
    pub const INDEX: u8 = 0x3F;
}

/// Smallest encoded message: version, type, CRC-32 (an empty body).
pub const MIN_MSG_LEN: usize = 6;

/// A read/write view over one frame's payload.
#[derive(Debug, Clone)]
pub struct Frame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Frame<T> {
    /// A view without checks; accessors may then return garbage but never panic.
    pub const fn new_unchecked(buffer: T) -> Frame<T> {
        Frame { buffer }
    }
    /// A view, after [`Frame::check_len`].
    pub fn new_checked(buffer: T) -> Result<Frame<T>, Error> {
        let f = Frame::new_unchecked(buffer);
        f.check_len()?;
        Ok(f)
    }
    /// [`Error::Truncated`] unless the buffer holds the whole header (2 bytes, 3 in a first
    /// frame) and at most 64 bytes.
    pub fn check_len(&self) -> Result<(), Error> {
        let b = self.buffer.as_ref();
        let need = if self.is_first() {
            field::FIRST_PAYLOAD
        } else {
            field::NEXT_PAYLOAD
        };
        if b.len() < need {
            Err(Error::Truncated)
        } else if b.len() > 64 {
            Err(Error::Overflow)
        } else {
            Ok(())
        }
    }
    /// The underlying buffer.
    pub fn into_inner(self) -> T {
        self.buffer
    }
    fn byte(&self, i: usize) -> u8 {
        self.buffer.as_ref().get(i).copied().unwrap_or(0)
    }
    /// FIRST flag.
    pub fn is_first(&self) -> bool {
        self.byte(field::FLAGS) & field::F_FIRST != 0
    }
    /// LAST flag.
    pub fn is_last(&self) -> bool {
        self.byte(field::FLAGS) & field::F_LAST != 0
    }
    /// Frame index within the message (0..=63).
    pub fn index(&self) -> u8 {
        self.byte(field::FLAGS) & field::INDEX
    }
    /// Message sequence number.
    pub fn seq(&self) -> u8 {
        self.byte(field::SEQ)
    }
    /// Total message length (meaningful in a first frame).
    pub fn total_len(&self) -> u8 {
        self.byte(field::LEN)
    }
    /// The message bytes this frame carries (possibly with padding in a last frame).
    pub fn payload(&self) -> &[u8] {
        let start = if self.is_first() {
            field::FIRST_PAYLOAD
        } else {
            field::NEXT_PAYLOAD
        };
        self.buffer.as_ref().get(start..).unwrap_or(&[])
    }
}

impl<T: AsRef<[u8]> + AsMut<[u8]>> Frame<T> {
    fn set_byte(&mut self, i: usize, v: u8) {
        if let Some(b) = self.buffer.as_mut().get_mut(i) {
            *b = v;
        }
    }
    /// Writes flags and index.
    pub fn set_flags(&mut self, first: bool, last: bool, index: u8) {
        let mut v = index & field::INDEX;
        if first {
            v |= field::F_FIRST;
        }
        if last {
            v |= field::F_LAST;
        }
        self.set_byte(field::FLAGS, v);
    }
    /// Writes the sequence number.
    pub fn set_seq(&mut self, seq: u8) {
        self.set_byte(field::SEQ, seq);
    }
    /// Writes the total length (first frames).
    pub fn set_total_len(&mut self, len: u8) {
        self.set_byte(field::LEN, len);
    }
    /// The message bytes, writable (the header flags must be set first: they say where the
    /// payload starts).
    pub fn payload_mut(&mut self) -> &mut [u8] {
        let start = if self.is_first() {
            field::FIRST_PAYLOAD
        } else {
            field::NEXT_PAYLOAD
        };
        self.buffer.as_mut().get_mut(start..).unwrap_or(&mut [])
    }
}

/// Where a frame sits in its message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Position {
    /// The first frame (index 0), announcing the message length \[bytes\], ≥ [`MIN_MSG_LEN`].
    First {
        /// Total message length.
        total_len: u8,
    },
    /// A following frame, index 1..=63.
    Next {
        /// Frame index.
        index: u8,
    },
}

/// A frame header holding only valid states.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FrameRepr {
    /// Message sequence number.
    pub seq: u8,
    /// First or following frame.
    pub pos: Position,
    /// The last frame of its message.
    pub last: bool,
}

impl FrameRepr {
    /// Parses a header. [`Error::Truncated`] for a short frame; [`Error::BadHeader`] for a
    /// first frame with a non-zero index or a length below [`MIN_MSG_LEN`], or a following
    /// frame with index 0.
    pub fn parse<T: AsRef<[u8]>>(frame: &Frame<T>) -> Result<FrameRepr, Error> {
        frame.check_len()?;
        let pos = if frame.is_first() {
            if frame.index() != 0 || usize::from(frame.total_len()) < MIN_MSG_LEN {
                return Err(Error::BadHeader);
            }
            Position::First {
                total_len: frame.total_len(),
            }
        } else {
            if frame.index() == 0 {
                return Err(Error::BadHeader);
            }
            Position::Next {
                index: frame.index(),
            }
        };
        Ok(FrameRepr {
            seq: frame.seq(),
            pos,
            last: frame.is_last(),
        })
    }
    /// Header length \[bytes\].
    pub const fn header_len(&self) -> usize {
        match self.pos {
            Position::First { .. } => field::FIRST_PAYLOAD,
            Position::Next { .. } => field::NEXT_PAYLOAD,
        }
    }
    /// Frame length for `payload_len` message bytes.
    pub const fn buffer_len(&self, payload_len: usize) -> usize {
        self.header_len() + payload_len
    }
    /// Writes the header into `frame` (whose buffer must hold [`FrameRepr::header_len`] bytes;
    /// shorter buffers are written as far as they go).
    pub fn emit<T: AsRef<[u8]> + AsMut<[u8]>>(&self, frame: &mut Frame<T>) {
        match self.pos {
            Position::First { total_len } => {
                frame.set_flags(true, self.last, 0);
                frame.set_total_len(total_len);
            }
            Position::Next { index } => frame.set_flags(false, self.last, index),
        }
        frame.set_seq(self.seq);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // A first frame of a 9-byte message, seq 7: header 80 07 09, then 5 message bytes; its last
    // frame: header 41 07 (LAST, index 1), then the other 4.
    static FIRST: [u8; 8] = [0x80, 0x07, 0x09, 0x01, 0x83, 0xaa, 0xbb, 0xcc];
    static LAST: [u8; 6] = [0x41, 0x07, 0xdd, 0xee, 0xff, 0x11];

    #[test]
    fn deconstruct() {
        let f = Frame::new_checked(&FIRST[..]).unwrap();
        assert!(f.is_first() && !f.is_last());
        assert_eq!((f.index(), f.seq(), f.total_len()), (0, 7, 9));
        assert_eq!(f.payload(), &[0x01, 0x83, 0xaa, 0xbb, 0xcc]);
        let g = Frame::new_checked(&LAST[..]).unwrap();
        assert!(!g.is_first() && g.is_last());
        assert_eq!((g.index(), g.seq()), (1, 7));
        assert_eq!(g.payload(), &[0xdd, 0xee, 0xff, 0x11]);
    }

    #[test]
    fn construct() {
        let mut b = [0xa5u8; 8];
        let mut f = Frame::new_unchecked(&mut b[..]);
        f.set_flags(true, false, 0);
        f.set_seq(7);
        f.set_total_len(9);
        f.payload_mut()
            .copy_from_slice(&[0x01, 0x83, 0xaa, 0xbb, 0xcc]);
        assert_eq!(b, FIRST);
    }

    #[test]
    fn parse() {
        let r = FrameRepr::parse(&Frame::new_unchecked(&FIRST[..])).unwrap();
        assert_eq!(
            r,
            FrameRepr {
                seq: 7,
                pos: Position::First { total_len: 9 },
                last: false
            }
        );
        let r = FrameRepr::parse(&Frame::new_unchecked(&LAST[..])).unwrap();
        assert_eq!(
            r,
            FrameRepr {
                seq: 7,
                pos: Position::Next { index: 1 },
                last: true
            }
        );
        assert_eq!(
            FrameRepr::parse(&Frame::new_unchecked(&[0x80u8, 1][..])),
            Err(Error::Truncated)
        );
        assert_eq!(
            FrameRepr::parse(&Frame::new_unchecked(&[0x81u8, 1, 9][..])),
            Err(Error::BadHeader)
        );
        assert_eq!(
            FrameRepr::parse(&Frame::new_unchecked(&[0x80u8, 1, 5][..])),
            Err(Error::BadHeader)
        );
        assert_eq!(
            FrameRepr::parse(&Frame::new_unchecked(&[0x00u8, 1, 5][..])),
            Err(Error::BadHeader)
        );
    }

    #[test]
    fn emit() {
        let mut b = [0xa5u8; 6];
        let r = FrameRepr {
            seq: 7,
            pos: Position::Next { index: 1 },
            last: true,
        };
        let mut f = Frame::new_unchecked(&mut b[..]);
        r.emit(&mut f);
        f.payload_mut().copy_from_slice(&LAST[2..]);
        assert_eq!(b, LAST);
        assert_eq!(r.buffer_len(4), 6);
    }
}
