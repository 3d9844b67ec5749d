//! The firmware images under QEMU (`qemu-system-arm`, semihosting on): [`Qemu`] runs the
//! protocol firmware with its UART0 bridged to TCP; [`run`] runs a bench or test image to its
//! exit and returns what it printed. `gough firmware`, `gough replay`, the firmware tests and
//! `cargo xtask` all start QEMU here.
use gough::proto::auth::slot;
use gough::proto::{Key, MacLen, Policy};
use std::io::Read;
use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Child, Command as Proc, Stdio};
use std::time::{Duration, Instant};

/// Where the firmware reads its key slot (`firmware/src/mps2.rs` `KEY_SLOT`; outside the image,
/// `memory.x`).
pub const KEY_SLOT: u32 = 0x003F_FF00;

/// A QEMU board: its `-cpu` and `-machine`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Board {
    /// `-cpu`.
    pub cpu: &'static str,
    /// `-machine`.
    pub machine: &'static str,
}

/// The Cortex-M4F board of the firmware (`memory.x`).
pub const MPS2_AN386: Board = Board {
    cpu: "cortex-m4",
    machine: "mps2-an386",
};
/// The Cortex-M0 board of the no-FPU bench (nRF51822).
pub const MICROBIT: Board = Board {
    cpu: "cortex-m0",
    machine: "microbit",
};
/// The Cortex-M3 board of the no-FPU bench's large tables (4 MB).
pub const MPS2_AN385: Board = Board {
    cpu: "cortex-m3",
    machine: "mps2-an385",
};

/// `qemu-system-arm` on `board` with `elf`, semihosting on (exit codes, output), run in
/// `workdir` (where semihosting writes files), stdin closed.
fn command(board: &Board, elf: &Path, workdir: &Path) -> Proc {
    let mut cmd = Proc::new("qemu-system-arm");
    cmd.current_dir(workdir)
        .args(["-cpu", board.cpu, "-machine", board.machine])
        .args(["-semihosting-config", "enable=on,target=native"])
        .arg("-kernel")
        .arg(elf)
        .stdin(Stdio::null());
    cmd
}

fn spawn_error(e: std::io::Error) -> String {
    format!("qemu-system-arm: {e} (install it: apt-get install qemu-system-arm)")
}

/// Runs `elf` on `board` with `-nographic` and the `extra` arguments (e.g. `-icount shift=6`)
/// until it exits; returns its exit code (semihosting) and what it printed. A run that
/// outlives `timeout` is killed and reported as hung.
pub fn run(
    board: &Board,
    elf: &Path,
    extra: &[&str],
    workdir: &Path,
    timeout: Duration,
) -> Result<(i32, String), String> {
    let elf = elf
        .canonicalize()
        .map_err(|e| format!("{}: {e}", elf.display()))?;
    std::fs::create_dir_all(workdir).map_err(|e| format!("{}: {e}", workdir.display()))?;
    let mut child = command(board, &elf, workdir)
        .arg("-nographic")
        .args(extra)
        .stdout(Stdio::piped())
        .spawn()
        .map_err(spawn_error)?;
    let mut out = child.stdout.take();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        if let Some(o) = out.as_mut() {
            let _ = o.read_to_string(&mut s);
        }
        s
    });
    let t0 = Instant::now();
    let code = loop {
        if let Ok(Some(st)) = child.try_wait() {
            break st.code().unwrap_or(-1);
        }
        if t0.elapsed() > timeout {
            let _ = child.kill();
            let _ = child.wait();
            return Err(format!("{} hung (killed after {timeout:?})", elf.display()));
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    Ok((code, reader.join().unwrap_or_default()))
}

/// The firmware package directory.
pub fn firmware_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../firmware")
}

/// Path of a release firmware binary (`gough-firmware`, `selftest`, ...).
pub fn firmware_elf(bin: &str) -> PathBuf {
    firmware_dir()
        .join("target/thumbv7em-none-eabihf/release")
        .join(bin)
}

