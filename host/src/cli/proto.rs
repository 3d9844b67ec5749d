//! `gough proto ...`: the CAN protocol's description.
use clap::Subcommand;
use std::path::PathBuf;

/// `gough proto ...`
#[derive(Subcommand)]
pub enum ProtoCmd {
    /// Print the DBC description of the bus (identifiers, frame header, message types).
    Dbc {
        /// Write to this file instead of stdout.
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

/// `gough proto dbc`
pub fn run(cmd: ProtoCmd) -> Result<(), String> {
    let ProtoCmd::Dbc { out } = cmd;
    let mut s = String::new();
    gough::proto::dbc::write(&mut s).map_err(|e| e.to_string())?;
    match out {
        Some(p) => std::fs::write(&p, s).map_err(|e| format!("{}: {e}", p.display())),
        None => {
            print!("{s}");
            Ok(())
        }
    }
}
