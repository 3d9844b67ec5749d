//! The core against the MFeval 4.0 oracle (`host-tests/data/oracle/`, see its README): every
//! file, every mode, every usable column, in f64 and in f32.
//!
//! Oracle = correctness reference written by somebody else. Budgets: `gough_host_tests::tolerance`.
//! Deliberate differences from MFeval are listed in `DIFFERENCES` with the reason; each is a
//! column we compare in a documented transformed way, never a column we skip silently.

use gough::mf::{Options, Params};
use gough_host::csvio;
use gough_host::mfrun::Precision;
use gough_host::mfrun::{eval_row, InputRow};
use gough_host_tests::tolerance;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("data")
}

/// Kind of budget a column gets.
#[derive(Clone, Copy)]
enum Unit {
    Force,
    Moment,
    /// dimensionless friction coefficient: force budget / FNOMIN
    Mu,
    /// a length in m (trail, relaxation length): moment budget / FNOMIN
    Length,
}

/// (oracle column, our column in `Output`, unit)
const COLUMNS: &[(&str, Unit)] = &[
    ("out_Fx", Unit::Force),
    ("out_Fy", Unit::Force),
    ("out_Mx", Unit::Moment),
    ("out_My", Unit::Moment),
    ("out_Mz", Unit::Moment),
    ("out_kappa", Unit::Mu),
    ("out_t", Unit::Length),
    ("out_mux", Unit::Mu),
    ("out_muy", Unit::Mu),
    ("out_Mzr", Unit::Moment),
    ("out_Kya", Unit::Force),
    ("out_Kxk", Unit::Force),
    ("out_sigmax", Unit::Length),
    ("out_sigmay", Unit::Length),
];

/// Deliberate differences, printed with the report (also in docs/magic-formula.md).
const DIFFERENCES: &[&str] = &[
    "out_muy: we report |muy| (a friction coefficient); MFeval reports the signed value when \
     limit checks are off (mode 2xx) and |muy| when they are on. Compared as magnitudes.",
    "mode 112 out_Mz/out_Mzr: MFeval gives NaN at phit = 0 (0/0 in zeta7); we take the limit. \
     NaN rows are not comparable and are counted, not compared.",
];

fn ours(o: &gough::mf::Output<f64>, col: &str) -> f64 {
    match col {
        "out_Fx" => o.fx,
        "out_Fy" => o.fy,
        "out_Mx" => o.mx,
        "out_My" => o.my,
        "out_Mz" => o.mz,
        "out_kappa" => o.kappa,
        "out_t" => o.t,
        "out_mux" => o.mu_x,
        "out_muy" => o.mu_y,
        "out_Mzr" => o.m_zr,
        "out_Kya" => o.k_ya,
        "out_Kxk" => o.k_xk,
        "out_sigmax" => o.sigma_x,
        "out_sigmay" => o.sigma_y,
        _ => f64::NAN,
    }
}

fn tyre_for(stem: &str) -> PathBuf {
    let name = stem.strip_suffix("_mfeval40").unwrap_or(stem);
    data().join("tyres").join(format!("{name}.tir"))
}

struct Failure(String);

fn check_file(path: &Path, prec: Precision, report: &mut Vec<String>) -> Vec<Failure> {
    let fname = path.file_stem().unwrap().to_str().unwrap().to_string();
    let mut parts = fname.split("__");
    let (stem, sweep, mode) = (
        parts.next().unwrap(),
        parts.next().unwrap(),
        parts.next().unwrap(),
    );
    let mode: u16 = mode.trim_start_matches("mode").parse().unwrap();
    let opts = Options::from_use_mode(mode).unwrap();
    let text = std::fs::read_to_string(tyre_for(stem)).unwrap();
    let p64: Params<f64> = gough::tir::parse(&text)
        .unwrap_or_else(|e| panic!("{stem}: {e}"))
        .params;
    let p32 = p64.cast::<f32>();
    let (fnomin, r0) = (p64.fnomin, p64.unloaded_radius);
    // The inputs, and every column by name (the oracle marks undefined values NaN).
    let inputs = csvio::read_with::<InputRow>(path, true).unwrap();
    let t = csvio::read_with::<BTreeMap<String, f64>>(path, true).unwrap();
    for &(col, _) in COLUMNS {
        assert!(t.has(col), "{fname}: no column {col}");
    }
    let mut failures = Vec::new();
    let mut worst = vec![(0.0f64, 0usize); COLUMNS.len()];
    let mut nan_rows = 0;
    for ((row, inp), line) in t.rows.iter().zip(&inputs.rows).zip(&t.lines) {
        let input = inp.input();
        let out = eval_row(&p64, &p32, &input, &opts, prec)
            .unwrap_or_else(|e| panic!("{fname}: line {line}: {e}"));
        for (k, &(col, unit)) in COLUMNS.iter().enumerate() {
            let mut want = row.get(col).copied().unwrap_or(f64::NAN);
            let mut got = ours(&out, col);
            if !want.is_finite() {
                nan_rows += 1;
                continue;
            }
            if col == "out_muy" {
                want = want.abs();
                got = got.abs();
            }
            let tol = match unit {
                Unit::Force => tolerance::force(fnomin, prec),
                Unit::Moment => tolerance::moment(fnomin, r0, prec),
                Unit::Mu => tolerance::force(fnomin, prec) / fnomin,
                Unit::Length => tolerance::moment(fnomin, r0, prec) / fnomin,
            };
            let err = (got - want).abs();
            if err.is_nan() || err > tol {
                failures.push(Failure(format!(
                    "{fname} {prec:?} line {line} {col}: ours {got:.9e} oracle {want:.9e} |err| {err:.3e} > {tol:.3e}  (in: {:?})",
                    inp.values()
                )));
            }
            if err > worst[k].0 || err.is_nan() {
                worst[k] = (err, *line);
            }
        }
    }
    let _ = sweep;
    let w: Vec<String> = COLUMNS
        .iter()
        .zip(&worst)
        .map(|((c, _), (e, _))| format!("{}={:.1e}", c.trim_start_matches("out_"), e))
        .collect();
    report.push(format!(
        "{fname} [{prec:?}] rows={} nan={nan_rows}: {}",
        t.rows.len(),
        w.join(" ")
    ));
    failures
}

fn run(prec: Precision) {
    let mut files: Vec<PathBuf> = std::fs::read_dir(data().join("oracle"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    files.sort();
    assert!(files.len() >= 70, "oracle files missing: {}", files.len());
    let mut report = Vec::new();
    let mut failures = Vec::new();
    for f in &files {
        failures.extend(check_file(f, prec, &mut report));
    }
    for r in &report {
        println!("{r}");
    }
    for d in DIFFERENCES {
        println!("deliberate difference: {d}");
    }
    if !failures.is_empty() {
        for f in failures.iter().take(40) {
            eprintln!("{}", f.0);
        }
        panic!("{} oracle mismatches ({prec:?})", failures.len());
    }
}

#[test]
fn oracle_f64() {
    run(Precision::F64);
}

#[test]
fn oracle_f32() {
    run(Precision::F32);
}
