//! What a run records: chosen variables at every (or every k-th) communication point, and a
//! whole run from a system file with what it recorded kept even when it fails.

use std::ffi::CString;
use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use crate::capture;
use crate::error::MasterError;
use crate::interface::BaseType;
use crate::simulation::RunEnd;
use crate::spec::SystemSpec;
use crate::system::System;
use crate::unit::Unit;

/// The most values recording reserves room for ahead (2²⁴, 128 MiB).
pub const RESERVE_VALUES: usize = 1 << 24;

/// Recorded rows, stored one after the other in one buffer so that recording into reserved
/// room allocates nothing: row k is the `width` values from `k × width`, time first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Rows {
    values: Vec<f64>,
    width: usize,
}

impl Rows {
    fn new(width: usize) -> Self {
        Self { values: Vec::new(), width }
    }

    /// The number of rows.
    pub fn len(&self) -> usize {
        self.values.len().checked_div(self.width).unwrap_or(0)
    }

    /// Whether nothing is recorded.
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Row `k`, if there is one.
    pub fn get(&self, k: usize) -> Option<&[f64]> {
        self.values.get(k * self.width..(k + 1) * self.width)
    }

    /// The last row, if any.
    pub fn last(&self) -> Option<&[f64]> {
        self.len().checked_sub(1).and_then(|k| self.get(k))
    }

    /// The rows in order.
    pub fn iter(&self) -> std::slice::ChunksExact<'_, f64> {
        self.values.chunks_exact(self.width.max(1))
    }

    /// The rows as one vector each.
    pub fn to_vecs(&self) -> Vec<Vec<f64>> {
        self.iter().map(<[f64]>::to_vec).collect()
    }

    /// Makes room for `rows` more rows, up to [`RESERVE_VALUES`] values in all: a longer
    /// recording grows as it goes.
    fn reserve(&mut self, rows: usize) {
        let wanted = rows.saturating_mul(self.width).min(RESERVE_VALUES.saturating_sub(self.values.len()));
        self.values.reserve(wanted);
    }

    fn clear(&mut self) {
        self.values.clear();
    }
}

impl std::ops::Index<usize> for Rows {
    type Output = [f64];
    fn index(&self, k: usize) -> &[f64] {
        self.get(k).unwrap_or_else(|| panic!("row {k} of {}", self.len()))
    }
}

impl<'a> IntoIterator for &'a Rows {
    type Item = &'a [f64];
    type IntoIter = std::slice::ChunksExact<'a, f64>;
    fn into_iter(self) -> Self::IntoIter {
        self.iter()
    }
}

/// The recorded variables and their rows.
pub(crate) struct Recorder {
    names: Vec<String>,
    recorded: Vec<(usize, u32, BaseType)>,
    pub rows: Rows,
    /// Per row, the String columns' values in column order.
    pub texts: Vec<Vec<String>>,
    /// Record every k-th communication point.
    pub every: u64,
}

impl Recorder {
    /// Records `recorded` (unit, value reference, type) under `names`.
    pub fn new(names: Vec<String>, recorded: Vec<(usize, u32, BaseType)>) -> Self {
        let width = recorded.len() + 1;
        Self { names, recorded, rows: Rows::new(width), texts: Vec::new(), every: 1 }
    }

    /// Makes room for `rows` more rows, so that recording them allocates nothing (unless a
    /// String variable is recorded).
    pub fn reserve(&mut self, rows: usize) {
        if !self.recorded.is_empty() {
            self.rows.reserve(rows);
            self.texts.reserve(rows.min(RESERVE_VALUES / self.rows.width));
        }
    }

    /// Takes the rows out as one vector each, leaving none.
    pub fn take(&mut self) -> Vec<Vec<f64>> {
        let rows = self.rows.to_vecs();
        self.rows.clear();
        self.texts.clear();
        rows
    }

    /// "time", then the recorded variables.
    pub fn columns(&self) -> Vec<String> {
        std::iter::once("time".to_owned()).chain(self.names.iter().cloned()).collect()
    }

    /// The base type of each column, "time" (Real) first.
    pub fn column_types(&self) -> Vec<BaseType> {
        std::iter::once(BaseType::Real).chain(self.recorded.iter().map(|r| r.2)).collect()
    }

    /// Appends the row of communication point `time` [s].
    pub fn record(&mut self, units: &mut [Unit], time: f64) -> Result<(), MasterError> {
        if self.recorded.is_empty() {
            return Ok(());
        }
        let start = self.rows.values.len();
        let mut texts = Vec::new();
        self.rows.values.push(time);
        for &(u, vr, base) in &self.recorded {
            let unit = &mut units[u];
            let mark = capture::mark();
            let v = match base.access() {
                BaseType::Real => {
                    let mut x = [0.0];
                    unit.get_real(&[vr], &mut x).map(|_| x[0])
                }
                BaseType::Integer => {
                    let mut x = [0];
                    unit.get_integer(&[vr], &mut x).map(|_| x[0] as f64)
                }
                BaseType::Boolean => {
                    let mut x = [0];
                    unit.get_boolean(&[vr], &mut x).map(|_| f64::from(x[0] != 0))
                }
                _ => {
                    let mut x = [CString::default()];
                    unit.get_string(&[vr], &mut x).map(|()| {
                        let [text] = x;
                        texts.push(text.to_string_lossy().into_owned());
                        f64::NAN
                    })
                }
            };
            match v {
                Ok(v) => self.rows.values.push(v),
                Err(e) => {
                    // A row is whole or absent.
                    self.rows.values.truncate(start);
                    let mut x = unit.fail(e, mark, Some(time));
                    x.message += " (recording)";
                    return Err(x);
                }
            }
        }
        self.texts.push(texts);
        Ok(())
    }
}

/// What [`run`] gives back: the recording, how the run ended and what it had to say.
pub struct RunOutcome {
    /// Column names, "time" first.
    pub columns: Vec<String>,
    /// The base type of each column.
    pub column_types: Vec<BaseType>,
    /// Rows recorded (up to the failure, if there was one); a String column holds NaN.
    pub rows: Vec<Vec<f64>>,
    /// Per row, the String columns' values in column order.
    pub texts: Vec<Vec<String>>,
    /// How the run ended, if it did not fail.
    pub end: Option<RunEnd>,
    /// Why the run failed before `stop`.
    pub error: Option<MasterError>,
    /// Notices of the run (a stop time it could not land on, a discarded step).
    pub notices: Vec<String>,
}

/// Builds and runs a described system; relative paths are taken from `base`. Errors before
/// the first step are returned as `Err`; a failure during the run keeps the rows so far.
/// `interrupt`, when raised, ends the run at the next communication point.
pub fn run(spec: &SystemSpec, base: &Path, interrupt: Option<Arc<AtomicBool>>) -> Result<RunOutcome, MasterError> {
    let s = &spec.simulation;
    let system = System::from_spec(spec, base)?;
    let mut sim = system.initialize(s.start, s.step, s.algorithm, &s.record)?;
    sim.record_every(s.record_every);
    sim.on_discard(s.on_discard);
    sim.schedule(&spec.event)?;
    if let Some(flag) = interrupt {
        sim.interrupt_on(flag);
    }
    let (end, error) = match sim.run_until(s.stop) {
        Ok(end) => (Some(end), None),
        Err(e) => (None, Some(e)),
    };
    let (columns, column_types, notices) = (sim.columns(), sim.column_types(), sim.notices().to_vec());
    let texts = sim.texts().to_vec();
    Ok(RunOutcome { columns, column_types, rows: sim.take_rows(), texts, end, error, notices })
}
