//! Instruction counts of the combined-slip Magic Formula on the Cortex-M4F, under QEMU with
//! `-icount shift=0` (one instruction = 1 ns of virtual time; SysTick counts the 25 MHz core
//! clock, i.e. one count per 40 instructions, calibrated below on a loop of known length).
//!
//! Each workload is bracketed by `bench_start`/`bench_stop`: exported, never inlined, with
//! distinct bodies, so an outside instruction counter (a QEMU plugin, a debugger) can check
//! the figures. Printed: instructions per evaluation, and the largest error against the f64
//! path over the same inputs.
#![no_std]
#![no_main]

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::{syst::SystClkSource, SYST};
use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::hprintln;
use gough::math::{Backend, Float, Libm};
use gough::mf::{self, Input, Options, Params};
use gough_firmware::mps2;

static WRAPS: AtomicU32 = AtomicU32::new(0);
const RELOAD: u32 = 0x00FF_FFFF;
/// Evaluations per workload.
const N: usize = 256;

/// Marks the start of a measured workload (its id in r0).
#[no_mangle]
#[inline(never)]
pub extern "C" fn bench_start(id: u32) {
    core::hint::black_box(id);
    cortex_m::asm::nop();
}

/// Marks the end of a measured workload (its id in r0).
#[no_mangle]
#[inline(never)]
pub extern "C" fn bench_stop(id: u32) {
    core::hint::black_box(id.wrapping_add(0x5700));
    cortex_m::asm::nop();
    cortex_m::asm::nop();
}

fn now() -> u64 {
    loop {
        let w = WRAPS.load(Ordering::SeqCst);
        let c = SYST::get_current();
        if WRAPS.load(Ordering::SeqCst) == w {
            return u64::from(w) * u64::from(RELOAD + 1) + u64::from(RELOAD - c);
        }
    }
}

#[exception]
fn SysTick() {
    WRAPS.fetch_add(1, Ordering::SeqCst);
}

fn inputs(i: usize) -> (f64, f64, f64) {
    // A grid over the operating range: Fz 0.5..1.5 FNOMIN, kappa -0.2..0.2, alpha -0.15..0.15.
    let a = (i % 16) as f64 / 15.0;
    let b = ((i / 16) % 16) as f64 / 15.0;
    (
        6752.0 * (0.5 + a),
        -0.2 + 0.4 * b,
        -0.15 + 0.3 * ((i * 7 % 16) as f64 / 15.0),
    )
}

fn input<F: Float>(i: usize) -> Input<F> {
    let (fz, k, a) = inputs(i);
    Input {
        fz: F::from_f64(fz),
        kappa: F::from_f64(k),
        alpha: F::from_f64(a),
        gamma: F::ZERO,
        phit: F::ZERO,
        vx: F::from_f64(16.6),
        p: None,
    }
}

/// Runs workload `id`: N f32 evaluations with backend `M`; returns (counts, max |ΔFx|,|ΔFy|, max |ΔMz|).
fn run<M: Backend<f32>>(
    id: u32,
    p32: &Params<f32>,
    p64: &Params<f64>,
    opts: &Options,
) -> (u64, f64, f64) {
    let mut ins = [Input::<f32>::default(); N];
    for (i, x) in ins.iter_mut().enumerate() {
        *x = input::<f32>(i);
    }
    let mut out = [(0f32, 0f32, 0f32); N];
    bench_start(id);
    let t0 = now();
    for (x, o) in ins.iter().zip(out.iter_mut()) {
        if let Ok(r) = mf::eval::<f32, M>(p32, core::hint::black_box(x), opts) {
            *o = (r.fx, r.fy, r.mz);
        }
    }
    let t1 = now();
    bench_stop(id);
    let (mut ef, mut em) = (0f64, 0f64);
    for (i, o) in out.iter().enumerate() {
        if let Ok(r) = mf::eval::<f64, Libm>(p64, &input::<f64>(i), opts) {
            ef = ef
                .max((o.0 as f64 - r.fx).abs())
                .max((o.1 as f64 - r.fy).abs());
            em = em.max((o.2 as f64 - r.mz).abs());
        }
    }
    (t1 - t0, ef, em)
}

#[entry]
fn main() -> ! {
    let Some(cp) = cortex_m::Peripherals::take() else {
        mps2::exit(false)
    };
    let mut syst = cp.SYST;
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(RELOAD);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
    // After `clear_current` the counter reads 0 until its first reload: wait for it.
    while SYST::get_current() == 0 {}

    // Calibration: a loop of exactly 2 instructions per iteration (subs + bne).
    const LOOPS: u32 = 1_000_000;
    bench_start(0);
    let t0 = now();
    // SAFETY: a register-only countdown loop.
    unsafe {
        core::arch::asm!("1:", "subs {0}, #1", "bne 1b", inout(reg) LOOPS => _, options(nomem, nostack));
    }
    let t1 = now();
    bench_stop(0);
    let per_count = (2 * LOOPS) as f64 / (t1 - t0) as f64;
    hprintln!("calibration: {} instructions per SysTick count", per_count);

    let Ok(t) = gough::tir::parse(gough_firmware::BUNDLED_TIR) else {
        mps2::exit(false)
    };
    let p64 = t.params;
    let p32 = p64.cast::<f32>();
    let opts = Options::default();
    let (c, ef, em) = run::<Libm>(1, &p32, &p64, &opts);
    hprintln!(
        "libm: {} instructions per combined evaluation (Fx, Fy, Mz, Mx, My); max error vs f64: forces {:.3e} N, Mz {:.3e} N m",
        (c as f64 * per_count / N as f64) as u32, ef, em
    );
    #[cfg(feature = "micromath")]
    {
        let (c, ef, em) = run::<gough::math::Micromath>(2, &p32, &p64, &opts);
        hprintln!(
            "micromath: {} instructions per combined evaluation; max error vs f64: forces {:.3e} N, Mz {:.3e} N m",
            (c as f64 * per_count / N as f64) as u32, ef, em
        );
    }
    #[cfg(feature = "fast")]
    {
        let (c, ef, em) = run::<gough::math::Fast>(3, &p32, &p64, &opts);
        hprintln!(
            "fast: {} instructions per combined evaluation; max error vs f64: forces {:.3e} N, Mz {:.3e} N m",
            (c as f64 * per_count / N as f64) as u32,
            ef,
            em
        );
    }
    #[cfg(not(feature = "micromath"))]
    hprintln!(
        "micromath: not built (firmware feature `micromath` needs gough's `micromath` backend)"
    );
    mps2::exit(true)
}
