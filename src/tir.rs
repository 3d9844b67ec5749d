//! `.tir` tyre property files (TNO / ADAMS text format) → [`Params`], without allocation.
//!
//! ```text
//! [MODEL]
//! FITTYP          = 61            $Magic Formula version number
//! TYRESIDE        = 'LEFT'
//! [VERTICAL]
//! FNOMIN          = 4000          $Nominal wheel load \[N\]
//! ```
//!
//! [`parse`] reads the whole text once, line by line, into a [`Params<f64>`] (cast it with
//! [`Params::cast`] for an `f32` device), then fills the defaults of absent keys and checks the
//! result with [`validate`]. Problems that make the parameter set unusable are an [`Error`]
//! carrying the 1-based line; everything else is reported as a [`Warning`] in [`Tir`].
//!
//! Syntax accepted:
//! - `$` and `!` start a comment (except inside `'quoted strings'`); blank lines are skipped;
//!   LF, CRLF or CR line ends, spaces and tabs anywhere.
//! - `[SECTION]` headers, case-insensitive; an unknown section is an error.
//! - `KEY = value`; keys are case-insensitive. Numbers are Rust/C floats, with Fortran `D`
//!   exponents (`1.0D-3`) accepted too. Values in `[UNITS]` and `[MDI_HEADER]` are strings.
//! - The tables `[SHAPE]`, `[DEFLECTION_LOAD_CURVE]` and `[BOTTOMING_CURVE]`: rows of bare
//!   numbers and a `{header}` line, skipped.
//!
//! Units must be SI (`[UNITS]` is checked); axes are ISO-W as in every `.tir` file.

use core::fmt;

use crate::math::Float;
use crate::mf::{Key, Need, Params, Side, Version, IGNORED_KEYS};

/// Value stored in an absent range-of-validity key (`FZMIN`, `ALPMAX`, ...): "no limit".
///
/// Minimum keys get `-NO_LIMIT`, maximum keys `+NO_LIMIT`. Finite (and representable as `f32`)
/// so that the parameter set stays finite after [`Params::cast`].
pub const NO_LIMIT: f64 = 1.0e30;

/// Capacity of [`Tir::warnings`]; further warnings are only counted.
pub const MAX_WARNINGS: usize = 32;

/// A successfully read `.tir` file.
#[derive(Debug, Clone, PartialEq)]
pub struct Tir {
    /// The parameter set, SI units, ISO-W axes. Version from `FITTYP`; keys the version does not
    /// read are left at zero (λ scaling factors at one).
    pub params: Params<f64>,
    /// Things worth knowing that did not stop the file from loading, in the order found (reading
    /// first, then the defaults of absent keys).
    pub warnings: heapless::Vec<Warning, MAX_WARNINGS>,
    /// Number of warnings that did not fit in [`Tir::warnings`].
    pub warnings_dropped: u16,
}

/// Why a `.tir` text was rejected, and where.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Error {
    /// 1-based line of the text the error refers to; 0 when it concerns the whole file (a
    /// missing key, say).
    pub line: u32,
    /// What is wrong.
    pub kind: ErrorKind,
}

/// What is wrong with a `.tir` text.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum ErrorKind {
    /// A key the file's version requires is absent.
    MissingKey(Key),
    /// The value of a numeric key is not a finite number.
    BadNumber(Key),
    /// A key is given twice with different values (the line is the second one).
    DuplicateKey(Key),
    /// `FITTYP` names a Magic Formula version this crate does not evaluate.
    UnsupportedFittyp(i64),
    /// `FITTYP` is not an integer.
    BadFittyp,
    /// `FITTYP` is given twice with different values.
    DuplicateFittyp,
    /// `TYRESIDE` is not one of `'LEFT'`, `'RIGHT'`, `'UNKNOWN'`, `'SYMMETRIC'`.
    BadTyreside,
    /// `TYRESIDE` is given twice with different values.
    DuplicateTyreside,
    /// A `[SECTION]` header this reader does not know.
    UnknownSection,
    /// A line that is neither a comment, a `[SECTION]` header, `KEY = value` nor a row of a
    /// table section; or a `'quoted string` without its closing quote.
    Syntax,
    /// A `[UNITS]` entry other than SI (meter, newton, radian, kg, second, pascal).
    UnsupportedUnit,
    /// A value that makes the parameter set unusable; see [`validate`].
    Invalid(Key, Invalid),
}

impl ErrorKind {
    /// The key the error concerns, if it concerns one.
    pub const fn key(&self) -> Option<Key> {
        match self {
            ErrorKind::MissingKey(k)
            | ErrorKind::BadNumber(k)
            | ErrorKind::DuplicateKey(k)
            | ErrorKind::Invalid(k, _) => Some(*k),
            _ => None,
        }
    }
}

/// Why a parameter value is unusable (see [`validate`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum Invalid {
    /// Must be > 0 (a load, radius, speed, pressure or shape factor).
    NotPositive,
    /// Must be ≥ 0.
    Negative,
    /// Must be ≠ 0 (the equations divide by it).
    Zero,
    /// NaN or ±∞.
    NotFinite,
    /// A range of validity whose minimum (this key) exceeds its maximum.
    EmptyRange,
}

/// Something worth knowing about a `.tir` text that loaded anyway.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Warning {
    /// 1-based line the warning refers to; 0 for the whole file (an absent key, say).
    pub line: u32,
    /// What was noticed.
    pub kind: WarningKind,
}

/// What was noticed about a `.tir` text that loaded anyway.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
#[non_exhaustive]
pub enum WarningKind {
    /// A key this reader does not know; its line was ignored.
    UnknownKey,
    /// An extension coefficient is absent: taken as 0, i.e. that effect is not modelled.
    AbsentAssumedZero(Key),
    /// A range-of-validity key is absent: taken as [`NO_LIMIT`] (`-NO_LIMIT` for a minimum).
    AbsentNoLimit(Key),
    /// Some MF 6.x turn-slip coefficients are absent (taken as 0): turn-slip evaluation is
    /// unavailable. Given once.
    NoTurnSlip,
    /// The file has no `FITTYP`: read as an ADAMS PAC2002 file, i.e. MF-Tyre 5.2.
    NoFittypAssumedPac2002,
    /// A key is given again with the same value (the line is the repeated one).
    DuplicateKeySameValue(Key),
    /// `VXLOW` is 0: the low-speed reductions never act.
    ZeroVxlow,
}

/// Section kinds: how the lines of a section are read.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Section {
    /// Before the first header, or any section of `KEY = value` lines.
    Plain,
    /// `[UNITS]`: unit strings, checked.
    Units,
    /// `[MDI_HEADER]`: file metadata, ignored.
    Header,
    /// `[SHAPE]`, `[DEFLECTION_LOAD_CURVE]`, `[BOTTOMING_CURVE]`: rows of numbers, skipped.
    Table,
}

