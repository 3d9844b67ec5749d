//! CRC-32/ISO-HDLC (the CRC of zlib, Ethernet, PNG; Python's `zlib.crc32`): reflected,
//! polynomial 0x04C11DB7 (0xEDB88320 reflected), initial value and final XOR 0xFFFF_FFFF,
//! check value 0xCBF4_3926 for `b"123456789"`.
//!
//! Used over every encoded message and, as the parameter-set hash, over an uploaded `.tir`
//! text (so `python3 -c 'import zlib,sys; print(hex(zlib.crc32(open(sys.argv[1],"rb").read())))'`
//! gives the hash a device reports). One 1 KiB table, built at compile time.

// Indexing in a const block: `i < 256` by the loop bound, checked at compile time.
#[allow(clippy::indexing_slicing)]
const TABLE: [u32; 256] = {
    let mut t = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut k = 0;
        while k < 8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
            k += 1;
        }
        t[i] = c;
        i += 1;
    }
    t
};

/// A running CRC-32, for data that arrives in pieces.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Crc32(u32);

impl Default for Crc32 {
    fn default() -> Self {
        Self::new()
    }
}

impl Crc32 {
    /// A CRC over no data yet.
    pub const fn new() -> Self {
        Crc32(0xFFFF_FFFF)
    }
    /// Adds `data`.
    pub fn update(&mut self, data: &[u8]) {
        let mut c = self.0;
        for &b in data {
            let i = ((c ^ u32::from(b)) & 0xFF) as u8;
            // `i` is a u8, the table has 256 entries: the fallback is unreachable.
            c = TABLE.get(usize::from(i)).copied().unwrap_or(0) ^ (c >> 8);
        }
        self.0 = c;
    }
    /// The CRC of everything added so far.
    pub const fn finish(self) -> u32 {
        self.0 ^ 0xFFFF_FFFF
    }
}

/// CRC-32/ISO-HDLC of `data`.
pub fn crc32(data: &[u8]) -> u32 {
    let mut c = Crc32::new();
    c.update(data);
    c.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn check_value() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
        let mut c = Crc32::new();
        c.update(b"1234");
        c.update(b"56789");
        assert_eq!(c.finish(), 0xCBF4_3926);
    }
}
