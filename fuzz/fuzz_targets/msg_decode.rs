//! `proto::Msg::decode` on any bytes: never panics; whatever decodes re-encodes and decodes to
//! the same message (the CRC is not checked under `cfg(fuzzing)`).
//!
//! Run: `cargo +nightly fuzz run msg_decode -- -max_total_time=60`.
#![no_main]

use gough::proto::{Msg, MAX_MSG_LEN};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(m) = Msg::decode(data) {
        let mut buf = [0u8; MAX_MSG_LEN];
        let n = m.encode(&mut buf).expect("a decoded message re-encodes");
        let again = Msg::decode(&buf[..n]).expect("and decodes again");
        // NaN != NaN: compare the encodings instead of the values.
        let mut buf2 = [0u8; MAX_MSG_LEN];
        let n2 = again.encode(&mut buf2).expect("re-encodes");
        assert_eq!(&buf[..n], &buf2[..n2]);
    }
});
