//! `cargo xtask <task>`: the project's task runner (the README's test command is
//! `cargo xtask test-all`, and `.ci/run` calls exactly that).
//!
//! Tasks:
//! - `test-all`: installs the embedded targets, builds the core for thumbv7em-none-eabihf and
//!   thumbv6m-none-eabi, checks formatting and lints, runs every host test (core unit and
//!   property tests, doc tests, the MFeval oracle, the CLI), builds the firmware and runs it
//!   under QEMU (installing `qemu-system-arm` with apt-get when it is missing and we may); the
//!   Python tests run in `.venv` (created here, with `host-tests/python/requirements.txt`);
//!   then the C API (`capi/`): header current, static library for the host and the devices,
//!   the host C test, the C example firmware under QEMU against the Rust firmware (installing
//!   `gcc-arm-none-eabi` and `libnewlib-arm-none-eabi` the same way).
//! - `qemu-check`: only ensures QEMU is present.
//! - `python`: only the Python package's steps of `test-all` (the abi3 wheel built, installed
//!   into `.venv` and into a fresh venv without cargo, the pytest suite `python/tests`).
//! - `capi`: only the C API's steps of `test-all` (builds the firmware's `capi_ref` first).
//! - `firmware [--m0]`: only the firmware steps of `test-all` (the M4F firmware: build, selftest
//!   against its golden output, panic/HardFault, the SLCAN replay and garbage tests, the
//!   python-can client, the STM32F405 link with its sizes, the M4F bench); `--m0` adds the
//!   Cortex-M0/M3 bench of `firmware-m0/`.
//! - `header [--check]`: writes `capi/include/gough.h` with cbindgen (or checks it is current).
//! - `snapshot [--overwrite]`: runs the firmware selftest under QEMU and compares its output with
//!   `firmware/golden/selftest.out` (or rewrites it).
mod capi;
mod firmware;
mod header;

use std::io::{BufRead, BufReader};
use std::process::{Command, ExitCode, Stdio};

const TARGETS: [&str; 3] = [
    "thumbv7em-none-eabihf",
    "thumbv6m-none-eabi",
    "thumbv7m-none-eabi",
];

fn main() -> ExitCode {
    START.get_or_init(std::time::Instant::now);
    let task = std::env::args().nth(1).unwrap_or_default();
    let result = match task.as_str() {
        "test-all" => test_all(),
        "qemu-check" => ensure_qemu(),
        "header" => header::header(std::env::args().any(|a| a == "--check")),
        "capi" => ensure_qemu()
            .and_then(|()| firmware::build_mps2())
            .and_then(|()| capi::test_all(&firmware::elf("capi_ref"), &mut 0)),
        "firmware" => ensure_qemu().and_then(|()| {
            let mut passed = 0;
            firmware::test_m4f(&mut passed)?;
            if std::env::args().any(|a| a == "--m0") {
                firmware::bench_m0()?;
                passed += 1;
            }
            println!("\nfirmware: {passed} passed");
            Ok(())
        }),
        "python" => {
            let (mut passed, mut failed) = (0, 0);
            WheelBuild::start()
                .and_then(|w| python_package(w, &mut passed))
                .and_then(|()| pytest(&["python/tests"], &mut passed, &mut failed))
                .map(|()| println!("\npython: {passed} passed, {failed} failed"))
        }
        "snapshot" => ensure_qemu()
            .and_then(|()| firmware::snapshot(std::env::args().any(|a| a == "--overwrite"))),
        _ => Err(format!(
            "unknown task '{task}'; tasks: test-all, qemu-check, snapshot [--overwrite], header [--check], capi, firmware [--m0], python"
        )),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("xtask: FAILED: {e}");
            ExitCode::FAILURE
        }
    }
}

fn root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// When the task started: every step's header and the summary give the time since then (which
/// step costs what, from the log of one run).
static START: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();

/// mm:ss since the task started.
fn elapsed() -> String {
    let s = START
        .get_or_init(std::time::Instant::now)
        .elapsed()
        .as_secs();
    format!("{:02}:{:02}", s / 60, s % 60)
}

fn step(name: &str) {
    eprintln!("\n==> [{}] {name}", elapsed());
}

fn run(cmd: &mut Command) -> Result<(), String> {
    let shown = format!("{cmd:?}");
    let status = cmd.status().map_err(|e| format!("{shown}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{shown} exited with {status}"))
    }
}

fn cargo() -> Command {
    let mut c = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    c.current_dir(root());
    c
}

