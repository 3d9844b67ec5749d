//! SLCAN (Lawicel CAN232/CANUSB ASCII protocol): classic CAN frames as text lines, for links
//! without a CAN controller (QEMU's UART, a TCP socket, USB-serial adapters). Both ends use it:
//! the firmware on its UART, the host on QEMU's TCP serial port; python-can's `slcan`
//! interface is an independent implementation of the same text.
//!
//! ```text
//! tIIILDD..[CR]        standard data frame: 3 hex digits id, 1 digit length 0..8, 2 hex per byte
//! TIIIIIIIILDD..[CR]   extended data frame (8 hex digits id)
//! rIIIL[CR], RIIIIIIIIL[CR]  remote frames
//! other letters        commands (O open, C close, S/s bit rate, V/v version, N serial, F flags, Z timestamps ...)
//! [CR] answers OK, [BEL] (0x07) answers an error; a device acknowledges a sent frame with z[CR]/Z[CR].
//! ```
//!
//! [`Decoder`] never panics on any byte sequence: overlong lines, bad hex, wrong lengths are
//! reported as [`SlcanError`] and the decoder resynchronises at the next CR.

use embedded_can::{ExtendedId, Id, StandardId};

/// A classic CAN frame (≤ 8 data bytes) implementing [`embedded_can::Frame`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct CanFrame {
    id: u32,
    extended: bool,
    remote: bool,
    len: u8,
    data: [u8; 8],
}

impl CanFrame {
    /// The identifier as a number (11 or 29 bits).
    pub const fn raw_id(&self) -> u32 {
        self.id
    }
    /// A standard data frame; `None` if `id` > 0x7FF or `data` > 8 bytes.
    pub fn standard(id: u16, data: &[u8]) -> Option<CanFrame> {
        <CanFrame as embedded_can::Frame>::new(StandardId::new(id)?, data)
    }
}

impl embedded_can::Frame for CanFrame {
    fn new(id: impl Into<Id>, data: &[u8]) -> Option<Self> {
        let mut d = [0u8; 8];
        d.get_mut(..data.len())?.copy_from_slice(data);
        let (id, extended) = match id.into() {
            Id::Standard(s) => (u32::from(s.as_raw()), false),
            Id::Extended(e) => (e.as_raw(), true),
        };
        Some(CanFrame {
            id,
            extended,
            remote: false,
            len: u8::try_from(data.len()).ok()?,
            data: d,
        })
    }
    fn new_remote(id: impl Into<Id>, dlc: usize) -> Option<Self> {
        let mut f = Self::new(id, &[])?;
        f.remote = true;
        f.len = u8::try_from(dlc).ok().filter(|&l| l <= 8)?;
        Some(f)
    }
    fn is_extended(&self) -> bool {
        self.extended
    }
    fn is_remote_frame(&self) -> bool {
        self.remote
    }
    fn id(&self) -> Id {
        if self.extended {
            ExtendedId::new(self.id)
                .map(Id::Extended)
                .unwrap_or(Id::Extended(ExtendedId::ZERO))
        } else {
            u16::try_from(self.id)
                .ok()
                .and_then(StandardId::new)
                .map(Id::Standard)
                .unwrap_or(Id::Standard(StandardId::ZERO))
        }
    }
    fn dlc(&self) -> usize {
        usize::from(self.len)
    }
    fn data(&self) -> &[u8] {
        if self.remote {
            &[]
        } else {
            self.data.get(..usize::from(self.len)).unwrap_or(&[])
        }
    }
}

/// Longest line \[bytes\]: `T` + 8 id + 1 length + 16 data + CR.
pub const MAX_LINE: usize = 27;

const HEX: &[u8; 16] = b"0123456789ABCDEF";

fn hex_digit(n: u32) -> u8 {
    HEX.get((n & 0xF) as usize).copied().unwrap_or(b'0')
}

