//! Instruction counts of the combined-slip Magic Formula on the Cortex-M4F, under QEMU with
//! `-icount shift=6` (one instruction = 64 ns of virtual time; SysTick counts the 25 MHz core
//! clock, i.e. 1.6 counts per instruction, calibrated on a loop of known length by the benches'
//! clock, `gough_workloads::clock`: a sample timed alone is counted to the instruction; with
//! `shift=0` a count is 40 instructions).
//!
//! Each workload is bracketed by `bench_start`/`bench_stop`: exported, never inlined, with
//! distinct bodies, so an outside instruction counter (a QEMU plugin, a debugger) can check
//! the figures. Printed: instructions per evaluation, and the largest error against the f64
//! path over the same inputs; then, per wheel per sample, the friction estimator alone (the bank,
//! `mu::bank::Bank`) and the firmware's whole per-wheel pipeline (transient filter + Magic
//! Formula + bank, `wheel::Corner`), the pipeline with `Fast` and `Libm`, on 1 kHz slaloms with
//! sensor noise on a dry, a wet and an icy road: the mean over the stream (one bracket) and the
//! worst sample (each sample timed alone); the RAM, and the stack the pipeline takes.
#![no_std]
#![no_main]

use core::mem::size_of;
use core::ptr::addr_of_mut;
use cortex_m_rt::{entry, exception};
use cortex_m_semihosting::hprintln;
use gough::math::{Backend, Libm};
use gough::mf::{self, Input, Options, Params};
use gough::mu::{self, Bank, Reading, State};
use gough::proto::{AckCode, Estimate, Forces, Measurement, Settings};
use gough::wheel::{self, Corner};
use gough_firmware::app::{self, App};
use gough_firmware::{mps2, stack};
use gough_workloads::clock::{self, now};
use gough_workloads::marks::{bench_start, bench_stop};
// N, `input`: the grid the M0 bench measures too.
use gough_workloads::points::{input, N};
use gough_workloads::slalom as workload;

