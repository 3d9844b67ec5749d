//! Loading a `.tir` file with a one-line error naming the file.
use gough::mf::Params;
use gough::tir;
use std::path::Path;

/// A loaded tyre: parameters and the reader's warnings, rendered.
pub struct Tyre {
    /// Parameters in f64.
    pub params: Params<f64>,
    /// Warnings of the reader (`line N: ...`).
    pub warnings: Vec<String>,
}

/// Reads and parses `path`; the error is one line: `FILE: line N: what`.
pub fn load(path: &Path) -> Result<Tyre, String> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
    let t = tir::parse(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut warnings: Vec<String> = t.warnings.iter().map(|w| w.to_string()).collect();
    if t.warnings_dropped > 0 {
        warnings.push(format!("... and {} more warnings", t.warnings_dropped));
    }
    Ok(Tyre {
        params: t.params,
        warnings,
    })
}

/// The bundled MF 6.1 tyre (`host-tests/data/tyres/MagicFormula61_Parameters.tir`), as the
/// bench and the demo run it; for the unit tests.
#[cfg(test)]
pub(crate) fn bundled() -> Params<f64> {
    load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../host-tests/data/tyres/MagicFormula61_Parameters.tir"
    )))
    .expect("the bundled tyre")
    .params
}