/// Writes `frame` as one SLCAN line (with its CR) into `out`; returns the line.
pub fn encode<'b>(frame: &CanFrame, out: &'b mut [u8; MAX_LINE]) -> &'b [u8] {
    let mut n = 0usize;
    let mut put = |b: u8| {
        if let Some(s) = out.get_mut(n) {
            *s = b;
            n += 1;
        }
    };
    let (letter, digits) = match (frame.extended, frame.remote) {
        (false, false) => (b't', 3),
        (true, false) => (b'T', 8),
        (false, true) => (b'r', 3),
        (true, true) => (b'R', 8),
    };
    put(letter);
    for i in (0..digits).rev() {
        put(hex_digit(frame.id >> (4 * i)));
    }
    put(b'0' + frame.len.min(8));
    if !frame.remote {
        for &b in frame.data.get(..usize::from(frame.len)).unwrap_or(&[]) {
            put(hex_digit(u32::from(b) >> 4));
            put(hex_digit(u32::from(b)));
        }
    }
    put(b'\r');
    out.get(..n).unwrap_or(&[])
}

/// What a complete line was.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Line {
    /// A CAN frame.
    Frame(CanFrame),
    /// A command or an answer: its first letter (`O`, `C`, `S`, `V`, `z`, ...); the rest of the
    /// line is not interpreted.
    Command(u8),
    /// An empty line (a bare CR: the OK answer).
    Empty,
    /// A BEL (0x07): the error answer.
    Bell,
}

/// Why a line was not understood.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SlcanError {
    /// More than [`MAX_LINE`] bytes before the CR.
    TooLong,
    /// A character that is not a hex digit where one is needed, or a non-ASCII letter.
    BadChar,
    /// The line's length does not match its frame type and data length.
    BadLength,
    /// An identifier out of range (standard > 0x7FF, extended > 0x1FFF_FFFF).
    BadId,
}

impl core::fmt::Display for SlcanError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(match self {
            SlcanError::TooLong => "SLCAN line too long",
            SlcanError::BadChar => "bad character in SLCAN line",
            SlcanError::BadLength => "SLCAN line length does not match its frame",
            SlcanError::BadId => "CAN identifier out of range",
        })
    }
}

impl core::error::Error for SlcanError {}

/// Byte-by-byte SLCAN line decoder.
#[derive(Debug, Clone)]
pub struct Decoder {
    line: [u8; MAX_LINE],
    len: usize,
    overlong: bool,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

fn unhex(b: u8) -> Option<u32> {
    match b {
        b'0'..=b'9' => Some(u32::from(b - b'0')),
        b'a'..=b'f' => Some(u32::from(b - b'a' + 10)),
        b'A'..=b'F' => Some(u32::from(b - b'A' + 10)),
        _ => None,
    }
}

fn unhex_n(s: &[u8]) -> Option<u32> {
    s.iter()
        .try_fold(0u32, |a, &b| Some(a.checked_mul(16)? | unhex(b)?))
}

fn parse_line(l: &[u8]) -> Result<Line, SlcanError> {
    let Some((&letter, rest)) = l.split_first() else {
        return Ok(Line::Empty);
    };
    let (digits, extended, remote) = match letter {
        b't' => (3, false, false),
        b'T' => (8, true, false),
        b'r' => (3, false, true),
        b'R' => (8, true, true),
        b'A'..=b'Z' | b'a'..=b'z' => return Ok(Line::Command(letter)),
        _ => return Err(SlcanError::BadChar),
    };
    let (id_s, rest) = rest.split_at_checked(digits).ok_or(SlcanError::BadLength)?;
    let (&len_c, data_s) = rest.split_first().ok_or(SlcanError::BadLength)?;
    let id = unhex_n(id_s).ok_or(SlcanError::BadChar)?;
    let len = unhex(len_c).ok_or(SlcanError::BadChar)?;
    if len > 8 {
        return Err(SlcanError::BadLength);
    }
    let id: Id = if extended {
        Id::Extended(ExtendedId::new(id).ok_or(SlcanError::BadId)?)
    } else {
        Id::Standard(
            u16::try_from(id)
                .ok()
                .and_then(StandardId::new)
                .ok_or(SlcanError::BadId)?,
        )
    };
    let len = len as usize;
    use embedded_can::Frame as _;
    if remote {
        if !data_s.is_empty() {
            return Err(SlcanError::BadLength);
        }
        return CanFrame::new_remote(id, len)
            .map(Line::Frame)
            .ok_or(SlcanError::BadLength);
    }
    if data_s.len() != 2 * len {
        return Err(SlcanError::BadLength);
    }
    let mut data = [0u8; 8];
    for (d, pair) in data.iter_mut().zip(data_s.chunks_exact(2)) {
        *d = u8::try_from(unhex_n(pair).ok_or(SlcanError::BadChar)?).unwrap_or(0);
    }
    CanFrame::new(id, data.get(..len).unwrap_or(&[]))
        .map(Line::Frame)
        .ok_or(SlcanError::BadLength)
}

impl Decoder {
    /// An empty decoder.
    pub const fn new() -> Self {
        Decoder {
            line: [0; MAX_LINE],
            len: 0,
            overlong: false,
        }
    }

