//! One loaded FMU: the unzipped import (kept alive for its binary) and its instance, over
//! the `fmi` crate.

use std::fmt;

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::InstanceCS;

use crate::capture;
use crate::error::MasterError;
use crate::system::UnitPlan;

/// An instantiated unit.
pub(crate) struct Unit {
    pub name: String,
    pub instance: InstanceCS,
    _import: Fmi2Import,
}

impl Unit {
    /// Unzips and instantiates the FMU of `plan` under the unit's name.
    pub fn load(plan: &UnitPlan) -> Result<Self, MasterError> {
        capture::install();
        let err = |m: String| MasterError::new(m).unit(&plan.name);
        let path = &plan.path;
        let import: Fmi2Import = fmi::import::from_path(path).map_err(|e| err(format!("cannot load {}: {e}", path.display())))?;
        let before = capture::mark();
        let instance = import.instantiate_cs(&plan.name, false, false).map_err(|e| {
            let mut x = err(format!("fmi2Instantiate of {} failed: {e}", path.display()));
            x.log = capture::since(before, &plan.name);
            x
        })?;
        Ok(Self { name: plan.name.clone(), instance, _import: import })
    }

    /// The error of a failed call `call`, with what the FMU logged since `since`.
    pub fn fail(&self, call: &str, status: impl fmt::Debug, since: usize, time: Option<f64>) -> MasterError {
        let mut e = MasterError::new(format!("{call} returned {status:?}")).unit(&self.name);
        e.time = time;
        e.log = capture::since(since, &self.name);
        e
    }
}
