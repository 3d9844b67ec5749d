//! `gough mu bench --quick` end to end: the structure of its report, not the estimator's
//! figures (they change with the estimator). The vehicle suite's tables come first, then the
//! wheel cases' sections; every tyre it lists appears in every table and in `wheel_cases.csv`,
//! the counts of the tables add up to the CSV's, the rates and levels appear, the warm run
//! stands beside the cold one, the threads change nothing, and `--seeds` writes one run per
//! seed and their summary.
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn gough(args: &[&str]) -> Output {
    let o = Command::new(gough_host_tests::gough_bin())
        .args(args)
        .output()
        .expect("run gough");
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gough-mu-bench-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn data(p: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("data")
        .join(p)
        .to_string_lossy()
        .into_owned()
}

/// `gough mu bench --quick` (with `extra`) into `dir`: its stdout and table.md (empty when it
/// wrote none: `--seeds`).
fn quick(dir: &Path, extra: &[&str]) -> (String, String) {
    let (tir, tyres) = (data("tyres/MagicFormula61_Parameters.tir"), data("tyres"));
    let mut args = vec!["mu", "bench", "--quick", "--tir", &tir, "--tyres", &tyres];
    let out = dir.to_str().unwrap();
    args.extend(["--out", out]);
    args.extend(extra);
    let o = gough(&args);
    let md = std::fs::read_to_string(dir.join("table.md")).unwrap_or_default();
    (String::from_utf8_lossy(&o.stdout).into_owned(), md)
}

/// "n of N" at the start of `s`.
fn n_of(s: &str) -> (usize, usize) {
    let mut it = s.split_whitespace();
    let n = it.next().unwrap().parse().unwrap();
    assert_eq!(it.next(), Some("of"), "{s}");
    let t = it
        .next()
        .unwrap()
        .trim_end_matches([';', ','])
        .parse()
        .unwrap();
    (n, t)
}

/// The cells of a markdown table row.
fn cells(row: &str) -> Vec<&str> {
    row.trim()
        .trim_matches('|')
        .split(" | ")
        .map(str::trim)
        .collect()
}

/// The rows of the table under `header` (the first line starting with it).
fn table<'a>(md: &'a str, header: &str) -> Vec<Vec<&'a str>> {
    md.lines()
        .skip_while(|l| !l.starts_with(header))
        .skip(2)
        .take_while(|l| l.starts_with('|'))
        .map(cells)
        .collect()
}