    /// Feeds one byte; a complete line (at CR or BEL) gives `Some`. LF is ignored (some
    /// tools end lines with CR LF).
    pub fn push(&mut self, b: u8) -> Option<Result<Line, SlcanError>> {
        match b {
            b'\r' => {
                let r = if self.overlong {
                    Err(SlcanError::TooLong)
                } else {
                    parse_line(self.line.get(..self.len).unwrap_or(&[]))
                };
                self.len = 0;
                self.overlong = false;
                Some(r)
            }
            0x07 => {
                self.len = 0;
                self.overlong = false;
                Some(Ok(Line::Bell))
            }
            b'\n' => None,
            _ => {
                match self.line.get_mut(self.len) {
                    Some(s) => {
                        *s = b;
                        self.len += 1;
                    }
                    None => self.overlong = true,
                }
                None
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use embedded_can::Frame as _;

    fn decode_all(s: &[u8]) -> std::vec::Vec<Result<Line, SlcanError>> {
        let mut d = Decoder::new();
        s.iter().filter_map(|&b| d.push(b)).collect()
    }

    #[test]
    fn round_trip() {
        let f = CanFrame::standard(0x301, &[0x80, 0x00, 0x09, 0xAB]).unwrap();
        let mut out = [0u8; MAX_LINE];
        let l = encode(&f, &mut out);
        assert_eq!(
            l,
            b"t301480000 9AB\r"
                .as_slice()
                .iter()
                .copied()
                .filter(|&c| c != b' ')
                .collect::<std::vec::Vec<_>>()
                .as_slice()
        );
        assert_eq!(decode_all(l), [Ok(Line::Frame(f))]);
        let e = CanFrame::new(
            ExtendedId::new(0x1234_5678).unwrap(),
            &[1, 2, 3, 4, 5, 6, 7, 8],
        )
        .unwrap();
        let l = encode(&e, &mut out).to_vec();
        assert_eq!(
            l,
            b"T12345678801020304050607 08\r"
                .iter()
                .copied()
                .filter(|&c| c != b' ')
                .collect::<std::vec::Vec<_>>()
        );
        assert_eq!(decode_all(&l), [Ok(Line::Frame(e))]);
        let r = CanFrame::new_remote(StandardId::new(0x12).unwrap(), 3).unwrap();
        assert_eq!(encode(&r, &mut out), b"r0123\r");
        assert_eq!(decode_all(b"r0123\r"), [Ok(Line::Frame(r))]);
    }

    #[test]
    fn garbage_and_commands() {
        let r = decode_all(b"O\rS6\r\rt12\rt1233AABB\rt800 0\r\x07xyzzy\r\xff\r");
        assert_eq!(
            r,
            [
                Ok(Line::Command(b'O')),
                Ok(Line::Command(b'S')),
                Ok(Line::Empty),
                Err(SlcanError::BadLength),
                Err(SlcanError::BadLength),
                Err(SlcanError::BadChar),
                Ok(Line::Bell),
                Ok(Line::Command(b'x')),
                Err(SlcanError::BadChar),
            ]
        );
        let long = [b'a'; 100];
        let mut d = Decoder::new();
        for &b in &long {
            assert_eq!(d.push(b), None);
        }
        assert_eq!(d.push(b'\r'), Some(Err(SlcanError::TooLong)));
        assert_eq!(d.push(b'\r'), Some(Ok(Line::Empty)));
        assert_eq!(decode_all(b"t8000\r"), [Err(SlcanError::BadId)]);
    }
}
