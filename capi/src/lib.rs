//! gough's C API: the core for C firmware, as the static library `libgough.a` and
//! the header `capi/include/gough.h` (generated from this crate by cbindgen: `cargo xtask header`;
//! `cargo xtask test-all` fails when the checked-in header differs from a fresh generation).
//!
//! - **No allocation**: every state lives in an opaque, 8-byte aligned storage struct that the
//!   caller declares (`static`, or on its stack) — `gough_params_t`, `gough_wheel_t`,
//!   `gough_estimator_t`, `gough_preview_t`, `gough_rx_t`; their sizes are the `GOUGH_*_SIZE` macros. An
//!   `*_init`/`*_parse` call writes a storage and marks it; any other call on a storage that was
//!   not written so returns `GOUGH_E_UNINIT`.
//! - **No panics across the boundary**: the core does not panic; every function returns
//!   `GOUGH_OK` (0) or a negative `GOUGH_E_*` code. A null pointer is an error
//!   (`GOUGH_E_NULL`), never a crash; the pointers documented as optional may be null.
//! - **Borrowed storage**: a wheel and an estimator keep a pointer to the parameter storage
//!   they were initialised with: that storage must outlive them and must not be rewritten while
//!   they are used.
//! - **Units and axes**: SI units; forces and moments in ISO-W (the wheel's contact point: x
//!   forward, y left, z up), as `gough::mf`.
//!
//! The math backend is `gough::math::Fast` in f32 (what the firmware runs: a C image and the
//! Rust firmware compute the same bits) and `gough::math::Libm` in f64 (`gough_mf_eval_f64`,
//! MFeval's precision).
#![cfg_attr(target_os = "none", no_std)]
#![allow(non_camel_case_types)]
// Raw pointers from C are checked for null before use; each `unsafe` block says why it holds.
#![allow(clippy::missing_safety_doc)]
// The core is a dependency named `core_gough` here: this library's own name is `gough`.

// One module per part of the API, declared in the header's order (cbindgen follows it; rustfmt
// keeps each in its own group); their items are the crate's (`pub use`), as C sees them.
mod codes;

mod storage;

mod tir;

mod formula;

mod pipeline;

mod estimator;

mod preview;

mod protocol;

pub use codes::*;
pub use estimator::*;
pub use formula::*;
pub use pipeline::*;
pub use preview::*;
pub use protocol::*;
pub use storage::*;
pub use tir::*;

// What the modules share: the core's types and the standard pointers and sizes.
use core::mem::{align_of, size_of};
use core::ptr;
use core_gough::math::{Fast, Libm};
use core_gough::mf::{self, EvalError, Input, Options, Params, Side};
use core_gough::mu::preview::Preview;
use core_gough::mu::{self, Bank};
use core_gough::proto::{self, Feed, Msg, Mtu, Reassembler, Segmenter, Settings, MSG_BUF};
use core_gough::wheel::{self, Corner};

/// On the device the core never panics; the handler must still exist. It stops the core
/// (an ABS/ESC controller's watchdog takes over).
#[cfg(target_os = "none")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    loop {
        core::hint::spin_loop();
    }
}

#[cfg(test)]
mod tests;
