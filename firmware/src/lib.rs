//! gough firmware: the board-independent application ([`app`]) and the boards.
//!
//! The loop (docs/architecture.md): CAN frames → `proto::Reassembler` → `Msg`; measurements
//! are queued and, at each 1 kHz tick, run through their wheel's pipeline ([`gough::wheel`]: the
//! relaxation-length filter, `mf::eval` at the transient slips, the friction estimator
//! [`gough::mu::Bank`]; f32, `math::Fast` by default); the predicted forces and the estimates go
//! back as `Msg::Forces` and `Msg::Estimate` through `proto::Segmenter`.
//!
//! Boards: [`mps2`] (QEMU mps2-an386: SLCAN over the CMSDK UART0, SysTick, semihosting) and
//! `src/bin/stm32f4.rs` (STM32F405, bxCAN1 through stm32f4xx-hal). Any driver implementing
//! `embedded_can::nb::Can` plugs into [`app::App::poll`] and [`app::App::tick`].
#![no_std]

#[cfg(all(feature = "mps2", feature = "stm32f4"))]
compile_error!("choose one board: `mps2` (default) or `--no-default-features --features stm32f4`");

pub mod app;
#[cfg(feature = "mps2")]
pub mod mps2;
pub mod stack;

/// Firmware version reported in `Status` (major, minor, patch).
pub const VERSION: [u8; 3] = [0, 4, 0];

/// The parameter set a device boots with, until one is uploaded.
pub const BUNDLED_TIR: &str =
    include_str!("../../host-tests/data/tyres/MagicFormula61_Parameters.tir");
