//! gough firmware on QEMU mps2-an386: CAN over SLCAN on UART0, a 1 kHz SysTick loop.
//!
//! Boots with the bundled MF 6.1 tyre, answers each `Measurement` with `Forces` at the next
//! tick, takes parameter uploads, settings and commands; `Command::Stop` sends the final
//! `Status`, prints the counters and exits QEMU with code 0. Run it with `gough firmware run`
//! (bridges UART0 to TCP), or `cargo run --release` (UART0 on stdio).
#![no_std]
#![no_main]

use core::sync::atomic::Ordering;
use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::hprintln;
use gough::proto::ParamSource;
use gough_firmware::app::{App, Event};
use gough_firmware::mps2::{self, SlcanPort, TICKS};
use gough_firmware::{stack, BUNDLED_TIR};

static mut APP: App = App::new();

#[entry]
fn main() -> ! {
    // SAFETY: first thing in main, below the live frames.
    unsafe { stack::paint() };
    // SAFETY: the only reference to APP, taken once.
    let app: &'static mut App = unsafe { &mut *core::ptr::addr_of_mut!(APP) };
    app.can_stop = true;
    app.stack_probe = Some(stack::peak);
    if let Err(line) = app.load_tir(BUNDLED_TIR, ParamSource::Bundled) {
        hprintln!("bundled tyre rejected at line {}", line);
        mps2::exit(false);
    }
    let cp = cortex_m::Peripherals::take().unwrap_or_else(|| mps2::exit(false));
    let mut port = SlcanPort::take_uart0().unwrap_or_else(|| mps2::exit(false));
    mps2::start_systick(cp.SYST);
    defmt::info!("gough firmware {=[u8]} up", &gough_firmware::VERSION[..]);
    hprintln!(
        "gough firmware ready: params {:08x}",
        app.status().param_hash
    );
    let mut last = 0u32;
    loop {
        let now = TICKS.load(Ordering::Relaxed);
        app.link_errors = port.errors;
        match app.poll(&mut port, now) {
            Some(Event::Stop) => {
                let s = app.status();
                defmt::info!("stop: {}", s);
                hprintln!(
                    "stop: rx frames {} messages {} dropped {} duplicates {}; link errors {}; eval errors {}; tx {}; stack peak {} bytes",
                    s.rx.frames,
                    s.rx.messages,
                    s.rx.dropped(),
                    s.rx.duplicates,
                    s.link_errors,
                    s.eval_errors,
                    s.tx_messages,
                    s.stack_peak
                );
                mps2::exit(true);
            }
            Some(Event::Reset) => cortex_m::peripheral::SCB::sys_reset(),
            None => {}
        }
        if now != last {
            last = now;
            app.tick(&mut port, now);
        } else if !port.rx_pending() {
            // Sleep until the next byte (UART0 RX interrupt) or tick (SysTick).
            cortex_m::asm::wfi();
        }
    }
}

#[exception]
fn SysTick() {
    mps2::on_systick();
}
