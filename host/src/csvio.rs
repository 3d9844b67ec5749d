//! The one reader of CSV logs: a header row, comma-separated cells, `#` comment lines, each row
//! deserialised (the `csv` crate) into a serde-derived row type whose field names are the
//! column names. Optional columns are `Option` fields with `#[serde(default)]`.
//!
//! Errors name the file, the line (1-based, counting the header) and the column, so a user can
//! go straight to the cell; every numeric cell must be finite unless asked otherwise. Writing
//! goes to a temporary file that is renamed at the end, so a failed run never leaves a
//! half-written output.

use csv::StringRecord;
use serde::de::DeserializeOwned;
use std::fmt;
use std::path::{Path, PathBuf};
/// A CSV error with its location.
#[derive(Debug, Clone, PartialEq)]
pub struct CsvError {
    /// File the error is in.
    pub file: PathBuf,
    /// 1-based line (0: the file as a whole).
    pub line: usize,
    /// Column name, when the error is in a cell or a missing column.
    pub column: Option<String>,
    /// What is wrong.
    pub msg: String,
}

impl fmt::Display for CsvError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if self.line > 0 {
            write!(f, ": line {}", self.line)?;
        }
        if let Some(c) = &self.column {
            write!(f, ", column {c}")?;
        }
        write!(f, ": {}", self.msg)
    }
}

impl std::error::Error for CsvError {}

/// The rows of a file, deserialised.
#[derive(Debug, Clone)]
pub struct Rows<R> {
    /// All column names of the header, in file order.
    pub header: Vec<String>,
    /// The rows.
    pub rows: Vec<R>,
    /// 1-based file line of each row.
    pub lines: Vec<usize>,
}

impl<R> Rows<R> {
    /// Whether the header has column `name`.
    pub fn has(&self, name: &str) -> bool {
        self.header.iter().any(|h| h == name)
    }
}

/// One row of a wheel's measurement log (`gough replay`, `gough mu estimate`): `t,fz,fy,mz`
/// required; `fx,vx,alpha,kappa,gamma,wheel,omega` optional (SI, rad, ISO-W; `t` in s, `wheel`
/// 0..3 = FL, FR, RL, RR, `omega` the wheel speed in rad/s).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
pub struct WheelRow {
    /// Time \[s\].
    pub t: f64,
    /// Vertical load Fz \[N\].
    pub fz: f64,
    /// Lateral force Fy \[N\].
    pub fy: f64,
    /// Aligning torque Mz \[N·m\].
    pub mz: f64,
    /// Longitudinal force Fx \[N\].
    #[serde(default)]
    pub fx: Option<f64>,
    /// Forward speed Vx \[m/s\].
    #[serde(default)]
    pub vx: Option<f64>,
    /// Slip angle α \[rad\].
    #[serde(default)]
    pub alpha: Option<f64>,
    /// Longitudinal slip κ.
    #[serde(default)]
    pub kappa: Option<f64>,
    /// Inclination γ \[rad\].
    #[serde(default)]
    pub gamma: Option<f64>,
    /// Wheel index 0..3.
    #[serde(default)]
    pub wheel: Option<f64>,
    /// Wheel speed ω \[rad/s\].
    #[serde(default)]
    pub omega: Option<f64>,
}

/// Reads `path` into rows of `R`; every numeric cell must be a finite number.
pub fn read<R: DeserializeOwned>(path: &Path) -> Result<Rows<R>, CsvError> {
    read_with(path, false)
}

/// [`read`], optionally accepting non-finite cells (`NaN`, `Inf`: reference data that marks
/// undefined values).
pub fn read_with<R: DeserializeOwned>(path: &Path, allow_nan: bool) -> Result<Rows<R>, CsvError> {
    let text = std::fs::read_to_string(path).map_err(|e| CsvError {
        file: path.to_path_buf(),
        line: 0,
        column: None,
        msg: format!("cannot read: {e}"),
    })?;
    parse_with(&text, path, allow_nan)
}

/// [`read`] on text already in memory; `file` names it in errors.
pub fn parse<R: DeserializeOwned>(text: &str, file: &Path) -> Result<Rows<R>, CsvError> {
    parse_with(text, file, false)
}

/// The 1-based lines of `text` that hold records (the header first): not blank, not a `#`
/// comment. A numeric log has no quoted line breaks, so record k is on the k-th of them.
fn record_lines(text: &str) -> Vec<usize> {
    text.lines()
        .enumerate()
        .filter(|(_, l)| {
            let l = l.trim();
            !l.is_empty() && !l.starts_with('#')
        })
        .map(|(i, _)| i + 1)
        .collect()
}