#[exception]
fn SysTick() {
    clock::on_systick();
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

/// Instructions per call of each kernel of backend `M` (mean over 256 arguments spread over the
/// ranges the Magic Formula uses), less the loop's own cost.
fn kernels<M: Backend<f32>>(name: &str, per_count: f64) {
    const K: usize = 256;
    let mut xs = [0f32; K];
    for (i, x) in xs.iter_mut().enumerate() {
        *x = -3.0 + 6.0 * i as f32 / K as f32;
    }
    let time = |f: &dyn Fn(f32) -> f32| {
        let t0 = now();
        let mut acc = 0f32;
        for x in xs.iter() {
            acc += f(core::hint::black_box(*x));
        }
        core::hint::black_box(acc);
        now() - t0
    };
    let base = time(&|x| x) as f64;
    let per = |c: u64| ((c as f64 - base) * per_count / K as f64 + 0.5) as u32;
    hprintln!(
        "kernels, {}: instructions per call: sin {} cos {} tan {} atan {} exp {} ln {} sqrt {}",
        name,
        per(time(&|x| M::sin(x))),
        per(time(&|x| M::cos(x))),
        per(time(&|x| M::tan(0.5 * x))),
        per(time(&|x| M::atan(3.0 * x))),
        per(time(&|x| M::exp(x))),
        per(time(&|x| M::ln(x.abs() + 0.1))),
        per(time(&|x| M::sqrt(x.abs()))),
    );
}

/// The staged Magic Formula (`mf::prepared`) with backend `M` over the 256 points
/// of `points.rs`: the load stage (`Prepared::new`, one per point), the friction stage
/// (`Prepared::with_mu`), the slip stage (`Prepared::eval`), the slip stage with ∂/∂κ and ∂/∂α
/// (`eval_d`) and with ∂/∂λμ too (`eval_d_mu`). Each as `bench: <name> mean=<n> worst=<n>
/// ram=<bytes>`: instructions per call, the mean over the 256 (one bracket, loop included) and
/// the worst call (each timed alone, less the timer's own cost); ram is the state the stage
/// keeps (`Prepared<f32>`, `Mu<f32>`). Each slip-stage result is checked against `mf::eval`.
fn staged<M: Backend<f32>>(name: &str, first_id: u32, per_count: f64, p32: &Params<f32>) {
    use gough::mf::prepared::{Mu, Operating, Prepared};
    let opts = Options {
        moments: false,
        ..Options::default()
    };
    let ins: [Input<f32>; N] = core::array::from_fn(input::<f32>);
    let op = |x: &Input<f32>| Operating::from(x);
    // The timer's own cost [counts].
    let overhead = clock::overhead();
    let print = |what: &str, total: u64, worst: f64, ram: usize| {
        hprintln!(
            "bench: {}_{} mean={} worst={} ram={}",
            what,
            name,
            (total as f64 * per_count / N as f64 + 0.5) as u32,
            ((worst - overhead).max(0.0) * per_count + 0.5) as u32,
            ram
        );
    };
    // Load stage: one per point.
    let mut preps: [Option<Prepared<f32>>; 16] = [None; 16];
    let id = first_id;
    bench_start(id);
    let t0 = now();
    for x in ins.iter() {
        if let Ok(p) = Prepared::new::<M>(p32, &op(core::hint::black_box(x)), &opts) {
            core::hint::black_box(&p);
        }
    }
    let total = now() - t0;
    bench_stop(id);
    let mut worst = 0f64;
    for (i, x) in ins.iter().enumerate() {
        let t0 = now();
        let r = Prepared::new::<M>(p32, &op(core::hint::black_box(x)), &opts).ok();
        core::hint::black_box(&r);
        let t = now() - t0;
        worst = worst.max(t as f64);
        // Points i and i + 16k share the load (points.rs: Fz depends on i % 16 alone).
        if let Some(slot) = preps.get_mut(i % 16) {
            *slot = r;
        }
    }
    print("mf_load_stage", total, worst, size_of::<Prepared<f32>>());
    let prep = |i: usize| preps.get(i % 16).and_then(|p| p.as_ref());
    // Friction stage: λμ 0.5 at each point's load.
    bench_start(id + 1);
    let t0 = now();
    for i in 0..N {
        if let Some(p) = prep(i) {
            core::hint::black_box(&p.with_mu(0.5, 0.5));
        }
    }
    let total = now() - t0;
    bench_stop(id + 1);
    let mut worst = 0f64;
    for i in 0..N {
        if let Some(p) = prep(i) {
            let t0 = now();
            core::hint::black_box(&p.with_mu(core::hint::black_box(0.5), 0.5));
            worst = worst.max((now() - t0) as f64);
        }
    }
    print("mf_mu_stage", total, worst, size_of::<Mu<f32>>());
    // The slip stages; each result checked against mf::eval at the same point (the staged
    // evaluation is mf::eval's own code, so they agree to the bit).
    let mut bad = 0u32;
    let mut slip = |what: &str, id: u32, f: &dyn Fn(&Prepared<f32>, &Input<f32>) -> f32| {
        bench_start(id);
        let t0 = now();
        for (i, x) in ins.iter().enumerate() {
            if let Some(p) = prep(i) {
                core::hint::black_box(f(p, core::hint::black_box(x)));
            }
        }
        let total = now() - t0;
        bench_stop(id);
        let mut worst = 0f64;
        for (i, x) in ins.iter().enumerate() {
            if let Some(p) = prep(i) {
                let t0 = now();
                let fy = f(p, core::hint::black_box(x));
                worst = worst.max((now() - t0) as f64);
                let r = mf::eval::<f32, M>(p32, x, &opts).map_or(f32::NAN, |r| r.fy);
                if fy != r {
                    bad += 1;
                }
            }
        }
        print(what, total, worst, size_of::<Prepared<f32>>());
    };
    slip("mf_slip_stage", id + 2, &|p, x| {
        p.eval::<M>(x.kappa, x.alpha).map_or(f32::NAN, |r| r.fy)
    });
    slip("mf_slip_stage_d_kappa_alpha", id + 3, &|p, x| {
        p.eval_d::<M>(p.mu(), x.kappa, x.alpha)
            .map_or(f32::NAN, |(r, d)| {
                core::hint::black_box(d).alpha.fy * 0.0 + r.fy
            })
    });
    slip("mf_slip_stage_d_kappa_alpha_mu", id + 4, &|p, x| {
        p.eval_d_mu::<M>(1.0, x.kappa, x.alpha)
            .map_or(f32::NAN, |(r, d)| {
                core::hint::black_box(d).lmu.fy * 0.0 + r.fy
            })
    });
    hprintln!(
        "staged MF, {}: slip stage vs mf::eval over {} points: {} differ",
        name,
        N,
        bad
    );
}

/// Samples in the estimator's stream (1 s at 1 kHz).
const NS: usize = 1000;
static mut STREAM: [Measurement; NS] = [workload::EMPTY; NS];

/// Per-sample figures of one workload, in instructions.
struct PerSample {
    mean: u32,
    max: u32,
    /// Mean over the samples the estimator found identifiable.
    mean_identifiable: u32,
    identifiable: usize,
}

/// The timer: instructions per SysTick count, and the cost of timing one sample \[counts\].
#[derive(Clone, Copy)]
struct Clock {
    per_count: f64,
    overhead: f64,
}

/// Runs `step` over the stream twice: once in one bracket (the mean), once timing each sample
/// (the worst, less the timer's own cost); `step` returns the estimator's state. `fresh` makes
/// the per-wheel state for each pass.
fn per_sample<S>(
    id: u32,
    clock: Clock,
    stream: &[Measurement],
    fresh: impl Fn() -> S,
    step: impl Fn(&mut S, &Measurement) -> State,
) -> PerSample {
    let mut st = fresh();
    bench_start(id);
    let t0 = now();
    for m in stream {
        core::hint::black_box(step(&mut st, core::hint::black_box(m)));
    }
    let t1 = now();
    bench_stop(id);
    let Clock {
        per_count,
        overhead,
    } = clock;
    let mean = (t1 - t0) as f64 * per_count / stream.len() as f64;
    let mut st = fresh();
    let (mut max, mut sum_id, mut n_id) = (0f64, 0f64, 0usize);
    for m in stream {
        let t0 = now();
        let state = step(&mut st, core::hint::black_box(m));
        let t1 = now();
        let ins = ((t1 - t0) as f64 - overhead).max(0.0) * per_count;
        max = max.max(ins);
        if state == State::Identifiable {
            sum_id += ins;
            n_id += 1;
        }
    }
    PerSample {
        mean: mean as u32,
        max: max as u32,
        mean_identifiable: if n_id > 0 {
            (sum_id / n_id as f64) as u32
        } else {
            0
        },
        identifiable: n_id,
    }
}

/// The firmware's whole per-wheel pipeline (`wheel::Corner`: transient filter + MF + the bank,
/// started as the App starts it) with backend `M`: a readable line and a
/// `bench: wheel_<name>_<stream> mean=<n> worst=<n> ram=<bytes>` line.
fn pipeline_figures<M: Backend<f32>>(
    name: &str,
    stream_name: &str,
    id: u32,
    clock: Clock,
    p: &Params<f32>,
    stream: &[Measurement],
) {
    let settings = Settings::default();
    let w = per_sample(
        id,
        clock,
        stream,
        || {
            let mut w = Corner::new();
            let started = w.start_estimator::<M>(p, settings.estimator_config());
            core::hint::black_box(&started);
            w
        },
        |w, m| {
            // As the App: the protocol's messages from the corner's answers.
            let x = wheel::Measurement::from(m);
            let f = w
                .forces::<M>(p, settings.limits, &x)
                .map(|o| Forces::new(m.wheel, m.t_us, &o))
                .map_err(AckCode::from);
            core::hint::black_box(&f);
            w.estimate::<M>(p, &x)
                .map(|e| Estimate::new(m.wheel, m.t_us, &e))
                .map_or(State::Fallback, |e| e.state)
        },
    );
    hprintln!(
        "pipeline (transient filter + MF + bank estimator, firmware wheel::Corner), {}: {} instructions per wheel per sample (mean over {} samples; identifiable samples {} mean; worst sample {}; {} identifiable)",
        name, w.mean, NS, w.mean_identifiable, w.max, w.identifiable
    );
    hprintln!(
        "bench: wheel_{}_{} mean={} worst={} ram={}",
        name,
        stream_name,
        w.mean,
        w.max,
        size_of::<Corner<f32>>()
    );
}

/// The exact-model bank estimator ([`gough::mu::bank::Bank`]) alone, with backend `M`: its
/// instructions per sample (mean over the stream, worst sample) and its state's RAM, as a
/// `bench: mu_bank_<name>_<stream> mean=<n> worst=<n> ram=<bytes>` line.
fn bank_figures<M: Backend<f32>>(
    name: &str,
    stream_name: &str,
    id: u32,
    clock: Clock,
    p: &Params<f32>,
    stream: &[Measurement],
) {
    if Bank::new::<M>(p, None, mu::Config::default()).is_err() {
        hprintln!("bank: no friction in the tyre file");
        return;
    }
    let e = per_sample(
        id,
        clock,
        stream,
        || Bank::new::<M>(p, None, mu::Config::default()).ok(),
        |est, m| {
            let Some(est) = est.as_mut() else {
                return State::Fallback;
            };
            est.update::<M>(p, &wheel::sample::<f32, M>(p, &m.into()))
                .state
        },
    );
    hprintln!(
        "bench: mu_bank_{}_{} mean={} worst={} ram={}",
        name,
        stream_name,
        e.mean,
        e.max,
        size_of::<Bank<f32>>()
    );
    // A rear wheel's bank told by the preview (`Bank::preview`) every 7th sample — far more
    // often than a front wheel identifies anew, and at every phase of a batch's fit: the
    // mixture takes a slot of a sample's work (`mu::SLOTS`), so the worst sample stays the
    // bank's own. The reading is the rear's own profile one sample before (what a front
    // wheel on the same road reports), taken and handed inside the timed step.
    let e = per_sample(
        id + 1,
        clock,
        stream,
        || {
            Bank::new::<M>(p, None, mu::Config::default())
                .ok()
                .map(|b| (b, 0u32))
        },
        |st, m| {
            let Some((est, i)) = st.as_mut() else {
                return State::Fallback;
            };
            *i = i.wrapping_add(1);
            if *i % 7 == 0 {
                if let Some(r) = Reading::new(&est.profile(), 0.9) {
                    est.preview::<M>(r);
                }
            }
            est.update::<M>(p, &wheel::sample::<f32, M>(p, &m.into()))
                .state
        },
    );
    hprintln!(
        "bench: mu_bank_previewed_{}_{} mean={} worst={} ram={}",
        name,
        stream_name,
        e.mean,
        e.max,
        size_of::<Bank<f32>>()
    );
}

#[entry]
fn main() -> ! {
    // SAFETY: first thing in main.
    unsafe { stack::paint() };
    let Some(cp) = cortex_m::Peripherals::take() else {
        mps2::exit(false)
    };
    clock::start(cp.SYST);

    // Calibration: a loop of exactly 2 instructions per iteration (subs + bne).
    const LOOPS: u32 = 1_000_000;
    bench_start(0);
    let per_count = clock::calibrate(LOOPS);
    bench_stop(0);
    hprintln!("calibration: {} instructions per SysTick count", per_count);

    let Ok(t) = gough::tir::parse(gough_firmware::BUNDLED_TIR) else {
        mps2::exit(false)
    };
    let p64 = t.params;
    let p32 = p64.cast::<f32>();
    // The combined Fx, Fy, Mz alone (the instruction target's unit; what a friction or stability controller
    // needs: `Options::moments` off), then with Mx and My.
    for (k, (moments, what)) in [
        (
            false,
            "combined Fx, Fy, Mz evaluation (Options::moments off)",
        ),
        (true, "combined evaluation with Mx, My"),
    ]
    .into_iter()
    .enumerate()
    {
        let opts = Options {
            moments,
            ..Options::default()
        };
        let id = 1 + 3 * k as u32;
        let line = |name: &str, (c, ef, em): (u64, f64, f64)| {
            hprintln!(
                "{}: {} instructions per {}; max error vs f64: forces {:.3e} N, Mz {:.3e} N m",
                name,
                (c as f64 * per_count / N as f64) as u32,
                what,
                ef,
                em
            );
        };
        line("libm", run::<Libm>(id, &p32, &p64, &opts));
        #[cfg(feature = "micromath")]
        line(
            "micromath",
            run::<gough::math::Micromath>(id + 1, &p32, &p64, &opts),
        );
        #[cfg(feature = "fast")]
        line("fast", run::<gough::math::Fast>(id + 2, &p32, &p64, &opts));
    }
    #[cfg(feature = "fast")]
    kernels::<gough::math::Fast>("fast", per_count);
    #[cfg(feature = "fast")]
    staged::<gough::math::Fast>("fast", 90, per_count, &p32);
    #[cfg(not(feature = "micromath"))]
    hprintln!(
        "micromath: not built (firmware feature `micromath` needs gough's `micromath` backend)"
    );

    // The friction estimator and the per-wheel pipeline.
    hprintln!(
        "RAM per wheel: Bank<f32> {} bytes, wheel::Corner (filter + estimator) {} bytes; App {} bytes (four wheels); Params<f32> {} bytes",
        size_of::<Bank<f32>>(),
        size_of::<Corner<f32>>(),
        size_of::<App>(),
        size_of::<Params<f32>>()
    );
    // SAFETY: the only reference to STREAM, taken once.
    let stream = unsafe { &mut *addr_of_mut!(STREAM) };
    // The timer's own cost per timed sample [counts].
    let clock = Clock {
        per_count,
        overhead: clock::overhead(),
    };
    // Streams: the slalom on the tyre's own surface (λμ 1) with and without camber; then on a
    // wet and an icy road.
    for (k, (camber, mu, what, short)) in [
        (
            0.02,
            1.0,
            "λμ 1 (dry), camber measured (roll, ±0.02 rad)",
            "dry",
        ),
        (
            0.0,
            1.0,
            "λμ 1 (dry), no camber in the message (static 0)",
            "dry_nocamber",
        ),
        (0.02, 0.5, "λμ 0.5 (wet), camber measured", "wet"),
        (0.02, 0.2, "λμ 0.2 (ice), camber measured", "ice"),
    ]
    .into_iter()
    .enumerate()
    {
        workload::slalom(&p32, mu, camber, stream);
        hprintln!("stream: 1 s slalom at 1 kHz, noise; {}", what);
        let id = 30 + 10 * k as u32;
        bank_figures::<app::Math>(app::MATH_NAME, short, id + 5, clock, &p32, stream);
        // The stack the pipeline takes (repainted, so that the peak is this run's, plus this
        // frame's share, `before`).
        // SAFETY: nothing lives below the current frame (SysTick's handler frames come and go).
        unsafe { stack::paint() };
        let before = stack::peak();
        pipeline_figures::<app::Math>(app::MATH_NAME, short, id + 1, clock, &p32, stream);
        hprintln!(
            "stack: pipeline {} {} bytes",
            app::MATH_NAME,
            stack::peak() - before
        );
        if cfg!(feature = "fast") {
            pipeline_figures::<Libm>("libm", short, id + 3, clock, &p32, stream);
        }
    }
    preview_figures::<app::Math>(app::MATH_NAME, 80, clock, &p32, stream);
    auth_figures(90, clock);
    mps2::exit(true)
}

/// The key check of every message the device receives (`gough::proto::auth::Verifier::check`,
/// what `App::poll` adds per message): per secured message of each kind (AES-128-CMAC over its
/// identifier, body, counter and epoch, constant-time compare of the 8-byte MAC, the freshness),
/// and per unsecured measurement (the check that lets it through); with every message
/// authenticated (`Policy::All`) per secured `Measurement` and four-wheel `CompactBatch`, and
/// per answer the device secures (`Verifier::seal`: encoding, CMAC, CRC; the plain encoding's
/// cost subtracted, so the figure is what the option adds). `bench: auth_<kind> mean=<n>
/// worst=<n> ram=<Verifier bytes>` and `bench: auth_seal_<kind> …` lines.
fn auth_figures(id: u32, clock: Clock) {
    use gough::proto::auth::{Policy, Signer, Verifier};
    use gough::proto::{
        id as cid, Bytes, CalibrationState, Command, CompactBatch, CompactResults,
        CompactWheelResult, Key, MacLen, Msg, ParamChunk, Wheel, MAX_MSG_LEN,
    };
    const K: usize = 32;
    let key = Key::new([0x7e; 16]);
    let chunk = Msg::ParamChunk(ParamChunk {
        offset: 480,
        data: Bytes::new(&[b'x'; 48]).unwrap_or_else(|| mps2::exit(false)),
    });
    let cal = Msg::SetCalibration(CalibrationState {
        wheel: Wheel::RearLeft,
        value: [1.0; 4],
        sigma: [0.1; 4],
        batches: 7,
    });
    let settings = Msg::Settings(Settings::default());
    let meas = Msg::Measurement(Measurement {
        fz: 4000.0,
        alpha: Some(0.02),
        ..Measurement::default()
    });
    // A measurement with every field (the replay's: t, Fz, α, κ, vx, γ), and a full batch.
    let full = Measurement {
        wheel: Wheel::RearRight,
        t_us: 123_456_789,
        fz: 4000.0,
        fy: -1234.5,
        mz: 21.4,
        alpha: Some(0.02),
        kappa: Some(-0.01),
        vx: Some(20.0),
        gamma: Some(0.01),
        ..Measurement::default()
    };
    let wheels = Wheel::ALL.map(|wheel| Measurement { wheel, ..full });
    let batch = CompactBatch::new(full.t_us, &wheels).unwrap_or_else(|| mps2::exit(false));
    let kinds: [(&str, Msg, bool); 7] = [
        ("settings", settings, true),
        ("command", Msg::Command(Command::Reset), true),
        ("calibration", cal, true),
        ("param_chunk", chunk, true),
        ("measurement_unsecured", meas, false),
        ("measurement", Msg::Measurement(full), true),
        ("compact_batch", Msg::CompactBatch(batch), true),
    ];
    for (k, (name, msg, secured)) in kinds.iter().enumerate() {
        let mut signer = Signer::new(key, MacLen::DEFAULT, 3, 0);
        let mut bufs = [[0u8; MAX_MSG_LEN]; K];
        let mut lens = [0usize; K];
        for (b, n) in bufs.iter_mut().zip(lens.iter_mut()) {
            let r = if *secured {
                signer.seal(cid::of(msg.msg_type()), msg, b)
            } else {
                msg.encode(b)
            };
            *n = r.unwrap_or_else(|_| mps2::exit(false));
        }
        let c = cid::of(msg.msg_type());
        let pass = |v: &mut Verifier, i: usize| {
            let b = bufs[i].get(..lens[i]).unwrap_or(&[]);
            v.check(c, msg, core::hint::black_box(b)).is_ok()
        };
        let policy = if *secured {
            Policy::All
        } else {
            Policy::StateChanging
        };
        let verifier = || Verifier::new(key, MacLen::DEFAULT, 3).with_policy(policy);
        let mut v = verifier();
        bench_start(id + k as u32);
        let t0 = now();
        let mut ok = 0;
        for i in 0..K {
            ok += usize::from(pass(&mut v, i));
        }
        let t1 = now();
        bench_stop(id + k as u32);
        let mean = (t1 - t0) as f64 * clock.per_count / K as f64;
        let mut v = verifier();
        let mut worst = 0f64;
        for i in 0..K {
            let t0 = now();
            ok += usize::from(pass(&mut v, i));
            let t1 = now();
            worst = worst.max(((t1 - t0) as f64 - clock.overhead).max(0.0) * clock.per_count);
        }
        if ok != 2 * K {
            hprintln!("auth: {} refused", name);
            mps2::exit(false);
        }
        hprintln!(
            "bench: auth_{} mean={} worst={} ram={}",
            name,
            mean as u32,
            worst as u32,
            size_of::<Verifier>()
        );
    }
    // The answers the device secures under `Policy::All`: sealed minus plain encoding.
    let forces = Forces {
        wheel: Wheel::RearRight,
        t_us: full.t_us,
        fx: -812.5,
        fy: 2310.25,
        mz: -40.5,
        flags: 0,
    };
    let estimate = Estimate {
        wheel: Wheel::RearRight,
        t_us: full.t_us,
        mu: 0.91,
        sigma: 0.05,
        state: State::Identifiable,
        mu_min: 0.6,
        change: false,
        mismatch: false,
    };
    let res = CompactWheelResult::or_na(Some(&forces), Some(&estimate));
    let results = CompactResults {
        t_us: full.t_us,
        wheels: [res; 4],
    };
    let answers: [(&str, Msg); 3] = [
        ("forces", Msg::Forces(forces)),
        ("estimate", Msg::Estimate(estimate)),
        ("compact_results", Msg::CompactResults(results)),
    ];
    for (k, (name, msg)) in answers.iter().enumerate() {
        let c = cid::of(msg.msg_type());
        let mut out = [0u8; MAX_MSG_LEN];
        let mut plain = Verifier::new(key, MacLen::DEFAULT, 3);
        let mut dev = Verifier::new(key, MacLen::DEFAULT, 3).with_policy(Policy::All);
        let mut run = |v: &mut Verifier| {
            let t0 = now();
            let n = v.seal(c, core::hint::black_box(msg), &mut out);
            let t1 = now();
            if n.is_err() {
                mps2::exit(false);
            }
            ((t1 - t0) as f64 - clock.overhead).max(0.0) * clock.per_count
        };
        let (mut sum, mut worst, mut base) = (0f64, 0f64, 0f64);
        bench_start(id + 10 + k as u32);
        for _ in 0..K {
            base += run(&mut plain);
            let t = run(&mut dev);
            sum += t;
            worst = worst.max(t);
        }
        bench_stop(id + 10 + k as u32);
        let plain_mean = base / K as f64;
        hprintln!(
            "bench: auth_seal_{} mean={} worst={} ram={}",
            name,
            (sum / K as f64 - plain_mean) as u32,
            (worst - plain_mean) as u32,
            size_of::<Verifier>()
        );
    }
}

/// The front-to-rear preview (`gough::mu::preview`) with backend `M`: a reading handed to a
/// rear wheel's bank (`Bank::preview`) and mixed over the cells by its next update (one per
/// rear sample at most, a few per change of surface), and the rear's per-sample roll-on with a full
/// queue and nothing arriving (`Preview::rear`). `bench: mu_preview_mix_<name> mean=<n>
/// worst=<n> ram=<Preview bytes>` and `bench: mu_preview_roll_<name> …` lines.
fn preview_figures<M: Backend<f32>>(
    name: &str,
    id: u32,
    clock: Clock,
    p: &Params<f32>,
    stream: &[Measurement],
) {
    use gough::mu::preview::{self, Preview};
    let Ok(mut b) = Bank::new::<M>(p, None, mu::Config::default()) else {
        return;
    };
    let Ok(mut pv) = Preview::new(preview::Config::with_wheelbase(2.9f32)) else {
        return;
    };
    let mut profile = [0f32; mu::CELLS];
    for (k, x) in profile.iter_mut().enumerate() {
        *x = 0.5 * (k as f32 - 4.0) * (k as f32 - 4.0);
    }
    const K: usize = 64;
    let timed = |f: &mut dyn FnMut(usize)| {
        bench_start(id);
        let (mut sum, mut max) = (0f64, 0f64);
        for i in 0..K {
            let t0 = now();
            f(i);
            let t1 = now();
            let ins = ((t1 - t0) as f64 - clock.overhead).max(0.0) * clock.per_count;
            sum += ins;
            max = max.max(ins);
        }
        bench_stop(id);
        ((sum / K as f64) as u32, max as u32)
    };
    // Handed over, then mixed in by the next update's work (a sample with no contact, so
    // that the update does nothing else).
    let none = mu::Sample {
        t_us: 0,
        fz: 0.0,
        fy: 0.0,
        mz: 0.0,
        fx: None,
        kappa: None,
        vx: None,
        gamma: None,
    };
    let (mean, worst) = timed(&mut |i| {
        let w = if i % 2 == 0 { 0.9 } else { 0.5 };
        if let Some(r) = Reading::new(core::hint::black_box(&profile), w) {
            b.preview::<M>(r);
        }
        b.update::<M>(p, core::hint::black_box(&none));
    });
    hprintln!(
        "bench: mu_preview_mix_{} mean={} worst={} ram={}",
        name,
        mean,
        worst,
        size_of::<Preview<f32>>()
    );
    // Readings on their way: a front wheel's identifications over the last stream.
    if let Ok(mut f) = Bank::new::<M>(p, None, mu::Config::default()) {
        for m in stream {
            f.update::<M>(p, &wheel::sample::<f32, M>(p, &m.into()));
            pv.front(&f);
        }
    }
    let pending = pv.pending();
    let (mean, worst) = timed(&mut |i| {
        let s = mu::Sample {
            t_us: 1000 * i as u32,
            fz: 4000.0,
            fy: 0.0,
            mz: 0.0,
            fx: None,
            kappa: None,
            vx: Some(0.001),
            gamma: None,
        };
        pv.rear::<M>(&mut b, core::hint::black_box(&s));
    });
    hprintln!(
        "preview: {} readings on their way while rolling on",
        pending
    );
    hprintln!(
        "bench: mu_preview_roll_{} mean={} worst={} ram={}",
        name,
        mean,
        worst,
        size_of::<Preview<f32>>()
    );
}
