//! The bench workloads of gough's firmware images, one definition for every place that runs
//! them: the M4F firmware's `bench` and `profile` binaries, the M0/M3 bench (`firmware-m0`) and
//! its build script, which computes on the host what the device must reproduce.
//!
//! - [`points`] — the Magic Formula bench's grid of inputs.
//! - [`slalom`] — the friction estimator's measurement stream (a noisy slalom).
//! - [`streams`] — the estimator streams of the no-FPU bench (the slalom at 100 Hz), the bank's
//!   100 Hz settings and the hash of its estimates.
//! - [`filter_point`] — the transient-filter bench's stream.
//! - [`marks`] (feature `marks`) — `bench_start`/`bench_stop`, the markers outside counters find.
//! - `clock` (feature `clock`, Cortex-M targets only) — the SysTick cycle clock the benches time
//!   with, calibrated.
//!
//! `no_std`, no heap; every stream is generated one sample at a time, so a device with little
//! RAM need not hold it, and gives the same bits on every target (IEEE f32, no FMA
//! contraction).
#![no_std]
#![deny(missing_docs)]

#[cfg(all(feature = "clock", target_arch = "arm"))]
pub mod clock;
mod filter;
#[cfg(feature = "marks")]
pub mod marks;
pub mod points;
pub mod slalom;
pub mod streams;

pub use filter::filter_point;