/// Runs `cargo test ...`, echoing its output, and adds up the "test result" lines.
fn cargo_test(args: &[&str], passed: &mut u64, failed: &mut u64) -> Result<(), String> {
    let mut c = cargo();
    c.arg("test").args(args);
    count_tests(c, passed, failed)
}

/// Runs the test target `name` as `cargo test --workspace` built it (`args` to the test
/// binary), from its package's directory as cargo runs it, adding up its results. Not `cargo
/// test -p PKG --test NAME`: that resolves the features of that package alone, and rebuilt the
/// core, the host and the tests (74 s of the fresh-clone run) for one test binary.
fn workspace_test(
    name: &str,
    args: &[&str],
    passed: &mut u64,
    failed: &mut u64,
) -> Result<(), String> {
    let mut c = cargo();
    c.args(["test", "--workspace", "--no-run", "--message-format=json"])
        .stdout(Stdio::piped());
    let out = c.output().map_err(|e| format!("{c:?}: {e}"))?;
    if !out.status.success() {
        return Err(format!("{c:?} exited with {}", out.status));
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let found = text.lines().find_map(|line| {
        let v: serde_json::Value = serde_json::from_str(line).ok()?;
        let target = v.get("target")?;
        let is_test = target
            .get("kind")?
            .as_array()?
            .iter()
            .any(|k| k.as_str() == Some("test"));
        if v.get("reason")?.as_str()? != "compiler-artifact"
            || target.get("name")?.as_str()? != name
            || !is_test
        {
            return None;
        }
        let exe = v.get("executable")?.as_str()?;
        let manifest = v.get("manifest_path")?.as_str()?;
        let dir = std::path::Path::new(manifest).parent()?.to_path_buf();
        Some((std::path::PathBuf::from(exe), dir))
    });
    let (exe, dir) = found.ok_or_else(|| format!("no test target '{name}' in the workspace"))?;
    let mut t = Command::new(exe);
    t.args(args).current_dir(dir);
    count_tests(t, passed, failed)
}

/// Runs a test command, echoing its output, and adds up the "test result" lines.
fn count_tests(mut c: Command, passed: &mut u64, failed: &mut u64) -> Result<(), String> {
    c.stdout(Stdio::piped());
    let shown = format!("{c:?}");
    let mut child = c.spawn().map_err(|e| format!("{shown}: {e}"))?;
    if let Some(out) = child.stdout.take() {
        for line in BufReader::new(out).lines().map_while(Result::ok) {
            println!("{line}");
            if let Some(rest) = line.strip_prefix("test result: ") {
                for part in rest.split(';') {
                    let part = part
                        .trim()
                        .trim_start_matches("ok. ")
                        .trim_start_matches("FAILED. ");
                    let mut it = part.split_whitespace();
                    if let (Some(n), Some(what)) = (it.next(), it.next()) {
                        let n: u64 = n.parse().unwrap_or(0);
                        match what {
                            "passed" => *passed += n,
                            "failed" => *failed += n,
                            _ => {}
                        }
                    }
                }
            }
        }
    }
    let status = child.wait().map_err(|e| format!("{shown}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{shown} exited with {status}"))
    }
}

fn have(cmd: &str) -> bool {
    Command::new(cmd)
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .map(|s| s.success())
        .unwrap_or(false)
}

fn ensure_targets() -> Result<(), String> {
    step("rustup target add (idempotent; rust-toolchain.toml's `targets` does not add them to an installed toolchain)");
    if have("rustup") {
        let mut c = Command::new("rustup");
        c.current_dir(root()).args(["target", "add"]).args(TARGETS);
        run(&mut c)
    } else {
        eprintln!("rustup not found: assuming the targets {TARGETS:?} are installed");
        Ok(())
    }
}

/// Are we root (and may install packages)?
fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .map(|o| o.stdout.starts_with(b"0"))
        .unwrap_or(false)
}

fn ensure_qemu() -> Result<(), String> {
    step("qemu-system-arm");
    if have("qemu-system-arm") {
        return Ok(());
    }
    if is_root() && have("apt-get") {
        eprintln!("qemu-system-arm is missing: installing it with apt-get");
        let _ = run(Command::new("apt-get").arg("update").stdout(Stdio::null()));
        run(Command::new("apt-get").args([
            "install",
            "-y",
            "--no-install-recommends",
            "qemu-system-arm",
        ]))?;
    }
    if have("qemu-system-arm") {
        Ok(())
    } else {
        Err(
            "qemu-system-arm is required to run the firmware tests; install it (Debian/Ubuntu: \
             `sudo apt-get install qemu-system-arm`) and run again"
                .into(),
        )
    }
}

