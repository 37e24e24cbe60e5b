//! What a run records: chosen variables at every (or every k-th) communication point, and a
//! whole run from a system file with what it recorded kept even when it fails.

use std::path::Path;

use fmi::fmi2::instance::Common;

use crate::capture;
use crate::error::MasterError;
use crate::interface::BaseType;
use crate::spec::SystemSpec;
use crate::system::System;
use crate::unit::Unit;

/// The recorded variables and their rows.
pub(crate) struct Recorder {
    names: Vec<String>,
    recorded: Vec<(usize, u32, BaseType)>,
    pub rows: Vec<Vec<f64>>,
    /// Record every k-th communication point.
    pub every: u64,
}

impl Recorder {
    /// Records `recorded` (unit, value reference, type) under `names`.
    pub fn new(names: Vec<String>, recorded: Vec<(usize, u32, BaseType)>) -> Self {
        Self { names, recorded, rows: Vec::new(), every: 1 }
    }

    /// "time", then the recorded variables.
    pub fn columns(&self) -> Vec<String> {
        std::iter::once("time".to_owned()).chain(self.names.iter().cloned()).collect()
    }

    /// Appends the row of communication point `time` [s].
    pub fn record(&mut self, units: &mut [Unit], time: f64) -> Result<(), MasterError> {
        if self.recorded.is_empty() {
            return Ok(());
        }
        let mut row = Vec::with_capacity(self.recorded.len() + 1);
        row.push(time);
        for &(u, vr, base) in &self.recorded {
            let unit = &mut units[u];
            let mark = capture::mark();
            let v = match base {
                BaseType::Real => {
                    let mut x = [0.0];
                    unit.instance.get_real(&[vr], &mut x).map(|_| x[0])
                }
                BaseType::Integer => {
                    let mut x = [0];
                    unit.instance.get_integer(&[vr], &mut x).map(|_| x[0] as f64)
                }
                _ => {
                    let mut x = [0];
                    unit.instance.get_boolean(&[vr], &mut x).map(|_| x[0] as f64)
                }
            };
            row.push(v.map_err(|e| unit.fail("fmi2Get (recording)", e, mark, Some(time)))?);
        }
        self.rows.push(row);
        Ok(())
    }
}

/// What [`run`] gives back: the recording, and the error that stopped it early, if any.
pub struct RunOutcome {
    /// Column names, "time" first.
    pub columns: Vec<String>,
    /// Rows recorded (up to the failure, if there was one).
    pub rows: Vec<Vec<f64>>,
    /// Why the run stopped before `stop`.
    pub error: Option<MasterError>,
}

/// Builds and runs a described system; relative paths are taken from `base`. Errors before
/// the first step are returned as `Err`; a failure during the run keeps the rows so far.
pub fn run(spec: &SystemSpec, base: &Path) -> Result<RunOutcome, MasterError> {
    let s = &spec.simulation;
    let system = System::from_spec(spec, base)?;
    let mut sim = system.initialize(s.start, s.step, s.algorithm, &s.record)?;
    sim.record_every(s.record_every);
    let error = sim.run_until(s.stop).err();
    Ok(RunOutcome { columns: sim.columns(), rows: sim.take_rows(), error })
}
