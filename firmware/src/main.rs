//! gough firmware on QEMU mps2-an386: CAN over SLCAN on UART0, a 1 kHz SysTick loop.
//!
//! Boots with the bundled MF 6.1 tyre, answers each `Measurement` with `Forces` (and, once the
//! estimator's table is built, an `Estimate`) at the next tick, takes parameter uploads,
//! settings and commands; `Command::Stop` sends the final `Status`, prints the counters and
//! exits QEMU with code 0. Run it with `gough firmware run` (bridges UART0 to TCP), or
//! `cargo run --release` (UART0 on stdio).
//!
//! Contexts, by priority: the UART0 receive interrupt (bytes → queue); SysTick, every ms: poll
//! (frames → messages, commands at once, measurements queued) and tick (the queued measurements
//! through their wheels' pipelines), then the table mailbox; thread mode: builds the estimator's
//! table when the App asks for one (at boot and after each parameter upload; ~10 000 Magic
//! Formula evaluations), preempted by both, and sleeps otherwise. A build never delays a frame
//! or a tick.
#![no_std]
#![no_main]

use core::cell::RefCell;
use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;
use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::hprintln;
use critical_section::Mutex;
use gough::mu::{BuildError, GoughTable};
use gough::proto::ParamSource;
use gough_firmware::app::{self, App, Event, TableJob};
use gough_firmware::mps2::{self, SlcanPort};
use gough_firmware::{stack, BUNDLED_TIR};

/// The device state: set up by `main` before SysTick starts, then used by SysTick only.
static mut APP: App = App::new();
/// The CAN port: likewise.
static mut PORT: Option<SlcanPort> = None;
/// The estimators' table (its size: the `table build` line of the `bench` output). Written by thread mode only while a [`TableJob`] is out (the
/// App then holds no reference to it); read through the App's `&'static` once installed.
static mut TABLE: MaybeUninit<GoughTable<f32>> = MaybeUninit::uninit();

type Built = (u32, Result<&'static GoughTable<f32>, BuildError>);

/// SysTick ↔ thread mode: a table job out, a finished build back.
struct Mailbox {
    job: Option<TableJob>,
    done: Option<Built>,
}

static MAILBOX: Mutex<RefCell<Mailbox>> = Mutex::new(RefCell::new(Mailbox {
    job: None,
    done: None,
}));

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
        app.estimator = true;
        app.stack_probe = Some(stack::peak);
        if let Err(line) = app.load_tir(BUNDLED_TIR, ParamSource::Bundled) {
            hprintln!("bundled tyre rejected at line {}", line);
            mps2::exit(false);
        }
        hprintln!(
            "gough firmware ready: params {:08x}",
            app.status().param_hash
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
        let job = critical_section::with(|cs| MAILBOX.borrow_ref_mut(cs).job.take());
        match job {
            Some(job) => {
                // SAFETY: a job is out, so the App holds no reference into TABLE (it dropped
                // them in `table_job`) and takes none until this build is handed back below;
                // thread mode is the only writer.
                let slot = unsafe { &mut *addr_of_mut!(TABLE) };
                let built = app::build_table(&job, slot);
                critical_section::with(|cs| {
                    MAILBOX.borrow_ref_mut(cs).done = Some((job.gen, built));
                });
            }
            // Sleep until the next interrupt (a byte, a tick).
            None => cortex_m::asm::wfi(),
        }
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
    let done = critical_section::with(|cs| MAILBOX.borrow_ref_mut(cs).done.take());
    if let Some((gen, built)) = done {
        app.table_built(port, gen, built);
    }
    if let Some(job) = app.table_job() {
        critical_section::with(|cs| MAILBOX.borrow_ref_mut(cs).job = Some(job));
    }
}
