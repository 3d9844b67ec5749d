//! `proto::slcan::Decoder` on any byte stream: never panics; every decoded frame re-encodes
//! to a line that decodes to the same frame.
//!
//! Run: `cargo +nightly fuzz run slcan -- -max_total_time=60`.
#![no_main]

use gough::proto::slcan::{encode, Decoder, Line, MAX_LINE};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut d = Decoder::new();
    for &b in data {
        if let Some(Ok(Line::Frame(f))) = d.push(b) {
            let mut out = [0u8; MAX_LINE];
            let line = encode(&f, &mut out);
            let mut d2 = Decoder::new();
            let back: Vec<_> = line.iter().filter_map(|&c| d2.push(c)).collect();
            assert_eq!(back, [Ok(Line::Frame(f))]);
        }
    }
});