/// Every section this reader knows (upper case) and how it is read.
const SECTIONS: &[(&str, Section)] = &[
    ("MDI_HEADER", Section::Header),
    ("UNITS", Section::Units),
    ("MODEL", Section::Plain),
    ("DIMENSION", Section::Plain),
    ("OPERATING_CONDITIONS", Section::Plain),
    ("INERTIA", Section::Plain),
    ("VERTICAL", Section::Plain),
    ("STRUCTURAL", Section::Plain),
    ("CONTACT_PATCH", Section::Plain),
    ("INFLATION_PRESSURE_RANGE", Section::Plain),
    ("VERTICAL_FORCE_RANGE", Section::Plain),
    ("LONG_SLIP_RANGE", Section::Plain),
    ("SLIP_ANGLE_RANGE", Section::Plain),
    ("INCLINATION_ANGLE_RANGE", Section::Plain),
    ("SCALING_COEFFICIENTS", Section::Plain),
    ("LONGITUDINAL_COEFFICIENTS", Section::Plain),
    ("OVERTURNING_COEFFICIENTS", Section::Plain),
    ("LATERAL_COEFFICIENTS", Section::Plain),
    ("ROLLING_COEFFICIENTS", Section::Plain),
    ("ALIGNING_COEFFICIENTS", Section::Plain),
    ("TURNSLIP_COEFFICIENTS", Section::Plain),
    // Vendor / ADAMS extras seen in real files.
    ("GOODYEAR", Section::Plain),
    ("TIRE_CONDITIONS", Section::Plain),
    // Tables.
    ("SHAPE", Section::Table),
    ("DEFLECTION_LOAD_CURVE", Section::Table),
    ("BOTTOMING_CURVE", Section::Table),
];

/// Accepted spellings (lower case) of the SI unit of each `[UNITS]` entry.
const UNITS: &[(&str, &[&str])] = &[
    ("LENGTH", &["meter", "meters", "metre", "metres", "m"]),
    ("FORCE", &["newton", "newtons", "n"]),
    ("ANGLE", &["radian", "radians", "rad"]),
    ("MASS", &["kg", "kilogram", "kilograms"]),
    ("TIME", &["second", "seconds", "sec", "s"]),
    ("PRESSURE", &["pascal", "pascals", "pa"]),
];

/// Minimum/maximum pairs of the ranges of validity.
const RANGES: &[(Key, Key)] = &[
    (Key::PRESMIN, Key::PRESMAX),
    (Key::FZMIN, Key::FZMAX),
    (Key::KPUMIN, Key::KPUMAX),
    (Key::ALPMIN, Key::ALPMAX),
    (Key::CAMMIN, Key::CAMMAX),
];

const KEY_COUNT: usize = Key::ALL.len();

/// Index of a key in [`Key::ALL`] (declaration order, no explicit discriminants).
fn index(key: Key) -> usize {
    key as usize
}

/// Reads a `.tir` text into a validated parameter set.
///
/// Never panics and never allocates. The first problem found stops the reading: errors while
/// reading come in line order; then `FITTYP`, missing required keys (line 0) and [`validate`]
/// (with the line the offending key was read from).
pub fn parse(text: &str) -> Result<Tir, Error> {
    let mut reader = Reader::new();
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    // LF and CRLF files split on '\n' (the '\r' is trimmed); old CR-only files on '\r'.
    let sep = if text.contains('\n') { '\n' } else { '\r' };
    for (i, line) in text.split(sep).enumerate() {
        let n = u32::try_from(i.saturating_add(1)).unwrap_or(u32::MAX);
        reader
            .line(line, n)
            .map_err(|kind| Error { line: n, kind })?;
    }
    reader.finish()
}

/// Checks a parameter set for values that make the equations meaningless.
///
/// Usable on hand-built parameter sets too. Checks, in [`Key::ALL`] order, the first failure
/// being returned:
/// - every value is finite;
/// - `FNOMIN`, `UNLOADED_RADIUS`, `LONGVL` > 0; `VXLOW` ≥ 0;
/// - the shape factors `PCX1`, `PCY1`, `QCZ1` > 0 (paper, eqs. (24), (35), (51));
/// - `PDX1`, `PDY1`, `PKX1`, `PKY1`, `PKY2` ≠ 0 (the equations divide by them);
/// - for MF 6.x, `NOMPRES` and `INFLPRES` > 0;
/// - then every range of validity has minimum ≤ maximum (reported on the minimum key).
///
/// Keys the version does not read are only checked for finiteness.
pub fn validate<F: Float>(p: &Params<F>) -> Result<(), (Key, Invalid)> {
    for &key in Key::ALL {
        let v = p.get(key);
        if !v.is_finite() {
            return Err((key, Invalid::NotFinite));
        }
        if !key.since().covers(p.version) {
            continue;
        }
        let bad = match rule(key) {
            Rule::Any => None,
            Rule::Positive => (v <= F::ZERO).then_some(Invalid::NotPositive),
            Rule::NonNegative => (v < F::ZERO).then_some(Invalid::Negative),
            Rule::NonZero => (v == F::ZERO).then_some(Invalid::Zero),
        };
        if let Some(why) = bad {
            return Err((key, why));
        }
    }
    for &(min, max) in RANGES {
        if p.get(min) > p.get(max) {
            return Err((min, Invalid::EmptyRange));
        }
    }
    Ok(())
}

#[derive(Clone, Copy)]
enum Rule {
    Any,
    Positive,
    NonNegative,
    NonZero,
}

fn rule(key: Key) -> Rule {
    match key {
        Key::FNOMIN
        | Key::UNLOADED_RADIUS
        | Key::LONGVL
        | Key::PCX1
        | Key::PCY1
        | Key::QCZ1
        | Key::NOMPRES
        | Key::INFLPRES => Rule::Positive,
        Key::VXLOW => Rule::NonNegative,
        Key::PDX1 | Key::PDY1 | Key::PKX1 | Key::PKY1 | Key::PKY2 => Rule::NonZero,
        _ => Rule::Any,
    }
}

/// Why a rule exists, for messages.
fn reason(key: Key) -> &'static str {
    match key {
        Key::PCX1 | Key::PCY1 | Key::QCZ1 => " (shape factor)",
        Key::PDX1 | Key::PDY1 | Key::PKX1 | Key::PKY1 | Key::PKY2 => " (divisor)",
        Key::FNOMIN => " (nominal load)",
        Key::UNLOADED_RADIUS => " (free radius)",
        Key::LONGVL => " (reference speed)",
        Key::NOMPRES | Key::INFLPRES => " (pressure)",
        _ => "",
    }
}

/// PAC2002 pressure keys, read only when the MF 6 key itself is absent.
const ALIASES: &[(&str, Key)] = &[("IP", Key::INFLPRES), ("IP_NOM", Key::NOMPRES)];

/// State of one reading.
struct Reader {
    params: Params<f64>,
    /// Line each key was read from; 0 = absent.
    lines: [u32; KEY_COUNT],
    /// PAC2002 alias values (`IP`, `IP_NOM`) and their lines, in [`ALIASES`] order.
    aliases: [(f64, u32); 2],
    fittyp: Option<i64>,
    tyreside: Option<Option<Side>>,
    section: Section,
    warnings: heapless::Vec<Warning, MAX_WARNINGS>,
    warnings_dropped: u16,
}

impl Reader {
    fn new() -> Self {
        Reader {
            params: Params::zeroed(Version::Mf52),
            lines: [0; KEY_COUNT],
            aliases: [(0.0, 0); 2],
            fittyp: None,
            tyreside: None,
            section: Section::Plain,
            warnings: heapless::Vec::new(),
            warnings_dropped: 0,
        }
    }

    fn warn(&mut self, line: u32, kind: WarningKind) {
        if self.warnings.push(Warning { line, kind }).is_err() {
            self.warnings_dropped = self.warnings_dropped.saturating_add(1);
        }
    }

