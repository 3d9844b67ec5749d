//! `cargo xtask header [--check]`: generates `capi/include/gough.h` from `capi/src/lib.rs` with
//! cbindgen (the library from crates.io, settings in `capi/cbindgen.toml`); `--check` (part of
//! `test-all`) fails when the checked-in header differs from a fresh generation.
use crate::{root, step};

fn generate() -> Result<String, String> {
    let dir = root().join("capi");
    let cfg = cbindgen::Config::from_file(dir.join("cbindgen.toml"))
        .map_err(|e| format!("capi/cbindgen.toml: {e}"))?;
    let bindings = cbindgen::Builder::new()
        .with_crate(&dir)
        .with_config(cfg)
        .generate()
        .map_err(|e| format!("cbindgen: {e}"))?;
    let mut out = Vec::new();
    bindings.write(&mut out);
    String::from_utf8(out).map_err(|e| format!("cbindgen wrote non-UTF-8: {e}"))
}

/// Writes the header, or (`check`) compares it with the checked-in one.
pub fn header(check: bool) -> Result<(), String> {
    step("C header: capi/include/gough.h = a fresh cbindgen generation from capi/src/lib.rs");
    let path = root().join("capi/include/gough.h");
    let fresh = generate()?;
    if !check {
        std::fs::write(&path, &fresh).map_err(|e| format!("{}: {e}", path.display()))?;
        eprintln!("wrote {}", path.display());
        return Ok(());
    }
    let old = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    if old != fresh {
        for (i, (a, b)) in old.lines().zip(fresh.lines()).enumerate() {
            if a != b {
                eprintln!("line {}: checked in `{a}`, generated `{b}`", i + 1);
                break;
            }
        }
        return Err(format!(
            "{} differs from a fresh cbindgen generation (run `cargo xtask header` and commit it)",
            path.display()
        ));
    }
    eprintln!("{} is up to date", path.display());
    Ok(())
}
