//! `gough tir ...`: tyre property files.
use crate::tyre;
use clap::Subcommand;
use std::path::PathBuf;

/// `gough tir ...`
#[derive(Subcommand)]
pub enum TirCmd {
    /// Load and validate a .tir file; print version, FNOMIN, R0 and warnings.
    Check {
        /// Tyre property file (.tir).
        file: PathBuf,
    },
}

/// Runs a `gough tir` command.
pub fn run(cmd: TirCmd) -> Result<(), String> {
    let TirCmd::Check { file } = cmd;
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
