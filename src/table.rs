//! Numeric CSV tables with a header row: strict reading (every error names the file, line and
//! column) and writing in the shortest round-trip form, atomically to a file (it appears whole
//! or not at all), or streamed to standard output (`-`), a device or a FIFO (see
//! [`crate::output`]).

use std::fmt;
use std::path::{Path, PathBuf};

/// A CSV file's problem, with where it is. Lines and columns count from 1.
#[derive(Debug, thiserror::Error)]
pub struct TableError {
    /// The file.
    pub path: PathBuf,
    /// Line in the file, if the problem has one.
    pub line: Option<u64>,
    /// Column number and name, if the problem has one.
    pub column: Option<(usize, String)>,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for TableError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.path.display())?;
        if let Some(line) = self.line {
            write!(f, ", line {line}")?;
        }
        if let Some((number, name)) = &self.column {
            write!(f, ", column {number} ({name})")?;
        }
        write!(f, ": {}", self.message)
    }
}

/// A table of finite numbers read from CSV, column-major by name.
#[derive(Clone, Debug, PartialEq)]
pub struct NumericTable {
    /// Column names, as in the header without a unit in brackets (`qd_1 [rad/s]` is `qd_1`).
    pub names: Vec<String>,
    /// Each column's unit, when the header gives one in brackets after the name.
    pub units: Vec<Option<String>>,
    /// Each column's number in the file (from 1).
    pub positions: Vec<usize>,
    /// One vector per column, in header order.
    pub columns: Vec<Vec<f64>>,
    /// File line of each row (for later messages about a row).
    pub lines: Vec<u64>,
    /// The file read.
    pub path: PathBuf,
}

impl NumericTable {
    /// Reads `path`, requiring every column in `required` to be present; every cell must be a
    /// finite number. Extra columns are read too.
    pub fn read(path: &Path, required: &[&str]) -> Result<Self, TableError> {
        Self::read_selected(path, required, false)
    }

    /// Reads only the columns `wanted` of `path` (each required); the cells of other columns
    /// are not parsed and may hold anything.
    pub fn read_only(path: &Path, wanted: &[&str]) -> Result<Self, TableError> {
        Self::read_selected(path, wanted, true)
    }

    /// Reads a table from `source` as [`NumericTable::read`] reads a file; `path` names the
    /// source in messages.
    pub fn from_reader(source: Box<dyn std::io::Read>, path: &Path, required: &[&str]) -> Result<Self, TableError> {
        Self::parse(csv_reader_of(source), path, required, false)
    }

    fn read_selected(path: &Path, required: &[&str], only: bool) -> Result<Self, TableError> {
        let reader = csv_reader(path).map_err(|e| TableError {
            path: path.to_path_buf(),
            line: None,
            column: None,
            message: format!("cannot open: {e}"),
        })?;
        Self::parse(reader, path, required, only)
    }