/// [`parse`], optionally accepting non-finite cells.
pub fn parse_with<R: DeserializeOwned>(
    text: &str,
    file: &Path,
    allow_nan: bool,
) -> Result<Rows<R>, CsvError> {
    let err = |line: usize, column: Option<&str>, msg: String| CsvError {
        file: file.to_path_buf(),
        line,
        column: column.map(str::to_string),
        msg,
    };
    let mut rdr = csv::ReaderBuilder::new()
        .comment(Some(b'#'))
        .trim(csv::Trim::All)
        .from_reader(text.as_bytes());
    let headers = rdr
        .headers()
        .map_err(|e| err(0, None, e.to_string()))?
        .clone();
    if headers.iter().all(str::is_empty) {
        return Err(err(0, None, "empty file: no header row".into()));
    }
    let header: Vec<String> = headers.iter().map(str::to_string).collect();
    let at = record_lines(text);
    // The columns `R` reads (a struct's fields; every column for a map).
    let fields = serde_aux::serde_introspection::serde_introspect::<R>();
    let read: Vec<bool> = header
        .iter()
        .map(|h| fields.is_empty() || fields.contains(&h.as_str()))
        .collect();
    let line_of = |k: usize| at.get(k).copied().unwrap_or(0);
    // A required column is missing: found on the header line even when no row follows.
    let probe = StringRecord::from(vec!["0"; headers.len()]);
    if let Err(e) = probe.deserialize::<R>(Some(&headers)) {
        let msg = e.to_string();
        if let Some(name) = msg
            .split_once("missing field `")
            .and_then(|(_, rest)| rest.split_once('`'))
            .map(|(name, _)| name)
        {
            return Err(err(
                line_of(0),
                Some(name),
                format!("missing required column (header has: {})", header.join(",")),
            ));
        }
    }
    let mut rows = Vec::new();
    let mut lines = Vec::new();
    for (k, rec) in rdr.records().enumerate() {
        let line = line_of(k + 1);
        let rec = rec.map_err(|e| match e.kind() {
            csv::ErrorKind::UnequalLengths {
                expected_len, len, ..
            } => err(
                line,
                None,
                format!("{len} cells, header has {expected_len}"),
            ),
            _ => err(line, None, e.to_string()),
        })?;
        let not_a_number = |k: usize| {
            let cell = rec.get(k).unwrap_or("");
            err(
                line,
                headers.get(k),
                format!("not a finite number: '{cell}'"),
            )
        };
        if !allow_nan {
            if let Some(k) = rec
                .iter()
                .zip(&read)
                .position(|(c, &r)| r && c.parse::<f64>().is_ok_and(|v| !v.is_finite()))
            {
                return Err(not_a_number(k));
            }
        }
        let row = rec
            .deserialize::<R>(Some(&headers))
            .map_err(|e| match e.kind() {
                csv::ErrorKind::Deserialize { err: de, .. } => match de.field() {
                    Some(k) => not_a_number(k as usize),
                    None => err(line, None, de.to_string()),
                },
                _ => err(line, None, e.to_string()),
            })?;
        rows.push(row);
        lines.push(line);
    }
    Ok(Rows {
        header,
        rows,
        lines,
    })
}

/// Writes a CSV atomically: to `path.tmp`, then renamed to `path`.
pub fn write(path: &Path, header: &[&str], rows: &[Vec<f64>]) -> std::io::Result<()> {
    use std::io::Write;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let tmp = path.with_extension("csv.tmp");
    {
        let f = std::fs::File::create(&tmp)?;
        let mut w = std::io::BufWriter::new(f);
        writeln!(w, "{}", header.join(","))?;
        for r in rows {
            let mut first = true;
            for v in r {
                if !first {
                    w.write_all(b",")?;
                }
                first = false;
                write!(w, "{v:.12e}")?;
            }
            w.write_all(b"\n")?;
        }
        w.flush()?;
    }
    std::fs::rename(&tmp, path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Debug, Deserialize, PartialEq)]
    struct Row {
        a: f64,
        c: f64,
        #[serde(default)]
        b: Option<f64>,
        #[serde(default)]
        z: Option<f64>,
    }

    fn p(text: &str) -> Result<Rows<Row>, CsvError> {
        parse(text, Path::new("f.csv"))
    }

    #[test]
    fn reads_required_and_optional() {
        let t = p("a,b,c\n1,2,3\r\n# note\n4,5,6\n").unwrap();
        assert_eq!(
            t.rows,
            vec![
                Row {
                    a: 1.0,
                    c: 3.0,
                    b: Some(2.0),
                    z: None
                },
                Row {
                    a: 4.0,
                    c: 6.0,
                    b: Some(5.0),
                    z: None
                }
            ]
        );
        assert_eq!(t.lines, vec![2, 4]);
        assert!(t.has("b") && !t.has("z"));
    }

    #[test]
    fn errors_name_line_and_column() {
        let e = p("a,b,c\n1,2,3\n3,x,4\n").unwrap_err();
        assert_eq!((e.line, e.column.as_deref()), (3, Some("b")));
        assert!(e.to_string().contains("'x'"), "{e}");
        let e = p("a,b\n1,2\n").unwrap_err();
        assert_eq!((e.line, e.column.as_deref()), (1, Some("c")));
        let e = p("a,b,c\n1\n").unwrap_err();
        assert_eq!(e.line, 2);
        assert!(
            p("a,c,other\n1,2,nan\n").is_ok(),
            "a column it does not read"
        );
        let e = p("a,c\nnan,1\n").unwrap_err();
        assert_eq!((e.line, e.column.as_deref()), (2, Some("a")));
        assert!(parse_with::<Row>("a,c\nnan,1\n", Path::new("f"), true).is_ok());
        assert!(p("").is_err());
    }
}