    /// Reads line number `n` (without its terminator).
    fn line(&mut self, raw: &str, n: u32) -> Result<(), ErrorKind> {
        let line = strip_comment(raw).trim();
        if line.is_empty() {
            return Ok(());
        }
        if let Some(rest) = line.strip_prefix('[') {
            let name = rest.strip_suffix(']').ok_or(ErrorKind::Syntax)?.trim();
            self.section = SECTIONS
                .iter()
                .find(|(s, _)| s.eq_ignore_ascii_case(name))
                .map(|&(_, kind)| kind)
                .ok_or(ErrorKind::UnknownSection)?;
            return Ok(());
        }
        if self.section == Section::Table && is_table_row(line) {
            return Ok(());
        }
        let (key, value) = line.split_once('=').ok_or(ErrorKind::Syntax)?;
        let (key, value) = (key.trim(), value.trim());
        if key.is_empty() || key.contains(|c: char| c.is_whitespace() || c == '\'') {
            return Err(ErrorKind::Syntax);
        }
        // A string must be closed; bare words are allowed (and are what they are).
        let text = unquote(value).ok_or(ErrorKind::Syntax)?;
        match self.section {
            Section::Header => Ok(()),
            Section::Units => self.unit(key, text, n),
            Section::Plain | Section::Table => self.entry(key, value, text, n),
        }
    }

    fn unit(&mut self, key: &str, text: &str, line: u32) -> Result<(), ErrorKind> {
        match UNITS.iter().find(|(k, _)| k.eq_ignore_ascii_case(key)) {
            Some((_, accepted)) if accepted.iter().any(|u| u.eq_ignore_ascii_case(text)) => Ok(()),
            Some(_) => Err(ErrorKind::UnsupportedUnit),
            None => {
                self.warn(line, WarningKind::UnknownKey);
                Ok(())
            }
        }
    }

    /// A `KEY = value` line outside `[UNITS]`/`[MDI_HEADER]`; `text` is `value` unquoted.
    fn entry(&mut self, key: &str, value: &str, text: &str, line: u32) -> Result<(), ErrorKind> {
        if let Some(k) = Key::from_name(key) {
            let v = parse_number(value).ok_or(ErrorKind::BadNumber(k))?;
            let slot = self.lines.get_mut(index(k)).ok_or(ErrorKind::Syntax)?;
            if *slot != 0 {
                if self.params.get(k) != v {
                    return Err(ErrorKind::DuplicateKey(k));
                }
                self.warn(line, WarningKind::DuplicateKeySameValue(k));
                return Ok(());
            }
            *slot = line;
            self.params.set(k, v);
            return Ok(());
        }
        if key.eq_ignore_ascii_case("FITTYP") {
            let f = parse_integer(value).ok_or(ErrorKind::BadFittyp)?;
            match self.fittyp {
                Some(old) if old != f => return Err(ErrorKind::DuplicateFittyp),
                _ => self.fittyp = Some(f),
            }
            return Ok(());
        }
        if key.eq_ignore_ascii_case("TYRESIDE") {
            let side = parse_side(text).ok_or(ErrorKind::BadTyreside)?;
            match self.tyreside {
                Some(old) if old != side => return Err(ErrorKind::DuplicateTyreside),
                _ => self.tyreside = Some(side),
            }
            return Ok(());
        }
        if let Some((slot, &(_, k))) = self
            .aliases
            .iter_mut()
            .zip(ALIASES)
            .find(|(_, (name, _))| name.eq_ignore_ascii_case(key))
        {
            let v = parse_number(value).ok_or(ErrorKind::BadNumber(k))?;
            if slot.1 != 0 {
                if slot.0 != v {
                    return Err(ErrorKind::DuplicateKey(k));
                }
                self.warn(line, WarningKind::DuplicateKeySameValue(k));
            } else {
                *slot = (v, line);
            }
            return Ok(());
        }
        if !IGNORED_KEYS.iter().any(|k| k.eq_ignore_ascii_case(key)) {
            self.warn(line, WarningKind::UnknownKey);
        }
        Ok(())
    }

    fn finish(mut self) -> Result<Tir, Error> {
        let whole = |kind| Error { line: 0, kind };
        let version = match self.fittyp {
            Some(f) => Version::from_fittyp(f).ok_or(whole(ErrorKind::UnsupportedFittyp(f)))?,
            None => {
                self.warn(0, WarningKind::NoFittypAssumedPac2002);
                Version::Mf52
            }
        };
        self.params.version = version;
        self.params.tyreside = self.tyreside.flatten();
        for (&(v, line), &(_, k)) in self.aliases.iter().zip(ALIASES) {
            if let Some(slot) = self.lines.get_mut(index(k)) {
                if line != 0 && *slot == 0 {
                    *slot = line;
                    self.params.set(k, v);
                }
            }
        }
        let mut turn_slip_warned = false;
        for &k in Key::ALL {
            if !k.since().covers(version) {
                // Not read by this version: back to the `Params::zeroed` value.
                self.params
                    .set(k, if k.need() == Need::Scale { 1.0 } else { 0.0 });
                continue;
            }
            if self.lines.get(index(k)).is_some_and(|&l| l != 0) {
                continue;
            }
            // Absent: the value is still the one `Params::zeroed` gave (1 for λ, else 0).
            match k.need() {
                Need::Required => return Err(whole(ErrorKind::MissingKey(k))),
                Need::Scale => {}
                Need::Extension => self.warn(0, WarningKind::AbsentAssumedZero(k)),
                Need::Range => {
                    let is_min = k.name().ends_with("MIN");
                    self.params
                        .set(k, if is_min { -NO_LIMIT } else { NO_LIMIT });
                    self.warn(0, WarningKind::AbsentNoLimit(k));
                }
                Need::TurnSlip => {
                    if !turn_slip_warned {
                        turn_slip_warned = true;
                        self.warn(0, WarningKind::NoTurnSlip);
                    }
                }
            }
        }
        if let Err((k, why)) = validate(&self.params) {
            let line = self.lines.get(index(k)).copied().unwrap_or(0);
            return Err(Error {
                line,
                kind: ErrorKind::Invalid(k, why),
            });
        }
        if self.params.vxlow == 0.0 {
            let line = self.lines.get(index(Key::VXLOW)).copied().unwrap_or(0);
            self.warn(line, WarningKind::ZeroVxlow);
        }
        Ok(Tir {
            params: self.params,
            warnings: self.warnings,
            warnings_dropped: self.warnings_dropped,
        })
    }
}

/// The line up to its first `$` or `!` outside a `'quoted string'`.
fn strip_comment(line: &str) -> &str {
    let mut quoted = false;
    let end = line.find(|c: char| {
        if c == '\'' {
            quoted = !quoted;
        }
        !quoted && (c == '$' || c == '!')
    });
    match end {
        Some(i) => line.get(..i).unwrap_or(line),
        None => line,
    }
}

/// The inside of a `'quoted string'`, or a bare word as is; `None` if the quote is not closed.
fn unquote(value: &str) -> Option<&str> {
    match value.strip_prefix('\'') {
        Some(rest) => rest.strip_suffix('\'').map(str::trim),
        None => Some(value),
    }
}

/// A `{header}` line or a row of bare numbers.
fn is_table_row(line: &str) -> bool {
    line.starts_with('{')
        || line.split_whitespace().all(|t| {
            t.chars()
                .all(|c| c.is_ascii_digit() || matches!(c, '+' | '-' | '.' | 'e' | 'E' | 'd' | 'D'))
        })
}

