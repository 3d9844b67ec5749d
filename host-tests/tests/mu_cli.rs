//! `gough mu estimate` / `gough mu demo` end to end, and their bad-input paths.
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn gough(args: &[&str]) -> Output {
    gough_in(Path::new("."), args)
}

/// `gough` run from the directory `dir` (as a user runs it from the repository's root).
fn gough_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(gough_host_tests::gough_bin())
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run gough")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gough-mu-cli-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn tyre() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data/tyres/MagicFormula61_Parameters.tir")
        .to_string_lossy()
        .into_owned()
}

/// A steady-state log from the Magic Formula itself: the slip angle ramps up on a μ = 0.5 road.
fn write_log(path: &Path) {
    use gough::math::Libm;
    use gough::mf::{self, Input, Options};
    let p = gough::tir::parse(&std::fs::read_to_string(tyre()).unwrap())
        .unwrap()
        .params;
    let mu0 = mf::eval::<f64, Libm>(
        &p,
        &Input {
            fz: p.fnomin,
            vx: 20.0,
            ..Input::default()
        },
        &Options {
            limits: false,
            ..Options::default()
        },
    )
    .unwrap()
    .mu_y;
    let mut q = p.clone();
    q.lmux = 0.5 / mu0;
    q.lmuy = 0.5 / mu0;
    let mut s = String::from("t,fz,fy,mz,fx,vx,alpha,kappa\n");
    for i in 0..1500 {
        let t = i as f64 * 1e-3;
        let alpha = 0.04 * (t / 0.8).min(1.0);
        let o = mf::eval::<f64, Libm>(
            &q,
            &Input {
                fz: 6000.0,
                alpha,
                vx: 20.0,
                ..Input::default()
            },
            &Options::default(),
        )
        .unwrap();
        s += &format!("{t},{},{},{},{},20,{alpha},0\n", o.fz, o.fy, o.mz, o.fx);
    }
    std::fs::write(path, s).unwrap();
}