#[test]
fn bench_quick_reports_every_tyre_level_and_rate_and_its_counts_add_up() {
    let dir = tmp("quick");
    let (stdout, md) = quick(&dir, &["--warm"]);
    assert_eq!(stdout, md);
    // The vehicle suite's tables first (its first three cases), then the wheel cases' sections.
    assert!(md.starts_with("| manoeuvre | road | estimator |"), "{md}");
    let order = [
        "## The bank against the others, case by case",
        "## Wheel-surfaces the bank does not read within 0.15 s",
        "## Warm start: the vehicle suite",
        "## By tyre",
        "## A tyre that is not its file",
        "## Sample rates",
        "## Warm start\n",
    ];
    let at: Vec<usize> = order
        .iter()
        .map(|h| md.find(h).unwrap_or_else(|| panic!("{h}: {md}")))
        .collect();
    assert!(at.windows(2).all(|w| w[0] < w[1]), "{at:?}");
    assert_eq!(
        md.lines()
            .filter(|l| l.starts_with("| step-steer | mu=") && l.contains("| bank |"))
            .count(),
        3
    );

    // The tyres: the three of the quick subset, each with its own Mz noise; the file the
    // reader refuses is listed as skipped.
    let tyres = table(&md, "| tyre | model | FNOMIN [N] |");
    let names: BTreeSet<&str> = tyres.iter().map(|r| r[0]).collect();
    let want: BTreeSet<&str> = [
        "MagicFormula61_Parameters.tir",
        "FSAE_Defaults.tir",
        "MagicFormula52_Parameters.tir",
    ]
    .into();
    assert_eq!(names, want);
    for r in &tyres {
        let (fnomin, r0, mz): (f64, f64, f64) = (
            r[2].parse().unwrap(),
            r[3].parse().unwrap(),
            r[5].parse().unwrap(),
        );
        assert!((mz - 7.5e-4 * fnomin * r0).abs() < 1e-3, "{r:?}");
    }
    assert!(md.contains("Skipped: Model_Unstable.tir: the reader refuses it"));

    // wheel_cases.csv: one row per case, every field there, no case failed.
    let csv = std::fs::read_to_string(dir.join("wheel_cases.csv")).unwrap();
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(!rows.is_empty());
    for r in &rows {
        assert_eq!(r.len(), head.len(), "{r:?}");
        assert_eq!(r[col("error")], "", "{r:?}");
        assert_ne!(r[col("warm_identifiable")], "", "{r:?}");
    }
    let csv_tyres: BTreeSet<&str> = rows.iter().map(|r| r[col("tyre")]).collect();
    assert_eq!(csv_tyres, want);
    let rates: BTreeSet<&str> = rows.iter().map(|r| r[col("rate_hz")]).collect();
    assert_eq!(rates, ["100", "1000", "200"].into());
    let levels: BTreeSet<&str> = rows.iter().map(|r| r[col("level")]).collect();
    assert_eq!(levels, ["1×", "exact"].into());
    // Exact: the file itself; 1×: within the envelope.
    for r in &rows {
        let f = |c: &str| r[col(c)].parse::<f64>().unwrap();
        let (ky, shy, p) = (f("ky"), f("shy_rad"), f("pressure"));
        if r[col("level")] == "exact" {
            assert_eq!((ky, shy, p), (1.0, 0.0, 1.0), "{r:?}");
        } else {
            assert!((ky - 1.0).abs() <= 0.1 && shy.abs() <= 0.002 && (p - 1.0).abs() <= 0.15);
        }
    }

    // The counts add up: per tyre and level (By tyre), per level (the closing lines), against
    // the CSV's rows at 200 Hz.
    let sum = |keep: &dyn Fn(&Vec<&str>) -> bool, c: &str| -> usize {
        rows.iter()
            .filter(|r| keep(r))
            .map(|r| r[col(c)].parse::<usize>().unwrap())
            .sum()
    };
    let by_tyre = table(&md, "| tyre | tyre on the car |");
    assert_eq!(by_tyre.len(), 3 * 2, "{by_tyre:?}");
    for r in &by_tyre {
        let keep = |x: &Vec<&str>| {
            x[col("tyre")] == r[0] && x[col("level")] == r[1] && x[col("rate_hz")] == "200"
        };
        assert_eq!(
            n_of(r[2]),
            (sum(&keep, "ws_within"), sum(&keep, "ws_total")),
            "{r:?}"
        );
        assert_eq!(n_of(r[5]).1, sum(&keep, "change_flags"), "{r:?}");
        assert_eq!(n_of(r[8]).1, sum(&keep, "steps"), "{r:?}");
    }
    for level in ["exact", "1×"] {
        let line = md
            .lines()
            .find(|l| l.starts_with(&format!("wheel cases, {level} (")))
            .unwrap_or_else(|| panic!("{level}: {md}"));
        let keep = |x: &Vec<&str>| x[col("level")] == level && x[col("rate_hz")] == "200";
        let n_cases = rows.iter().filter(|r| keep(r)).count();
        assert!(
            line.contains(&format!("(3 tyres, {n_cases} cases at 200 Hz)")),
            "{line}"
        );
        let ws = line.split("utilisation 0.5 on ").nth(1).unwrap();
        assert_eq!(
            n_of(ws),
            (sum(&keep, "ws_within"), sum(&keep, "ws_total")),
            "{line}"
        );
        let steps = line.split("read within 0.2 s: ").nth(1).unwrap();
        assert_eq!(n_of(steps).1, sum(&keep, "steps"), "{line}");
        // The level's row in "A tyre that is not its file" is the same tally.
        let row = table(&md, "| tyre on the car | wheel-surfaces")
            .into_iter()
            .find(|r| r[0] == level)
            .unwrap();
        assert!(ws.starts_with(row[1]), "{row:?} {line}");
    }
    // Every rate, in "Sample rates"; each one's wheel-surfaces are its CSV rows'.
    let rates_table = table(&md, "| rate [Hz] | tyre on the car |");
    let listed: BTreeSet<&str> = rates_table.iter().map(|r| r[0]).collect();
    assert_eq!(listed, ["100", "1000", "200"].into());
    for r in &rates_table {
        if r[0] != "200" {
            let keep = |x: &Vec<&str>| x[col("rate_hz")] == r[0] && x[col("level")] == r[1];
            assert_eq!(
                n_of(r[2]),
                (sum(&keep, "ws_within"), sum(&keep, "ws_total"))
            );
        }
    }
    // The warm run beside the cold one: every tyre and level, the cold figure the By-tyre one.
    let warm = table(&md, "| tyre | tyre on the car | wheel-surfaces within 150 ms | worst p95 | worst off by > 0.2 | false change flags |");
    assert_eq!(warm.len(), 2 + 3 * 2, "{warm:?}");
    for r in &by_tyre {
        let w = warm.iter().find(|w| w[0] == r[0] && w[1] == r[1]).unwrap();
        assert!(w[2].starts_with(&format!("{} / ", r[2])), "{w:?} {r:?}");
    }

    // The threads change nothing, nor does `--warm` the cold figures.
    let (_, one) = quick(&tmp("quick-one-thread"), &["--jobs", "1"]);
    let cut = |s: &str| s[s.find("## By tyre").unwrap()..].to_string();
    let strip_warm = |s: String| s[..s.find("## Warm start\n").unwrap_or(s.len())].to_string();
    assert_eq!(cut(&one).trim_end(), strip_warm(cut(&md)).trim_end());
}

/// `--seeds 1-2`: each seed's run in its folder, seed 1's the same as a run with `--seed 1`;
/// `seeds.md` with a row per seed and level and the worst.
#[test]
fn bench_seeds_runs_each_seed_and_sums_them_up() {
    let dir = tmp("seeds");
    let (stdout, _) = quick(&dir, &["--only", "wheel", "--seeds", "1-2"]);
    let seeds = std::fs::read_to_string(dir.join("seeds.md")).unwrap();
    assert_eq!(stdout, seeds);
    assert!(!dir.join("table.md").exists());
    let one = std::fs::read_to_string(dir.join("seed-1/table.md")).unwrap();
    let two = std::fs::read_to_string(dir.join("seed-2/table.md")).unwrap();
    assert!(one.starts_with("\n## By tyre") && one.contains("noise seed 1."));
    assert!(two.contains("noise seed 2.") && one != two.replace("noise seed 2.", "noise seed 1."));
    let (_, alone) = quick(&tmp("seed-1"), &["--only", "wheel", "--seed", "1"]);
    assert_eq!(alone, one);
    let rows = table(&seeds, "| seed | tyre on the car |");
    let keys: Vec<(&str, &str)> = rows.iter().map(|r| (r[0], r[1])).collect();
    assert_eq!(
        keys,
        [
            ("1", "exact"),
            ("1", "1×"),
            ("2", "exact"),
            ("2", "1×"),
            ("worst", "exact"),
            ("worst", "1×")
        ]
    );
    // No vehicle suite asked for: none summed up.
    assert!(!seeds.contains("## The vehicle suite"));
}
