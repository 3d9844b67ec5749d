//! Puts the memory map where cortex-m-rt's `link.x` finds it as `memory.x`
//! (`memory-microbit.x`, the nRF51822, for thumbv6m; `memory-an385.x`, the MPS2 AN385, for
//! thumbv7m), and computes on the host what the bench checks on the device: the f64 reference
//! outputs (Fx, Fy, Mz) of the bench's points (`mf::eval::<f64, Libm>` on the bundled MF 6.1
//! tyre) and of its transient-filter stream (κ', α'), written to `$OUT_DIR/reference.rs` with the
//! tyre's parameters as `gough::tir::parse` reads them (f64; the bench casts them at boot); and
//! the friction estimator's table for that tyre as a `static` in flash (`$OUT_DIR/estimator.rs`:
//! f32 with feature `mu`, Q31.32 with `mu-fix`), with the outcome the estimator must reproduce on
//! the device for each bench stream.
use gough::fixed::Fix;
#[cfg(feature = "mu-fix")]
use gough::fixed::FixMath;
use gough::math::{Backend, Fast, Float, Libm};
use gough::mf::{self, Options};
use gough::mu::{table::Curve, Config, GoughTable, MuEstimator};
use std::{env, fmt::Write as _, fs, path::PathBuf};

use gough_workloads::points::{input, N};
use gough_workloads::streams::{cast_sample, hash, Feed, HASH0, SAMPLES, STREAMS};
use gough_workloads::{filter_point, slalom as workload};

/// A table value as a Rust literal of its bits (exact, NaN and infinities included).
trait Lit: Copy {
    fn lit(self) -> String;
}

impl Lit for f32 {
    fn lit(self) -> String {
        format!("b(0x{:08x})", self.to_bits())
    }
}

impl Lit for Fix {
    fn lit(self) -> String {
        format!("x({})", self.to_bits())
    }
}

fn list(xs: impl IntoIterator<Item = String>) -> String {
    format!("[{}]", xs.into_iter().collect::<Vec<_>>().join(", "))
}

fn curve<F: Lit>(c: &Curve<F>) -> String {
    format!(
        "gough::mu::table::Curve {{ f: {}, rise: {}, tau0: {}, sat: {}, anchor: {}, x_sat: {}, x_floor: {}, len: {}, rise_len: {}, peak: {}, f_top: {}, band_scale: {}, fx_free: {}, band: {} }}",
        list(c.f.iter().map(|&x| x.lit())),
        list(c.rise.iter().map(|&(f, t)| format!("({}, {})", f.lit(), t.lit()))),
        c.tau0.lit(),
        list(c.sat.iter().map(|&x| x.lit())),
        c.anchor.lit(),
        c.x_sat.lit(),
        c.x_floor.lit(),
        c.len,
        c.rise_len,
        c.peak,
        c.f_top.lit(),
        c.band_scale.lit(),
        list(c.fx_free.iter().map(|&x| x.lit())),
        list(c.band.iter().map(|x| list(x.iter().map(|&v| v.lit())))),
    )
}

/// The estimator's table in `F` as a `static` named `name` (Rust source), and the expected
/// outcome of each stream (`expect`): a hash of every estimate (μ, σ, state) the estimator
/// gives on the host, which the device must reproduce bit for bit (IEEE f32 on both with no FMA
/// contraction; Q31.32 is integer arithmetic).
fn estimator<F: Float + Lit + Feed, M: Backend<F>>(
    p: &gough::mf::Params<f64>,
    name: &str,
    expect: &str,
    how: &str,
) -> String {
    let pf = p.cast::<F>();
    // On the heap: the Q31.32 table is twice the f32 one, too large for a thread's stack.
    let mut t = Box::new(GoughTable::<F>::zeroed());
    t.for_wheel_into::<M>(&pf, None)
        .expect("a usable Gough table");
    let ty = core::any::type_name::<F>();
    let mut s = format!(
        "/// The friction estimator's table for the bundled tyre, built on the host by build.rs\n\
         /// (`{how}`), in flash.\n\
         pub static {name}: gough::mu::GoughTable<{ty}> = gough::mu::GoughTable {{\n",
    );
    let curves = list(t.curves.iter().map(|g| {
        list(
            g.iter()
                .map(|j| list(j.iter().map(|side| list(side.iter().map(curve))))),
        )
    }));
    writeln!(
        s,
        "    fz: {},\n    lam: {},\n    cam: {},\n    curves: {},\n    fy_sign: {},\n    mu0: {},\n    mu_ratio: {},\n    mirrored: {},\n}};",
        list(t.fz.iter().map(|&x| x.lit())),
        list(t.lam.iter().map(|&x| x.lit())),
        list(t.cam.iter().map(|&x| x.lit())),
        curves,
        t.fy_sign.lit(),
        t.mu0.lit(),
        t.mu_ratio.lit(),
        t.mirrored
    )
    .expect("write");
    writeln!(s, "/// Expected (hash, identifiable samples, last μ hash) per stream of [`STREAMS`].\npub static {expect}: [(u32, u32, u32); STREAMS.len()] = [").expect("write");
    let p32 = p.cast::<f32>();
    for &(mu, camber, _) in STREAMS.iter() {
        let mut est = MuEstimator::for_tyre(&t, &pf, Config::default());
        let (mut h, mut seen, mut last) = (HASH0, 0u32, 0u32);
        for m in workload::Slalom::new(&p32, mu, camber).take(SAMPLES) {
            let e = est.update::<M>(&cast_sample(&m.sample(m.t_us as f32 / 1.0e6)));
            h = hash(h, &e);
            seen += u32::from(e.state == gough::mu::State::Identifiable);
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
    // The estimator's tables, for the builds that run it: f32 (feature `mu`) and Q31.32
    // (feature `mu-fix`: a Cortex-M3 with 4 MB, not the nRF51822).
    let mut est = String::from(
        "#[allow(dead_code)]\nconst fn b(x: u32) -> f32 {\n    f32::from_bits(x)\n}\n",
    );
    if cfg!(feature = "mu") {
        est.push_str(&estimator::<f32, Fast>(
            &p,
            "TABLE",
            "EXPECT",
            "GoughTable::<f32>::for_tyre::<math::Fast>",
        ));
    }
    #[cfg(feature = "mu-fix")]
    {
        est.push_str(
            "#[allow(dead_code)]\nconst fn x(v: i64) -> gough::fixed::Fix {\n    gough::fixed::Fix::from_bits(v)\n}\n",
        );
        est.push_str(&estimator::<Fix, FixMath>(
            &p,
            "TABLE_FIX",
            "EXPECT_FIX",
            "GoughTable::<Fix>::for_tyre::<FixMath>",
        ));
    }
    fs::write(out.join("estimator.rs"), est).expect("write estimator.rs");
    println!("cargo:rerun-if-changed={}", tir_path.display());
    println!("cargo:rerun-if-changed=memory-microbit.x");
    println!("cargo:rerun-if-changed=memory-an385.x");
    println!("cargo:rerun-if-changed=../src");
    println!("cargo:rerun-if-changed=build.rs");
}
