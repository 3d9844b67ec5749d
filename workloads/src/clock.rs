//! The benches' cycle clock: SysTick counting the core clock down from [`RELOAD`] (its 24
//! bits), its wraps counted by the SysTick exception, read as one count since the start; the
//! calibration of counts against instructions on a loop of known length, and the clock's own
//! cost per reading. Under QEMU with `-icount` the core clock is virtual time, so counts
//! convert to instructions exactly (64 ns each with `shift=6`, 1 ns with `shift=0`).
//!
//! Each bench binary declares the exception and calls [`on_systick`] from it (`cortex-m-rt`
//! takes exception handlers from the binary):
//!
//! ```ignore
//! #[exception]
//! fn SysTick() {
//!     gough_workloads::clock::on_systick();
//! }
//! ```
//!
//! [`start_systick`] is also how the firmware starts its 1 kHz tick.

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::{syst::SystClkSource, SYST};

/// SysTick's reload for the cycle clock: the full 24 bits.
pub const RELOAD: u32 = 0x00FF_FFFF;

/// Readings of the clock's own cost averaged by [`overhead`].
pub const OVERHEAD_RUNS: u32 = 64;

/// SysTick wraps since [`start`].
static WRAPS: AtomicU32 = AtomicU32::new(0);

/// Starts SysTick on the core clock, counting down from `reload`, with its exception.
pub fn start_systick(syst: &mut SYST, reload: u32) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(reload);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

/// Starts the cycle clock ([`start_systick`] with [`RELOAD`]) and waits for its first reload
/// (after `clear_current` the counter reads 0 until then).
pub fn start(mut syst: SYST) {
    start_systick(&mut syst, RELOAD);
    while SYST::get_current() == 0 {}
}

/// The SysTick exception's body in a bench binary: counts a wrap. (A load and a store: ARMv6-M
/// has no read-modify-write atomics, and this handler is the only writer.)
pub fn on_systick() {
    WRAPS.store(
        WRAPS.load(Ordering::SeqCst).wrapping_add(1),
        Ordering::SeqCst,
    );
}

/// Counts of the core clock since [`start`] (a wrap that lands between the two reads of the
/// wrap count is read again).
pub fn now() -> u64 {
    loop {
        let w = WRAPS.load(Ordering::SeqCst);
        let c = SYST::get_current();
        if WRAPS.load(Ordering::SeqCst) == w {
            return u64::from(w) * u64::from(RELOAD + 1) + u64::from(RELOAD - c);
        }
    }
}

/// Instructions per count: `loops` turns of a loop of exactly 2 instructions (subs + bne)
/// timed by the clock.
pub fn calibrate(loops: u32) -> f64 {
    let t0 = now();
    // SAFETY: a register-only countdown loop (r0: a low register, as ARMv6-M's 16-bit `subs`
    // needs).
    unsafe {
        core::arch::asm!("1:", "subs r0, #1", "bne 1b", inout("r0") loops => _, options(nomem, nostack));
    }
    let t1 = now();
    2.0 * f64::from(loops) / (t1 - t0) as f64
}

/// The clock's own cost of timing nothing \[counts\], the mean over [`OVERHEAD_RUNS`] readings:
/// what a timed bracket subtracts.
pub fn overhead() -> f64 {
    let mut o = 0u64;
    for _ in 0..OVERHEAD_RUNS {
        let t0 = now();
        core::hint::black_box(0);
        o += now() - t0;
    }
    o as f64 / f64::from(OVERHEAD_RUNS)
}