/// The project's Python venv (`.venv`, created when missing) with
/// `host-tests/python/requirements.txt` installed; returns its interpreter.
pub fn venv() -> Result<std::path::PathBuf, String> {
    let venv = root().join(".venv");
    let py = venv.join("bin/python");
    let req = root().join("host-tests/python/requirements.txt");
    if !py.exists() {
        run(Command::new("python3").arg("-m").arg("venv").arg(&venv))?;
    }
    run(Command::new(&py)
        .args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
            "-r",
        ])
        .arg(&req))?;
    Ok(py)
}

/// The cargo target directory (`CARGO_TARGET_DIR`, else `target/`).
fn target_dir() -> std::path::PathBuf {
    std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root().join("target"))
}

/// `pip install` into the interpreter `py` (quiet).
fn pip(py: &std::path::Path) -> Command {
    let mut c = Command::new(py);
    c.args([
        "-m",
        "pip",
        "install",
        "--quiet",
        "--disable-pip-version-check",
    ]);
    c
}

/// The wheel of the Python package (python/) being built in the background: `maturin build
/// --release` into `target/wheels`, abi3 (one wheel for CPython ≥ 3.9), at `nice` 10 in its own
/// target directory (`target/wheel-build`, so that it never waits for the other builds' lock).
/// Started before the other steps, beside them at a lower priority: the release build of the
/// lanes is one codegen unit, about 3.5 minutes on one core, and the checks and lints leave a
/// core idle for part of their time (the fresh-clone run at 6cdbb95: the wheel was ready 2
/// minutes after the Python step began, the test command 23:32 → 19:25 with the debug CLI
/// change). Killed (its process group) if the run ends first.
pub struct WheelBuild {
    child: Option<std::process::Child>,
    log: std::path::PathBuf,
    wheels: std::path::PathBuf,
}

impl WheelBuild {
    /// Installs the Python requirements (.venv, both requirement files), then starts maturin.
    fn start() -> Result<WheelBuild, String> {
        let py = venv()?;
        run(pip(&py)
            .arg("-r")
            .arg(root().join("python/requirements-test.txt")))?;
        let venv = root().join(".venv");
        let wheels = target_dir().join("wheels");
        if wheels.exists() {
            std::fs::remove_dir_all(&wheels).map_err(|e| format!("{}: {e}", wheels.display()))?;
        }
        std::fs::create_dir_all(target_dir()).map_err(|e| e.to_string())?;
        let log = target_dir().join("wheel-build.log");
        let out = std::fs::File::create(&log).map_err(|e| format!("{}: {e}", log.display()))?;
        let err = out.try_clone().map_err(|e| e.to_string())?;
        let mut c = Command::new("nice");
        c.args(["-n", "10"])
            .arg(venv.join("bin/maturin"))
            .current_dir(root().join("python"))
            .args(["build", "--release", "--quiet", "--out"])
            .arg(&wheels)
            .env("CARGO_TARGET_DIR", target_dir().join("wheel-build"))
            // The wheel is stripped (pyproject.toml): the release profile's line tables would
            // only cost time (the lanes' build 255 → 203 s without them).
            .env("CARGO_PROFILE_RELEASE_DEBUG", "0")
            .env("VIRTUAL_ENV", &venv)
            .env("PATH", {
                let mut p = std::ffi::OsString::from(venv.join("bin"));
                p.push(":");
                p.push(std::env::var_os("PATH").unwrap_or_default());
                p
            })
            .stdin(Stdio::null())
            .stdout(out)
            .stderr(err);
        std::os::unix::process::CommandExt::process_group(&mut c, 0);
        let shown = format!("{c:?}");
        let child = c.spawn().map_err(|e| format!("{shown}: {e}"))?;
        println!(
            "wheel: building in the background (pid {}, log {})",
            child.id(),
            log.display()
        );
        Ok(WheelBuild {
            child: Some(child),
            log,
            wheels,
        })
    }

    /// Waits for the build, echoes its log, and returns the wheel's directory.
    fn finish(mut self) -> Result<std::path::PathBuf, String> {
        let status = match self.child.take() {
            Some(mut c) => c.wait().map_err(|e| e.to_string())?,
            None => return Err("the wheel build was not started".into()),
        };
        let text = std::fs::read_to_string(&self.log).unwrap_or_default();
        print!("{text}");
        if status.success() {
            Ok(self.wheels.clone())
        } else {
            Err(format!(
                "maturin build (log {}) exited with {status}",
                self.log.display()
            ))
        }
    }
}

