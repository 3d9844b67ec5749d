//! `gough firmware ...`: the firmware under QEMU, its UART bridged to TCP.
use crate::device::{self, Qemu};
use clap::{Args, Subcommand};
use gough::proto::{MacLen, Policy};
use std::path::PathBuf;
use std::time::Duration;

/// `gough firmware ...`
#[derive(Subcommand)]
pub enum FirmwareCmd {
    /// Build the firmware, start it in QEMU (mps2-an386) and bridge its UART0 (SLCAN) to TCP.
    ///
    /// Waits until QEMU exits (the firmware exits on `Command::Stop`) and returns its code.
    /// Clients: `gough replay --port PORT`, or python-can with
    /// `can.Bus(interface="slcan", channel="socket://127.0.0.1:PORT")`.
    Run(RunArgs),
}

/// Where the firmware comes from and how it is reached.
#[derive(Args, Clone)]
pub struct RunArgs {
    /// Firmware ELF to run (default: the release build of firmware/, built first).
    #[arg(long)]
    pub elf: Option<PathBuf>,
    /// Do not build the firmware first.
    #[arg(long)]
    pub no_build: bool,
    /// TCP port for UART0 (default: a free one, printed).
    #[arg(long)]
    pub port: Option<u16>,
    /// Working directory of QEMU (the defmt log `firmware.defmt` and the device's
    /// non-volatile boot counter `gough-nv.bin` land there).
    #[arg(long, default_value = "target/qemu")]
    pub workdir: PathBuf,
    /// Device key file (32 hexadecimal digits; `firmware/keys/test.key` is the TEST KEY): the
    /// firmware is started with it provisioned (at "flash time", never on the bus), and
    /// `gough replay` signs its state-changing messages with it. Without it the device has no
    /// key and refuses every upload, settings, calibration, reset and stop.
    #[arg(long, value_name = "KEY")]
    pub key_file: Option<PathBuf>,
    /// MAC length the device is provisioned with \[bytes, 4..=8\] (with `--key-file`).
    #[arg(long, default_value_t = 8, value_parser = clap::value_parser!(u8).range(4..=8))]
    pub mac_len: u8,
    /// Authenticate measurements and answers too (with `--key-file`): the device is provisioned
    /// to refuse every unsecured message (but the status request) and to sign everything it
    /// sends, and `gough replay` signs its measurements and checks every answer
    /// (docs/protocol.md, "Security").
    #[arg(long, requires = "key_file")]
    pub secure_all: bool,
}

impl RunArgs {
    /// What the device authenticates (`--secure-all`).
    pub fn policy(&self) -> Policy {
        if self.secure_all {
            Policy::All
        } else {
            Policy::StateChanging
        }
    }
}

/// Starts the firmware of `args` under QEMU (building it first unless told not to).
pub fn start(args: &RunArgs) -> Result<Qemu, String> {
    let elf = match &args.elf {
        Some(e) => e.clone(),
        None => {
            if !args.no_build {
                device::build_firmware()?;
            }
            device::firmware_elf("gough-firmware")
        }
    };
    let key = args.key_file.as_deref().map(device::read_key).transpose()?;
    let mac_len = MacLen::new(args.mac_len).ok_or("--mac-len: 4..=8")?;
    Qemu::start_keyed(
        &elf,
        &args.workdir,
        false,
        args.port,
        key.as_ref().map(|k| (k, mac_len, args.policy())),
    )
}

/// `gough firmware run`
pub fn run(cmd: FirmwareCmd) -> Result<(), String> {
    let FirmwareCmd::Run(args) = cmd;
    let mut q = start(&args)?;
    eprintln!(
        "firmware UART0 (SLCAN) on tcp 127.0.0.1:{p}; python-can: can.Bus(interface=\"slcan\", channel=\"socket://127.0.0.1:{p}\")",
        p = q.port
    );
    match q.wait(Duration::from_secs(u64::MAX / 4)) {
        Some(0) => Ok(()),
        Some(c) => Err(format!("firmware exited with code {c}")),
        None => Err("QEMU did not exit".into()),
    }
}
