//! gough firmware on an STM32F405 with bxCAN1 (PB8 RX, PB9 TX) at 500 kbit/s, through
//! stm32f4xx-hal. The same `App` as on QEMU; the driver is `bxcan::Can`, which implements
//! `embedded_can::nb::Can`. defmt logs over RTT. Built and linked in CI (flash/RAM reported
//! by `cargo xtask test-all`); not run there (no hardware).
//!
//! Magic Formula and transient filter only: the friction estimator's table (98 KB, and as much
//! again of stack while the core builds it by value) does not fit the 128 KiB SRAM next to the
//! App, so `App::estimator` stays off here — no table job, no `Estimate`, commits acknowledged
//! at once.
#![no_std]
#![no_main]

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m_rt::{entry, exception};
use defmt_rtt as _;
use gough::proto::ParamSource;
use gough_firmware::app::{App, Event};
use gough_firmware::{stack, BUNDLED_TIR};
use stm32f4xx_hal::{can::Can, pac, prelude::*, rcc::Config};

static TICKS: AtomicU32 = AtomicU32::new(0);
static mut APP: App = App::new();

#[entry]
fn main() -> ! {
    // SAFETY: first thing in main, below the live frames.
    unsafe { stack::paint() };
    // SAFETY: the only reference to APP, taken once.
    let app: &'static mut App = unsafe { &mut *core::ptr::addr_of_mut!(APP) };
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
    let mut syst = cp.SYST;
    syst.set_clock_source(cortex_m::peripheral::syst::SystClkSource::Core);
    syst.set_reload(168_000 - 1);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
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