impl Drop for WheelBuild {
    fn drop(&mut self) {
        if let Some(c) = self.child.take() {
            // The whole group: maturin and the cargo and rustc it started.
            let _ = Command::new("kill")
                .args(["-TERM", "--", &format!("-{}", c.id())])
                .status();
        }
    }
}

/// Installs the Python package (the wheel of `build`) into `.venv` for the Python tests, and
/// into a fresh venv with no cargo on PATH, where `python/wheel_check.py` runs `Tyre.eval`
/// (counted as one test). docs/python.md has the build times measured against the `maturin
/// develop` dev build this replaces.
fn python_package(build: WheelBuild, passed: &mut u64) -> Result<(), String> {
    let wheels = build.finish()?;
    let py = venv()?;
    let found: Vec<std::path::PathBuf> = std::fs::read_dir(&wheels)
        .map_err(|e| format!("{}: {e}", wheels.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "whl"))
        .collect();
    let wheel = match found.as_slice() {
        [w] if w.to_string_lossy().contains("-abi3-") => w.clone(),
        _ => {
            return Err(format!(
                "{}: expected one abi3 wheel, found {found:?}",
                wheels.display()
            ))
        }
    };
    println!("wheel: {}", wheel.display());
    run(pip(&py)
        .args(["--force-reinstall", "--no-deps"])
        .arg(&wheel))?;
    // A fresh venv, and no cargo or rustc on PATH: the wheel installs and runs without Rust.
    let fresh = target_dir().join("wheel-venv");
    if fresh.exists() {
        std::fs::remove_dir_all(&fresh).map_err(|e| format!("{}: {e}", fresh.display()))?;
    }
    let path = std::env::join_paths(
        std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())
            .filter(|d| !d.join("cargo").exists() && !d.join("rustc").exists()),
    )
    .map_err(|e| e.to_string())?;
    let no_rust = |c: &mut Command| {
        c.env("PATH", &path);
        for v in [
            "CARGO",
            "RUSTC",
            "RUSTDOC",
            "RUSTUP_TOOLCHAIN",
            "CARGO_TARGET_DIR",
        ] {
            c.env_remove(v);
        }
    };
    // GOUGH_WHEEL_PYTHON: the interpreter of the fresh venv (default python3), e.g. a CPython
    // 3.9 to check the abi3 wheel's oldest version.
    let base = std::env::var_os("GOUGH_WHEEL_PYTHON").unwrap_or_else(|| "python3".into());
    let mut c = Command::new(&base);
    no_rust(&mut c);
    run(c.arg("-m").arg("venv").arg(&fresh))?;
    let fpy = fresh.join("bin/python");
    let mut c = pip(&fpy);
    no_rust(&mut c);
    run(c.arg(&wheel))?;
    let mut c = Command::new(&fpy);
    no_rust(&mut c);
    // -I: not the script's directory on sys.path (python/ holds the source package).
    run(c
        .current_dir(&fresh)
        .arg("-I")
        .arg(root().join("python/wheel_check.py"))
        .arg(root()))?;
    *passed += 1;
    Ok(())
}

/// The debug `gough` binary, built as the host tests build it (`host-tests`' `gough_bin`: the
/// same package and flags, so that this finds it built): without the `lanes` feature, which a
/// debug build never runs.
pub fn debug_cli() -> Result<std::path::PathBuf, String> {
    run(cargo().args([
        "build",
        "-p",
        "gough-host",
        "--bin",
        "gough",
        "--no-default-features",
        "--features",
        "plot",
    ]))?;
    Ok(target_dir().join("debug/gough"))
}

/// Runs pytest on `tests` in the venv with `GOUGH` = the debug `gough` binary (the host tests
/// built it), echoing its output, and adds up its closing line ("N passed, M failed"). The
/// CLI-equality test of the gap diagnosis runs both sides `--exact`: the release wheel evaluates
/// the fits in lanes and a debug CLI row by row (`gap::sim::Sim::lanes`), which differ in the
/// last bits; a release CLI only for this test cost 4 to 5 minutes of the test command.
fn pytest(tests: &[&str], passed: &mut u64, failed: &mut u64) -> Result<(), String> {
    let py = venv()?;
    let gough = debug_cli()?;
    let mut c = Command::new(&py);
    c.current_dir(root())
        .args(["-m", "pytest", "-q", "-p", "no:cacheprovider"])
        .args(tests)
        .env("GOUGH", gough)
        .stdout(Stdio::piped());
    let shown = format!("{c:?}");
    let mut child = c.spawn().map_err(|e| format!("{shown}: {e}"))?;
    if let Some(out) = child.stdout.take() {
        for line in BufReader::new(out).lines().map_while(Result::ok) {
            println!("{line}");
            for part in line.trim_matches('=').split(',') {
                let mut it = part.split_whitespace();
                if let (Some(n), Some(what)) = (it.next(), it.next()) {
                    match (n.parse::<u64>(), what) {
                        (Ok(n), "passed") => *passed += n,
                        (Ok(n), "failed") => *failed += n,
                        _ => {}
                    }
                }
            }
        }
    }
    let status = child.wait().map_err(|e| format!("{shown}: {e}"))?;
    if status.success() {
        Ok(())
    } else {
        Err(format!("{shown} exited with {status}"))
    }
}