#[test]
fn estimate_reads_mu_from_a_log() {
    let log = tmp("log.csv");
    write_log(&log);
    for (method, prec) in [
        ("bank", "f64"),
        ("bank", "f32"),
        ("hsu-gerdes", "f64"),
        ("slip-slope", "f64"),
    ] {
        let out = tmp(&format!("est-{method}-{prec}.csv"));
        let o = gough(&[
            "mu",
            "estimate",
            "--tir",
            &tyre(),
            "--log",
            log.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--method",
            method,
            "--precision",
            prec,
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let text = std::fs::read_to_string(&out).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("t,mu,sigma,state"));
        let last: Vec<&str> = lines.last().unwrap().split(',').collect();
        let mu: f64 = last[1].parse().unwrap();
        assert!(["identifiable", "not_identifiable", "fallback"].contains(&last[3]));
        if method == "bank" {
            assert_eq!(last[3], "identifiable");
            assert!((mu - 0.5).abs() < 0.05, "{method} {prec}: μ {mu}");
        }
    }
}

fn expect_error(log_text: &str, want: &[&str]) {
    let log = tmp(&format!(
        "bad-{}.csv",
        want.join("-").replace([' ', ',', '.'], "")
    ));
    std::fs::write(&log, log_text).unwrap();
    let out = tmp("bad-out.csv");
    let _ = std::fs::remove_file(&out);
    let o = gough(&[
        "mu",
        "estimate",
        "--tir",
        &tyre(),
        "--log",
        log.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(e.trim().lines().count(), 1, "one-line error: {e}");
    for w in want {
        assert!(e.contains(w), "'{e}' should mention '{w}'");
    }
    assert!(!out.exists());
}

#[test]
fn bad_logs_give_one_line_errors() {
    expect_error("t,fz,fy\n0,1,2\n", &["mz", "line 1"]);
    expect_error(
        "t,fz,fy,mz\n0,6000,100,1\n0,6000,100,1\n",
        &["line 3", "time does not increase"],
    );
    expect_error("t,fz,fy,mz\n0,6000,abc,1\n", &["line 2", "fy", "abc"]);
    expect_error("t,fz,fy,mz,fx\n0,6000,1,1,nan\n", &["line 2", "fx"]);
}

#[test]
fn demo_runs_and_writes_its_outputs() {
    let dir = tmp("demo");
    let o = gough(&[
        "mu",
        "demo",
        "--tir",
        &tyre(),
        "--manoeuvre",
        "step-steer",
        "--road",
        "mu=0.5",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for f in ["estimates.csv", "log_fl.csv", "mu.png", "gough.png"] {
        assert!(dir.join(f).exists(), "{f}");
    }
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(table.contains("fl") && table.contains("rr"), "{table}");
}

/// The README's main command prints the table its console block shows (the demo is
/// deterministic: one noise seed), run as a new user runs it, from the repository's root with
/// the defaults; so that block cannot go stale unnoticed. (Only `--out` differs, and with it the
/// last line, which names the files.) The same for docs/estimator.md's `mu estimate --why`
/// block on the demo's log.
#[test]
fn readme_demo_block_is_what_the_demo_prints() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let cmd = "$ cargo run --release --bin gough -- mu demo\n";
    let start = readme.find(cmd).expect("the README's demo command") + cmd.len();
    let block: Vec<&str> = readme[start..]
        .lines()
        .take_while(|l| !l.starts_with("-> ") && !l.starts_with("```"))
        .collect();
    assert!(block.len() >= 6, "{block:?}");
    let dir = tmp("readme-demo");
    let o = gough_in(&root, &["mu", "demo", "--out", dir.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    let printed: Vec<&str> = out.lines().take_while(|l| !l.starts_with("-> ")).collect();
    assert_eq!(
        printed, block,
        "README.md's demo block differs from what `gough mu demo` prints"
    );
    // docs/estimator.md's `mu estimate --why` on the demo's front-left log prints what its
    // block shows (the paths moved to this test's directory).
    let page = std::fs::read_to_string(root.join("docs/estimator.md")).unwrap();
    let cmd = "$ cargo run --release --bin gough -- ";
    let start = page
        .find(&format!("{cmd}mu estimate "))
        .expect("docs/estimator.md's estimate command");
    let mut lines = page[start..].lines();
    let args: Vec<String> = lines.next().unwrap()[cmd.len()..]
        .split(' ')
        .map(|a| match a {
            "out/demo/log_fl.csv" => dir.join("log_fl.csv").to_string_lossy().into_owned(),
            "out/est.csv" => dir.join("est.csv").to_string_lossy().into_owned(),
            a => a.to_owned(),
        })
        .collect();
    let block: Vec<String> = lines
        .take_while(|l| !l.starts_with("```"))
        .map(|l| l.replace("out/est.csv", &dir.join("est.csv").to_string_lossy()))
        .collect();
    let o = gough_in(&root, &args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(
        err.lines().collect::<Vec<_>>(),
        block,
        "docs/estimator.md's estimate block differs from what `gough mu estimate` prints"
    );
}

/// `gough` with `args` fails with a one-line error that `says` something.
fn one_line_error(args: &[&str], says: &str) {
    let bad = gough(args);
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains(says), "{err}");
}

/// `gough mu bound` on the bundled tyre and the bench's first `cases` cases, written to `dir`,
/// with `extra` arguments.
fn bound(cases: &str, dir: &Path, extra: &[&str]) -> Output {
    let (tir, out) = (tyre(), dir.to_str().unwrap().to_string());
    let mut args = vec![
        "mu", "bound", "--tir", &tir, "--cases", cases, "--out", &out,
    ];
    args.extend_from_slice(extra);
    gough(&args)
}

/// `gough mu bound` on the bench's first three cases (step steer on μ 1.0, 0.7, 0.5): a row per
/// wheel and surface that reaches utilisation 0.5, σ_CRB falling from that moment to 150 ms
/// later (information only accumulates), "decidable" exactly where 1.96·σ ≤ 0.1, and the
/// bank's latency beside it (those of `gough mu bench`, `bench_writes_its_tables_and_bound_reads_the_same_bank`):
/// on these cases every one of the ten decidable and read within 150 ms. With the tyre's
/// calibration unknown too, σ only grows, and "decidable" is again exactly 1.96·σ ≤ 0.1.
#[test]
fn bound_gives_each_wheel_a_crb_and_the_estimator_s_latency() {
    let dir = tmp("bound");
    let o = bound("3", &dir, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(dir.join("bound.csv")).unwrap();
    assert!(csv.starts_with(
        "manoeuvre,road,wheel,mu,sigma_at_util,sigma_at_deadline,decidable,sigma_cal_at_deadline,decidable_cal,bank_latency_s,ml_within\n"
    ));
    let mut rows = 0;
    for line in csv.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        assert_eq!(f.len(), 11, "{line}");
        let (at_util, at_dead) = (f[4].parse::<f64>().unwrap(), f[5].parse::<f64>().unwrap());
        assert!(at_dead > 0.0 && at_dead <= at_util, "{line}");
        assert_eq!(f[6] == "true", 1.96 * at_dead <= 0.1, "{line}");
        assert_eq!(f[6], "true", "{line}");
        let cal: f64 = f[7].parse().unwrap();
        assert!(cal >= at_dead * (1.0 - 1e-9), "{line}");
        assert_eq!(f[8] == "true", 1.96 * cal <= 0.1, "{line}");
        let lat: f64 = f[9].parse().unwrap();
        assert!(lat <= 0.15, "{line}");
        rows += 1;
    }
    assert_eq!(rows, 10, "{csv}");
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(table.contains("decidable"), "{table}");
    // A file that is not there: a one-line error, no table.
    one_line_error(
        &[
            "mu",
            "bound",
            "--tir",
            "/nonexistent/tyre.tir",
            "--cases",
            "1",
        ],
        "/nonexistent/tyre.tir",
    );
}

/// `gough mu bound --ml-window S` gives the maximum-likelihood reference that much of the
/// run-up. On the step steer on μ 1.0 a 50 ms window reads neither wheel within ±0.1 by the
/// deadline, a 300 ms window both: what decides μ there is the way the point got there, not the
/// last few readings. A window outside (0, 10] s is a one-line error, before the tyre is read.
#[test]
fn the_reference_needs_the_run_up() {
    let within = |window: &str| {
        let dir = tmp(&format!("bound_ml_{window}"));
        let o = bound("1", &dir, &["--ml-window", window]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let table = String::from_utf8_lossy(&o.stdout).into_owned();
        assert!(table.contains(&format!("({window} s window)")), "{table}");
        let csv = std::fs::read_to_string(dir.join("bound.csv")).unwrap();
        csv.lines()
            .skip(1)
            .map(|l| {
                (
                    l.split(',').nth(2).unwrap().to_string(),
                    l.ends_with(",true"),
                )
            })
            .collect::<Vec<_>>()
    };
    let fl_rl = |w: bool| vec![("fl".to_string(), w), ("rl".to_string(), w)];
    assert_eq!(within("0.05"), fl_rl(false));
    assert_eq!(within("0.3"), fl_rl(true));
    for bad in ["0", "-1", "nan", "11"] {
        let arg = format!("--ml-window={bad}");
        one_line_error(
            &["mu", "bound", "--tir", "/nonexistent/tyre.tir", &arg],
            "--ml-window",
        );
    }
}

/// `gough mu bench` on the first three cases (step steer on μ 1.0, 0.7, 0.5): the rows of the
/// estimators (the peers, then the bank; no other), the closing lines, the bank against the
/// others, and every wheel-surface of the bank with its latency (`wheels.csv`), as many as the
/// bank's rows of `table.csv` count; `gough mu bound` on the same cases puts beside each
/// wheel-surface the bank's latency that `wheels.csv` has (the same wheels, the same run).
#[test]
fn bench_writes_its_tables_and_bound_reads_the_same_bank() {
    let dir = tmp("bench-tables");
    // The bench's vehicle suite only (its wheel cases: tests/mu_bench.rs).
    let args = |cmd: &'static str| -> Vec<String> {
        let mut a = [
            "mu",
            cmd,
            "--tir",
            &tyre(),
            "--cases",
            "3",
            "--out",
            dir.join(cmd).to_str().unwrap(),
        ]
        .map(String::from)
        .to_vec();
        if cmd == "bench" {
            a.extend(["--only", "vehicle"].map(String::from));
        }
        a
    };
    let run = |cmd: &'static str| {
        let a = args(cmd);
        let o = gough(&a.iter().map(String::as_str).collect::<Vec<_>>());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        o
    };
    let out = run("bench");
    let text = String::from_utf8_lossy(&out.stdout);
    // One row per case and estimator, in the bench's order.
    let methods: Vec<&str> = text
        .lines()
        .filter(|l| l.starts_with("| step-steer | mu=1.0 |"))
        .map(|l| l.split(" | ").nth(2).unwrap())
        .collect();
    assert_eq!(methods, ["hsu-gerdes", "slip-slope", "bank"], "{text}");
    // The issue's cases are the suite without its five straight ABS stops, counted apart.
    let suite = gough_host::mu::bench::suite();
    assert_eq!(
        suite
            .iter()
            .filter(|c| c.group == gough_host::mu::bench::Group::StraightStop)
            .count(),
        5
    );
    assert_eq!(suite.len(), 34);
    assert!(
        text.contains("bank, without the straight ABS stops: within ±0.1 within 0.15 s of utilisation 0.5 on ")
            && text.contains(" of 3 cases and "),
        "{text}"
    );
    // The bank against each other estimator, case by case, on the issue's measures.
    assert!(
        text.contains("## The bank against the others, case by case")
            && text.contains("bank against hsu-gerdes: ws level or ahead on ")
            && text.contains("bank against slip-slope: ws level or ahead on ")
            && text.contains(" of 3 cases; p95 on "),
        "{text}"
    );
    // Change flags counted, and the false ones among them.
    assert!(
        text.contains(" false change alarms of ") && text.contains(" change flags; worst p95"),
        "{text}"
    );
    // Each method's identifiable share, over all samples and those at utilisation ≥ 0.5.
    assert!(
        text.contains("bank: identifiable on ")
            && text.contains(" % of those at utilisation 0.5 or more ("),
        "{text}"
    );
    // Every wheel-surface of the bank with its latency (`wheels.csv`), as many as the bank's
    // rows of `table.csv` count, and the misses listed in the table.
    assert!(
        text.contains("## Wheel-surfaces the bank does not read within 0.15 s"),
        "{text}"
    );
    let wheels = std::fs::read_to_string(dir.join("bench/wheels.csv")).unwrap();
    let rows: Vec<Vec<&str>> = wheels
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let table = std::fs::read_to_string(dir.join("bench/table.csv")).unwrap();
    let (within, total) = table
        .lines()
        .filter(|l| l.contains(",bank,"))
        .map(|l| {
            let f: Vec<&str> = l.rsplitn(3, ',').collect();
            (
                f[1].parse::<usize>().unwrap(),
                f[0].parse::<usize>().unwrap(),
            )
        })
        .fold((0, 0), |(a, b), (c, d)| (a + c, b + d));
    assert!(total > 0);
    assert_eq!(rows.len(), total, "{wheels}");
    assert_eq!(
        rows.iter().filter(|r| r[8] == "true").count(),
        within,
        "{wheels}"
    );
    // `gough mu bound`: the same wheel-surfaces, each with the latency `wheels.csv` gives it.
    run("bound");
    let bound = std::fs::read_to_string(dir.join("bound/bound.csv")).unwrap();
    let b: Vec<Vec<&str>> = bound
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    assert_eq!(b.len(), rows.len(), "{bound}\n{wheels}");
    for (w, b) in rows.iter().zip(&b) {
        assert_eq!((w[0], w[1], w[2]), (b[0], b[1], b[2]), "{w:?} {b:?}");
        match (w[7].parse::<f64>(), b[9].parse::<f64>()) {
            (Ok(x), Ok(y)) => assert!((x - y).abs() <= 5e-4, "{w:?} {b:?}"),
            (x, y) => assert!(x.is_err() && y.is_err(), "{w:?} {b:?}"),
        }
    }
    // A quick bench run (the first `cases` cases) into dir/`name` with `extra` arguments:
    // its output directory and table.md.
    let quick = |name: &str, cases: &str, extra: &[&str]| {
        let out = dir.join(name);
        let tir = tyre();
        let mut args = vec![
            "mu", "bench", "--tir", &tir, "--cases", cases, "--only", "vehicle",
        ];
        args.extend(["--out", out.to_str().unwrap()]);
        args.extend(extra);
        let o = gough(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let md = std::fs::read_to_string(out.join("table.md")).unwrap();
        (out, md)
    };
    // The sensors can be changed too (`--noise-mz`, `--noise-f`, `--delay`); the table says
    // so, and a value out of range is a one-line error.
    let (_, md) = quick(
        "bench-quiet",
        "1",
        &["--noise-mz", "0", "--noise-f", "0", "--delay", "0"],
    );
    assert!(
        md.contains(
            "Sensor model changed from the default: Mz 0 N·m rms, F 0.00 % Fz rms, 0.0 ms delay."
        ),
        "{md}"
    );
    one_line_error(
        &["mu", "bench", "--cases", "1", "--delay", "-0.01"],
        "--delay -0.01",
    );
    one_line_error(&["mu", "bench", "--seeds", "5-1"], "--seeds 5-1");
    let out = tmp("bench-no-tyres");
    one_line_error(
        &[
            "mu",
            "bench",
            "--only",
            "wheel",
            "--tyres",
            "/nonexistent",
            "--out",
            out.to_str().unwrap(),
        ],
        "/nonexistent",
    );
    // The estimators can be given a tyre that is not the simulated one (`--model-error`):
    // the table says so, and a name the file format does not have, a delta that is not a
    // number or a tyre the `.tir` checks refuse is a one-line error.
    let (_, md) = quick(
        "bench-model-error",
        "1",
        &["--model-error", "PHY1=0.002,pvy1=-0.01"],
    );
    assert!(
        md.contains("the estimators' tyre is")
            && md.contains("with PHY1=0.002, PVY1=-0.01; the simulation's is the file."),
        "{md}"
    );
    let tir = tyre();
    for (e, says) in [
        ("PHZ9=0.1", "no .tir parameter 'PHZ9'"),
        ("PHY1=inf", "not a finite number"),
        ("FNOMIN=-1e9", "FNOMIN"),
    ] {
        one_line_error(
            &[
                "mu",
                "bench",
                "--tir",
                &tir,
                "--cases",
                "1",
                "--only",
                "vehicle",
                "--model-error",
                e,
            ],
            says,
        );
    }
}

/// `gough mu map` on the bundled MF 6.1 tyre: steady, noise-free points of the tyre's own Magic
/// Formula through the bank, each held for 150 ms at 1 kHz. Every surface at every load is read
/// below the peak, its first estimate within ±0.1 and within 2σ of the truth (what
/// `identifiable` promises; on a steady point the surface within a cell is barely informed, and
/// the first estimates lean by up to +0.075). On the dry road at Fz0 μ becomes identifiable
/// only above utilisation 0.5 (the curves of μ 1.0 and 1.1 are under 1.2 mm of trail apart
/// there); at Fz0 and above μ ≥ 0.3 is read from utilisation 0.6 at most and every surface from
/// 0.7. Without an Fx measurement (`--no-fx`) no surface is read sooner, μ ≥ 0.3 still at every
/// load. With camber (`--gamma ±0.0225`, 1.3°): where the camber thrust adds to the force the
/// curves of μ and μ + 0.1 all but touch at utilisation 0.5 for μ ≥ 0.6 (the trail no longer
/// tells them apart) and the bank reads none of those sooner than without camber; against it
/// they are further apart than without camber and every surface is read sooner, from
/// utilisation 0.45 at most. A bad file or camber is a one-line error.
#[test]
fn map_says_from_which_utilisation_mu_is_read() {
    let run = |name: &str, extra: &[&str]| -> Vec<Vec<f64>> {
        let csv = tmp(name);
        let tir = tyre();
        let mut args = vec!["mu", "map", "--tir", &tir, "--out", csv.to_str().unwrap()];
        args.extend_from_slice(extra);
        let o = gough(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let table = String::from_utf8_lossy(&o.stdout);
        assert_eq!(
            table.lines().filter(|l| l.starts_with("| 0.")).count(),
            9,
            "{table}"
        );
        assert!(
            table.contains("the bank's defaults at 1 kHz for 150 ms per point"),
            "{table}"
        );
        let text = std::fs::read_to_string(&csv).unwrap();
        text.lines()
            .skip(1)
            .map(|l| {
                l.split(',')
                    .map(|x| x.parse().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect()
    };
    // Where read, the first estimate is within ±0.1 and within 2σ of the truth.
    let honest = |rows: &[Vec<f64>], what: &str| {
        for r in rows.iter().filter(|r| r[2].is_finite()) {
            let (mu, load, err, sigma) = (r[0], r[1], r[3], r[4]);
            assert!(
                err.abs() < 0.1 && err.abs() <= 2.0 * sigma,
                "{what}: μ {mu} load {load}: first estimate off by {err}, σ {sigma}"
            );
        }
    };
    let rows = run("map.csv", &[]);
    let no_fx = run("map_no_fx.csv", &["--no-fx"]);
    assert_eq!((rows.len(), no_fx.len()), (30, 30));
    honest(&rows, "Fx measured");
    honest(&no_fx, "no Fx");
    for r in &rows {
        let (mu, load, util, gap) = (r[0], r[1], r[2], r[6]);
        assert!(util.is_finite(), "μ {mu} load {load}: never identifiable");
        // From a cold start the calibration's σ of the trail (in μ's σ) holds a steady point
        // back until the force nears the limit: at Fz0 and above, every surface is read from
        // utilisation 0.9 at the latest (the v2 bank, which took the file as exact: 0.6, and
        // 0.7 on ice; docs/estimator.md, "From which utilisation it reads μ").
        if load >= 1.0 {
            let latest = 0.9;
            assert!(
                util <= latest,
                "μ {mu} load {load}: from utilisation {util}"
            );
        }
        assert!(
            gap > 0.0,
            "μ {mu} load {load}: the grippier curve's trail is longer"
        );
    }
    for (r, n) in rows.iter().zip(&no_fx) {
        let (mu, load) = (r[0], r[1]);
        assert_eq!((mu, load), (n[0], n[1]));
        assert!(
            n[2].is_nan() || n[2] >= r[2],
            "no Fx: μ {mu} load {load} read from {} against {} with Fx",
            n[2],
            r[2]
        );
        assert!(
            mu < 0.25 || n[2].is_finite(),
            "no Fx: μ {mu} load {load} never read"
        );
    }
    let dry = rows.iter().find(|r| r[0] == 1.0 && r[1] == 1.0).unwrap();
    assert!(dry[2] > 0.5, "dry at Fz0 read from utilisation {}", dry[2]);
    assert!((0.0006..0.0012).contains(&dry[6]), "trail gap {} m", dry[6]);
    // Camber (`--gamma`): on this tyre γ > 0 adds camber thrust to the force of the sweep
    // (α > 0, Fy < 0) and shortens the trail; γ < 0 works against it.
    let with = run("map_gamma_with.csv", &["--gamma=0.0225"]);
    let against = run("map_gamma_against.csv", &["--gamma=-0.0225"]);
    honest(&with, "with the thrust");
    honest(&against, "against the thrust");
    for (r, a) in rows.iter().zip(&against) {
        let (mu, load, util) = (a[0], a[1], a[2]);
        assert!(
            // Sooner than without camber at every μ and load (from 0.30–0.42 with the v2 bank,
            // which took the file as exact; now the trail's σ holds a steady point back).
            util < r[2],
            "against the thrust: μ {mu} load {load} read from utilisation {util} ({} without camber)",
            r[2]
        );
    }
    for (r, w) in rows.iter().zip(&with).filter(|(r, _)| r[0] >= 0.6) {
        assert!(
            w[2].is_nan() || w[2] >= r[2],
            "with the thrust: μ {} load {} read from utilisation {} ({} without camber)",
            w[0],
            w[1],
            w[2],
            r[2]
        );
    }
    let at_fz0 = |rows: &[Vec<f64>], mu: f64| -> Vec<f64> {
        rows.iter()
            .find(|r| r[0] == mu && r[1] == 1.0)
            .unwrap()
            .clone()
    };
    for &mu in &[1.0, 0.9, 0.8, 0.7, 0.6, 0.5, 0.4, 0.3, 0.2, 0.1] {
        let (plain, w, a) = (at_fz0(&rows, mu), at_fz0(&with, mu), at_fz0(&against, mu));
        // The physics: with the thrust the curve of μ + 0.1 comes no further from μ's at
        // utilisation 0.5 than without camber, and for μ ≥ 0.6 it all but touches it (under
        // 0.4 mm of trail apart); against it, the curves are further apart.
        assert!(
            w[6] < plain[6],
            "μ {mu}: gap {} with the thrust vs {}",
            w[6],
            plain[6]
        );
        if mu >= 0.6 {
            assert!(w[6].abs() < 4e-4, "μ {mu}: gap {} m with the thrust", w[6]);
        }
        assert!(
            a[6] > plain[6],
            "μ {mu}: gap {} against the thrust vs {}",
            a[6],
            plain[6]
        );
    }
    // A camber that is no angle is a one-line error, not a map of "not identifiable".
    let tir = tyre();
    let o = gough(&["mu", "map", "--tir", &tir, "--gamma=nan"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("--gamma"), "{err}");
    let bad = tmp("bad.tir");
    std::fs::write(&bad, "[MODEL]\nFITTYP = 61\nPDY1 = abc\n").unwrap();
    let o = gough(&["mu", "map", "--tir", bad.to_str().unwrap()]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(err.contains("bad.tir"), "{err}");
}

/// `gough mu estimate` gives the same estimates for a log whose clock reads 10⁶ s more (the
/// estimator takes wrapping microsecond differences, never a growing float time).
#[test]
fn the_clock_offset_of_a_log_changes_nothing() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let src = std::fs::read_to_string(root.join("examples/gap_thermal_mu.csv")).unwrap();
    let mut lines = src.lines();
    let header = lines.next().unwrap();
    assert!(header.starts_with("t,"), "{header}");
    let mut shifted = format!("{header}\n");
    for l in lines {
        let (t, rest) = l.split_once(',').unwrap();
        let t: f64 = t.parse().unwrap();
        shifted.push_str(&format!("{},{rest}\n", t + 1.0e6));
    }
    let (a, b) = (tmp("offset-a.csv"), tmp("offset-b.csv"));
    std::fs::write(&a, &src).unwrap();
    std::fs::write(&b, &shifted).unwrap();
    let est = |log: &Path, out: &Path| {
        let o = gough(&[
            "mu",
            "estimate",
            "--tir",
            &tyre(),
            "--log",
            log.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        std::fs::read_to_string(out).unwrap()
    };
    let (ea, eb) = (est(&a, &tmp("offset-a.est")), est(&b, &tmp("offset-b.est")));
    let cols = |s: &str| -> Vec<String> {
        s.lines()
            .skip(1)
            .map(|l| l.split_once(',').unwrap().1.to_string())
            .collect()
    };
    let (ca, cb) = (cols(&ea), cols(&eb));
    assert_eq!(ca.len(), src.lines().count() - 1);
    assert_eq!(ca, cb, "estimates differ with the clock offset");
    // Not a vacuous comparison: the log excites the tyre, and the estimator reads μ on it.
    assert!(ca
        .iter()
        .any(|l| l.ends_with("identifiable") && !l.ends_with("not_identifiable")));
}

/// A four-wheel log (a `wheel` column, rows interleaved): the slalom onto ice of the bench, as
/// its sensors measure it.
fn write_car_log(path: &Path) -> usize {
    use gough_host::mu::bench::{measure, simulate_case, suite, Sensors};
    let p = gough_host::tyre::load(Path::new(&tyre())).unwrap().params;
    let case = suite()
        .into_iter()
        .find(|c| c.road == "step=1.0@0,0.3@90")
        .unwrap();
    let log = simulate_case(&p, &case).unwrap();
    let traces: Vec<_> = (0..4)
        .map(|w| measure(&log, w, &Sensors::default(), 1))
        .collect();
    let mut s = String::from("t,wheel,fz,fy,mz,fx,vx,kappa,gamma\n");
    let n = traces[0].rows.len();
    for i in 0..n {
        for (w, tr) in traces.iter().enumerate() {
            let r = &tr.rows[i];
            let v = |x: Option<f64>| x.unwrap();
            s.push_str(&format!(
                "{},{w},{},{},{},{},{},{},{}\n",
                r.t,
                r.fz,
                r.fy,
                r.mz,
                v(r.fx),
                v(r.vx),
                v(r.kappa),
                v(r.gamma)
            ));
        }
    }
    std::fs::write(path, s).unwrap();
    n
}

#[test]
fn a_four_wheel_log_runs_each_wheel_and_the_preview() {
    let log = tmp("car.csv");
    let n = write_car_log(&log);
    let tir = tyre();
    let run = |out: &str, extra: &[&str]| -> Vec<(f64, usize, f64, String)> {
        let text = estimate_to(&log, &tmp(out), extra);
        let mut lines = text.lines();
        assert_eq!(lines.next(), Some("t,wheel,mu,sigma,state"));
        lines
            .map(|l| {
                let v: Vec<&str> = l.split(',').collect();
                (
                    v[0].parse().unwrap(),
                    v[1].parse().unwrap(),
                    v[2].parse().unwrap(),
                    v[4].to_string(),
                )
            })
            .collect()
    };
    let alone = run("car-alone.est", &[]);
    let told = run("car-told.est", &["--wheelbase", "2.9"]);
    assert_eq!((alone.len(), told.len()), (4 * n, 4 * n));
    // The front wheels are never touched; the rear ones are told of the ice.
    let mut rear_differs = 0;
    for (a, b) in alone.iter().zip(&told) {
        if a.1 < 2 {
            assert_eq!(a, b);
        } else {
            rear_differs += usize::from(a.2 != b.2);
        }
    }
    assert!(rear_differs > 0);
    // On the ice (x ≥ 90 m, from t ≈ 5.2 s on), each rear wheel reads 0.3 identifiable no later
    // with the preview than without it but for the sample the mixture's slot may take from the
    // batch's fits (the rear-right: 1 ms later), and the rear-left sooner.
    let first = |est: &[(f64, usize, f64, String)], w: usize| {
        est.iter()
            .filter(|e| e.1 == w && e.0 > 5.2)
            .find(|e| e.3 == "identifiable" && (e.2 - 0.3).abs() <= 0.1)
            .map(|e| e.0)
            .unwrap()
    };
    for w in 2..4 {
        // `-- --nocapture` prints the figures docs/estimator.md quotes.
        println!(
            "wheel {w}: identifiable on the ice from {} s told, {} s alone",
            first(&told, w),
            first(&alone, w)
        );
        assert!(first(&told, w) <= first(&alone, w) + 0.0015, "wheel {w}");
    }
    assert!(first(&told, 2) < first(&alone, 2));
    // One wheel's methods refuse it; a wheel index out of range is a one-line error.
    one_line_error(
        &[
            "mu",
            "estimate",
            "--tir",
            &tyre(),
            "--log",
            log.to_str().unwrap(),
            "--out",
            tmp("car-peer.est").to_str().unwrap(),
            "--method",
            "hsu-gerdes",
        ],
        "the hsu-gerdes method reads one wheel's log (this one has several wheels)",
    );
    let bad = tmp("car-bad.csv");
    std::fs::write(&bad, "t,wheel,fz,fy,mz\n0.001,4,4000,100,-2\n").unwrap();
    one_line_error(
        &[
            "mu",
            "estimate",
            "--tir",
            &tyre(),
            "--log",
            bad.to_str().unwrap(),
            "--out",
            tmp("car-bad.est").to_str().unwrap(),
        ],
        "column wheel: 4 is not 0, 1, 2 or 3",
    );
    // Time increases per wheel, not across them; a wheelbase must be a positive number.
    std::fs::write(
        &bad,
        "t,wheel,fz,fy,mz\n0.001,0,4000,100,-2\n0.001,1,4000,100,-2\n0.0005,1,4000,100,-2\n",
    )
    .unwrap();
    let bad_est = tmp("car-bad.est");
    let args = |extra: &'static str| {
        let mut v = vec![
            "mu".to_string(),
            "estimate".into(),
            "--tir".into(),
            tyre(),
            "--log".into(),
            bad.to_str().unwrap().into(),
            "--out".into(),
            bad_est.to_str().unwrap().into(),
        ];
        v.extend(extra.split_whitespace().map(String::from));
        v
    };
    let a = args("");
    one_line_error(
        &a.iter().map(String::as_str).collect::<Vec<_>>(),
        "line 4, column t: time does not increase (0.0005 after 0.001, wheel 1)",
    );
    let ok_log = tmp("car-ok.csv");
    std::fs::write(
        &ok_log,
        "t,wheel,fz,fy,mz\n0.001,0,4000,100,-2\n0.001,2,4000,100,-2\n",
    )
    .unwrap();
    one_line_error(
        &[
            "mu",
            "estimate",
            "--tir",
            &tir,
            "--log",
            ok_log.to_str().unwrap(),
            "--out",
            bad_est.to_str().unwrap(),
            "--wheelbase",
            "0",
        ],
        "--wheelbase 0:",
    );
}

/// `gough mu calibrate` puts right a file whose force shift is 2 mrad off, from a log of a
/// surface of known μ: the bench's sine with dwell on μ 1.0 (a step steer, one operating point,
/// cannot tell the trail's shift from its scale), its left-hand wheels written as a car's log
/// (each wheel in its own axes: the bundled file's right-hand tyre is mirrored for them), the
/// file's PHY1 moved by +0.002. The calibration's
/// trail shift (SHt − SHy: without the slip angle an offset of PHY1 is one of QHZ1 the other
/// way) reads +2 mrad within 0.5 mrad; the calibration file reads back as
/// `--calibration-in` takes it; the written `.tir` has QHZ1 − PHY1 within 0.5 mrad of the
/// tyre's own and the other coefficients as the calibration says. A μ outside the estimator's
/// surfaces, a μ the log's batches cannot be, `--side` on a car's log: one-line errors.
#[test]
fn calibrate_puts_a_shifted_file_right() {
    use gough_host::mu::bench::{measure, simulate_case, suite, Sensors};
    use gough_host::tyre::set_in_tir;
    let dir = tmp("calibrate");
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(tyre()).unwrap();
    let p = gough_host::tyre::load(Path::new(&tyre())).unwrap().params;
    let wrong = dir.join("wrong.tir");
    std::fs::write(
        &wrong,
        set_in_tir(&text, gough::mf::Key::PHY1, p.phy1 + 0.002).unwrap(),
    )
    .unwrap();
    let case = &suite()[5];
    assert_eq!(
        (case.manoeuvre, case.road.as_str()),
        ("sine-dwell", "mu=1.0")
    );
    let log = simulate_case(&p, case).unwrap();
    let mut csv = String::from("t,wheel,fz,fy,mz,fx,vx,kappa,gamma\n");
    let tr: Vec<_> = [0, 2]
        .map(|w| (w, measure(&log, w, &Sensors::default(), 1)))
        .into_iter()
        .collect();
    for i in 0..tr[0].1.rows.len() {
        for (w, t) in &tr {
            let r = &t.rows[i];
            let v = |x: Option<f64>| x.unwrap();
            csv += &format!(
                "{},{w},{},{},{},{},{},{},{}\n",
                r.t,
                r.fz,
                r.fy,
                r.mz,
                v(r.fx),
                v(r.vx),
                v(r.kappa),
                v(r.gamma)
            );
        }
    }
    let log_path = dir.join("log.csv");
    std::fs::write(&log_path, csv).unwrap();
    let out = dir.join("calibrated.tir");
    let cal = dir.join("cal.json");
    let (w, l, o, cj) = (
        wrong.to_str().unwrap(),
        log_path.to_str().unwrap(),
        out.to_str().unwrap(),
        cal.to_str().unwrap(),
    );
    let r = gough(&[
        "mu",
        "calibrate",
        "--tir",
        w,
        "--log",
        l,
        "--mu",
        "1.0",
        "--out",
        o,
        "--calibration-out",
        cj,
    ]);
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    println!("{stdout}");
    assert!(stdout.contains("wheel FrontLeft (") && stdout.contains("wheel RearLeft ("));
    assert!(stdout.contains("the wheels combined"), "{stdout}");
    let cals = gough_host::mu::calfile::CalibrationFile::read(&cal).unwrap();
    assert_eq!(cals.len(), 2);
    for (_, c) in &cals {
        assert!(c.batches > 100, "{c:?}");
        assert!((c.value[2] - 0.002).abs() < 0.0005, "trail shift {c:?}");
    }
    let q = gough_host::tyre::load(&out).unwrap().params;
    let (dq, dp) = (q.qhz1 - q.phy1, p.qhz1 - p.phy1);
    assert!((dq - dp).abs() < 0.0005, "QHZ1 − PHY1 {dq} against {dp}");
    let wr = gough_host::tyre::load(Path::new(w)).unwrap().params;
    let one = gough_host::mu::calibrate::combine(
        &cals.iter().map(|(_, c)| *c).collect::<Vec<_>>(),
        &gough_host::mu::calibrate::config().cal_sigma,
    );
    assert!((q.ltr - wr.ltr * f64::from(one.value[0])).abs() < 1e-6 * wr.ltr.abs().max(1.0));
    assert!((q.lkx - wr.lkx * f64::from(one.value[3])).abs() < 1e-6 * wr.lkx.abs().max(1.0));
    // A μ outside the surfaces, a μ the log cannot be, --side on a car's log.
    for (extra, says) in [
        (&["--mu", "3.0"][..], "the estimator's surfaces"),
        (&["--mu", "0.8"][..], "excited batches"),
        (
            &["--mu", "1.0", "--side", "left"][..],
            "--side is a one-wheel log's",
        ),
    ] {
        let mut args = vec!["mu", "calibrate", "--tir", w, "--log", l];
        args.extend_from_slice(extra);
        one_line_error(&args, says);
    }
}

/// `--side`: a one-wheel log of a left-hand wheel in its own axes (Fy, Mz, α negated against
/// the bundled right-hand file's) with `--side left` gives the estimates the same log in the
/// file's axes gives with the default `--side file`, to the digit; `--side right` on the file's
/// own side too. A car's log refuses `--side`.
#[test]
fn a_wheel_on_the_other_side_is_mounted_by_side() {
    let dir = tmp("side");
    std::fs::create_dir_all(&dir).unwrap();
    let file_axes = dir.join("file.csv");
    write_log(&file_axes);
    let text = std::fs::read_to_string(&file_axes).unwrap();
    let mut left = String::new();
    for (i, line) in text.lines().enumerate() {
        if i == 0 {
            left += line;
        } else {
            let c: Vec<&str> = line.split(',').collect();
            let neg = |s: &str| format!("{}", -s.parse::<f64>().unwrap());
            left += &format!(
                "{},{},{},{},{},{},{},{}",
                c[0],
                c[1],
                neg(c[2]),
                neg(c[3]),
                c[4],
                c[5],
                neg(c[6]),
                c[7]
            );
        }
        left += "\n";
    }
    let left_axes = dir.join("left.csv");
    std::fs::write(&left_axes, left).unwrap();
    let tir = tyre();
    let run =
        |log: &Path, side: &str, out: &str| estimate_to(log, &dir.join(out), &["--side", side]);
    let want = run(&file_axes, "file", "a.csv");
    assert!(want.contains(",identifiable"), "the log is read");
    assert_eq!(run(&left_axes, "left", "b.csv"), want);
    assert_eq!(run(&file_axes, "right", "c.csv"), want);
    assert_ne!(run(&left_axes, "file", "d.csv"), want);
    let car = dir.join("car.csv");
    std::fs::write(&car, "t,wheel,fz,fy,mz\n0,0,4000,0,0\n0,1,4000,0,0\n").unwrap();
    one_line_error(
        &[
            "mu",
            "estimate",
            "--tir",
            &tir,
            "--log",
            car.to_str().unwrap(),
            "--out",
            dir.join("e.csv").to_str().unwrap(),
            "--side",
            "left",
        ],
        "--side is a one-wheel log's",
    );
}

/// `gough mu estimate` of the bundled tyre on `log` into `out` with `extra` arguments; the
/// estimates' CSV.
fn estimate_to(log: &Path, out: &Path, extra: &[&str]) -> String {
    let tir = tyre();
    let mut args = vec![
        "mu",
        "estimate",
        "--tir",
        &tir,
        "--log",
        log.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = gough(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::read_to_string(out).unwrap()
}

/// `--calibration-out` then `--calibration-in` on the bundled replay log: the file names each
/// property, the second run starts from the first's calibration (its batches carried on, its
/// first estimates not the cold start's), and a file the estimator refuses is a one-line error.
#[test]
fn a_calibration_file_starts_the_next_run_warm() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let log = root.join("examples/replay_log.csv");
    let log = log.to_str().unwrap();
    let t = tyre();
    let (e1, e2) = (tmp("cal-e1.csv"), tmp("cal-e2.csv"));
    let (c1, c2) = (tmp("cal-1.json"), tmp("cal-2.json"));
    let run = |out: &Path, extra: &[&str]| {
        let mut args = vec!["mu", "estimate", "--tir", &t, "--log", log];
        args.extend(["--out", out.to_str().unwrap()]);
        args.extend(extra);
        let o = gough(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    run(&e1, &["--calibration-out", c1.to_str().unwrap()]);
    run(
        &e2,
        &[
            "--calibration-in",
            c1.to_str().unwrap(),
            "--calibration-out",
            c2.to_str().unwrap(),
        ],
    );
    let batches = |p: &Path| -> Vec<u64> {
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap();
        assert_eq!(v["format"], "gough-calibration-1");
        v["wheels"]
            .as_array()
            .unwrap()
            .iter()
            .map(|w| {
                for name in ["trail", "trail_shape", "trail_shift", "kx"] {
                    assert!(
                        w["properties"][name]["value"].as_f64().unwrap().is_finite(),
                        "{w}"
                    );
                    assert!(
                        w["properties"][name]["sigma"].as_f64().unwrap() >= 0.0,
                        "{w}"
                    );
                }
                w["batches"].as_u64().unwrap()
            })
            .collect()
    };
    let (b1, b2) = (batches(&c1), batches(&c2));
    assert_eq!(b1.len(), 2, "the log's two wheels");
    assert!(b1.iter().all(|b| *b > 0), "the log calibrates: {b1:?}");
    // The second run started from the first's batches and added its own.
    assert!(b1.iter().zip(&b2).all(|(a, b)| b > a), "{b1:?} -> {b2:?}");
    let rows = |p: &Path| -> Vec<String> {
        std::fs::read_to_string(p)
            .unwrap()
            .lines()
            .skip(1)
            .map(String::from)
            .collect()
    };
    let (r1, r2) = (rows(&e1), rows(&e2));
    assert_eq!(r1.len(), r2.len());
    let first_diff = r1.iter().zip(&r2).position(|(a, b)| a != b);
    assert!(
        first_diff.is_some_and(|k| k < 40),
        "a warm start reads the first batches differently: first difference at {first_diff:?}"
    );
    // Refused: a value beyond its bound (the core's check), a property misspelt (the file's).
    let bad = tmp("cal-bad.json");
    let text = std::fs::read_to_string(&c1).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut far = v.clone();
    far["wheels"][0]["properties"]["trail"]["value"] = 5.0.into();
    std::fs::write(&bad, far.to_string()).unwrap();
    let args = |p: &Path| {
        let mut a = vec!["mu", "estimate", "--tir", &t, "--log", log, "--out"];
        a.push(e2.to_str().unwrap());
        a.push("--calibration-in");
        a.push(p.to_str().unwrap());
        a.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    let run_err = |p: &Path, says: &str| {
        let a = args(p);
        let o = gough(&a.iter().map(String::as_str).collect::<Vec<_>>());
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains(says), "{err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    };
    run_err(
        &bad,
        "wheel 0: refused: a calibration value lies beyond its bound",
    );
    let text = text.replacen("\"kx\"", "\"kappa_x\"", 1);
    std::fs::write(&bad, text).unwrap();
    run_err(&bad, "unknown property 'kappa_x'");
    // The peers keep no calibration (and read one wheel's log: this one has two).
    let o = gough(&[
        "mu",
        "estimate",
        "--tir",
        &t,
        "--log",
        log,
        "--out",
        e2.to_str().unwrap(),
        "--method",
        "slip-slope",
        "--calibration-out",
        c2.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("slip-slope"));
}
