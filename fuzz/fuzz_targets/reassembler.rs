//! `proto::Reassembler::feed` on any frame sequence: never panics, every delivered message
//! re-encodes. Input: frames as [len, bytes...] records,
//! each with a time step. The CRC check is skipped under `cfg(fuzzing)`, so bodies are reached.
//!
//! Run: `cargo +nightly fuzz run reassembler -- -max_total_time=60` (seed corpus: real frames
//! in `corpus/reassembler/`).
#![no_main]

use gough::proto::{Feed, Reassembler, MSG_BUF};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut r = Reassembler::<MSG_BUF>::new();
    let mut now = 0u32;
    let mut rest = data;
    while let Some((&head, tail)) = rest.split_first() {
        let n = usize::from(head & 0x7F).min(tail.len());
        now = now.wrapping_add(u32::from(head >> 7) * 60);
        let (frame, t) = tail.split_at(n);
        rest = t;
        if let Feed::Done(m) = r.feed(frame, now) {
            let mut buf = [0u8; gough::proto::MAX_MSG_LEN];
            assert!(m.encode(&mut buf).is_ok());
        }
    }
});