/// A finite number, Rust/C syntax, Fortran `D`/`d` exponent accepted.
fn parse_number(s: &str) -> Option<f64> {
    let v: f64 = if s.contains(['d', 'D']) {
        let mut buf: heapless::String<64> = heapless::String::new();
        for c in s.chars() {
            buf.push(if matches!(c, 'd' | 'D') { 'e' } else { c })
                .ok()?;
        }
        buf.parse().ok()?
    } else {
        s.parse().ok()?
    };
    v.is_finite().then_some(v)
}

/// An integer, also written as an integral float (`61.0`).
fn parse_integer(s: &str) -> Option<i64> {
    if let Ok(i) = s.parse::<i64>() {
        return Some(i);
    }
    let v = parse_number(s)?;
    // Integral and well inside the i64 range (the cast saturates, the comparison checks).
    let i = v as i64;
    (i as f64 == v && v.abs() < 9.0e15).then_some(i)
}

/// `TYRESIDE`: `Some(None)` for a tyre with no side (unknown or symmetric).
fn parse_side(s: &str) -> Option<Option<Side>> {
    const SIDES: &[(&str, Option<Side>)] = &[
        ("LEFT", Some(Side::Left)),
        ("RIGHT", Some(Side::Right)),
        ("UNKNOWN", None),
        ("SYMMETRIC", None),
    ];
    SIDES
        .iter()
        .find(|(name, _)| name.eq_ignore_ascii_case(s))
        .map(|&(_, side)| side)
}

impl fmt::Display for Invalid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Invalid::NotPositive => "must be > 0",
            Invalid::Negative => "must be >= 0",
            Invalid::Zero => "must not be 0",
            Invalid::NotFinite => "must be finite",
            Invalid::EmptyRange => "greater than the maximum of its range",
        })
    }
}

impl fmt::Display for ErrorKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            ErrorKind::MissingKey(k) => write!(f, "missing required key {}", k.name()),
            ErrorKind::BadNumber(k) => write!(f, "{}: not a finite number", k.name()),
            ErrorKind::DuplicateKey(k) => {
                write!(f, "{}: given again with a different value", k.name())
            }
            ErrorKind::UnsupportedFittyp(n) => {
                write!(f, "unsupported FITTYP = {n} (supported: 5, 6, 21, 61, 62)")
            }
            ErrorKind::BadFittyp => f.write_str("FITTYP: not an integer"),
            ErrorKind::DuplicateFittyp => f.write_str("FITTYP: given again with a different value"),
            ErrorKind::BadTyreside => {
                f.write_str("TYRESIDE: expected 'LEFT', 'RIGHT', 'UNKNOWN' or 'SYMMETRIC'")
            }
            ErrorKind::DuplicateTyreside => {
                f.write_str("TYRESIDE: given again with a different value")
            }
            ErrorKind::UnknownSection => f.write_str("unknown [SECTION]"),
            ErrorKind::Syntax => f.write_str(
                "syntax error: expected a comment, [SECTION], KEY = value or a table row",
            ),
            ErrorKind::UnsupportedUnit => {
                f.write_str("unsupported unit (only SI: meter, newton, radian, kg, second, pascal)")
            }
            ErrorKind::Invalid(k, Invalid::EmptyRange) => {
                let max = RANGES
                    .iter()
                    .find(|r| r.0 == k)
                    .map_or("its maximum", |r| r.1.name());
                write!(f, "{}: greater than {max} (empty range)", k.name())
            }
            ErrorKind::Invalid(k, why) => write!(f, "{}: {why}{}", k.name(), reason(k)),
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line != 0 {
            write!(f, "line {}: ", self.line)?;
        }
        self.kind.fmt(f)
    }
}

impl core::error::Error for Error {}

impl fmt::Display for WarningKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            WarningKind::UnknownKey => f.write_str("unknown key, line ignored"),
            WarningKind::AbsentAssumedZero(k) => {
                write!(f, "{} absent: taken as 0 (effect not modelled)", k.name())
            }
            WarningKind::AbsentNoLimit(k) => write!(f, "{} absent: no limit", k.name()),
            WarningKind::NoTurnSlip => {
                f.write_str("turn-slip coefficients absent: turn-slip evaluation unavailable")
            }
            WarningKind::NoFittypAssumedPac2002 => {
                f.write_str("no FITTYP: read as ADAMS PAC2002 (MF-Tyre 5.2)")
            }
            WarningKind::DuplicateKeySameValue(k) => {
                write!(f, "{}: given again with the same value", k.name())
            }
            WarningKind::ZeroVxlow => f.write_str("VXLOW = 0: no low-speed reduction"),
        }
    }
}