    fn parse(mut reader: csv::Reader<Box<dyn std::io::Read>>, path: &Path, required: &[&str], only: bool) -> Result<Self, TableError> {
        let err = |line: Option<u64>, column: Option<(usize, String)>, message: String| TableError {
            path: path.to_path_buf(),
            line,
            column,
            message,
        };
        let (names, units): (Vec<String>, Vec<Option<String>>) = reader
            .headers()
            .map_err(|e| err(Some(1), None, format!("cannot read the header: {}", csv_cause(&e))))?
            .iter()
            .map(split_unit)
            .unzip();
        if names.iter().all(|n| n.is_empty()) {
            return Err(err(Some(1), None, "the file is empty; a header row is needed".into()));
        }
        for want in required {
            if !names.iter().any(|n| n == want) {
                return Err(err(Some(1), None, format!("missing column '{want}' (the header has: {})", names.join(", "))));
            }
        }
        for (i, name) in names.iter().enumerate() {
            if names[..i].contains(name) {
                return Err(err(Some(1), Some((i + 1, name.clone())), "column name repeated".into()));
            }
        }
        // Which file columns are parsed, in the order kept.
        let keep: Vec<usize> = if only {
            required.iter().map(|w| names.iter().position(|n| n == w).expect("checked above")).collect()
        } else {
            (0..names.len()).collect()
        };
        let mut columns = vec![Vec::new(); keep.len()];
        let mut lines = Vec::new();
        for record in reader.records() {
            let record = record.map_err(|e| {
                let line = e.position().map(|p| p.line());
                err(line, None, csv_cause(&e))
            })?;
            let line = record.position().map_or(0, |p| p.line());
            for (k, &c) in keep.iter().enumerate() {
                let cell = record.get(c).unwrap_or("");
                let at = || Some((c + 1, names[c].clone()));
                let value: f64 = cell.parse().map_err(|_| err(Some(line), at(), format!("'{cell}' is not a number")))?;
                if !value.is_finite() {
                    return Err(err(Some(line), at(), format!("{cell} is not a finite number")));
                }
                columns[k].push(value);
            }
            lines.push(line);
        }
        if lines.is_empty() {
            return Err(err(None, None, "no data rows after the header".into()));
        }
        let (names, units) = keep.iter().map(|&c| (names[c].clone(), units[c].clone())).unzip();
        let positions = keep.iter().map(|c| c + 1).collect();
        Ok(Self { names, units, positions, columns, lines, path: path.to_path_buf() })
    }

    /// The unit the header gives column `name`, if any.
    pub fn unit(&self, name: &str) -> Option<&str> {
        self.names.iter().position(|n| n == name).and_then(|i| self.units[i].as_deref())
    }

    /// The file line of row `row` (0-based).
    pub fn line(&self, row: usize) -> u64 {
        self.lines[row]
    }

    /// The column called `name`, if present.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.names.iter().position(|n| n == name).map(|i| &self.columns[i][..])
    }

    /// Number of data rows.
    pub fn rows(&self) -> usize {
        self.lines.len()
    }

    /// Checks that column `name` strictly increases, naming the first row where it does not.
    pub fn require_increasing(&self, name: &str) -> Result<(), TableError> {
        let index = self.names.iter().position(|n| n == name).expect("column checked on read");
        let col = &self.columns[index];
        for r in 1..col.len() {
            if col[r] <= col[r - 1] {
                return Err(TableError {
                    path: self.path.clone(),
                    line: Some(self.lines[r]),
                    column: Some((self.positions[index], name.to_owned())),
                    message: format!("{name} must increase from row to row, but {} follows {}", col[r], col[r - 1]),
                });
            }
        }
        Ok(())
    }
}

/// A CSV reader of `path`, decompressing a `.gz` file on the fly (logs are large). Lines are
/// limited to [`MAX_LINE_BYTES`], so a file that is no table (`/dev/zero`, a binary) ends in
/// an error at once instead of filling the memory; the rows are read as they come.
pub(crate) fn csv_reader(path: &Path) -> std::io::Result<csv::Reader<Box<dyn std::io::Read>>> {
    let file = std::fs::File::open(path)?;
    let source: Box<dyn std::io::Read> = if path.extension().is_some_and(|e| e == "gz") {
        Box::new(flate2::read::MultiGzDecoder::new(std::io::BufReader::new(file)))
    } else {
        Box::new(file)
    };
    Ok(csv_reader_of(source))
}

/// A CSV reader of `source` (see [`csv_reader`]).
pub fn csv_reader_of(source: Box<dyn std::io::Read>) -> csv::Reader<Box<dyn std::io::Read>> {
    let limited: Box<dyn std::io::Read> = Box::new(LineLimit { inner: source, line: 1, length: 0 });
    csv::ReaderBuilder::new().trim(csv::Trim::All).from_reader(limited)
}

/// Longest line of a CSV file read [bytes]: a row of a thousand numbers is under 30 kB.
pub const MAX_LINE_BYTES: usize = 1 << 20;

/// Passes bytes through, failing once a line grows beyond [`MAX_LINE_BYTES`].
struct LineLimit {
    inner: Box<dyn std::io::Read>,
    /// The line being read (from 1).
    line: u64,
    /// Its bytes so far.
    length: usize,
}