/// Builds the firmware binaries (release) with cargo, in the firmware's own workspace.
pub fn build_firmware() -> Result<(), String> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let st = Proc::new(cargo)
        .current_dir(firmware_dir())
        .args(["build", "--release", "--bins"])
        .env_remove("CARGO_TARGET_DIR")
        .status()
        .map_err(|e| format!("cargo build (firmware): {e}"))?;
    if st.success() {
        Ok(())
    } else {
        Err(format!("firmware build failed: {st}"))
    }
}

/// A free local TCP port (bound and released; QEMU binds it right after).
pub fn free_port() -> Result<u16, String> {
    TcpListener::bind("127.0.0.1:0")
        .and_then(|l| l.local_addr())
        .map(|a| a.port())
        .map_err(|e| format!("no free TCP port: {e}"))
}

/// A running QEMU with the firmware; killed on drop unless it exited.
pub struct Qemu {
    child: Child,
    /// TCP port of the bridged UART0.
    pub port: u16,
}

impl Qemu {
    /// Starts `elf` on mps2-an386 with UART0 on a free local TCP port (QEMU waits for the
    /// client before it runs the guest). Semihosting output goes to our stdout/stderr unless
    /// `quiet`; the defmt log goes to `firmware.defmt` in `workdir`.
    /// `port`: the TCP port, or `None` for a free one.
    pub fn start(
        elf: &Path,
        workdir: &Path,
        quiet: bool,
        port: Option<u16>,
    ) -> Result<Qemu, String> {
        Qemu::start_keyed(elf, workdir, quiet, port, None)
    }

    /// As [`Qemu::start`], the device provisioned at "flash time" with `key`, MACs of its
    /// length and its policy (what it authenticates): the key slot (`gough::proto::auth::slot`) written to `workdir/key-slot.bin` and
    /// loaded by QEMU's `-device loader` at the firmware's `KEY_SLOT` (0x003F_FF00), never sent
    /// on the bus. `None`: no key (the device refuses every state-changing message).
    pub fn start_keyed(
        elf: &Path,
        workdir: &Path,
        quiet: bool,
        port: Option<u16>,
        key: Option<(&Key, MacLen, Policy)>,
    ) -> Result<Qemu, String> {
        if !elf.exists() {
            return Err(format!(
                "{}: no such firmware binary (build it: cargo build --release in firmware/)",
                elf.display()
            ));
        }
        // QEMU runs in `workdir`: make the path absolute first.
        let elf = elf
            .canonicalize()
            .map_err(|e| format!("{}: {e}", elf.display()))?;
        let port = match port {
            Some(p) => p,
            None => free_port()?,
        };
        std::fs::create_dir_all(workdir).map_err(|e| format!("{}: {e}", workdir.display()))?;
        let mut cmd = command(&MPS2_AN386, &elf, workdir);
        cmd.args(["-display", "none", "-monitor", "none"])
            .arg("-serial")
            .arg(format!("tcp:127.0.0.1:{port},server=on,wait=on"));
        let slot_file = workdir.join("key-slot.bin");
        let _ = std::fs::remove_file(&slot_file);
        if let Some((k, n, p)) = key {
            std::fs::write(&slot_file, slot::encode(k, n, p))
                .map_err(|e| format!("{}: {e}", slot_file.display()))?;
            let slot_file = slot_file
                .canonicalize()
                .map_err(|e| format!("{}: {e}", slot_file.display()))?;
            cmd.arg("-device").arg(format!(
                "loader,file={},addr={KEY_SLOT:#x},force-raw=on",
                slot_file.display()
            ));
        }
        if quiet {
            cmd.stdout(Stdio::null());
        }
        let child = cmd.spawn().map_err(spawn_error)?;
        Ok(Qemu { child, port })
    }

    /// Waits up to `timeout` for QEMU to exit; its exit code (semihosting), or `None`.
    pub fn wait(&mut self, timeout: Duration) -> Option<i32> {
        let t0 = Instant::now();
        while t0.elapsed() < timeout {
            if let Ok(Some(st)) = self.child.try_wait() {
                return Some(st.code().unwrap_or(-1));
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        None
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        if let Ok(None) = self.child.try_wait() {
            let _ = self.child.kill();
            let _ = self.child.wait();
        }
    }
}
