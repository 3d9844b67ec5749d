//! The tyre calibration file of `gough mu estimate --calibration-in/--calibration-out` and
//! Python's `estimate_mu(calibration_in=, calibration_out=)`: each wheel's online calibration
//! (`gough::mu::calibration`, as the core exports it: [`Exported`]) as JSON, one entry per
//! wheel, each property by its core name ([`Property::name`]) with its value and σ:
//!
//! ```json
//! {"format": "gough-calibration-1",
//!  "wheels": [{"wheel": 0, "batches": 42,
//!              "properties": {"trail": {"value": 1.03, "sigma": 0.02}, "trail_shape": {..},
//!                             "trail_shift": {..}, "kx": {..}}}]}
//! ```
//!
//! Scales are factors (1 = the `.tir` file), the shift in rad; σ of a scale is relative (of its
//! logarithm). Reading checks the form (every property once, no other, wheels 0–3 once each);
//! whether the values are a calibration the estimator accepts (finite, within its bounds) is the
//! core's to say when they are imported ([`gough::mu::Bank::import_calibration`]).
use super::Estimator;
use gough::mu::calibration::{Exported, Property, PROPERTIES};
use gough::proto::Wheel;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The `format` of the files this version writes and reads.
pub const FORMAT: &str = "gough-calibration-1";

/// One property's value and σ.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Value {
    /// Value (a scale's factor, the shift in rad).
    pub value: f32,
    /// Its σ.
    pub sigma: f32,
}

/// One wheel's entry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WheelEntry {
    /// Wheel index 0–3 (FL, FR, RL, RR; one wheel's log is 0).
    pub wheel: usize,
    /// Batches that moved the calibration.
    pub batches: u32,
    /// By [`Property::name`].
    pub properties: BTreeMap<String, Value>,
}

/// The file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationFile {
    /// [`FORMAT`].
    pub format: String,
    /// The wheels, each at most once.
    pub wheels: Vec<WheelEntry>,
}

impl CalibrationFile {
    /// The file of these wheels' calibrations.
    pub fn new(cals: &[(Wheel, Exported)]) -> CalibrationFile {
        let wheels = cals
            .iter()
            .map(|(w, e)| WheelEntry {
                wheel: w.index(),
                batches: e.batches,
                properties: Property::ALL
                    .iter()
                    .enumerate()
                    .map(|(k, p)| {
                        (
                            p.name().to_string(),
                            Value {
                                value: e.value[k],
                                sigma: e.sigma[k],
                            },
                        )
                    })
                    .collect(),
            })
            .collect();
        CalibrationFile {
            format: FORMAT.into(),
            wheels,
        }
    }

    /// The wheels' calibrations, or what is wrong with the file's form.
    pub fn calibrations(&self) -> Result<Vec<(Wheel, Exported)>, String> {
        if self.format != FORMAT {
            return Err(format!("format '{}': expected '{FORMAT}'", self.format));
        }
        let mut out: Vec<(Wheel, Exported)> = Vec::new();
        for e in &self.wheels {
            let w = Wheel::from_index(e.wheel)
                .ok_or_else(|| format!("wheel {}: expected 0, 1, 2 or 3", e.wheel))?;
            if out.iter().any(|(x, _)| *x == w) {
                return Err(format!("wheel {} appears twice", e.wheel));
            }
            if let Some(k) = e
                .properties
                .keys()
                .find(|k| !Property::ALL.iter().any(|p| p.name() == k.as_str()))
            {
                let names: Vec<&str> = Property::ALL.iter().map(|p| p.name()).collect();
                return Err(format!(
                    "wheel {}: unknown property '{k}' (expected {})",
                    e.wheel,
                    names.join(", ")
                ));
            }
            let mut x = Exported {
                batches: e.batches,
                ..Exported::default()
            };
            for (k, p) in Property::ALL.iter().enumerate().take(PROPERTIES) {
                let v = e
                    .properties
                    .get(p.name())
                    .ok_or_else(|| format!("wheel {}: property '{}' missing", e.wheel, p.name()))?;
                x.value[k] = v.value;
                x.sigma[k] = v.sigma;
            }
            out.push((w, x));
        }
        Ok(out)
    }

    /// Reads and checks the file at `path`.
    pub fn read(path: &Path) -> Result<Vec<(Wheel, Exported)>, String> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| format!("{}: cannot read: {e}", path.display()))?;
        let f: CalibrationFile = serde_json::from_str(&text)
            .map_err(|e| format!("{}: not a calibration file: {e}", path.display()))?;
        f.calibrations()
            .map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Writes the file at `path` (through a temporary file, renamed).
    pub fn write(&self, path: &Path) -> Result<(), String> {
        let err = |e: std::io::Error| format!("{}: cannot write: {e}", path.display());
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(err)?;
        }
        let text = serde_json::to_string_pretty(self).map_err(|e| e.to_string())?;
        let tmp = path.with_extension("tmp");
        std::fs::write(&tmp, text + "\n").map_err(err)?;
        std::fs::rename(&tmp, path).map_err(err)
    }
}

/// Starts `est`'s wheels from the calibrations in the file at `path` (`--calibration-in`); an
/// error names the file and, for a calibration the estimator refuses, the wheel and why.
pub fn load_into(est: &mut dyn Estimator, path: &Path) -> Result<(), String> {
    for (w, c) in CalibrationFile::read(path)? {
        est.set_calibration(w, &c)
            .map_err(|e| format!("{}: wheel {}: refused: {e}", path.display(), w.index()))?;
    }
    Ok(())
}

/// Writes the calibrations of `est` at the wheels among `wheels` (each once, in wheel order) to
/// the file at `path` (`--calibration-out`).
pub fn save_from(est: &dyn Estimator, wheels: &[Wheel], path: &Path) -> Result<(), String> {
    let cals: Vec<(Wheel, Exported)> = Wheel::ALL
        .iter()
        .filter(|w| wheels.contains(w))
        .filter_map(|w| est.calibration(*w).map(|c| (*w, c)))
        .collect();
    CalibrationFile::new(&cals).write(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_reads_back_and_a_bad_one_says_why() {
        let e = Exported {
            value: [1.05, 0.9, 0.001, 1.1],
            sigma: [0.02, 0.05, 0.0005, 0.03],
            batches: 17,
        };
        let f = CalibrationFile::new(&[(Wheel::RearLeft, e)]);
        let text = serde_json::to_string(&f).unwrap();
        let back: CalibrationFile = serde_json::from_str(&text).unwrap();
        assert_eq!(back.calibrations().unwrap(), vec![(Wheel::RearLeft, e)]);
        assert!(text.contains("\"trail_shape\""), "{text}");
        let mut bad = f.clone();
        bad.wheels[0].properties.remove("kx");
        assert_eq!(
            bad.calibrations().unwrap_err(),
            "wheel 2: property 'kx' missing"
        );
        let mut bad = f.clone();
        bad.wheels[0].properties.insert(
            "lky".into(),
            Value {
                value: 1.0,
                sigma: 0.1,
            },
        );
        assert!(bad
            .calibrations()
            .unwrap_err()
            .contains("unknown property 'lky'"));
        let mut bad = f.clone();
        bad.wheels.push(bad.wheels[0].clone());
        assert_eq!(bad.calibrations().unwrap_err(), "wheel 2 appears twice");
        let mut bad = f.clone();
        bad.format = "x".into();
        assert!(bad.calibrations().unwrap_err().starts_with("format 'x'"));
        assert!(serde_json::from_str::<CalibrationFile>("{\"format\": 1}").is_err());
    }
}