impl fmt::Display for Warning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line != 0 {
            write!(f, "line {}: ", self.line)?;
        }
        self.kind.fmt(f)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;

    use super::*;
    use proptest::prelude::*;
    use std::format;
    use std::string::{String, ToString};
    use std::vec::Vec;

    const MF52: &str = include_str!("../host-tests/data/tyres/MagicFormula52_Parameters.tir");
    const MF61: &str = include_str!("../host-tests/data/tyres/MagicFormula61_Parameters.tir");
    const MF62: &str = include_str!("../host-tests/data/tyres/MagicFormula62_Parameters.tir");
    const MF61_43: &str =
        include_str!("../host-tests/data/tyres/MagicFormula61_Parameters_mfeval43.tir");
    const MF62_43: &str =
        include_str!("../host-tests/data/tyres/MagicFormula62_Parameters_mfeval43.tir");
    const BOOK: &str = include_str!("../host-tests/data/tyres/PacejkaBook_Defaults.tir");
    const TVD3: &str = include_str!("../host-tests/data/tyres/reference_tire_tvd3.tir");
    const FSAE: &str = include_str!("../host-tests/data/tyres/FSAE_Defaults.tir");
    const UNSTABLE: &str = include_str!("../host-tests/data/tyres/Model_Unstable.tir");
    const TRUCK40: &str = include_str!("../host-tests/data/tyres/335_65R22_5_G275MSA_40psi.tir");
    const TRUCK60: &str = include_str!("../host-tests/data/tyres/335_65R22_5_G275MSA_60psi.tir");
    const GENERIC: &str = include_str!("../host-tests/data/tyres/Generic_Pac02Tire.tir");
    const SEDAN: &str = include_str!("../host-tests/data/tyres/Sedan_Pac02Tire.tir");
    const CITYBUS: &str = include_str!("../host-tests/data/tyres/CityBus_Pac02Tire.tir");
    const MF185: &str = include_str!("../host-tests/data/tyres/mf_185_80R14.tir");

    /// Every bundled file that must load, with its expected version.
    const GOOD: &[(&str, &str, Version)] = &[
        ("MagicFormula52_Parameters", MF52, Version::Mf52),
        ("MagicFormula61_Parameters", MF61, Version::Mf61),
        ("MagicFormula62_Parameters", MF62, Version::Mf62),
        ("MagicFormula61_Parameters_mfeval43", MF61_43, Version::Mf61),
        ("MagicFormula62_Parameters_mfeval43", MF62_43, Version::Mf62),
        ("PacejkaBook_Defaults", BOOK, Version::Mf61),
        ("reference_tire_tvd3", TVD3, Version::Mf61),
        ("FSAE_Defaults", FSAE, Version::Mf61),
        ("335_65R22_5_G275MSA_40psi", TRUCK40, Version::Delft96),
        ("335_65R22_5_G275MSA_60psi", TRUCK60, Version::Delft96),
        ("Generic_Pac02Tire", GENERIC, Version::Mf52),
        ("Sedan_Pac02Tire", SEDAN, Version::Mf52),
        ("CityBus_Pac02Tire", CITYBUS, Version::Mf52),
        ("mf_185_80R14", MF185, Version::Mf52),
    ];

    fn ok(text: &str) -> Tir {
        match parse(text) {
            Ok(t) => t,
            Err(e) => panic!("{e}"),
        }
    }

    fn err(text: &str) -> Error {
        match parse(text) {
            Ok(_) => panic!("accepted"),
            Err(e) => e,
        }
    }

    /// 1-based number of the first line starting with `prefix`.
    fn line_of(text: &str, prefix: &str) -> u32 {
        let i = text
            .lines()
            .position(|l| l.starts_with(prefix))
            .unwrap_or_else(|| panic!("no line {prefix}"));
        u32::try_from(i + 1).unwrap()
    }

    /// `text` with the line starting with `prefix` replaced by `new` (kept line ends).
    fn replace_line(text: &str, prefix: &str, new: &str) -> String {
        let mut out = String::new();
        let mut done = false;
        for l in text.split_inclusive('\n') {
            if !done && l.starts_with(prefix) {
                done = true;
                out.push_str(new);
                out.push_str(if l.ends_with("\r\n") { "\r\n" } else { "\n" });
            } else {
                out.push_str(l);
            }
        }
        assert!(done, "no line {prefix}");
        out
    }

    fn kinds(t: &Tir) -> Vec<WarningKind> {
        t.warnings.iter().map(|w| w.kind).collect()
    }

    #[test]
    fn key_index_is_table_order() {
        for (i, &k) in Key::ALL.iter().enumerate() {
            assert_eq!(index(k), i);
        }
    }

    #[test]
    fn every_bundled_file_loads() {
        for &(name, text, version) in GOOD {
            let t = parse(text).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(t.params.version, version, "{name}");
            assert_eq!(validate(&t.params), Ok(()), "{name}");
            assert_eq!(validate(&t.params.cast::<f32>()), Ok(()), "{name}");
            // No file has unknown keys, unknown sections or missing required keys.
            assert!(
                t.warnings.iter().all(|w| w.kind != WarningKind::UnknownKey),
                "{name}: {:?}",
                t.warnings
            );
        }
    }

    #[test]
    fn bundled_file_warnings() {
        // MF 6.1/6.2, MF 5.2 with FITTYP and the MF 5.0 truck files are complete.
        for text in [
            MF52, MF61, MF62, MF61_43, MF62_43, BOOK, TVD3, FSAE, TRUCK40, TRUCK60,
        ] {
            let t = ok(text);
            assert!(t.warnings.is_empty(), "{:?}", t.warnings);
        }
        // PAC2002 files carry no FITTYP.
        for text in [GENERIC, CITYBUS, MF185] {
            assert_eq!(kinds(&ok(text)), [WarningKind::NoFittypAssumedPac2002]);
        }
        // The sedan file has no combined-slip, overturning or rolling coefficients.
        let t = ok(SEDAN);
        assert_eq!(
            t.warnings.first().map(|w| w.kind),
            Some(WarningKind::NoFittypAssumedPac2002)
        );
        assert!(t.warnings.contains(&Warning {
            line: 0,
            kind: WarningKind::AbsentAssumedZero(Key::RBX1)
        }));
        assert_eq!(t.warnings.len(), MAX_WARNINGS);
        assert_eq!(t.warnings_dropped, 2);
        assert_eq!(t.params.rbx1, 0.0);
        assert_eq!(t.params.ssz4, 0.0);
    }

    #[test]
    fn spot_values() {
        let t = ok(MF61);
        let p = &t.params;
        assert_eq!(p.version, Version::Mf61);
        assert_eq!(p.tyreside, Some(Side::Right));
        assert_eq!(p.fnomin, 6752.0);
        assert_eq!(p.unloaded_radius, 0.393581);
        assert_eq!(p.pdx1, 1.173695);
        assert_eq!(p.nompres, 260000.0);
        assert_eq!(p.lmuy, 1.0);
        // MF 5.x-only λ: not read by MF 6.1, stays 1 even though the file gives it.
        assert_eq!(p.lgax, 1.0);

        let p = ok(GENERIC).params;
        assert_eq!(p.version, Version::Mf52);
        assert_eq!(p.tyreside, Some(Side::Left));
        assert_eq!(p.fnomin, 35000.0);
        assert_eq!(p.unloaded_radius, 0.4699);
        assert_eq!(p.lfzo, 0.580904846);
        assert_eq!(p.pex4, 2.6509e-6); // written 2.6509e-006
        assert_eq!(p.ptx1, 1.5); // MF 5.x relaxation, read
                                 // MF 6-only keys are left at zero for a PAC2002 file even when given.
        assert_eq!(p.vertical_stiffness, 0.0);
        assert_eq!(p.ppx1, 0.0);
        assert_eq!(p.inflpres, 0.0);

        let p = ok(TRUCK40).params;
        assert_eq!(p.version, Version::Delft96);
        assert_eq!(p.tyreside, None); // 'UNKNOWN'
        assert_eq!(p.fnomin, 16929.0);
        assert_eq!(p.unloaded_radius, 0.4987);
        assert_eq!(p.pdx1, 9.8412e-1); // written 9.8412e-001
        assert_eq!(p.kpumax, 0.0);

        let p = ok(MF52).params;
        assert_eq!((p.version, p.tyreside), (Version::Mf52, None));
        assert_eq!((p.fnomin, p.unloaded_radius), (9416.6, 0.4));
        let p = ok(BOOK).params;
        assert_eq!((p.fnomin, p.unloaded_radius), (4000.0, 0.3135));
        assert_eq!(p.tyreside, Some(Side::Left)); // written 'Left'
        assert_eq!(ok(FSAE).params.fnomin, 1000.0);
    }

    #[test]
    fn fortran_d_exponent() {
        let text = replace_line(MF61, "PDX1 ", "PDX1 = 1.173695D0 $ Fortran");
        assert_eq!(ok(&text).params.pdx1, 1.173695);
        let text = replace_line(MF61, "PEX4 ", "pex4\t=\t3.820414d-1");
        assert_eq!(ok(&text).params.pex4, 0.3820414);
        let text = replace_line(MF61, "PEX4 ", "PEX4 = 1.0D");
        assert_eq!(
            err(&text),
            Error {
                line: line_of(MF61, "PEX4 "),
                kind: ErrorKind::BadNumber(Key::PEX4)
            }
        );
    }

    #[test]
    fn unstable_model_rejected() {
        let e = err(UNSTABLE);
        assert_eq!(
            e,
            Error {
                line: line_of(UNSTABLE, "PCX1 "),
                kind: ErrorKind::Invalid(Key::PCX1, Invalid::NotPositive)
            }
        );
        assert_eq!(e.to_string(), "line 155: PCX1: must be > 0 (shape factor)");
    }

    #[test]
    fn missing_required_key() {
        let text = replace_line(MF61, "FNOMIN ", "");
        let e = err(&text);
        assert_eq!(
            e,
            Error {
                line: 0,
                kind: ErrorKind::MissingKey(Key::FNOMIN)
            }
        );
        assert_eq!(e.to_string(), "missing required key FNOMIN");
        // A key required only by MF 6 is not needed by an MF 5.2 file.
        assert!(!MF52.contains("PPX1"));
        assert_eq!(ok(MF52).params.version, Version::Mf52);
        let text = replace_line(MF52, "FITTYP ", "FITTYP = 61");
        assert_eq!(err(&text).kind, ErrorKind::MissingKey(Key::INFLPRES));
        assert_eq!(
            err(&replace_line(MF61, "PPX1 ", "")).kind,
            ErrorKind::MissingKey(Key::PPX1)
        );
    }

    #[test]
    fn bad_number() {
        for bad in ["1.2.3", "", "'1.0'", "nan", "inf", "1e999", "12 34", "0x10"] {
            let text = replace_line(MF61, "PKY1 ", &format!("PKY1 = {bad}  $ c"));
            let e = err(&text);
            assert_eq!(
                e,
                Error {
                    line: line_of(MF61, "PKY1 "),
                    kind: ErrorKind::BadNumber(Key::PKY1)
                },
                "{bad}"
            );
        }
        assert_eq!(
            err(&replace_line(MF61, "PKY1 ", "PKY1 = ")).to_string(),
            format!("line {}: PKY1: not a finite number", line_of(MF61, "PKY1 "))
        );
    }

    #[test]
    fn duplicated_keys() {
        let l = line_of(MF61, "PKY1 ");
        let mut text = String::from(MF61);
        text.push_str("PKY1 = 2.0\n");
        let last = u32::try_from(MF61.lines().count() + 1).unwrap();
        assert_eq!(
            err(&text),
            Error {
                line: last,
                kind: ErrorKind::DuplicateKey(Key::PKY1)
            }
        );
        // Same value (written differently): a warning.
        let v = ok(MF61).params.pky1;
        let mut text = String::from(MF61);
        text.push_str(&format!("[LATERAL_COEFFICIENTS]\npky1 = {v:e}\n"));
        let t = ok(&text);
        assert_eq!(
            t.warnings.as_slice(),
            [Warning {
                line: last + 1,
                kind: WarningKind::DuplicateKeySameValue(Key::PKY1)
            }]
        );
        assert_eq!(t.params.pky1, v);
        assert!(l < last);
        // FITTYP and TYRESIDE.
        let text = format!("{MF61}FITTYP = 62\n");
        assert_eq!(
            err(&text),
            Error {
                line: last,
                kind: ErrorKind::DuplicateFittyp
            }
        );
        let text = format!("{MF61}FITTYP = 61\nTYRESIDE = 'right'\n");
        assert!(ok(&text).warnings.is_empty());
        let text = format!("{MF61}TYRESIDE = 'LEFT'\n");
        assert_eq!(
            err(&text),
            Error {
                line: last,
                kind: ErrorKind::DuplicateTyreside
            }
        );
        // MASS is a unit in [UNITS] and a number in [INERTIA]: not a duplicate.
        assert!(MF61.contains("MASS"));
    }

    #[test]
    fn sections() {
        let l = line_of(MF61, "[VERTICAL]");
        let text = replace_line(MF61, "[VERTICAL]", "[VERTIKAL]   $ typo");
        let e = err(&text);
        assert_eq!(
            e,
            Error {
                line: l,
                kind: ErrorKind::UnknownSection
            }
        );
        assert_eq!(e.to_string(), format!("line {l}: unknown [SECTION]"));
        // Case-insensitive, inner blanks and comments allowed.
        let text = replace_line(MF61, "[VERTICAL]", "[ vertical ]\t! comment");
        assert_eq!(ok(&text).params, ok(MF61).params);
        // Unclosed header.
        let text = replace_line(MF61, "[VERTICAL]", "[VERTICAL");
        assert_eq!(
            err(&text),
            Error {
                line: l,
                kind: ErrorKind::Syntax
            }
        );
        // Table rows are fine in tables only.
        let text = replace_line(MF61, "[VERTICAL]", "[VERTICAL]\n1.0 2.0");
        assert_eq!(
            err(&text),
            Error {
                line: l + 1,
                kind: ErrorKind::Syntax
            }
        );
        let text = format!("{MF61}[SHAPE]\n{{radial width}}\n 1.0 0.0\n1.0D0\t-0.5e-1\n");
        assert_eq!(ok(&text).params, ok(MF61).params);
        // A line of text in a table is still a syntax error.
        let text = format!("{MF61}[SHAPE]\n1.0 abc\n");
        assert_eq!(err(&text).kind, ErrorKind::Syntax);
    }

    #[test]
    fn syntax_errors() {
        for bad in [
            "just words",
            "= 5",
            "TWO WORDS = 1",
            "FILE_TYPE = 'tir",
            "'X' = 1",
        ] {
            let text = replace_line(MF61, "PKY1 ", bad);
            assert_eq!(
                err(&text),
                Error {
                    line: line_of(MF61, "PKY1 "),
                    kind: ErrorKind::Syntax
                },
                "{bad}"
            );
        }
    }

    #[test]
    fn line_ends() {
        // LF file → CRLF and CR-only: same parameters, same line numbers.
        assert!(!GENERIC.contains('\r'));
        let crlf = GENERIC.replace('\n', "\r\n");
        let cr = GENERIC.replace('\n', "\r");
        assert_eq!(ok(&crlf), ok(GENERIC));
        assert_eq!(ok(&cr), ok(GENERIC));
        // CRLF file → LF.
        assert!(SEDAN.contains("\r\n"));
        assert_eq!(ok(&SEDAN.replace("\r\n", "\n")), ok(SEDAN));
        // Error lines are right in CRLF files too.
        let l = line_of(SEDAN, "FNOMIN ");
        let text = replace_line(SEDAN, "FNOMIN ", "FNOMIN = x");
        assert!(text.contains("FNOMIN = x\r\n"));
        assert_eq!(
            err(&text),
            Error {
                line: l,
                kind: ErrorKind::BadNumber(Key::FNOMIN)
            }
        );
        // A byte-order mark is skipped.
        assert_eq!(ok(&format!("\u{feff}{MF61}")), ok(MF61));
    }

    #[test]
    fn comments_and_quotes() {
        let base = ok(MF61).params;
        let text = replace_line(MF61, "FNOMIN ", "  FNOMIN\t=\t6752\t!nominal $ load 'x'");
        assert_eq!(ok(&text).params, base);
        let text = replace_line(MF61, "FNOMIN ", "FNOMIN=6752$");
        assert_eq!(ok(&text).params, base);
        let text = replace_line(MF61, "FNOMIN ", "$FNOMIN = 1");
        assert_eq!(err(&text).kind, ErrorKind::MissingKey(Key::FNOMIN));
        // `$` and `!` inside quotes are not comments.
        let text = replace_line(MF61, "FILE_TYPE", "FILE_TYPE = 'ti$r!' $ 'comment'");
        assert_eq!(ok(&text).params, base);
        let text = replace_line(
            MF61,
            "PROPERTY_FILE_FORMAT",
            "PROPERTY_FILE_FORMAT = 'MF$61 ! x' $ quoted $ and ! kept",
        );
        assert_eq!(ok(&text).params, base);
        let text = replace_line(MF61, "TYRESIDE", "TYRESIDE = ' left ' $ 'RIGHT'");
        assert_eq!(ok(&text).params.tyreside, Some(Side::Left));
        let text = replace_line(MF61, "TYRESIDE", "TYRESIDE = Symmetric");
        assert_eq!(ok(&text).params.tyreside, None);
        let text = replace_line(MF61, "TYRESIDE", "TYRESIDE = 'up'");
        assert_eq!(err(&text).kind, ErrorKind::BadTyreside);
    }

    #[test]
    fn units() {
        let l = line_of(MF61, "LENGTH");
        let text = replace_line(MF61, "LENGTH", "LENGTH = 'mm'");
        assert_eq!(
            err(&text),
            Error {
                line: l,
                kind: ErrorKind::UnsupportedUnit
            }
        );
        let text = replace_line(MF61, "ANGLE", "angle = 'DEG'");
        assert_eq!(err(&text).kind, ErrorKind::UnsupportedUnit);
        let text = replace_line(MF61, "ANGLE", "ANGLE = 'RAD' $ ok");
        assert_eq!(ok(&text).params, ok(MF61).params);
        let text = replace_line(MF61, "MASS", "MASS = 'lb'");
        assert_eq!(err(&text).kind, ErrorKind::UnsupportedUnit);
        let text = replace_line(MF61, "MASS", "MASS = 'kg'\nPRESSURE = 'psi'");
        assert_eq!(err(&text).kind, ErrorKind::UnsupportedUnit);
        let text = replace_line(MF61, "MASS", "MASS = 'kg'\nTEMPERATURE = 'celsius'");
        assert_eq!(
            kinds(&ok(&text)),
            [WarningKind::UnknownKey],
            "unknown [UNITS] entry"
        );
        // `MASS` outside [UNITS] is a number (ignored).
        let mass = MF61.lines().filter(|l| l.starts_with("MASS")).count();
        assert_eq!(mass, 2);
    }

    #[test]
    fn fittyp() {
        let l = line_of(MF61, "FITTYP");
        let text = replace_line(MF61, "FITTYP", "FITTYP = 7");
        let e = err(&text);
        assert_eq!(
            e,
            Error {
                line: 0,
                kind: ErrorKind::UnsupportedFittyp(7)
            }
        );
        assert_eq!(
            e.to_string(),
            "unsupported FITTYP = 7 (supported: 5, 6, 21, 61, 62)"
        );
        let text = replace_line(MF61, "FITTYP", "FITTYP = 6.5");
        assert_eq!(
            err(&text),
            Error {
                line: l,
                kind: ErrorKind::BadFittyp
            }
        );
        let text = replace_line(MF61, "FITTYP", "FITTYP = 62.0");
        assert_eq!(ok(&text).params.version, Version::Mf62);
        let text = replace_line(MF52, "FITTYP", "FITTYP = 21");
        assert_eq!(ok(&text).params.version, Version::Mf52);
        let text = replace_line(MF52, "FITTYP", "FITTYP = 5");
        assert_eq!(ok(&text).params.version, Version::Delft96);
        let text = replace_line(MF61, "FITTYP", "FITTYP = 99999999999999999999");
        assert_eq!(err(&text).kind, ErrorKind::BadFittyp);
    }

    #[test]
    fn absent_keys_defaults() {
        // Range → no limit.
        let text = replace_line(MF61, "FZMAX ", "");
        let t = ok(&text);
        assert_eq!(t.params.fzmax, NO_LIMIT);
        assert_eq!(kinds(&t), [WarningKind::AbsentNoLimit(Key::FZMAX)]);
        let text = replace_line(MF61, "CAMMIN ", "");
        assert_eq!(ok(&text).params.cammin, -NO_LIMIT);
        // Extension → 0.
        let text = replace_line(MF61, "RBX1 ", "");
        let t = ok(&text);
        assert_eq!(t.params.rbx1, 0.0);
        assert_eq!(
            t.warnings.as_slice(),
            [Warning {
                line: 0,
                kind: WarningKind::AbsentAssumedZero(Key::RBX1)
            }]
        );
        assert_eq!(
            t.warnings[0].to_string(),
            "RBX1 absent: taken as 0 (effect not modelled)"
        );
        // Scale → 1, silently.
        let text = replace_line(MF61, "LMUY ", "");
        let t = ok(&text);
        assert_eq!((t.params.lmuy, t.warnings.len()), (1.0, 0));
        // Turn slip → 0, one warning for all of them.
        let text: String = MF61
            .split_inclusive('\n')
            .filter(|l| !l.starts_with("PDXP") && !l.starts_with("QCRP"))
            .collect();
        let t = ok(&text);
        assert_eq!(kinds(&t), [WarningKind::NoTurnSlip]);
        assert_eq!((t.params.pdxp1, t.params.qcrp2), (0.0, 0.0));
    }

    #[test]
    fn pac2002_pressure_aliases() {
        let text = replace_line(MF61, "INFLPRES ", "IP = 230000");
        let text = replace_line(&text, "NOMPRES ", "IP_NOM = 240000");
        let p = ok(&text).params;
        assert_eq!((p.inflpres, p.nompres), (230000.0, 240000.0));
        // The MF 6 key wins over the alias.
        let text = replace_line(MF61, "INFLPRES ", "INFLPRES = 250000\nIP = 230000");
        assert_eq!(ok(&text).params.inflpres, 250000.0);
        let text = replace_line(MF61, "INFLPRES ", "IP = 230000\nIP = 1");
        assert_eq!(err(&text).kind, ErrorKind::DuplicateKey(Key::INFLPRES));
        let text = replace_line(MF61, "INFLPRES ", "IP = x");
        assert_eq!(err(&text).kind, ErrorKind::BadNumber(Key::INFLPRES));
    }

    #[test]
    fn invalid_values() {
        let cases: &[(&str, &str, Key, Invalid)] = &[
            ("FNOMIN ", "FNOMIN = 0", Key::FNOMIN, Invalid::NotPositive),
            (
                "UNLOADED_RADIUS ",
                "UNLOADED_RADIUS = -0.3",
                Key::UNLOADED_RADIUS,
                Invalid::NotPositive,
            ),
            ("LONGVL ", "LONGVL = 0", Key::LONGVL, Invalid::NotPositive),
            ("VXLOW ", "VXLOW = -1", Key::VXLOW, Invalid::Negative),
            ("PCY1 ", "PCY1 = -1.3", Key::PCY1, Invalid::NotPositive),
            ("QCZ1 ", "QCZ1 = 0", Key::QCZ1, Invalid::NotPositive),
            ("PDX1 ", "PDX1 = 0", Key::PDX1, Invalid::Zero),
            ("PDY1 ", "PDY1 = 0.0", Key::PDY1, Invalid::Zero),
            ("PKX1 ", "PKX1 = -0", Key::PKX1, Invalid::Zero),
            ("PKY1 ", "PKY1 = 0e5", Key::PKY1, Invalid::Zero),
            ("PKY2 ", "PKY2 = 0", Key::PKY2, Invalid::Zero),
            (
                "NOMPRES ",
                "NOMPRES = 0",
                Key::NOMPRES,
                Invalid::NotPositive,
            ),
            (
                "INFLPRES ",
                "INFLPRES = -1",
                Key::INFLPRES,
                Invalid::NotPositive,
            ),
            ("FZMIN ", "FZMIN = 20000", Key::FZMIN, Invalid::EmptyRange),
            ("ALPMAX ", "ALPMAX = -2", Key::ALPMIN, Invalid::EmptyRange),
        ];
        for &(prefix, new, key, why) in cases {
            let text = replace_line(MF61, prefix, new);
            let line = line_of(MF61, key.name());
            assert_eq!(
                err(&text),
                Error {
                    line,
                    kind: ErrorKind::Invalid(key, why)
                },
                "{new}"
            );
        }
        // VXLOW = 0 is allowed, with a warning.
        let text = replace_line(MF61, "VXLOW ", "VXLOW = 0");
        let t = ok(&text);
        assert_eq!(
            t.warnings.as_slice(),
            [Warning {
                line: line_of(MF61, "VXLOW"),
                kind: WarningKind::ZeroVxlow
            }]
        );
        // Pressures are not read (so not checked) by MF 5.2.
        let text = format!("{MF52}NOMPRES = -1\n");
        assert_eq!(ok(&text).params.nompres, 0.0);
    }

    #[test]
    fn validate_hand_built() {
        let mut p = Params::<f32>::zeroed(Version::Mf61);
        assert_eq!(validate(&p), Err((Key::LONGVL, Invalid::NotPositive)));
        let good = ok(MF61).params.cast::<f32>();
        assert_eq!(validate(&good), Ok(()));
        p.clone_from(&good);
        p.lgax = f32::NAN; // not read by MF 6.1, but still must be finite
        assert_eq!(validate(&p), Err((Key::LGAX, Invalid::NotFinite)));
        p.clone_from(&good);
        p.qbz1 = f32::INFINITY;
        assert_eq!(validate(&p), Err((Key::QBZ1, Invalid::NotFinite)));
        p.clone_from(&good);
        p.presmin = 3.0e5;
        p.presmax = 2.0e5;
        assert_eq!(validate(&p), Err((Key::PRESMIN, Invalid::EmptyRange)));
        // NO_LIMIT survives the cast to f32.
        let t = ok(&replace_line(MF61, "FZMAX ", ""));
        assert!(t.params.cast::<f32>().fzmax.is_finite());
    }

    #[test]
    fn warnings_overflow() {
        let mut text = String::from(MF61);
        for i in 0..40 {
            text.push_str(&format!("UNKNOWN_{i} = {i}\n"));
        }
        let t = ok(&text);
        assert_eq!(t.warnings.len(), MAX_WARNINGS);
        assert_eq!(t.warnings_dropped, 8);
        let first = u32::try_from(MF61.lines().count() + 1).unwrap();
        assert_eq!(
            t.warnings[0],
            Warning {
                line: first,
                kind: WarningKind::UnknownKey
            }
        );
        assert_eq!(
            t.warnings[0].to_string(),
            format!("line {first}: unknown key, line ignored")
        );
    }

    #[test]
    fn display() {
        let e = Error {
            line: 12,
            kind: ErrorKind::BadNumber(Key::FNOMIN),
        };
        assert_eq!(e.to_string(), "line 12: FNOMIN: not a finite number");
        let e = Error {
            line: 0,
            kind: ErrorKind::Invalid(Key::PKY2, Invalid::Zero),
        };
        assert_eq!(e.to_string(), "PKY2: must not be 0 (divisor)");
        let e: &dyn core::error::Error = &e;
        assert!(e.source().is_none());
        let e = Error {
            line: 9,
            kind: ErrorKind::Invalid(Key::FZMIN, Invalid::EmptyRange),
        };
        assert_eq!(
            e.to_string(),
            "line 9: FZMIN: greater than FZMAX (empty range)"
        );
        let w = Warning {
            line: 0,
            kind: WarningKind::NoFittypAssumedPac2002,
        };
        assert_eq!(
            w.to_string(),
            "no FITTYP: read as ADAMS PAC2002 (MF-Tyre 5.2)"
        );
    }

    #[test]
    fn odd_inputs_do_not_panic() {
        let long = "9".repeat(100_000);
        let long_d = format!("FNOMIN = 1{}D1", "0".repeat(1000));
        let inputs: [&str; 14] = [
            "",
            "\n\n\r\n",
            "[",
            "]",
            "=",
            "\0",
            "[UNITS]\nLENGTH = '",
            "'",
            "$'",
            "[SHAPE]\n{",
            "FITTYP = -9223372036854775808",
            "ä = ü\n[ß]",
            &long,
            &long_d,
        ];
        for s in inputs {
            let _ = parse(s);
        }
        assert_eq!(err("").kind, ErrorKind::MissingKey(Key::LONGVL));
        // Too long for the D-exponent buffer: a bad number, not a panic.
        assert_eq!(err(&long_d).kind, ErrorKind::BadNumber(Key::FNOMIN));
    }

    /// One edit of a real file: delete, duplicate or overwrite part of a line.
    #[derive(Debug, Clone)]
    enum Edit {
        Delete(usize),
        Duplicate(usize),
        Replace(usize, String),
        Insert(usize, usize, String),
    }

    fn edit() -> impl Strategy<Value = Edit> {
        prop_oneof![
            any::<usize>().prop_map(Edit::Delete),
            any::<usize>().prop_map(Edit::Duplicate),
            (any::<usize>(), "\\PC{0,20}").prop_map(|(i, s)| Edit::Replace(i, s)),
            (any::<usize>(), any::<usize>(), "[ -~\t\r\n]{0,8}")
                .prop_map(|(i, j, s)| Edit::Insert(i, j, s)),
        ]
    }

    fn apply(text: &str, edits: &[Edit]) -> String {
        let mut lines: Vec<String> = text.split('\n').map(String::from).collect();
        for e in edits {
            let n = lines.len().max(1);
            match e {
                Edit::Delete(i) => {
                    if !lines.is_empty() {
                        lines.remove(i % n);
                    }
                }
                Edit::Duplicate(i) => {
                    if let Some(l) = lines.get(i % n).cloned() {
                        lines.insert(i % n, l);
                    }
                }
                Edit::Replace(i, s) => {
                    if let Some(l) = lines.get_mut(i % n) {
                        *l = s.clone();
                    }
                }
                Edit::Insert(i, j, s) => {
                    if let Some(l) = lines.get_mut(i % n) {
                        let mut at = j % (l.len() + 1);
                        while !l.is_char_boundary(at) {
                            at -= 1;
                        }
                        l.insert_str(at, s);
                    }
                }
            }
        }
        lines.join("\n")
    }

    proptest! {
        #[test]
        fn never_panics_on_any_string(s in "\\PC*") {
            let _ = parse(&s);
        }

        #[test]
        fn never_panics_on_tir_like_text(s in "([\\[\\]=$!'{}\t\r\n .0-9eEdD+-]|FNOMIN|FITTYP|UNITS|SHAPE|PKY1|LENGTH){0,200}") {
            let _ = parse(&s);
        }

        #[test]
        fn never_panics_on_edited_files(
            file in 0..GOOD.len() + 1,
            edits in proptest::collection::vec(edit(), 0..12),
        ) {
            let text = GOOD.get(file).map_or(UNSTABLE, |g| g.1);
            let edited = apply(text, &edits);
            match parse(&edited) {
                Ok(t) => {
                    prop_assert_eq!(validate(&t.params), Ok(()));
                    prop_assert!(Key::ALL.iter().all(|&k| t.params.get(k).is_finite()));
                }
                Err(e) => {
                    // The line of an error is inside the text.
                    let lines = edited.split('\n').count();
                    prop_assert!(usize::try_from(e.line).unwrap() <= lines);
                    let _ = e.to_string();
                }
            }
        }
    }
}
