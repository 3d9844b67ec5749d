//! `gough::tir::parse` must never panic, whatever the text.
//!
//! Run: `cargo +nightly fuzz run tir_parse -- -max_total_time=120` (seed corpus: the bundled
//! `.tir` files in `corpus/tir_parse/`).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(s) = core::str::from_utf8(data) {
        let _ = gough::tir::parse(s);
    }
});
