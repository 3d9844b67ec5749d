//! Firmware steps of `test-all` (also alone: `cargo xtask firmware [--m0]`), and
//! `snapshot [--overwrite]` (the golden outputs).
use crate::{cargo, root, run, step};
use gough_host::device::qemu;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

const TARGET: &str = "thumbv7em-none-eabihf";

fn fw_dir() -> PathBuf {
    root().join("firmware")
}

pub fn elf(bin: &str) -> PathBuf {
    fw_dir()
        .join("target")
        .join(TARGET)
        .join("release")
        .join(bin)
}

fn fw_cargo() -> Command {
    let mut c = cargo();
    c.current_dir(fw_dir()).env_remove("CARGO_TARGET_DIR");
    c
}

pub fn build_mps2() -> Result<(), String> {
    step("firmware: build every mps2-an386 binary (thumbv7em-none-eabihf, release)");
    run(fw_cargo().args(["build", "--release", "--bins"]))
}

/// Runs `elf` under QEMU mps2-an386 (the host crate's launcher, [`qemu::run`]); returns (exit
/// code, stdout). A run that outlives `timeout` is killed and reported as hung.
fn qemu(elf: &Path, extra: &[&str], timeout: Duration) -> Result<(i32, String), String> {
    qemu::run(
        &qemu::MPS2_AN386,
        elf,
        extra,
        &root().join("target/qemu"),
        timeout,
    )
}

fn golden(name: &str) -> PathBuf {
    fw_dir().join("golden").join(format!("{name}.out"))
}

fn selftest(overwrite: bool) -> Result<(), String> {
    step("firmware selftest under QEMU: round trip, known MF output, garbage, upload (golden: firmware/golden/selftest.out)");
    let (code, out) = qemu(&elf("selftest"), &[], Duration::from_secs(120))?;
    print!("{out}");
    if code != 0 {
        return Err(format!("selftest exited with {code}"));
    }
    let g = golden("selftest");
    if overwrite {
        std::fs::write(&g, &out).map_err(|e| format!("{}: {e}", g.display()))?;
        eprintln!("wrote {}", g.display());
        return Ok(());
    }
    let want = std::fs::read_to_string(&g).map_err(|e| format!("{}: {e}", g.display()))?;
    if want != out {
        for (i, (a, b)) in want.lines().zip(out.lines()).enumerate() {
            if a != b {
                eprintln!("line {}: golden `{a}`, got `{b}`", i + 1);
            }
        }
        return Err(format!(
            "selftest output differs from {} (review, then `cargo xtask snapshot --overwrite`)",
            g.display()
        ));
    }
    Ok(())
}

/// `cargo xtask snapshot [--overwrite]`: builds, runs the selftest, compares or rewrites its golden output.
pub fn snapshot(overwrite: bool) -> Result<(), String> {
    build_mps2()?;
    selftest(overwrite)
}

fn must_fail(bin: &str, marker: &str) -> Result<(), String> {
    let (code, out) = qemu(&elf(bin), &[], Duration::from_secs(60))?;
    print!("{out}");
    if code == 1 && out.contains(marker) {
        eprintln!("{bin}: QEMU exited with code 1, as it must");
        Ok(())
    } else {
        Err(format!(
            "{bin}: exit code {code} (want 1), output must contain `{marker}`"
        ))
    }
}

/// Sizes of an ELF32 image: (flash, RAM, CCM) in bytes. Flash = allocated sections with contents
/// (vector table, code, read-only data, the initial values of .data and .ccmdata); RAM =
/// allocated sections at 0x2000_0000 and above (.data, .bss, .uninit); CCM = allocated sections
/// in 0x1000_0000..0x2000_0000 (the STM32F4's core-coupled RAM); the stack not included.
fn elf_sizes(path: &Path) -> Result<(u64, u64, u64), String> {
    let b = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let u16at = |o: usize| {
        b.get(o..o + 2)
            .map(|s| u16::from_le_bytes([s[0], s[1]]) as usize)
    };
    let u32at = |o: usize| {
        b.get(o..o + 4)
            .map(|s| u32::from_le_bytes([s[0], s[1], s[2], s[3]]) as u64)
    };
    if b.get(..5) != Some(&[0x7f, b'E', b'L', b'F', 1][..]) {
        return Err(format!("{}: not an ELF32 file", path.display()));
    }
    let bad = || format!("{}: truncated ELF", path.display());
    let shoff = u32at(0x20).ok_or_else(bad)? as usize;
    let shentsize = u16at(0x2e).ok_or_else(bad)?;
    let shnum = u16at(0x30).ok_or_else(bad)?;
    let (mut flash, mut ram, mut ccm) = (0, 0, 0);
    for i in 0..shnum {
        let h = shoff + i * shentsize;
        let (ty, flags, addr, size) = (
            u32at(h + 4).ok_or_else(bad)?,
            u32at(h + 8).ok_or_else(bad)?,
            u32at(h + 12).ok_or_else(bad)?,
            u32at(h + 20).ok_or_else(bad)?,
        );
        if flags & 2 == 0 {
            continue; // not SHF_ALLOC
        }
        if ty != 8 {
            flash += size; // PROGBITS (NOBITS = 8 takes no flash)
        }
        if addr >= 0x2000_0000 {
            ram += size;
        } else if addr >= 0x1000_0000 {
            ccm += size;
        }
    }
    Ok((flash, ram, ccm))
}

