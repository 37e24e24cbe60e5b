//! Numeric CSV tables with a header row: strict reading (every error names the file, line and
//! column) and atomic writing (a file appears whole or not at all).

use std::fmt;
use std::io::Write;
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

/// Permissions of the files we write: read-write for the owner, readable by others (as a
/// plain `create` under the usual umask would give), not the temporary file's 0600.
pub(crate) fn readable_file() -> std::fs::Permissions {
    use std::os::unix::fs::PermissionsExt;
    std::fs::Permissions::from_mode(0o644)
}

/// Writes `text` to `path` atomically: a temporary file beside it is renamed over `path` once
/// complete, so a failure leaves no partial file.
pub fn write_text_atomic(path: &Path, text: &str) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::Builder::new().permissions(readable_file()).prefix(".neurarm-").suffix(".tmp").tempfile_in(dir)?;
    tmp.write_all(text.as_bytes())?;
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// Writes a numeric table to `path` atomically: the rows go to a temporary file beside it,
/// which is renamed over `path` only once complete, so a failure leaves no partial file.
/// Numbers are written in Rust's shortest round-trip form, so reading gives the same bits.
pub fn write_atomic(path: &Path, names: &[String], rows: impl Iterator<Item = Vec<f64>>) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut tmp = tempfile::Builder::new().permissions(readable_file()).prefix(".neurarm-").suffix(".tmp").tempfile_in(dir)?;
    {
        let mut out = std::io::BufWriter::new(tmp.as_file_mut());
        writeln!(out, "{}", names.join(","))?;
        let mut line = String::new();
        for row in rows {
            line.clear();
            for (i, v) in row.iter().enumerate() {
                if i > 0 {
                    line.push(',');
                }
                line.push_str(&v.to_string());
            }
            writeln!(out, "{line}")?;
        }
        out.flush()?;
    }
    tmp.as_file().sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

/// An `io::Error` of writing `path` as a message naming the file, for `map_err`.
pub fn writing(path: &Path) -> impl Fn(std::io::Error) -> String + '_ {
    move |e| format!("writing {}: {e}", path.display())
}
