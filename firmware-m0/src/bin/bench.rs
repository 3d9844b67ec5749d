//! Instruction counts of the combined-slip Magic Formula, of one transient-filter step and of the
//! friction estimator at 100 Hz (`mu::bank::Bank`, one 10 ms sample per batch) on a Cortex-M0
//! without FPU (QEMU's `microbit`, an nRF51822) and on a Cortex-M3 without FPU (`--target
//! thumbv7m-none-eabi`, QEMU's `mps2-an385`), soft-float f32 with `math::Fast` (feature `fast`)
//! against Q31.32 fixed point (`fixed::Fix` + `fixed::FixMath`, feature `fix`); the estimator
//! with feature `mu`. Under
//! QEMU with `-icount shift=0`: one instruction = 1 ns of virtual time, SysTick counts the core
//! clock (16 MHz on the M0: 62.5 instructions per count; 25 MHz on the M3: 40), calibrated on a
//! loop of known length by the benches' clock (`gough_workloads::clock`, the M4F bench's too).
//!
//! The bundled MF 6.1 tyre is parsed by `gough::tir::parse` on the host, in build.rs, and
//! embedded as f64 values, converted at boot to `f32` and `Fix` as `Params::cast` does: parsing
//! on the device does not fit the nRF51822's 16 KiB of RAM (`tir::parse` alone takes a 7.9 KB
//! frame on thumbv6m, plus the `Params<f64>` it returns and the cast copies; it overflowed). Each
//! workload is bracketed by `bench_start`/`bench_stop` (exported, never inlined, distinct
//! bodies). It runs the points in blocks of [`B`] (inputs built before the clock starts, outputs
//! checked after it stops; the timer's own cost is subtracted); the largest error is against the
//! f64 reference that build.rs computes on the host for the same points.
#![no_std]
#![no_main]

use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::{debug, hprintln};
use gough::math::{Backend, Float};
use gough::mf::{self, Input, Options, Params};

// The workloads and markers of the M4F bench (one definition for both), and what build.rs
// computed from them on the host (this crate's own build output).
use gough_workloads::filter_point;
use gough_workloads::clock::{self, now};
use gough_workloads::marks::{bench_start, bench_stop};
use gough_workloads::points::{input, N};
#[cfg(feature = "mu")]
use gough_workloads::streams::{bank_sample, config, hash, stream, Feed, HASH0, SAMPLES, STREAMS};
include!(concat!(env!("OUT_DIR"), "/reference.rs"));
include!(concat!(env!("OUT_DIR"), "/estimator.rs"));

/// Points per timed block.
const B: usize = 16;
const PAINT: u32 = 0xDEAD_BEEF;

fn exit(ok: bool) -> ! {
    debug::exit(if ok {
        debug::EXIT_SUCCESS
    } else {
        debug::EXIT_FAILURE
    });
    #[allow(clippy::empty_loop)]
    loop {}
}

/// Panics print their message through semihosting and exit QEMU with failure, never hang.
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    cortex_m::interrupt::disable();
    hprintln!("panicked: {}", info);
    exit(false)
}

#[exception]
unsafe fn HardFault(frame: &cortex_m_rt::ExceptionFrame) -> ! {
    hprintln!("HardFault at pc {:#010x}", frame.pc());
    exit(false)
}

#[exception]
fn SysTick() {
    clock::on_systick();
}

extern "C" {
    static mut __sheap: u32;
    static _stack_start: u32;
}

/// Paints the free stack (from the end of static RAM to just below the current frame).
#[inline(never)]
fn paint() {
    let sp = cortex_m::register::msp::read() as usize - 64;
    let mut p = core::ptr::addr_of_mut!(__sheap) as usize;
    while p < sp {
        // SAFETY: unused RAM between the statics and the live stack.
        unsafe { core::ptr::write_volatile(p as *mut u32, PAINT) };
        p += 4;
    }
}

