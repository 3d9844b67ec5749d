//! `gough`: the command-line tool of the gough project (host side).
//!
//! Every subcommand wraps the core crate; see `gough --help` and [`gough_host::cli`].
use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    match gough_host::cli::run(gough_host::cli::Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(msg) => {
            eprintln!("error: {msg}");
            ExitCode::FAILURE
        }
    }
}
