//! Workloads for `tools/qemu_profile.py`: where the instructions go, by source file, function
//! and line, with `math::Fast` as the firmware runs it (MF 6.1 bundled tyre).
//!
//! 1. One combined Fx, Fy, Mz evaluation (`Options::moments` off): the 256 evaluations of the
//!    bench's grid in the first `bench_start`/`bench_stop` bracket.
//! 2. The friction estimator per wheel per sample (`mu::bank::Bank::update`, as the firmware's
//!    wheels run it: `wheel::sample`, the protocol's default settings): the bench's 1 s slalom
//!    with measured camber (1,000 samples) in the second bracket, on the dry road (λμ 1); the
//!    same on the icy road (λμ 0.2) in the third.
//!
//! The profiler counts the instructions QEMU executes in a bracket (`-d exec,in_asm`), then maps
//! them to source lines with the debug info. Everything else (parsing the `.tir`, building the
//! inputs and the streams, starting the estimator) is outside the brackets.
//!
//! ```console
//! $ cd firmware && cargo build --release --bin profile
//! $ python3 ../tools/qemu_profile.py target/thumbv7em-none-eabihf/release/profile --per 256
//! $ python3 ../tools/qemu_profile.py target/thumbv7em-none-eabihf/release/profile \
//!     --bracket 2 --only 'gough::mu::' --per 1000
//! $ python3 ../tools/qemu_profile.py target/thumbv7em-none-eabihf/release/profile \
//!     --bracket 3 --only 'gough::mu::' --per 1000
//! ```
//! (`--only` keeps the log to the estimator's functions.)
#![no_std]
#![no_main]

use core::ptr::addr_of_mut;
use cortex_m_rt::entry;
use gough::math::Fast;
use gough::mf::prepared::{Operating, Prepared};
use gough::mf::Params;
use gough::mf::{self, Input, Options};
use gough::mu::{self, Bank};
use gough::proto::{Measurement, Settings};
use gough_firmware::mps2;
use gough_workloads::marks::{bench_start, bench_stop};
use gough_workloads::points::{input, N};
use gough_workloads::slalom as workload;

/// Samples in the second bracket (the bench's stream).
const NS: usize = 1000;
static mut STREAM: [Measurement; NS] = [workload::EMPTY; NS];

#[entry]
fn main() -> ! {
    let Ok(t) = gough::tir::parse(gough_firmware::BUNDLED_TIR) else {
        mps2::exit(false)
    };
    let p32 = t.params.cast::<f32>();
    // Through a reference the optimiser cannot see into: the parameters are data, as on the
    // device (not constants folded from the f64 values).
    let p = core::hint::black_box(&p32);
    let opts = Options {
        moments: false,
        ..Options::default()
    };
    // The bench's grid (N points of `gough_workloads::points`).
    let mut ins = [Input::<f32>::default(); N];
    for (i, x) in ins.iter_mut().enumerate() {
        *x = input::<f32>(i);
    }
    let mut acc = 0f32;
    let mut failed = 0u32;
    bench_start(1);
    for x in ins.iter() {
        match mf::eval::<f32, Fast>(p, core::hint::black_box(x), &opts) {
            Ok(r) => acc += r.fx + r.fy + r.mz,
            Err(_) => failed += 1,
        }
    }
    bench_stop(1);
    core::hint::black_box(acc);

    // The estimator: the firmware's config, the bench's slalom with camber.
    // SAFETY: the only reference to STREAM, taken once.
    let stream = unsafe { &mut *addr_of_mut!(STREAM) };
    let cfg = Settings::default().estimator_config();
    let mut seen = [0u32; 2];
    for (k, mu) in [1.0, 0.2].into_iter().enumerate() {
        workload::slalom(&p32, mu, 0.02, stream);
        let Ok(est) = Bank::new::<Fast>(p, None, cfg) else {
            mps2::exit(false)
        };
        seen[k] = estimator_stream(2 + k as u32, est, p, stream);
    }
    // The staged MF's slip stage at the grid's loads: brackets 4 (values), 5 (with
    // ∂/∂κ, ∂/∂α) and 6 (with ∂/∂λμ too).
    let preps: [Option<Prepared<f32>>; 16] = core::array::from_fn(|i| {
        Prepared::new::<Fast>(p, &Operating::from(&ins[i]), &opts).ok()
    });
    let staged_ok = (4..7).all(|id| slip_stream(id, &preps, &ins).is_finite());
    mps2::exit(failed == 0 && acc.is_finite() && seen.iter().all(|&n| n > 0) && staged_ok)
}

/// Bracket `id` (4, 5, 6): the slip stage at the grid's points (its load from `preps`:
/// points i and i + 16k share the load), values; with the slopes in κ, α; with ∂/∂λμ too.
#[inline(never)]
fn slip_stream(id: u32, preps: &[Option<Prepared<f32>>; 16], ins: &[Input<f32>; N]) -> f32 {
    let mut acc = 0f32;
    bench_start(id);
    for (i, x) in ins.iter().enumerate() {
        let Some(p) = preps.get(i % 16).and_then(|p| p.as_ref()) else {
            continue;
        };
        let x = core::hint::black_box(x);
        acc += match id {
            4 => p.eval::<Fast>(x.kappa, x.alpha).map_or(f32::NAN, |r| r.fy),
            5 => p
                .eval_d::<Fast>(p.mu(), x.kappa, x.alpha)
                .map_or(f32::NAN, |(r, d)| r.fy + d.alpha.fy * 0.0),
            _ => p
                .eval_d_mu::<Fast>(1.0, x.kappa, x.alpha)
                .map_or(f32::NAN, |(r, d)| r.fy + d.lmu.fy * 0.0),
        };
    }
    bench_stop(id);
    acc
}

/// Bracket `id`: `Bank::update` over the stream, in a function of its own so that
/// `qemu_profile.py --only` can keep the log to it. Returns the identifiable samples.
#[inline(never)]
fn estimator_stream(id: u32, mut est: Bank<f32>, p: &Params<f32>, stream: &[Measurement]) -> u32 {
    let mut seen = 0u32;
    bench_start(id);
    for m in stream {
        let s = gough::wheel::sample::<f32, Fast>(p, &m.into());
        let e = est.update::<Fast>(p, core::hint::black_box(&s));
        seen += u32::from(e.state == mu::State::Identifiable);
    }
    bench_stop(id);
    seen
}