/// Peak stack use since [`paint`] \[bytes\].
fn stack_peak() -> usize {
    let top = core::ptr::addr_of!(_stack_start) as usize;
    let mut p = core::ptr::addr_of_mut!(__sheap) as usize;
    // SAFETY: reads RAM between the statics and the stack top.
    while p < top && unsafe { core::ptr::read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    top - p
}

/// Workload `id`: the N points with scalar `F` and backend `M`. Returns (SysTick counts less the
/// timer's cost, max |ΔFx|,|ΔFy| \[N\], max |ΔMz| \[N m\], failed evaluations).
#[inline(never)]
fn run<F: Float, M: Backend<F>>(id: u32, p: &Params<F>, overhead: u64) -> (u64, f64, f64, usize) {
    // The combined Fx, Fy, Mz (issue 7's unit): Mx, My off.
    let opts = Options {
        moments: false,
        ..Options::default()
    };
    let (mut counts, mut ef, mut em, mut failed) = (0u64, 0f64, 0f64, 0usize);
    bench_start(id);
    for base in (0..N).step_by(B) {
        let ins: [Input<F>; B] = core::array::from_fn(|j| input::<F>(base + j));
        let mut out = [None; B];
        let t0 = now();
        for (x, o) in ins.iter().zip(out.iter_mut()) {
            *o = mf::eval::<F, M>(p, core::hint::black_box(x), &opts)
                .ok()
                .map(|r| (r.fx, r.fy, r.mz));
        }
        let t1 = now();
        counts += (t1 - t0).saturating_sub(overhead);
        for (j, o) in out.iter().enumerate() {
            let r = REF.get(base + j).copied().unwrap_or([f64::NAN; 3]);
            match o {
                Some((fx, fy, mz)) if r.iter().all(|v| v.is_finite()) => {
                    ef = ef
                        .max((fx.to_f64() - r[0]).abs())
                        .max((fy.to_f64() - r[1]).abs());
                    em = em.max((mz.to_f64() - r[2]).abs());
                }
                _ => failed += 1,
            }
        }
    }
    bench_stop(id);
    (counts, ef, em, failed)
}

/// Workload `id`: the transient-slip filter alone (`relax::Transient::step`, eq. 20 exact over
/// the step, eq. 21), one 1 ms step per point as one wheel's 1 kHz stream: kinematics Vsx = κ·Vx,
/// Vsy = tan α·Vx and the relaxation lengths the Magic Formula gives at the point, all computed
/// before the clock starts. Each step's α' and κ' are compared with the f64 reference build.rs
/// computed on the host for the same stream ([`FILTER_REF`]). Returns the SysTick counts less
/// the timer's cost, the failed steps, and the largest errors |Δα'| \[rad\], |Δκ'| \[-\] with the
/// stream's largest reference |α'|, |κ'| (their scales).
#[inline(never)]
fn filter<F: Float, M: Backend<F>>(id: u32, p: &Params<F>, overhead: u64) -> (u64, usize, Errors) {
    use gough::relax::{Config, Kinematics, Sigma, Transient};
    let cfg = Config::from_params(p);
    let dt = F::from_f64(1e-3);
    let mut state = Transient::new(F::ZERO);
    let (mut counts, mut failed, mut err) = (0u64, 0usize, Errors::default());
    bench_start(id);
    for base in (0..N).step_by(B) {
        let ins: [(Kinematics<F>, Sigma<F>); B] =
            core::array::from_fn(|j| filter_point::<F, M>(p, base + j));
        let mut out = [None; B];
        let t0 = now();
        for ((k, s), o) in ins.iter().zip(out.iter_mut()) {
            *o = state.step::<M>(&cfg, dt, core::hint::black_box(k), s).ok();
        }
        let t1 = now();
        counts += (t1 - t0).saturating_sub(overhead);
        for (j, o) in out.iter().enumerate() {
            let [k_ref, a_ref] = FILTER_REF.get(base + j).copied().unwrap_or([f64::NAN; 2]);
            match o {
                Some(sl) if k_ref.is_finite() && a_ref.is_finite() => {
                    let (k, a) = (sl.kappa.to_f64(), sl.alpha.to_f64());
                    // NaN-safe: a non-finite output is a failed step, not a small error.
                    if !(k.is_finite() && a.is_finite()) {
                        failed += 1;
                    }
                    err.alpha = err.alpha.max((a - a_ref).abs());
                    err.kappa = err.kappa.max((k - k_ref).abs());
                    err.alpha_scale = err.alpha_scale.max(a_ref.abs());
                    err.kappa_scale = err.kappa_scale.max(k_ref.abs());
                }
                _ => failed += 1,
            }
        }
    }
    bench_stop(id);
    (counts, failed, err)
}

/// The transient filter's largest errors against f64 over the stream, and its scales.
#[derive(Default)]
struct Errors {
    alpha: f64,
    kappa: f64,
    alpha_scale: f64,
    kappa_scale: f64,
}

impl Errors {
    /// Within 0.5 % of the stream's largest slip, in α' and in κ' (issue 7's bound on the
    /// forces, applied to the filter's outputs, the slips the forces are evaluated at).
    fn ok(&self) -> bool {
        self.alpha <= 0.005 * self.alpha_scale && self.kappa <= 0.005 * self.kappa_scale
    }
}

/// Workload `id`: the friction estimator (`mu::bank::Bank::update` in `F` with backend `M`) at
/// 100 Hz ([`config`]: one 10 ms sample per batch) over each of [`STREAMS`], each sample timed
/// alone (SysTick: ±1 count per sample, exact on the mean); the stream is generated between the
/// samples, outside the clock. Every estimate is hashed and compared with the host's (`expect`,
/// from build.rs): the device must reproduce them bit for bit. Prints a
/// `bench: mu_bank_<core>_<backend>_100hz_<stream> mean=<n> worst=<n> ram=<bytes>` line per
/// stream (instructions per sample; `ram`: the bank's state, `size_of::<Bank<F>>()`). Returns
/// whether all streams matched.
#[cfg(feature = "mu")]
#[inline(never)]
fn bank<F: Float + Feed, M: Backend<F>>(
    id: u32,
    what: &str,
    short: &str,
    expect: &[(u32, u32, u32)],
    per_count: f64,
    overhead: u64,
) -> bool {
    use gough::mu::{Bank, State};
    let p = params::<F>();
    let p32 = params::<f32>();
    let mut ok = true;
    for (k, (&(mu, camber, stream_name, desc), &(want, want_seen, want_last))) in
        STREAMS.iter().zip(expect.iter()).enumerate()
    {
        let Ok(mut est) = Bank::new::<M>(&p, None, config::<F>()) else {
            hprintln!("{}: no bank for the bundled tyre", what);
            return false;
        };
        let (mut sum, mut worst, mut h, mut seen) = (0u64, 0u64, HASH0, 0u32);
        let (mut last, mut last_mu) = (0u32, 0f64);
        bench_start(id + k as u32);
        for m in stream(&p32, mu, camber) {
            let s = bank_sample::<F>(&m);
            let t0 = now();
            let e = est.update::<M>(&p, core::hint::black_box(&s));
            let t1 = now();
            let c = (t1 - t0).saturating_sub(overhead);
            sum += c;
            worst = worst.max(c);
            h = hash(h, &e);
            seen += u32::from(e.state == State::Identifiable);
            last = e.mu.feed(HASH0);
            last_mu = e.mu.to_f64();
        }
        bench_stop(id + k as u32);
        let same = (h, seen, last) == (want, want_seen, want_last);
        let mean = (sum as f64 * per_count / SAMPLES as f64) as u32;
        let worst = (worst as f64 * per_count) as u32;
        hprintln!(
            "{}: estimator at 100 Hz (Bank::update, batch 1), {}: {} instructions per wheel per sample (mean over {} samples; worst sample {}, ±{}); {} identifiable; last μ {:.4}; estimates {} the host's",
            what,
            desc,
            mean,
            SAMPLES,
            worst,
            (per_count + 0.5) as u32,
            seen,
            last_mu,
            if same { "identical to" } else { "DIFFER from" }
        );
        hprintln!(
            "bench: mu_bank_{}_{}_100hz_{} mean={} worst={} ram={}",
            env!("GOUGH_CORE_LC"),
            short,
            stream_name,
            mean,
            worst,
            core::mem::size_of::<Bank<F>>()
        );
        ok &= same && seen > 0;
    }
    ok
}

fn report(name: &str, per_count: f64, (c, ef, em, failed): (u64, f64, f64, usize)) -> bool {
    hprintln!(
        "{}: {} instructions per combined Fx, Fy, Mz evaluation (mean over {} points); max error vs f64: forces {:.3e} N, Mz {:.3e} N m; failed {}",
        name,
        (c as f64 * per_count / N as f64) as u32,
        N,
        ef,
        em,
        failed
    );
    failed == 0 && ef < 1.0 && em < 0.1
}

/// The bundled tyre in `F`: the f64 values `gough::tir::parse` read on the host (build.rs),
/// converted as [`Params::cast`] does.
#[inline(never)]
fn params<F: Float>() -> Params<F> {
    let mut p = Params::<F>::zeroed(VERSION);
    p.tyreside = TYRESIDE;
    for &(k, v) in PARAMS.iter() {
        p.set(k, F::from_f64(v));
    }
    p
}

/// One workload in a frame of its own (main's stays small: 16 KiB of RAM): parameters, the
/// Magic Formula, then the filter.
#[inline(never)]
fn workload<F: Float, M: Backend<F>>(id: u32, name: &str, per_count: f64, overhead: u64) -> bool {
    let p = params::<F>();
    let ok = report(name, per_count, run::<F, M>(id, &p, overhead));
    let (c, failed, e) = filter::<F, M>(id + 10, &p, overhead);
    hprintln!(
        "{}: {} instructions per transient-filter step (relax::Transient::step, mean over {} steps); max error vs f64: α' {:.3e} rad ({:.2e} of the largest |α'|, {:.4} rad), κ' {:.3e} ({:.2e} of the largest |κ'|, {:.4}); failed {}",
        name,
        (c as f64 * per_count / N as f64) as u32,
        N,
        e.alpha,
        e.alpha / e.alpha_scale,
        e.alpha_scale,
        e.kappa,
        e.kappa / e.kappa_scale,
        e.kappa_scale,
        failed
    );
    ok && failed == 0 && e.ok()
}

#[entry]
fn main() -> ! {
    paint();
    let Some(cp) = cortex_m::Peripherals::take() else {
        exit(false)
    };
    clock::start(cp.SYST);

    // Calibration: a loop of exactly 2 instructions per iteration (subs + bne).
    const LOOPS: u32 = 1_000_000;
    bench_start(0);
    let per_count = clock::calibrate(LOOPS);
    bench_stop(0);
    hprintln!("calibration: {} instructions per SysTick count", per_count);
    // The timer's own cost per bracket [counts] (whole counts).
    let overhead = clock::overhead() as u64;

    let mut ok = true;
    #[cfg(feature = "fast")]
    {
        ok &= workload::<f32, gough::math::Fast>(
            1,
            concat!(env!("GOUGH_CORE"), " soft-float f32, math::Fast"),
            per_count,
            overhead,
        );
    }
    #[cfg(all(feature = "mu", feature = "fast"))]
    {
        ok &= bank::<f32, gough::math::Fast>(
            30,
            concat!(env!("GOUGH_CORE"), " soft-float f32, math::Fast"),
            "fast",
            &EXPECT,
            per_count,
            overhead,
        );
    }
    #[cfg(feature = "fix")]
    {
        use gough::fixed::{Fix, FixMath};
        ok &= workload::<Fix, FixMath>(
            2,
            concat!(env!("GOUGH_CORE"), " Q31.32 fixed::Fix + FixMath"),
            per_count,
            overhead,
        );
    }
    #[cfg(all(feature = "mu", feature = "fix"))]
    {
        use gough::fixed::{Fix, FixMath};
        ok &= bank::<Fix, FixMath>(
            40,
            concat!(env!("GOUGH_CORE"), " Q31.32 fixed::Fix + FixMath"),
            "fix",
            &EXPECT_FIX,
            per_count,
            overhead,
        );
    }
    hprintln!(
        "stack peak {} bytes; Params<f32> {} bytes; Bank<f32> {} bytes",
        stack_peak(),
        core::mem::size_of::<Params<f32>>(),
        core::mem::size_of::<gough::mu::bank::Bank<f32>>()
    );
    exit(ok)
}
