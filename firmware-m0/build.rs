//! Puts `memory.x` (nRF51822) where cortex-m-rt's `link.x` finds it, and computes the f64
//! reference outputs (Fx, Fy, Mz) of the bench's points on the host: `mf::eval::<f64, Libm>` on
//! the bundled MF 6.1 tyre, written to `$OUT_DIR/reference.rs` with the tyre's parameters as
//! `gough::tir::parse` reads them (f64; the bench casts them at boot).
use gough::math::Libm;
use gough::mf::{self, Input, Options};
use std::{env, fmt::Write as _, fs, path::PathBuf};

include!("src/points.rs");

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
    fs::copy(dir.join("memory.x"), out.join("memory.x")).expect("copy memory.x");
    println!("cargo:rustc-link-search={}", out.display());

    let tir_path = dir.join("../host-tests/data/tyres/MagicFormula61_Parameters.tir");
    let text = fs::read_to_string(&tir_path).expect("read the bundled .tir");
    let p = gough::tir::parse(&text)
        .expect("parse the bundled .tir")
        .params;
    let mut s = String::from("/// f64 reference (Fx, Fy, Mz) per point, from build.rs.\npub static REF: [[f64; 3]; N] = [\n");
    for i in 0..N {
        let (fz, kappa, alpha) = inputs(i);
        let input = Input {
            fz,
            kappa,
            alpha,
            gamma: 0.0,
            phit: 0.0,
            vx: 16.6,
            p: None,
        };
        let (fx, fy, mz) = match mf::eval::<f64, Libm>(&p, &input, &Options::default()) {
            Ok(o) => (o.fx, o.fy, o.mz),
            Err(_) => (f64::NAN, f64::NAN, f64::NAN),
        };
        writeln!(s, "    [{}, {}, {}],", lit(fx), lit(fy), lit(mz)).expect("write");
    }
    s.push_str("];\n");
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
    println!("cargo:rerun-if-changed={}", tir_path.display());
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-changed=src/points.rs");
    println!("cargo:rerun-if-changed=build.rs");
}