fn report_size(what: &str, path: &Path) -> Result<(), String> {
    let (f, r, c) = elf_sizes(path)?;
    let ccm = if c > 0 {
        format!(", CCM {c} bytes ({:.1} KiB)", c as f64 / 1024.0)
    } else {
        String::new()
    };
    println!(
        "size {what}: flash {f} bytes ({:.1} KiB), static RAM {r} bytes ({:.1} KiB){ccm}",
        f as f64 / 1024.0,
        r as f64 / 1024.0
    );
    Ok(())
}

/// The TEST KEY the firmware tests provision and sign with.
fn test_key() -> PathBuf {
    root().join("firmware/keys/test.key")
}

/// The python-can client against the firmware provisioned with the test key; with `secure_all`
/// the device authenticates every message and the client runs its short `--secure-all`
/// scenario (about 2 s).
fn python_client(secure_all: bool) -> Result<(), String> {
    step(if secure_all {
        "python-can client with every message authenticated (--secure-all): signed measurements, every answer checked by Python's own CMAC"
    } else {
        "python-can client (independent protocol implementation) against the firmware"
    });
    let py = crate::venv()?;
    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map_err(|e| e.to_string())?
        .port();
    let gough = crate::debug_cli()?;
    let all: &[&str] = if secure_all { &["--secure-all"] } else { &[] };
    let mut fw = Command::new(&gough)
        .args(["firmware", "run", "--no-build", "--port", &port.to_string()])
        .arg("--key-file")
        .arg(test_key())
        .args(all)
        .arg("--elf")
        .arg(elf("gough-firmware"))
        .arg("--workdir")
        .arg(root().join("target/qemu-python"))
        .spawn()
        .map_err(|e| format!("{}: {e}", gough.display()))?;
    let client = run(Command::new(&py)
        .arg(root().join("host-tests/python/test_slcan_client.py"))
        .args(["--port", &port.to_string()])
        .arg("--gough")
        .arg(&gough)
        .arg("--tir")
        .arg(root().join("host-tests/data/tyres/MagicFormula61_Parameters.tir"))
        .arg("--key-file")
        .arg(test_key())
        .args(all));
    let t0 = Instant::now();
    let fw_status = loop {
        if let Ok(Some(st)) = fw.try_wait() {
            break Some(st);
        }
        if t0.elapsed() > Duration::from_secs(30) {
            let _ = fw.kill();
            let _ = fw.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(50));
    };
    client?;
    match fw_status {
        Some(st) if st.success() => Ok(()),
        other => Err(format!("firmware under the python client: {other:?}")),
    }
}

/// The firmware part of `test-all`: the M4F steps ([`test_m4f`]), then the M0/M3 bench; adds the
/// passed checks to `passed`.
pub fn test_all(passed: &mut u64) -> Result<(), String> {
    test_m4f(passed)?;
    bench_m0()?;
    *passed += 1;
    Ok(())
}

