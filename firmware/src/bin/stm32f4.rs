//! gough firmware on an STM32F405 with bxCAN1 (PB8 RX, PB9 TX) at 500 kbit/s, through
//! stm32f4xx-hal. The same `App` as on QEMU; the driver is `bxcan::Can`, which implements
//! `embedded_can::nb::Can`. defmt logs over RTT. Built and linked in CI (flash/RAM reported
//! by `cargo xtask test-all`); not run there (no hardware).
//!
//! Memory (`boards/stm32f405.x`): the App (~46 KiB: the 32 KiB upload buffer, the four wheels'
//! filters and friction estimators ~10 KiB, the parameters) lives in the 128 KiB SRAM with the
//! rest of `.data`/`.bss`; the stack has the 64 KiB CCM to itself (core-coupled: no DMA, which
//! the stack never needs), at least 20 KiB of it checked at link time (`cargo xtask firmware`
//! reports this image's SRAM and CCM use). A static that should live in CCM goes in the
//! `.ccmdata` section, whose initial values are copied from flash first thing in `main`
//! (cortex-m-rt initialises only SRAM); none does now.
//!
//! The loop polls bxCAN (whose receive FIFOs hold 3 frames each) and runs a tick per
//! millisecond; a parameter upload starts the estimators at once, so no long job runs between
//! polls. A board that must never lose frames while a tick runs would move polling into the
//! CAN receive interrupt, as the QEMU board does with its UART.
#![no_std]
#![no_main]

use core::ptr::addr_of_mut;
use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m_rt::{entry, exception};
use defmt_rtt as _;
use gough::proto::ParamSource;
use gough_firmware::app::{App, Event};
use gough_firmware::{stack, BUNDLED_TIR};
use stm32f4xx_hal::{can::Can, pac, prelude::*, rcc::Config};

static TICKS: AtomicU32 = AtomicU32::new(0);
/// The device state, in SRAM (`.data`: cortex-m-rt copies its initial value from flash); the
/// stack has the CCM.
static mut APP: App = App::new();

extern "C" {
    // boards/stm32f405.x: the `.ccmdata` section in CCM and its load address in flash.
    static mut __sccmdata: u32;
    static mut __eccmdata: u32;
    static __siccmdata: u32;
}

/// Copies `.ccmdata`'s initial values from flash to CCM, word by word.
///
/// # Safety
/// Call once, before anything reads or writes a `.ccmdata` static.
unsafe fn ccm_init() {
    let mut dst = addr_of_mut!(__sccmdata);
    let end = addr_of_mut!(__eccmdata);
    let mut src: *const u32 = core::ptr::addr_of!(__siccmdata);
    while dst < end {
        dst.write_volatile(src.read());
        dst = dst.add(1);
        src = src.add(1);
    }
}

#[entry]
fn main() -> ! {
    // SAFETY: first thing in main: nothing has touched a `.ccmdata` static; the stack lies
    // above `.ccmdata`.
    unsafe { ccm_init() };
    // SAFETY: below the live frames.
    unsafe { stack::paint() };
    // SAFETY: the only reference to APP, taken once.
    let app: &'static mut App = unsafe { &mut *addr_of_mut!(APP) };
    app.stack_probe = Some(stack::peak);
    let _ = app.load_tir(BUNDLED_TIR, ParamSource::Bundled);
    let (Some(dp), Some(cp)) = (pac::Peripherals::take(), cortex_m::Peripherals::take()) else {
        halt()
    };
    let mut rcc = dp
        .RCC
        .freeze(Config::hse(8.MHz()).sysclk(168.MHz()).pclk1(42.MHz()));
    let gpiob = dp.GPIOB.split(&mut rcc);
    let can = Can::new(dp.CAN1, (gpiob.pb9, gpiob.pb8), &mut rcc);
    // 500 kbit/s at 42 MHz APB1: BRP 6, TS1 11, TS2 2 (sample point 85.7 %).
    let mut can = bxcan::Can::builder(can)
        .set_bit_timing(0x001b_0005)
        .enable();
    can.modify_filters()
        .enable_bank(0, bxcan::Fifo::Fifo0, bxcan::filter::Mask32::accept_all());
    // SysTick at 1 kHz of the 168 MHz core clock.
    let mut syst = cp.SYST;
    gough_workloads::clock::start_systick(&mut syst, 168_000 - 1);
    defmt::info!("gough firmware on STM32F405 up");
    let mut last = 0;
    loop {
        let now = TICKS.load(Ordering::Relaxed);
        if let Some(Event::Reset) = app.poll(&mut can, now) {
            cortex_m::peripheral::SCB::sys_reset();
        }
        if now != last {
            last = now;
            app.tick(&mut can, now);
        }
    }
}

fn halt() -> ! {
    loop {
        cortex_m::asm::wfi();
    }
}

#[exception]
fn SysTick() {
    TICKS.fetch_add(1, Ordering::Relaxed);
}

#[exception]
unsafe fn HardFault(_frame: &cortex_m_rt::ExceptionFrame) -> ! {
    cortex_m::peripheral::SCB::sys_reset()
}

#[panic_handler]
fn panic(_info: &core::panic::PanicInfo) -> ! {
    cortex_m::peripheral::SCB::sys_reset()
}

#[defmt::panic_handler]
fn defmt_panic() -> ! {
    cortex_m::peripheral::SCB::sys_reset()
}
