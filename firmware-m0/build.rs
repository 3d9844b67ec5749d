//! Puts the memory map where cortex-m-rt's `link.x` finds it as `memory.x`
//! (`memory-microbit.x`, the nRF51822, for thumbv6m; `memory-an385.x`, the MPS2 AN385, for
//! thumbv7m), and computes on the host what the bench checks on the device: the f64 reference
//! outputs (Fx, Fy, Mz) of the bench's points (`mf::eval::<f64, Libm>` on the bundled MF 6.1
//! tyre) and of its transient-filter stream (κ', α'), written to `$OUT_DIR/reference.rs` with the
//! tyre's parameters as `gough::tir::parse` reads them (f64; the bench casts them at boot); and
//! the outcome the friction estimator (`gough::mu::bank::Bank` at 100 Hz, one sample per batch)
//! must reproduce on the device for each bench stream (`$OUT_DIR/estimator.rs`, with feature
//! `mu`: f32 with `math::Fast` with feature `fast`, Q31.32 with `FixMath` with feature `fix`).
use gough::math::{Backend, Float, Libm};
use gough::mf::{self, Options};
use gough::mu::{Bank, State};
use std::{env, fmt::Write as _, fs, path::PathBuf};

use gough_workloads::filter_point;
use gough_workloads::points::{input, N};
use gough_workloads::streams::{bank_sample, config, hash, stream, Feed, HASH0, STREAMS};

/// The expected outcome of the bank (`Bank<F>` with backend `M`, [`config`]) on each of
/// [`STREAMS`], run here on the host as the device runs it: (a hash of every estimate — μ, σ,
/// μ_min, state, change flag —, the identifiable samples, the last μ's hash). The device must
/// reproduce them bit for bit (IEEE f32 on both with no FMA contraction; Q31.32 is integer
/// arithmetic). Rust source of a `static` named `name`.
#[allow(dead_code)]
fn bank<F: Float + Feed, M: Backend<F>>(
    p: &gough::mf::Params<f64>,
    name: &str,
    how: &str,
) -> String {
    let pf = p.cast::<F>();
    let p32 = p.cast::<f32>();
    let mut s = format!(
        "/// Expected (hash, identifiable samples, last μ hash) per stream of [`STREAMS`]: `{how}`\n\
         /// run by build.rs on the host.\npub static {name}: [(u32, u32, u32); STREAMS.len()] = [\n"
    );
    for &(mu, camber, _, _) in STREAMS.iter() {
        let mut est =
            Bank::new::<M>(&pf, None, config::<F>()).expect("a bank for the bundled tyre");
        let (mut h, mut seen, mut last) = (HASH0, 0u32, 0u32);
        for m in stream(&p32, mu, camber) {
            let e = est.update::<M>(&pf, &bank_sample::<F>(&m));
            h = hash(h, &e);
            seen += u32::from(e.state == State::Identifiable);
            last = e.mu.feed(HASH0);
        }
        writeln!(s, "    (0x{h:08x}, {seen}, 0x{last:08x}),").expect("write");
    }
    s.push_str("];\n");
    s
}

/// The f64 reference of the bench's transient-filter stream (`relax::Transient::step`, one 1 ms
/// step per point, the relaxation lengths of `mf::eval` at the point, Vsx = κ·Vx,
/// Vsy = tan α·Vx), as the device runs it in `F`: (κ', α') per step.
fn filter_reference(p: &gough::mf::Params<f64>) -> String {
    use gough::relax::{Config, Transient};
    let cfg = Config::from_params(p);
    let mut state = Transient::new(0.0);
    let mut s = String::from(
        "/// f64 reference (κ', α') per transient-filter step of the bench's stream, from build.rs.\npub static FILTER_REF: [[f64; 2]; N] = [\n",
    );
    for i in 0..N {
        let (kin, sigma) = filter_point::<f64, Libm>(p, i);
        let (k, a) = match state.step::<Libm>(&cfg, 1e-3, &kin, &sigma) {
            Ok(sl) => (sl.kappa, sl.alpha),
            Err(_) => (f64::NAN, f64::NAN),
        };
        writeln!(s, "    [{}, {}],", lit(k), lit(a)).expect("write");
    }
    s.push_str("];\n");
    s
}

