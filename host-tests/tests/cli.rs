//! The `gough` binary end to end: what a user types, what they get, and every bad-input path
//! (one-line error naming file, line and column; exit code ≠ 0; no output file left behind).
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn gough(args: &[&str]) -> Output {
    Command::new(gough_host_tests::gough_bin())
        .args(args)
        .output()
        .expect("run gough")
}

fn data(rel: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data")
        .join(rel)
        .to_string_lossy()
        .into_owned()
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gough-cli-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn mf_eval_reproduces_the_oracle_end_to_end() {
    let input = data("oracle/MagicFormula61_Parameters_mfeval40__combined__mode111.csv");
    let out = tmp("combined.csv");
    for prec in ["f64", "f32"] {
        let o = gough(&[
            "mf",
            "eval",
            "--tir",
            &data("tyres/MagicFormula61_Parameters.tir"),
            "--input",
            &input,
            "--output",
            out.to_str().unwrap(),
            "--mode",
            "111",
            "--precision",
            prec,
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = std::fs::read_to_string(&out).unwrap();
        let mut lines = text.lines();
        assert_eq!(
            lines.next().unwrap(),
            "in_Fz,in_kappa,in_alpha,in_gamma,in_phit,in_Vx,in_P,Fx,Fy,Mz,Mx,My,mux,muy,Kya,Kxk,t,Mzr,sigmax,sigmay"
        );
        let ours: Vec<Vec<f64>> = lines
            .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
            .collect();
        let oracle = std::fs::read_to_string(&input).unwrap();
        let oracle: Vec<Vec<f64>> = oracle
            .lines()
            .skip(1)
            .map(|l| l.split(',').map(|c| c.parse().unwrap()).collect())
            .collect();
        assert_eq!(ours.len(), oracle.len());
        let tol = if prec == "f64" {
            1e-6 * 6752.0
        } else {
            1e-4 * 6752.0
        };
        for (a, b) in ours.iter().zip(&oracle) {
            assert!((a[7] - b[7]).abs() < tol, "Fx {} vs {}", a[7], b[7]); // Fx vs out_Fx
            assert!((a[8] - b[8]).abs() < tol, "Fy {} vs {}", a[8], b[8]); // Fy vs out_Fy
            assert!((a[9] - b[12]).abs() < tol * 0.4, "Mz {} vs {}", a[9], b[12]);
            // Mz vs out_Mz
        }
    }
}

#[test]
fn tir_check_reports_and_rejects() {
    let o = gough(&["tir", "check", &data("tyres/MagicFormula52_Parameters.tir")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let s = String::from_utf8_lossy(&o.stdout);
    assert!(
        s.contains("MF-Tyre 5.2") && s.contains("9416.6") && s.contains("0.4 m"),
        "{s}"
    );

    let o = gough(&["tir", "check", &data("tyres/Model_Unstable.tir")]);
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("Model_Unstable.tir") && e.contains("PCX1"),
        "{e}"
    );
    assert_eq!(e.trim().lines().count(), 1, "one-line error: {e}");
}

fn eval_expect_error(tir: &str, csv_text: &str, mode: &str, want: &[&str]) {
    let input = tmp(&format!(
        "in-{}.csv",
        want.join("_").replace([' ', '/', '.'], "")
    ));
    std::fs::write(&input, csv_text).unwrap();
    let out = tmp(&format!(
        "out-{}.csv",
        want.join("_").replace([' ', '/', '.'], "")
    ));
    let _ = std::fs::remove_file(&out);
    let o = gough(&[
        "mf",
        "eval",
        "--tir",
        tir,
        "--input",
        input.to_str().unwrap(),
        "--output",
        out.to_str().unwrap(),
        "--mode",
        mode,
    ]);
    assert!(!o.status.success(), "should fail: {want:?}");
    let e = stderr(&o);
    assert_eq!(e.trim().lines().count(), 1, "one-line error: {e}");
    for w in want {
        assert!(e.contains(w), "error '{e}' should mention '{w}'");
    }
    assert!(!out.exists(), "no output may be written on error");
}

#[test]
fn bad_inputs_give_one_line_errors_and_no_output() {
    let tir = data("tyres/MagicFormula61_Parameters.tir");
    let good_header = "in_Fz,in_kappa,in_alpha,in_gamma,in_phit,in_Vx,in_P";
    eval_expect_error(
        &tir,
        "in_Fz,in_kappa,in_gamma,in_Vx\n4000,0,0,10\n",
        "111",
        &["in_alpha", "line 1"],
    );
    eval_expect_error(
        &tir,
        &format!("{good_header}\n4000,0,0,0,0,10,0\n4000,0,abc,0,0,10,0\n"),
        "111",
        &["line 3", "in_alpha", "abc"],
    );
    eval_expect_error(
        &tir,
        &format!("{good_header}\n4000,0,0,0,0,10\n"),
        "111",
        &["line 2"],
    );
    eval_expect_error(
        &tir,
        &format!("{good_header}\n4000,0,0,0,0,10,0\n"),
        "311",
        &["--mode 311"],
    );
    eval_expect_error(
        &tir,
        "in_Fz,in_kappa,in_alpha,in_gamma\n4000,0,0,0\n",
        "111",
        &["in_Vx"],
    );
    eval_expect_error(
        &data("tyres/Model_Unstable.tir"),
        &format!("{good_header}\n4000,0,0,0,0,10,0\n"),
        "111",
        &["Model_Unstable.tir", "PCX1"],
    );
    eval_expect_error(
        &data("tyres/missing.tir"),
        &format!("{good_header}\n4000,0,0,0,0,10,0\n"),
        "111",
        &["missing.tir"],
    );
    // Turn slip on a file that has none: the row is named.
    eval_expect_error(
        &data("tyres/MagicFormula52_Parameters.tir"),
        &format!("{good_header}\n4000,0,0,0,0,10,0\n"),
        "112",
        &["line 2", "turn slip"],
    );
}

#[test]
fn bundled_example_runs() {
    let ex = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/mf_sweep.csv");
    let out = tmp("sweep.csv");
    let o = gough(&[
        "mf",
        "eval",
        "--tir",
        &data("tyres/MagicFormula61_Parameters.tir"),
        "--input",
        ex.to_str().unwrap(),
        "--output",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(
        std::fs::read_to_string(&out).unwrap().lines().count(),
        1 + 75 + 21
    );
}
