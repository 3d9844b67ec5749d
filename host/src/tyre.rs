//! Loading a `.tir` file with a one-line error naming the file, and writing coefficients into
//! its text ([`set_in_tir`], [`set_or_add_in_tir`]: `gough mu calibrate --out` and
//! `gough gap diagnose --write-tir`).
use gough::mf::{Key, Need, Params};
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

/// The `[SECTION]` a key the text lacks is added to: scaling factors λ to
/// `[SCALING_COEFFICIENTS]`; turn-slip coefficients (`P..P1`, `Q..P1`) to
/// `[TURNSLIP_COEFFICIENTS]`; the carcass stiffnesses and their load and pressure terms to
/// `[STRUCTURAL]`; `.X`/`.Y` force coefficients (P, R and the relaxation PT) to
/// `[LONGITUDINAL_COEFFICIENTS]`/`[LATERAL_COEFFICIENTS]`; `Q…` and `S…` to
/// `[ALIGNING_COEFFICIENTS]`. `None` for other keys (dimensions, operating conditions, ranges).
pub fn section_of(key: Key) -> Option<&'static str> {
    let name = key.name();
    let b = name.as_bytes();
    if key.need() == Need::Scale {
        return Some("[SCALING_COEFFICIENTS]");
    }
    if key.need() == Need::TurnSlip
        || (b.len() >= 5 && b[3] == b'P' && b[4].is_ascii_digit() && matches!(b[0], b'P' | b'Q'))
    {
        return Some("[TURNSLIP_COEFFICIENTS]");
    }
    if name.ends_with("_STIFFNESS")
        && (name.starts_with("LONGITUDINAL") || name.starts_with("LATERAL"))
        || name.starts_with("PCF")
    {
        return Some("[STRUCTURAL]");
    }
    if name.starts_with("QSX") {
        return Some("[OVERTURNING_COEFFICIENTS]");
    }
    if name.starts_with("QSY") {
        return Some("[ROLLING_COEFFICIENTS]");
    }
    if matches!(b.first(), Some(b'P' | b'R')) && b.len() >= 3 {
        return match b[2] {
            b'X' => Some("[LONGITUDINAL_COEFFICIENTS]"),
            b'Y' => Some("[LATERAL_COEFFICIENTS]"),
            _ => None,
        };
    }
    if matches!(b.first(), Some(b'Q' | b'S')) {
        return Some("[ALIGNING_COEFFICIENTS]");
    }
    None
}

/// [`set_in_tir`], or for a key the text lacks, the key added at the start of its section
/// ([`section_of`]; the section appended at the end of the text when the text has none),
/// with the comment `$added by {by}`; nothing added when `value` is what the reader takes for
/// the missing key (1 for a scaling factor, 0 otherwise).
pub fn set_or_add_in_tir(text: &str, key: Key, value: f64, by: &str) -> Result<String, String> {
    if let Ok(out) = set_in_tir(text, key, value) {
        return Ok(out);
    }
    let name = key.name();
    let default = if key.need() == Need::Scale { 1.0 } else { 0.0 };
    if value == default {
        return Ok(text.to_string());
    }
    let section = section_of(key)
        .ok_or_else(|| format!("{name} is not in the file and has no section to be added to"))?;
    let entry = format!("{name:<26}= {value:<15}\t $added by {by}\n");
    let mut out = String::with_capacity(text.len() + 60);
    let mut added = false;
    for line in text.split_inclusive('\n') {
        out.push_str(line);
        if !added && line.trim().eq_ignore_ascii_case(section) {
            if !line.ends_with('\n') {
                out.push('\n');
            }
            out.push_str(&entry);
            added = true;
        }
    }
    if !added {
        if !out.is_empty() && !out.ends_with('\n') {
            out.push('\n');
        }
        out.push_str(section);
        out.push('\n');
        out.push_str(&entry);
    }
    Ok(out)
}

