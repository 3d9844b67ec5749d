//! The Rust side of the C API's example: the same work as
//! `capi/examples/m4f/main.c`, through the Rust API the firmware uses (`gough::wheel::Corner`,
//! `gough::mu::bank::Bank`, `gough::proto`, math backend `app::Math`), printing the same result
//! lines — `cargo xtask test-all` compares them to the bit — and the same bench line for the
//! pipeline's instructions per wheel per sample (`bench: pipeline_replay_rust`; QEMU
//! `-icount shift=6`, the benches' SysTick clock `gough_workloads::clock`, calibrated).
//!
//! The stream is `examples/replay_log.csv` (what `gough replay` sends the firmware), read as
//! `gough_host::replay::read_log` reads it: f64 fields rounded to f32, t in µs.
#![no_std]
#![no_main]

use core::mem::{size_of, MaybeUninit};
use core::ptr::addr_of_mut;
use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::hprintln;
use gough::mf::{self, Input, Options};
use gough::mu::{self, Bank};
use gough::proto::{
    self, AckCode, Estimate, Forces, Measurement, Msg, Mtu, Segmenter, Settings,
};
use gough::wheel::{self, Corner};
use gough_firmware::app::Math;
use gough_firmware::mps2;
use gough_workloads::clock::{self, now};
use gough_workloads::marks::{bench_start, bench_stop};

#[exception]
fn SysTick() {
    clock::on_systick();
}

const LOG: &str = include_str!("../../../examples/replay_log.csv");
/// Rows of the stream.
const ROWS: usize = 200;

static mut STREAM: [Measurement; ROWS] = [gough_workloads::slalom::EMPTY; ROWS];
/// One step's answer: the forces or why none, and the estimate (with its change flag).
type Answer = (Result<Forces, AckCode>, Option<proto::Estimate>);
static mut OUT: [Answer; ROWS] = [(Err(AckCode::Ok), None); ROWS];

/// The log's rows (header and comments skipped); `None` if it does not have `ROWS` rows.
fn read(out: &mut [Measurement; ROWS]) -> Option<()> {
    let mut n = 0;
    for line in LOG.lines() {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') || line.starts_with('t') {
            continue;
        }
        let mut v = [0f64; 10];
        let mut k = 0;
        for (x, f) in v.iter_mut().zip(line.split(',')) {
            *x = f.trim().parse().ok()?;
            k += 1;
        }
        if k != 10 {
            return None;
        }
        let [t, wheel, fz, fy, mz, fx, vx, alpha, kappa, gamma] = v;
        *out.get_mut(n)? = Measurement {
            wheel: proto::Wheel::from_index(wheel as usize)?,
            // t ≥ 0: rounding half up is `read_log`'s round().
            t_us: (t * 1e6 + 0.5) as u32,
            fz: fz as f32,
            fy: fy as f32,
            mz: mz as f32,
            fx: Some(fx as f32),
            vx: Some(vx as f32),
            omega: None,
            delta: None,
            alpha: Some(alpha as f32),
            kappa: Some(kappa as f32),
            gamma: Some(gamma as f32),
        };
        n += 1;
    }
    (n == ROWS).then_some(())
}

/// The pipeline's step, as `gough_wheel_step` does it: forces, then the estimate.
#[inline(never)]
fn step(wheels: &mut [Corner<f32>; 4], p: &gough::mf::Params<f32>, m: &Measurement) -> Answer {
    let w = &mut wheels[m.wheel.index() & 3];
    let x = wheel::Measurement::from(m);
    let f = w
        .forces::<Math>(p, Settings::default().limits, &x)
        .map(|o| Forces::new(m.wheel, m.t_us, &o))
        .map_err(AckCode::from);
    let e = w
        .estimate::<Math>(p, &x)
        .map(|e| Estimate::new(m.wheel, m.t_us, &e));
    (f, e)
}

fn state_code(s: mu::State) -> i32 {
    match s {
        mu::State::Identifiable => 0,
        mu::State::NotIdentifiable => 1,
        mu::State::Fallback => 2,
    }
}

