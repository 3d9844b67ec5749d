//! Minimal CSV for numeric logs: a header row, comma-separated numbers, `#` comment lines.
//!
//! Errors name the file, the line (1-based, counting the header) and the column, so a user can
//! go straight to the cell. Writing goes to a temporary file that is renamed at the end, so a
//! failed run never leaves a half-written output.

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

/// A numeric table: the header and, per requested column, its values.
#[derive(Debug, Clone)]
pub struct Table {
    /// All column names of the header, in file order.
    pub header: Vec<String>,
    /// Rows of the requested columns, in the order requested.
    pub rows: Vec<Vec<f64>>,
    /// 1-based file line of each row.
    pub lines: Vec<usize>,
    /// For each optional column requested, whether it was present.
    pub present: Vec<bool>,
}

/// Reads `path`, keeping the `required` columns (error if absent) and the `optional` ones
/// (NaN-free: absent optional columns read as `default`). Every kept cell must be a finite
/// number. Returns columns in the order `required` then `optional`.
pub fn read(path: &Path, required: &[&str], optional: &[(&str, f64)]) -> Result<Table, CsvError> {
    read_with(path, required, optional, false)
}

/// [`read`], optionally accepting non-finite cells (`NaN`, `Inf`: reference data that marks undefined values).
pub fn read_with(
    path: &Path,
    required: &[&str],
    optional: &[(&str, f64)],
    allow_nan: bool,
) -> Result<Table, CsvError> {
    let err = |line: usize, column: Option<&str>, msg: String| CsvError {
        file: path.to_path_buf(),
        line,
        column: column.map(str::to_string),
        msg,
    };
    let text =
        std::fs::read_to_string(path).map_err(|e| err(0, None, format!("cannot read: {e}")))?;
    parse_with(&text, required, optional, allow_nan)
        .map_err(|(line, column, msg)| err(line, column.as_deref(), msg))
}

/// [`read`] on text already in memory; errors as (line, column, message).
#[allow(clippy::type_complexity)]
pub fn parse(
    text: &str,
    required: &[&str],
    optional: &[(&str, f64)],
) -> Result<Table, (usize, Option<String>, String)> {
    parse_with(text, required, optional, false)
}

/// [`parse`], optionally accepting `NaN` cells.
#[allow(clippy::type_complexity)]
pub fn parse_with(
    text: &str,
    required: &[&str],
    optional: &[(&str, f64)],
    allow_nan: bool,
) -> Result<Table, (usize, Option<String>, String)> {
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim_end_matches('\r')))
        .filter(|(_, l)| !l.trim().is_empty() && !l.trim_start().starts_with('#'));
    let Some((hline, header)) = lines.next() else {
        return Err((0, None, "empty file: no header row".into()));
    };
    let header: Vec<String> = header.split(',').map(|h| h.trim().to_string()).collect();
    let find = |name: &str| header.iter().position(|h| h == name);
    let mut idx = Vec::new();
    for &r in required {
        match find(r) {
            Some(i) => idx.push(Some(i)),
            None => {
                return Err((
                    hline,
                    Some(r.to_string()),
                    format!("missing required column (header has: {})", header.join(",")),
                ))
            }
        }
    }
    let mut present = Vec::new();
    for &(o, _) in optional {
        let i = find(o);
        present.push(i.is_some());
        idx.push(i);
    }
    let defaults: Vec<f64> = required
        .iter()
        .map(|_| 0.0)
        .chain(optional.iter().map(|&(_, d)| d))
        .collect();
    let names: Vec<&str> = required
        .iter()
        .copied()
        .chain(optional.iter().map(|&(n, _)| n))
        .collect();
    let mut rows = Vec::new();
    let mut row_lines = Vec::new();
    for (ln, line) in lines {
        let cells: Vec<&str> = line.split(',').collect();
        if cells.len() != header.len() {
            return Err((
                ln,
                None,
                format!("{} cells, header has {}", cells.len(), header.len()),
            ));
        }
        let mut row = Vec::with_capacity(idx.len());
        for (k, i) in idx.iter().enumerate() {
            let v = match i {
                Some(i) => {
                    let cell = cells.get(*i).map(|c| c.trim()).unwrap_or("");
                    match cell.parse::<f64>() {
                        Ok(v) if v.is_finite() || allow_nan => v,
                        _ => {
                            return Err((
                                ln,
                                names.get(k).map(|s| s.to_string()),
                                format!("not a finite number: '{cell}'"),
                            ))
                        }
                    }
                }
                None => defaults.get(k).copied().unwrap_or(0.0),
            };
            row.push(v);
        }
        rows.push(row);
        row_lines.push(ln);
    }
    Ok(Table {
        header,
        rows,
        lines: row_lines,
        present,
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

    #[test]
    fn reads_required_and_optional() {
        let t = parse(
            "a,b,c\n1,2,3\r\n# note\n4,5,6\n",
            &["c", "a"],
            &[("z", 7.0), ("b", 0.0)],
        )
        .unwrap();
        assert_eq!(
            t.rows,
            vec![vec![3.0, 1.0, 7.0, 2.0], vec![6.0, 4.0, 7.0, 5.0]]
        );
        assert_eq!(t.lines, vec![2, 4]);
        assert_eq!(t.present, vec![false, true]);
    }

    #[test]
    fn errors_name_line_and_column() {
        let e = parse("a,b\n1,2\n3,x\n", &["b"], &[]).unwrap_err();
        assert_eq!((e.0, e.1.as_deref()), (3, Some("b")));
        let e = parse("a,b\n1,2\n", &["q"], &[]).unwrap_err();
        assert_eq!((e.0, e.1.as_deref()), (1, Some("q")));
        let e = parse("a,b\n1\n", &["a"], &[]).unwrap_err();
        assert_eq!(e.0, 2);
        let e = parse("a\nnan\n", &["a"], &[]).unwrap_err();
        assert_eq!(e.0, 2);
        assert!(parse("", &["a"], &[]).is_err());
    }
}
