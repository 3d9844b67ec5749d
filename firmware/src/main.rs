//! gough firmware on QEMU mps2-an386: CAN over SLCAN on UART0, a 1 kHz SysTick loop.
//!
//! Boots with the bundled MF 6.1 tyre, answers each `Measurement` with `Forces` and an
//! `Estimate` (the wheel's friction estimator) at the next tick, takes parameter uploads,
//! settings and commands secured with the key provisioned in `mps2::KEY_SLOT` (none: it refuses
//! them; the epoch is the boot counter in `gough-nv.bin`, `mps2::next_epoch`); `Command::Stop` sends the final `Status`, prints the counters and
//! exits QEMU with code 0. Run it with `gough firmware run` (bridges UART0 to TCP), or
//! `cargo run --release` (UART0 on stdio).
//!
//! Contexts, by priority: the UART0 receive interrupt (bytes → queue); SysTick, every ms: poll
//! (frames → messages, commands at once, measurements queued) and tick (the queued measurements
//! through their wheels' pipelines: transient filter, Magic Formula, friction estimator);
//! thread mode sleeps. Nothing runs outside the interrupts: a parameter upload starts the
//! estimators at once (one Magic Formula evaluation each), and each estimator's work per sample
//! is bounded.
#![no_std]
#![no_main]

use core::ptr::addr_of_mut;
use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::hprintln;
use gough::proto::{ParamSource, Policy, Verifier};
use gough_firmware::app::{App, Event};
use gough_firmware::mps2::{self, SlcanPort};
use gough_firmware::{stack, BUNDLED_TIR};

/// The device state: set up by `main` before SysTick starts, then used by SysTick only.
static mut APP: App = App::new();
/// The CAN port: likewise.
static mut PORT: Option<SlcanPort> = None;
/// Poll calls per tick (each handles at most a budget of frames).
const POLLS: usize = 8;

#[entry]
fn main() -> ! {
    // SAFETY: first thing in main, below the live frames.
    unsafe { stack::paint() };
    {
        // SAFETY: SysTick is not started yet: the only reference to APP.
        let app: &mut App = unsafe { &mut *addr_of_mut!(APP) };
        app.can_stop = true;
        app.stack_probe = Some(stack::peak);
        if let Err(line) = app.load_tir(BUNDLED_TIR, ParamSource::Bundled) {
            hprintln!("bundled tyre rejected at line {}", line);
            mps2::exit(false);
        }
        // The key provisioned at flash time, and this boot's epoch (the non-volatile boot
        // counter, raised now): without either, every state-changing message is refused.
        let key = match (mps2::provisioned_key(), mps2::next_epoch()) {
            (Some((key, mac_len, policy)), Some(epoch)) => {
                app.provision(Verifier::new(key, mac_len, epoch).with_policy(policy));
                app.epoch_store = Some(mps2::store_epoch);
                match policy {
                    Policy::StateChanging => "provisioned",
                    Policy::All => "provisioned, every message authenticated",
                }
            }
            (Some(_), None) => "provisioned, but no epoch could be stored: refused",
            (None, _) => "none: state-changing messages refused",
        };
        hprintln!(
            "gough firmware ready: params {:08x}, key {}",
            app.status().param_hash,
            key
        );
    }
    let mut cp = cortex_m::Peripherals::take().unwrap_or_else(|| mps2::exit(false));
    let port = SlcanPort::take_uart0().unwrap_or_else(|| mps2::exit(false));
    // SAFETY: SysTick is not started yet: the only reference to PORT.
    unsafe { *addr_of_mut!(PORT) = Some(port) };
    mps2::set_priorities(&mut cp.SCB, &mut cp.NVIC);
    mps2::start_systick(cp.SYST);
    defmt::info!("gough firmware {=[u8]} up", &gough_firmware::VERSION[..]);
    loop {
        // Sleep until the next interrupt (a byte, a tick).
        cortex_m::asm::wfi();
    }
}

#[exception]
fn SysTick() {
    let now = mps2::on_systick();
    // SAFETY: once main has started SysTick, this handler is the only user of APP and PORT,
    // and it does not preempt itself.
    let app: &mut App = unsafe { &mut *addr_of_mut!(APP) };
    let Some(port) = (unsafe { (*addr_of_mut!(PORT)).as_mut() }) else {
        return;
    };
    for _ in 0..POLLS {
        app.link_errors = port.errors;
        match app.poll(port, now) {
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
        if !port.rx_pending() {
            break;
        }
    }
    app.tick(port, now);
}