fn lit(x: f64) -> String {
    if x.is_finite() {
        format!("{x:?}")
    } else {
        "f64::NAN".into()
    }
}

fn main() {
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("OUT_DIR"));
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    // The memory map of the machine the target runs on: the nRF51822 (QEMU `microbit`,
    // Cortex-M0) for thumbv6m, the MPS2 AN385 (QEMU `mps2-an385`, Cortex-M3) for thumbv7m.
    let map = match env::var("TARGET").as_deref() {
        Ok("thumbv7m-none-eabi") => "memory-an385.x",
        _ => "memory-microbit.x",
    };
    fs::copy(dir.join(map), out.join("memory.x")).expect("copy memory.x");
    let core = if map == "memory-microbit.x" {
        "M0"
    } else {
        "M3"
    };
    println!("cargo:rustc-env=GOUGH_CORE={core}");
    println!("cargo:rustc-env=GOUGH_CORE_LC={}", core.to_lowercase());
    println!("cargo:rustc-link-search={}", out.display());

    let tir_path = dir.join("../host-tests/data/tyres/MagicFormula61_Parameters.tir");
    let text = fs::read_to_string(&tir_path).expect("read the bundled .tir");
    let p = gough::tir::parse(&text)
        .expect("parse the bundled .tir")
        .params;
    let mut s = String::from("/// f64 reference (Fx, Fy, Mz) per point, from build.rs.\npub static REF: [[f64; 3]; N] = [\n");
    for i in 0..N {
        let (fx, fy, mz) = match mf::eval::<f64, Libm>(&p, &input::<f64>(i), &Options::default()) {
            Ok(o) => (o.fx, o.fy, o.mz),
            Err(_) => (f64::NAN, f64::NAN, f64::NAN),
        };
        writeln!(s, "    [{}, {}, {}],", lit(fx), lit(fy), lit(mz)).expect("write");
    }
    s.push_str("];\n");
    s.push_str(&filter_reference(&p));
    // The parameter set, parsed here (tir::parse needs ~8 KB of stack on thumbv6m: with the
    // Params<f64> it returns and the casts, more than the nRF51822's 16 KiB), cast at boot.
    writeln!(s, "/// The bundled tyre's version (host-parsed).\npub const VERSION: gough::mf::Version = gough::mf::Version::{:?};", p.version).expect("write");
    let side = match p.tyreside {
        Some(side) => format!("Some(gough::mf::Side::{side:?})"),
        None => "None".into(),
    };
    writeln!(
        s,
        "/// The bundled tyre's side.\npub const TYRESIDE: Option<gough::mf::Side> = {side};"
    )
    .expect("write");
    writeln!(s, "/// The bundled tyre's parameters (host-parsed, f64).\npub static PARAMS: [(gough::mf::Key, f64); {}] = [", gough::mf::Key::ALL.len()).expect("write");
    for &k in gough::mf::Key::ALL {
        writeln!(s, "    (gough::mf::Key::{k:?}, {}),", lit(p.get(k))).expect("write");
    }
    s.push_str("];\n");
    fs::write(out.join("reference.rs"), s).expect("write reference.rs");
    // The bank's expected outcomes, for the number formats this build runs.
    #[allow(unused_mut)] // nothing is added without feature `mu`
    let mut est = String::new();
    #[cfg(all(feature = "mu", feature = "fast"))]
    est.push_str(&bank::<f32, gough::math::Fast>(
        &p,
        "EXPECT",
        "Bank::<f32>::update::<math::Fast>",
    ));
    #[cfg(all(feature = "mu", feature = "fix"))]
    est.push_str(&bank::<gough::fixed::Fix, gough::fixed::FixMath>(
        &p,
        "EXPECT_FIX",
        "Bank::<Fix>::update::<FixMath>",
    ));
    fs::write(out.join("estimator.rs"), est).expect("write estimator.rs");
    println!("cargo:rerun-if-changed={}", tir_path.display());
    println!("cargo:rerun-if-changed=memory-microbit.x");
    println!("cargo:rerun-if-changed=memory-an385.x");
    println!("cargo:rerun-if-changed=../src");
    println!("cargo:rerun-if-changed=build.rs");
}