impl std::io::Read for LineLimit {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        for &b in &buf[..n] {
            if b == b'\n' {
                self.line += 1;
                self.length = 0;
            } else {
                self.length += 1;
                if self.length > MAX_LINE_BYTES {
                    return Err(std::io::Error::new(
                        std::io::ErrorKind::InvalidData,
                        format!("line {} is longer than {} MiB: this is not a CSV table", self.line, MAX_LINE_BYTES >> 20),
                    ));
                }
            }
        }
        Ok(n)
    }
}

/// A header cell as (name, unit): `qd_1 [rad/s]` is (`qd_1`, `rad/s`); a cell without brackets
/// has no unit.
pub(crate) fn split_unit(cell: &str) -> (String, Option<String>) {
    match cell.strip_suffix(']').and_then(|c| c.rsplit_once('[')) {
        Some((name, unit)) if !name.trim().is_empty() => (name.trim().to_owned(), Some(unit.trim().to_owned())),
        _ => (cell.to_owned(), None),
    }
}

/// A header cell for column `name` with `unit` (none for a dimensionless count).
pub fn header_cell(name: &str, unit: &str) -> String {
    if unit.is_empty() {
        name.to_owned()
    } else {
        format!("{name} [{unit}]")
    }
}

fn csv_cause(e: &csv::Error) -> String {
    match e.kind() {
        csv::ErrorKind::UnequalLengths { expected_len, len, .. } => {
            format!("{len} fields where the header has {expected_len}")
        }
        csv::ErrorKind::Io(io) => io.to_string(),
        csv::ErrorKind::Utf8 { .. } => "not valid UTF-8 text".into(),
        _ => e.to_string(),
    }
}

/// A builder of temporary files that become the files we write: on Unix read-write for the
/// owner and readable by others (as a plain `create` under the usual umask would give), not a
/// temporary file's 0600; elsewhere the platform's default.
pub(crate) fn readable_temp_file<'a>() -> tempfile::Builder<'a, 'a> {
    #[allow(unused_mut)] // mutated on Unix only
    let mut builder = tempfile::Builder::new();
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o644));
    builder
}

/// Writes `text` to `path` as [`crate::output`] says: a file appears whole or not at all (a
/// temporary file beside it, renamed over it; through a symbolic link, its target is
/// replaced), `-` is standard output, a device or FIFO is written directly.
pub fn write_text_atomic(path: &Path, text: &str) -> std::io::Result<()> {
    crate::output::write_bytes(path, text.as_bytes())
}

/// Writes a numeric table to `path` as [`write_text_atomic`] writes text: a file appears whole
/// or not at all, `-` is standard output, a device or FIFO is streamed. Numbers are written by
/// [`push_number`]: shortest round-trip form, so reading gives the same bits.
pub fn write_atomic(path: &Path, names: &[String], rows: impl Iterator<Item = Vec<f64>>) -> std::io::Result<()> {
    crate::output::write_output(path, |out| {
        writeln!(out, "{}", names.join(","))?;
        let mut line = String::new();
        for row in rows {
            line.clear();
            for (i, &v) in row.iter().enumerate() {
                if i > 0 {
                    line.push(',');
                }
                push_number(&mut line, v);
            }
            line.push('\n');
            out.write_all(line.as_bytes())?;
        }
        Ok(())
    })
}

/// Appends `value` to `text` as a CSV cell in its shortest round-trip form: the fewest
/// significant digits that read back as the same `f64` (bit for bit, -0 included), in plain
/// decimals for magnitudes from 1e-4 to below 1e16 and in exponent form outside (the choice
/// Python's `repr` makes): `0.25`, `3`, `-0`, `2.2e-308`, `1e16`, `5e-324`. Infinities and NaN
/// are `inf`, `-inf` and `NaN`, as Rust and numpy read them.
pub fn push_number(text: &mut String, value: f64) {
    use std::fmt::Write as _;
    let magnitude = value.abs();
    let plain = magnitude == 0.0 || !magnitude.is_finite() || (1e-4..1e16).contains(&magnitude);
    // Writing to a String cannot fail.
    let _ = if plain { write!(text, "{value}") } else { write!(text, "{value:e}") };
}

