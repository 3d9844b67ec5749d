//! `gough`: the command-line tool of the gough project (host side).
//!
//! Every subcommand wraps the core crate; see `gough --help`.
use clap::{Parser, Subcommand, ValueEnum};
use gough::mf::Options;
use gough_host::csvio;
use gough_host::mfrun::{self, INPUT_COLUMNS, OUTPUT_COLUMNS};
use gough_host::tolerance::Precision;
use gough_host::tyre;
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "gough",
    version,
    about = "Pacejka tyre models and road-friction estimation (host tool)"
)]
struct Cli {
    #[command(subcommand)]
    cmd: Cmd,
}

#[derive(Subcommand)]
enum Cmd {
    /// Magic Formula evaluation.
    Mf {
        #[command(subcommand)]
        cmd: MfCmd,
    },
    /// Tyre property (.tir) files.
    Tir {
        #[command(subcommand)]
        cmd: TirCmd,
    },
    /// CAN protocol (the DBC description of the bus).
    Proto {
        #[command(subcommand)]
        cmd: gough_host::fwcli::ProtoCmd,
    },
    /// The firmware under QEMU (mps2-an386), its UART bridged to TCP.
    Firmware {
        #[command(subcommand)]
        cmd: gough_host::fwcli::FirmwareCmd,
    },
    /// Upload a tyre, stream a measurement log to the firmware as CAN frames, record its answers.
    Replay(gough_host::fwcli::ReplayArgs),
    /// Vehicle simulation: run a manoeuvre, write DIR/log.csv and PNG plots.
    Sim(gough_host::sim::cli::SimArgs),
    /// Road-friction estimation: on a log, or benchmarked on simulated manoeuvres.
    Mu {
        #[command(subcommand)]
        cmd: gough_host::mu::cli::MuCmd,
    },
    /// Sim-to-real gap diagnosis: where the sim misses a log, which effect causes it.
    Gap {
        #[command(subcommand)]
        cmd: gough_host::gap::cli::GapCmd,
    },
}

#[derive(Subcommand)]
enum MfCmd {
    /// Evaluate the steady-state Magic Formula on every row of a CSV file.
    ///
    /// Input columns in_Fz,in_kappa,in_alpha,in_gamma,in_phit,in_Vx,in_P (SI, rad, ISO-W;
    /// in_P = 0 means INFLPRES; other columns are ignored). Output: the input columns, then
    /// Fx,Fy,Mz,Mx,My,mux,muy,Kya,Kxk,t,Mzr,sigmax,sigmay.
    Eval {
        /// Tyre property file (.tir).
        #[arg(long)]
        tir: PathBuf,
        /// Input CSV.
        #[arg(long)]
        input: PathBuf,
        /// Output CSV (written atomically).
        #[arg(long)]
        output: PathBuf,
        /// MFeval useMode: 1xx limits on / 2xx off; x1x alpha* off / x2x on; xx1 no turn slip /
        /// xx2 turn slip.
        #[arg(long, default_value_t = 111)]
        mode: u16,
        /// Float path: f64 (host) or f32 (the device's).
        #[arg(long, value_enum, default_value_t = Prec::F64)]
        precision: Prec,
    },
}

#[derive(Subcommand)]
enum TirCmd {
    /// Load and validate a .tir file; print version, FNOMIN, R0 and warnings.
    Check {
        /// Tyre property file (.tir).
        file: PathBuf,
    },
}

#[derive(Clone, Copy, ValueEnum)]
enum Prec {
    F64,
    F32,
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> Result<(), String> {
    match cli.cmd {
        Cmd::Proto { cmd } => gough_host::fwcli::proto(cmd),
        Cmd::Firmware { cmd } => gough_host::fwcli::firmware(cmd),
        Cmd::Replay(args) => gough_host::fwcli::replay(args),
        Cmd::Sim(args) => gough_host::sim::cli::run(args),
        Cmd::Mu { cmd } => gough_host::mu::cli::run(cmd),
        Cmd::Gap { cmd } => gough_host::gap::cli::run(cmd),
        Cmd::Tir {
            cmd: TirCmd::Check { file },
        } => {
            let t = tyre::load(&file)?;
            let p = &t.params;
            println!("{}: {}", file.display(), p.version.name());
            println!("  FNOMIN          {} N", p.fnomin);
            println!("  UNLOADED_RADIUS {} m", p.unloaded_radius);
            println!(
                "  TYRESIDE        {}",
                match p.tyreside {
                    Some(gough::mf::Side::Left) => "left",
                    Some(gough::mf::Side::Right) => "right",
                    None => "unknown",
                }
            );
            println!(
                "  turn slip       {}",
                if gough::mf::turnslip::available(p) {
                    "available"
                } else {
                    "not available"
                }
            );
            if t.warnings.is_empty() {
                println!("  no warnings");
            } else {
                println!("  {} warning(s):", t.warnings.len());
                for w in &t.warnings {
                    println!("    {w}");
                }
            }
            Ok(())
        }
        Cmd::Mf {
            cmd:
                MfCmd::Eval {
                    tir,
                    input,
                    output,
                    mode,
                    precision,
                },
        } => {
            let opts = Options::from_use_mode(mode).ok_or_else(|| {
                format!(
                    "--mode {mode}: expected 3 digits, each 1 or 2 (e.g. 111, 211, 121, 221, 112)"
                )
            })?;
            let t = tyre::load(&tir)?;
            let p64 = t.params;
            let p32 = p64.cast::<f32>();
            let prec = match precision {
                Prec::F64 => Precision::F64,
                Prec::F32 => Precision::F32,
            };
            let optional: Vec<(&str, f64)> = INPUT_COLUMNS[4..].iter().map(|&c| (c, 0.0)).collect();
            let table =
                csvio::read(&input, &INPUT_COLUMNS[..4], &optional).map_err(|e| e.to_string())?;
            if !table.present[1] {
                return Err(format!(
                    "{}: missing required column in_Vx",
                    input.display()
                ));
            }
            let mut rows = Vec::with_capacity(table.rows.len());
            for (row, line) in table.rows.iter().zip(&table.lines) {
                let inp = mfrun::input_of(row);
                let out = mfrun::eval_row(&p64, &p32, &inp, &opts, prec)
                    .map_err(|e| format!("{}: line {line}: {e}", input.display()))?;
                let mut r = row.clone();
                r.extend_from_slice(&mfrun::output_values(&out));
                rows.push(r);
            }
            let header: Vec<&str> = INPUT_COLUMNS
                .iter()
                .chain(OUTPUT_COLUMNS.iter())
                .copied()
                .collect();
            csvio::write(&output, &header, &rows)
                .map_err(|e| format!("{}: cannot write: {e}", output.display()))?;
            eprintln!("{} rows -> {}", rows.len(), output.display());
            Ok(())
        }
    }
}