/// The `.tir` text `text` with the value of `key` set to `value` (the rest of the line — its
/// alignment, a `$` comment — kept). Errors when the key is not in the text.
pub fn set_in_tir(text: &str, key: Key, value: f64) -> Result<String, String> {
    let mut found = false;
    let mut out = String::with_capacity(text.len() + 16);
    for line in text.split_inclusive('\n') {
        let body = line.trim_end_matches(['\n', '\r']);
        let end = &line[body.len()..];
        let hit = body
            .split_once('=')
            .filter(|(k, _)| k.trim().eq_ignore_ascii_case(key.name()));
        match hit {
            Some((k, v)) if !found => {
                let comment = v.find('$').map_or("", |i| &v[i..]);
                out.push_str(&format!("{k}= {value:<15}\t {comment}"));
                out.push_str(end);
                found = true;
            }
            _ => out.push_str(line),
        }
    }
    if found {
        Ok(out)
    } else {
        Err(format!("{} is not in the file", key.name()))
    }
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

/// The bundled MF 6.1 tyre's text and parameters; for the unit tests of what writes into it.
#[cfg(test)]
pub(crate) fn bundled_text() -> (String, Params<f64>) {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../host-tests/data/tyres/MagicFormula61_Parameters.tir"
    );
    (
        std::fs::read_to_string(path).expect("the bundled tyre"),
        bundled(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The value is replaced on its own line, the comment kept, and the file reads back with
    /// it and nothing else changed; a key the text lacks is an error.
    #[test]
    fn a_value_is_set_in_the_file_text() {
        let (text, p) = bundled_text();
        let out = set_in_tir(&text, Key::PHY1, -0.000811411).unwrap();
        let q = gough::tir::parse(&out).unwrap().params;
        let mut back = q.clone();
        assert_eq!(q.phy1, -0.000811411);
        back.phy1 = p.phy1;
        assert_eq!(back, p);
        assert!(out.contains("$Horizontal shift Shy at Fznom"));
        assert_eq!(out.lines().count(), text.lines().count());
        assert!(set_in_tir("[MODEL]\nFITTYP = 61\n", Key::PHY1, 0.0).is_err());
    }

    /// A key the text lacks goes to its section, or to a section appended when the text has
    /// none; it reads back; a value the reader takes for the missing key adds nothing.
    #[test]
    fn a_missing_key_is_added_to_its_section() {
        let text = "[MODEL]\nFITTYP = 61\n[SCALING_COEFFICIENTS]\nLFZO = 1\n";
        let out = set_or_add_in_tir(text, Key::LMUY, 0.9, "test").unwrap();
        assert!(out.contains("[SCALING_COEFFICIENTS]\nLMUY"), "{out}");
        let out = set_or_add_in_tir(&out, Key::PCFY1, 0.25, "test").unwrap();
        assert!(
            out.ends_with(
                "[STRUCTURAL]\nPCFY1                     = 0.25           \t $added by test\n"
            ),
            "{out}"
        );
        assert_eq!(
            set_or_add_in_tir(text, Key::LMUY, 1.0, "test").unwrap(),
            text
        );
        assert_eq!(section_of(Key::PKYP1), Some("[TURNSLIP_COEFFICIENTS]"));
        assert_eq!(section_of(Key::PPY1), Some("[LATERAL_COEFFICIENTS]"));
        assert_eq!(section_of(Key::RBX1), Some("[LONGITUDINAL_COEFFICIENTS]"));
        assert_eq!(
            section_of(Key::LONGITUDINAL_STIFFNESS),
            Some("[STRUCTURAL]")
        );
        assert_eq!(section_of(Key::QHZ1), Some("[ALIGNING_COEFFICIENTS]"));
        assert_eq!(section_of(Key::SSZ1), Some("[ALIGNING_COEFFICIENTS]"));
        assert_eq!(section_of(Key::FNOMIN), None);
        let (full, p) = bundled_text();
        let q = gough::tir::parse(&set_or_add_in_tir(&full, Key::PCFX1, 0.1, "t").unwrap())
            .unwrap()
            .params;
        assert_eq!(q.pcfx1, 0.1);
        assert_eq!(q.lmux, p.lmux);
    }
}
