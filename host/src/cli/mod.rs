//! The `gough` command line: one module per command group of `gough --help`.
//!
//! Every command wraps the core crate or this crate's libraries; the binary
//! (`src/bin/gough.rs`) only parses [`Cli`] and prints the error of [`run`].
use clap::{Parser, Subcommand};

pub mod firmware;
pub mod gap;
pub mod mf;
pub mod mu;
pub mod proto;
pub mod replay;
pub mod sim;
pub mod tir;

/// `gough`: the command-line tool of the gough project (host side).
#[derive(Parser)]
#[command(
    name = "gough",
    version,
    about = "Pacejka tyre models and road-friction estimation (host tool)"
)]
pub struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Magic Formula evaluation.
    Mf {
        #[command(subcommand)]
        cmd: mf::MfCmd,
    },
    /// Tyre property (.tir) files.
    Tir {
        #[command(subcommand)]
        cmd: tir::TirCmd,
    },
    /// CAN protocol (the DBC description of the bus).
    Proto {
        #[command(subcommand)]
        cmd: proto::ProtoCmd,
    },
    /// The firmware under QEMU (mps2-an386), its UART bridged to TCP.
    Firmware {
        #[command(subcommand)]
        cmd: firmware::FirmwareCmd,
    },
    /// Upload a tyre, stream a measurement log to the firmware as CAN frames, record its answers.
    Replay(replay::ReplayArgs),
    /// Vehicle simulation: run a manoeuvre, write DIR/log.csv and PNG plots.
    Sim(sim::SimArgs),
    /// Road-friction estimation: on a log, or benchmarked on simulated manoeuvres.
    Mu {
        #[command(subcommand)]
        cmd: mu::MuCmd,
    },
    /// Sim-to-real gap diagnosis: where the sim misses a log, which effect causes it.
    Gap {
        #[command(subcommand)]
        cmd: gap::GapCmd,
    },
}

/// Runs a parsed command line; the error is one line for the user.
pub fn run(cli: Cli) -> Result<(), String> {
    match cli.cmd {
        Cmd::Mf { cmd } => mf::run(cmd),
        Cmd::Tir { cmd } => tir::run(cmd),
        Cmd::Proto { cmd } => proto::run(cmd),
        Cmd::Firmware { cmd } => firmware::run(cmd),
        Cmd::Replay(args) => replay::run(args),
        Cmd::Sim(args) => sim::run(args),
        Cmd::Mu { cmd } => mu::run(cmd),
        Cmd::Gap { cmd } => gap::run(cmd),
    }
}