#[entry]
fn main() -> ! {
    let Some(cp) = cortex_m::Peripherals::take() else {
        mps2::exit(false)
    };
    clock::start(cp.SYST);
    let per_count = clock::calibrate(1_000_000);
    hprintln!(
        "calibration: {} instructions per 1000 SysTick counts",
        (per_count * 1000.0 + 0.5) as u32
    );

    let Ok(t) = gough::tir::parse(gough_firmware::BUNDLED_TIR) else {
        mps2::exit(false)
    };
    let p: &'static gough::mf::Params<f32> = {
        static mut P: MaybeUninit<gough::mf::Params<f32>> = MaybeUninit::uninit();
        // SAFETY: the only reference to P, taken once.
        unsafe { (*addr_of_mut!(P)).write(t.params.cast::<f32>()) }
    };

    let input = Input {
        fz: 6752.0,
        kappa: 0.05,
        alpha: 0.04,
        gamma: 0.0,
        phit: 0.0,
        vx: 16.6,
        p: None,
    };
    match mf::eval::<f32, Math>(p, &input, &Options::default()) {
        Ok(o) => hprintln!(
            "mf61 Fz 6752 kappa 0.05 alpha 0.04 use mode 111: Fx {:08x} Fy {:08x} Mz {:08x} flags {}",
            o.fx.to_bits(),
            o.fy.to_bits(),
            o.mz.to_bits(),
            o.flags.0
        ),
        Err(_) => mps2::exit(false),
    }

    // SAFETY: the only references to these statics, taken once.
    let (stream, out) = unsafe { (&mut *addr_of_mut!(STREAM), &mut *addr_of_mut!(OUT)) };
    if read(stream).is_none() {
        hprintln!("examples/replay_log.csv: not {} rows", ROWS);
        mps2::exit(false);
    }
    // Four wheels on their sides with their estimators, as `gough_wheel_init(..,
    // GOUGH_WHEEL_ESTIMATOR | GOUGH_WHEEL_LEFT or _RIGHT)`.
    let fresh = || {
        let mut w = proto::Wheel::ALL.map(|id| Corner::on(Some(id.side())));
        for x in &mut w {
            if x
                .start_estimator::<Math>(p, Settings::default().estimator_config())
                .is_err()
            {
                mps2::exit(false);
            }
        }
        w
    };

    let mut wheels = fresh();
    for (o, m) in out.iter_mut().zip(stream.iter()) {
        *o = step(&mut wheels, p, m);
    }
    for (i, (m, (f, e))) in stream.iter().zip(out.iter()).enumerate() {
        let (rc, f) = match f {
            Ok(f) => (0, *f),
            Err(c) => (
                if *c == AckCode::NoSlip { -8 } else { -6 },
                Forces {
                    wheel: m.wheel,
                    t_us: m.t_us,
                    fx: 0.0,
                    fy: 0.0,
                    mz: 0.0,
                    flags: 0,
                },
            ),
        };
        let (mu, sigma, mu_min, state, flags) = match e {
            Some(e) => (
                e.mu,
                e.sigma,
                e.mu_min,
                state_code(e.state),
                u32::from(e.change) | (u32::from(e.mismatch) << 2),
            ),
            None => (Settings::default().fallback_mu, 1.0, 0.0, 2, 2),
        };
        hprintln!(
            "row {} wheel {}: rc {} Fx {:08x} Fy {:08x} Mz {:08x} flags {}; mu {:08x} sigma {:08x} mu_min {:08x} state {} flags {}",
            i,
            m.wheel.index(),
            rc,
            f.fx.to_bits(),
            f.fy.to_bits(),
            f.mz.to_bits(),
            f.flags,
            mu.to_bits(),
            sigma.to_bits(),
            mu_min.to_bits(),
            state,
            flags
        );
    }

    // The estimator alone over wheel 0's samples.
    let Ok(mut bank) = Bank::new::<Math>(p, None, mu::Config::default()) else {
        mps2::exit(false)
    };
    for (i, m) in stream.iter().enumerate() {
        if m.wheel.index() != 0 {
            continue;
        }
        let s = mu::Sample {
            t_us: m.t_us,
            fz: m.fz,
            fy: m.fy,
            mz: m.mz,
            fx: m.fx,
            kappa: m.kappa,
            vx: m.vx,
            gamma: m.gamma,
        };
        let e = bank.update::<Math>(p, &s);
        let state = state_code(e.state);
        hprintln!(
            "estimator row {}: rc 0 mu {:08x} sigma {:08x} mu_min {:08x} state {} flags {}",
            i,
            e.mu.to_bits(),
            e.sigma.to_bits(),
            e.mu_min.to_bits(),
            state,
            u32::from(e.change) | (u32::from(e.mismatch) << 2)
        );
    }

    // The protocol: the last row's forces as a message.
    let last = stream[ROWS - 1];
    let f = match out[ROWS - 1].0 {
        Ok(f) => f,
        Err(_) => Forces {
            wheel: last.wheel,
            t_us: last.t_us,
            fx: 0.0,
            fy: 0.0,
            mz: 0.0,
            flags: 0,
        },
    };
    let msg = Msg::Forces(f);
    let Ok(mut seg) = Segmenter::new(&msg, 1, Mtu::Classic) else {
        mps2::exit(false)
    };
    let n = seg.frame_count();
    let mut buf = [0u8; 64];
    let Some(first) = seg.next_frame(&mut buf) else {
        mps2::exit(false)
    };
    hprintln!(
        "protocol: forces message in {} frames, id {:03x}, first {:02x} {:02x} {:02x}",
        n,
        proto::id::of(msg.msg_type()),
        first[0],
        first[1],
        first[2]
    );

    // Instructions per wheel per sample, as the C example measures them.
    let overhead = clock::overhead();
    let mut wheels = fresh();
    bench_start(31);
    let t0 = now();
    for (o, m) in out.iter_mut().zip(stream.iter()) {
        *o = step(&mut wheels, p, core::hint::black_box(m));
    }
    let t1 = now();
    bench_stop(31);
    let mean = (t1 - t0) as f64 * per_count / ROWS as f64;
    let mut wheels = fresh();
    let mut worst = 0f64;
    for (o, m) in out.iter_mut().zip(stream.iter()) {
        let a = now();
        *o = step(&mut wheels, p, core::hint::black_box(m));
        let b = now();
        worst = worst.max(((b - a) as f64 - overhead) * per_count);
    }
    hprintln!(
        "bench: pipeline_replay_rust mean={} worst={} ram={}",
        (mean + 0.5) as u32,
        (worst + 0.5) as u32,
        size_of::<Corner<f32>>()
    );
    mps2::exit(true)
}
