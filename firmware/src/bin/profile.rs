//! A workload for `tools/qemu_profile.py`: where the instructions of one combined Fx, Fy, Mz
//! evaluation go (MF 6.1 bundled tyre, `math::Fast`, `Options::moments` off — as the firmware
//! runs it), by source file, function and line.
//!
//! The 256 evaluations of the bench's grid run between one `bench_start`/`bench_stop` pair; the
//! profiler counts the instructions QEMU executes between them (`-d exec,in_asm`), then maps
//! them to source lines with the debug info. Everything else (parsing the `.tir`, building the
//! inputs) is outside the bracket.
//!
//! ```console
//! $ cd firmware && cargo build --release --bin profile && python3 ../tools/qemu_profile.py \
//!     target/thumbv7em-none-eabihf/release/profile --per 256
//! ```
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use gough::math::Fast;
use gough::mf::{self, Input, Options};
use gough_firmware::marks::{bench_start, bench_stop};
use gough_firmware::mps2;

/// Evaluations in the bracket (the bench's 256-point grid).
const N: usize = 256;

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
    // The bench's grid: Fz 0.5..1.5 FNOMIN, κ −0.2..0.2, α −0.15..0.15.
    let mut ins = [Input::<f32>::default(); N];
    for (i, x) in ins.iter_mut().enumerate() {
        let a = (i % 16) as f32 / 15.0;
        let b = ((i / 16) % 16) as f32 / 15.0;
        *x = Input {
            fz: 6752.0 * (0.5 + a),
            kappa: -0.2 + 0.4 * b,
            alpha: -0.15 + 0.3 * ((i * 7 % 16) as f32 / 15.0),
            vx: 16.6,
            ..Input::default()
        };
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
    mps2::exit(failed == 0 && acc.is_finite())
}