/// The Cortex-M4F firmware's steps of `test-all` (`cargo xtask firmware`): build, size,
/// selftest against its golden output, panic/HardFault, the SLCAN replay and garbage tests
/// (`host-tests/tests/firmware.rs`), the python-can client, the STM32F405 link, the bench. Adds
/// the passed checks to `passed`.
pub fn test_m4f(passed: &mut u64) -> Result<(), String> {
    build_mps2()?;
    report_size("mps2-an386 gough-firmware", &elf("gough-firmware"))?;
    selftest(false)?;
    *passed += 1;
    step("panic and HardFault exit QEMU with a failure code, never hang");
    must_fail("panic", "panicked")?;
    must_fail("hardfault", "HardFault")?;
    *passed += 2;
    step("firmware <-> host over SLCAN/TCP: replay equals the host's f32 run, garbage is counted");
    crate::workspace_test(
        "firmware",
        &["--ignored", "--test-threads", "1"],
        passed,
        &mut 0,
    )?;
    python_client(false)?;
    python_client(true)?;
    *passed += 2;
    step("STM32F405 with bxCAN (stm32f4xx-hal): build and link, flash/RAM/CCM (math::Fast; MF + transient filter + estimator: the App and its four estimators in SRAM, the stack in CCM, ≥ 20 KiB of it)");
    run(fw_cargo().args([
        "build",
        "--release",
        "--no-default-features",
        "--features",
        "stm32f4,fast",
        "--bin",
        "stm32f4",
    ]))?;
    report_size("stm32f405 stm32f4", &elf("stm32f4"))?;
    *passed += 1;
    step("bench: instructions on the M4F (QEMU -icount shift=6): combined MF evaluation; bank estimator and per-wheel pipeline per sample (dry, wet, icy road); RAM and stack");
    run(fw_cargo().args([
        "build",
        "--release",
        "--bin",
        "bench",
        "--features",
        "micromath,fast",
    ]))?;
    let (code, out) = qemu(
        &elf("bench"),
        &["-icount", "shift=6"],
        Duration::from_secs(300),
    )?;
    print!("{out}");
    if code != 0 {
        return Err(format!("bench exited with {code}"));
    }
    *passed += 1;
    Ok(())
}

/// The Cortex-M0 bench (`firmware-m0/`, QEMU microbit): the flash of the Magic Formula and
/// filter workloads in both number formats (the default build, the one to profile); then f32
/// with the friction estimator (feature `mu`) in an image of its own, its flash and its run (the
/// Q31.32 estimator does not fit the nRF51822: below); then both formats with the estimator in
/// one image on a Cortex-M3 (QEMU mps2-an385). Each run checks the Magic Formula
/// and the filter against f64 and the estimator's estimates against the host's, bit for bit.
pub fn bench_m0() -> Result<(), String> {
    step("bench: instructions on the M0 (QEMU microbit, -icount shift=0): combined MF evaluation and transient-filter step (each checked against f64) and the friction estimator at 100 Hz (mu::bank::Bank, batch 1; estimates equal to the host's bit for bit), soft-float f32 (math::Fast) with its flash (the Q31.32 estimator no longer fits the nRF51822); then both formats in one image on a Cortex-M3 (QEMU mps2-an385)");
    let dir = root().join("firmware-m0");
    let elf = dir.join("target/thumbv6m-none-eabi/release/bench");
    let m0_cargo = || {
        let mut c = cargo();
        c.current_dir(&dir).env_remove("CARGO_TARGET_DIR");
        c
    };
    run(m0_cargo().args(["build", "--release", "--bin", "bench"]))?;
    report_size(
        "microbit bench, Magic Formula and filter in both formats (no estimator)",
        &elf,
    )?;
    // The Q31.32 estimator no longer fits the nRF51822 since the bank calibrates its tyre: at
    // opt-level 3 its flash overflows the 256 KiB by 10,876 B, built for size its stack
    // overflows the 16 KiB of RAM. It runs on the Cortex-M3 image below.
    let what = "f32 math::Fast with the estimator";
    run(m0_cargo().args([
        "build",
        "--release",
        "--bin",
        "bench",
        "--no-default-features",
        "--features",
        "fast,mu",
    ]))?;
    report_size(&format!("microbit bench, {what}"), &elf)?;
    no_fpu_bench(&qemu::MICROBIT, &elf).map_err(|e| format!("M0 bench ({what}) {e}"))?;
    // Both number formats with the estimator in one image on a Cortex-M3 without FPU (QEMU
    // mps2-an385).
    run(m0_cargo().args([
        "build",
        "--release",
        "--bin",
        "bench",
        "--target",
        "thumbv7m-none-eabi",
        "--features",
        "mu",
    ]))?;
    let elf_m3 = dir.join("target/thumbv7m-none-eabi/release/bench");
    report_size("mps2-an385 (Cortex-M3) bench, every workload", &elf_m3)?;
    no_fpu_bench(&qemu::MPS2_AN385, &elf_m3).map_err(|e| format!("M3 bench {e}"))
}

/// Runs a no-FPU bench image on `board` (`-icount shift=0`), prints its output and fails on a
/// nonzero exit ("exited with N").
fn no_fpu_bench(board: &qemu::Board, elf: &Path) -> Result<(), String> {
    let (code, out) = qemu::run(
        board,
        elf,
        &["-icount", "shift=0"],
        &root().join("target/qemu"),
        Duration::from_secs(300),
    )?;
    print!("{out}");
    if code != 0 {
        return Err(format!("exited with {code}"));
    }
    Ok(())
}