fn test_all() -> Result<(), String> {
    let (mut passed, mut failed) = (0u64, 0u64);
    // A one-off build of everything: no incremental caches, and line tables (backtraces keep
    // their file:line) instead of full debug info in the dev and test builds. On a fresh clone
    // the two took the dev/test target from 6.1 GB to 1.1 GB (the full run had filled a
    // checker's disk), and they shorten every link. Set before anything starts, so that every
    // cargo below, and any a test or pytest starts, builds with the same settings; a value the
    // caller set is kept.
    for (key, value) in [
        ("CARGO_INCREMENTAL", "0"),
        ("CARGO_PROFILE_DEV_DEBUG", "line-tables-only"),
    ] {
        if std::env::var_os(key).is_none() {
            std::env::set_var(key, value);
        }
    }
    ensure_targets()?;
    step("Python requirements (.venv), and the Python package's wheel started in the background");
    let wheel = WheelBuild::start()?;
    step(&format!(
        "core compiles for {} (no_std, no alloc; cargo check), default and all backends",
        TARGETS.join(", ")
    ));
    // Checked, not built: the firmware, M0/M3 and C API steps below build the core for each
    // of these targets with the backends they run. The three targets in one cargo run each, so
    // that they are checked side by side (101 s built one target after another on a fresh clone,
    // 47 s checked together, on the 2-core machine).
    let targets: Vec<&str> = TARGETS.iter().flat_map(|t| ["--target", t]).collect();
    run(cargo()
        .args(["check", "-p", "gough", "--release"])
        .args(&targets))?;
    run(cargo()
        .args(["check", "-p", "gough", "--release"])
        .args(&targets)
        .args(["--features", "fast,micromath,fixed"]))?;
    step("formatting");
    run(cargo().args(["fmt", "--all", "--check"]))?;
    step("lints (the core denies unwrap/expect/panic/indexing outside tests)");
    run(cargo().args([
        "clippy",
        "--workspace",
        "--all-targets",
        "--",
        "-D",
        "warnings",
    ]))?;
    step("API docs build without warnings (broken or private intra-doc links; every feature)");
    run(cargo()
        // gough-capi's library is also named `gough` (libgough.a): rustdoc would write over the
        // core's pages. Its documentation is capi/include/gough.h and docs/c-api.md.
        .args([
            "doc",
            "--workspace",
            "--exclude",
            "gough-capi",
            "--no-deps",
            "--lib",
            "--all-features",
        ])
        .env("RUSTDOCFLAGS", "-D warnings"))?;
    step("host tests: core unit + property + doc tests, MFeval oracle, CLI");
    cargo_test(&["--workspace"], &mut passed, &mut failed)?;
    step("DBC files decoded by cantools (strict) against the host's frames (pytest in .venv)");
    pytest(&["host-tests/python/test_dbc.py"], &mut passed, &mut failed)?;
    ensure_qemu()?;
    firmware::test_all(&mut passed)?;
    capi::test_all(&firmware::elf("capi_ref"), &mut passed)?;
    // Last: the wheel, built in the background since the start, gets the core the QEMU steps
    // leave idle (before them it was still building when this step began: 2 to 3 minutes of
    // waiting in the fresh-clone runs at 6cdbb95 and aa9ee5a).
    step("Python package python/ (the abi3 wheel built in the background; into .venv, and into a fresh venv without cargo: Tyre.eval): oracle sweeps, CLI equality, fleet on a dask LocalCluster, logs (MDF4, BLF, ASC, candump)");
    python_package(wheel, &mut passed)?;
    pytest(&["python/tests"], &mut passed, &mut failed)?;
    println!(
        "\ntest-all: {passed} passed, {failed} failed in {} (mm:ss)",
        elapsed()
    );
    Ok(())
}