/// `value` as [`push_number`] writes it.
pub fn number(value: f64) -> String {
    let mut text = String::new();
    push_number(&mut text, value);
    text
}

/// An `io::Error` of writing `path` as a message naming the file, for `map_err`.
pub fn writing(path: &Path) -> impl Fn(std::io::Error) -> String + '_ {
    move |e| format!("writing {}: {e}", path.display())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_written_short() {
        let cases = [
            (2.2e-308, "2.2e-308"),
            (0.25, "0.25"),
            (3.0, "3"),
            (-0.0, "-0"),
            (0.0, "0"),
            (1e16, "1e16"),
            (1e15, "1000000000000000"),
            (1e-4, "0.0001"),
            (9.99e-5, "9.99e-5"),
            (5e-324, "5e-324"),
            (f64::MAX, "1.7976931348623157e308"),
            (f64::MIN_POSITIVE, "2.2250738585072014e-308"),
            (-123456789.125, "-123456789.125"),
            (0.1 + 0.2, "0.30000000000000004"),
            (f64::NAN, "NaN"),
            (f64::NEG_INFINITY, "-inf"),
        ];
        for (value, text) in cases {
            assert_eq!(number(value), text);
        }
    }

    /// Significant digits of a number as written (exponent and sign, point and leading zeros left out).
    fn significant_digits(text: &str) -> usize {
        let mantissa = text.split('e').next().unwrap();
        let digits: String = mantissa.chars().filter(char::is_ascii_digit).collect();
        let trimmed = digits.trim_start_matches('0');
        // An integer's trailing zeros in plain form are not significant.
        let trimmed = if mantissa.contains('.') { trimmed } else { trimmed.trim_end_matches('0') };
        trimmed.len().max(1)
    }

    #[test]
    fn every_value_reads_back_bit_identical_from_the_fewest_digits() {
        let mut values = vec![
            0.0,
            -0.0,
            5e-324,
            -5e-324,
            2.2e-308,
            f64::MIN_POSITIVE,
            f64::MIN_POSITIVE - 5e-324,
            1e308,
            -1e308,
            f64::MAX,
            f64::MIN,
            1.0,
            -7.0,
            9007199254740993.0,
            1e-4,
            9.999999999999999e-5,
            1e16,
            9999999999999998.0,
            0.1,
        ];
        // And many bit patterns, each a finite double (xorshift: no dependency, same every run).
        let mut x = 0x9E37_79B9_7F4A_7C15u64;
        while values.len() < 20_000 {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let v = f64::from_bits(x);
            if v.is_finite() {
                values.push(v);
            }
        }
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("extremes.csv");
        write_atomic(&path, &["v".into(), "twice".into()], values.iter().map(|&v| vec![v, v / 2.0])).unwrap();
        let table = NumericTable::read(&path, &["v", "twice"]).unwrap();
        for (k, &v) in values.iter().enumerate() {
            assert_eq!(table.columns[0][k].to_bits(), v.to_bits(), "{v:e}");
            assert_eq!(table.columns[1][k].to_bits(), (v / 2.0).to_bits(), "{:e}", v / 2.0);
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let longest = text.lines().flat_map(|l| l.split(',')).map(str::len).max().unwrap();
        assert!(longest <= 24, "a cell of {longest} characters");
        // Shortest: one significant digit fewer (rounded either way) does not give the value back.
        for &v in values.iter().filter(|v| **v != 0.0) {
            let digits = significant_digits(&number(v));
            if digits > 1 {
                let fewer: f64 = format!("{v:.*e}", digits - 2).parse().unwrap();
                assert_ne!(fewer.to_bits(), v.to_bits(), "{v:e} needs fewer than {digits} digits");
            }
        }
    }
}
