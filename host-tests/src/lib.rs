//! Helpers of the tests that hold gough against full precision and outside oracles: the
//! accuracy budgets against the MFeval oracle (one table for all tests, each with its reason)
//! and the path of the `gough` binary for the end-to-end tests of the command line.
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

pub mod tolerance;

/// The repository's root folder.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The MFeval oracle's sweep files (`host-tests/data/oracle/*.csv`), sorted by name; at least
/// the 70 the repository bundles (a test stops when some are missing).
pub fn oracle_files() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/oracle");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "csv"))
        .collect();
    files.sort();
    assert!(files.len() >= 70, "oracle files missing: {}", files.len());
    files
}

/// The `gough` binary of package `gough-host`, built (once per test process) in the profile of
/// the tests that ask for it, where `cargo build -p gough-host --bin gough` puts it
/// (`target/debug/gough`): the steps of `cargo xtask test-all` after the host tests that run
/// the binary then find it built (with `--target` it was a second build of the host crate).
/// Without the `lanes` feature (`--no-default-features --features plot`, as `cargo xtask`
/// builds it): a debug build never evaluates in lanes (`gap::sim::Sim::lanes`), and compiling
/// them took this build from about 1 to 2.5 minutes.
pub fn gough_bin() -> &'static Path {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| {
        let run = escargot::CargoBuild::new()
            .manifest_path(root().join("host/Cargo.toml"))
            .package("gough-host")
            .bin("gough")
            .no_default_features()
            .features("plot")
            .current_release()
            .run()
            .unwrap_or_else(|e| panic!("cannot build the gough binary: {e}"));
        run.path().to_path_buf()
    })
}
