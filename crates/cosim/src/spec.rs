//! The system file (TOML): FMUs, connections and how to simulate them, and the values a
//! system sets.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::error::{SpecError, SystemFileError};

/// How units are stepped within one communication step.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Algorithm {
    /// One after another, each passing its new outputs on before the next steps.
    #[default]
    GaussSeidel,
    /// All from the same inputs, then all outputs passed on.
    Jacobi,
}

impl Algorithm {
    /// The name the system file uses.
    pub fn name(self) -> &'static str {
        match self {
            Algorithm::GaussSeidel => "gauss-seidel",
            Algorithm::Jacobi => "jacobi",
        }
    }
}

/// What a unit that discards a step (`fmi2Discard`, `fmi3Discard`) does to a run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum OnDiscard {
    /// End the run at the last communication point every unit completed, keeping the rows,
    /// with a notice: what fmpy, fmusim and fmi-sim do.
    #[default]
    Stop,
    /// Fail the run (the rows so far are still kept).
    Error,
}

impl OnDiscard {
    fn is_default(&self) -> bool {
        *self == OnDiscard::Stop
    }
}

/// A value to set: the base type follows the variable, with integers accepted for reals and
/// an enumeration taking an item's value (an integer) or name (a string).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum Value {
    /// A Boolean.
    Boolean(bool),
    /// An integer (also accepted by Real variables).
    Integer(i64),
    /// A real.
    Real(f64),
    /// A string.
    String(String),
}

/// A system: FMUs, connections, and how to simulate it, as a system file (TOML) holds it:
/// `[[fmu]]` (name, path relative to the file, parameters), `[[connection]]` (from → to, a `*`
/// matching the same text on both sides), `[simulation]` and `[[event]]`. The format with an
/// example: README.md, "Co-simulation of FMUs".
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SystemSpec {
    /// The units, in declaration order.
    pub fmu: Vec<FmuEntry>,
    /// Output → input connections.
    #[serde(default)]
    pub connection: Vec<ConnectionSpec>,
    /// Time span, step, algorithm, recording.
    pub simulation: SimulationSpec,
    /// Changes while running: tunable parameters or unconnected inputs set at given times,
    /// or ramped over an interval.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub event: Vec<EventSpec>,
}

/// A change of variables while the system runs (`[[event]]` in a system file). A step change
/// (no `until`) sets each variable at the first communication point at or after `time`; a ramp
/// (with `until`) sets each Real variable at every communication point t up to `until` to the
/// line from its value at `time` to the value given. Only tunable parameters and inputs no
/// connection drives can change (checked before the run); events apply in time order, and in
/// file order at equal times.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EventSpec {
    /// When the change happens, or the ramp starts [s].
    pub time: f64,
    /// When the ramp ends [s]; absent for a step change.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub until: Option<f64>,
    /// "unit.variable" → the value set (the ramp's end value).
    pub set: BTreeMap<String, Value>,
}

impl EventSpec {
    /// Checks the times: finite, and for a ramp `until` after `time`.
    pub fn check(&self) -> Result<(), SpecError> {
        if !self.time.is_finite() {
            return Err(SpecError::EventTime { time: self.time });
        }
        match self.until {
            Some(until) if !(until.is_finite() && until > self.time) => Err(SpecError::RampEnd { time: self.time, until }),
            _ if self.set.is_empty() => Err(SpecError::EmptyEvent { time: self.time }),
            _ => Ok(()),
        }
    }
}

/// One FMU of a system.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FmuEntry {
    /// Unit name (instance name), used in connections as `name.variable`.
    pub name: String,
    /// Path of the `.fmu`, relative to the system file.
    pub path: String,
    /// Parameters (and unconnected inputs) to set before initialisation.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub parameters: BTreeMap<String, Value>,
}

/// A connection from an output to an input.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConnectionSpec {
    /// "unit.output".
    pub from: String,
    /// "unit.input".
    pub to: String,
}

/// How to simulate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationSpec {
    /// Start time [s].
    #[serde(default)]
    pub start: f64,
    /// Stop time [s].
    pub stop: f64,
    /// Communication step [s].
    pub step: f64,
    /// Stepping algorithm.
    #[serde(default)]
    pub algorithm: Algorithm,
    /// Variables to record ("unit.variable").
    #[serde(default)]
    pub record: Vec<String>,
    /// Record every k-th communication point.
    #[serde(default = "one")]
    pub record_every: u64,
    /// What a unit discarding a step does: `"stop"` (default) or `"error"`.
    #[serde(default, skip_serializing_if = "OnDiscard::is_default")]
    pub on_discard: OnDiscard,
}

fn one() -> u64 {
    1
}

impl SimulationSpec {
    /// Checks the time span and step: finite, a positive step, stop ≥ start.
    pub fn check(&self) -> Result<(), SpecError> {
        let valid = self.step > 0.0 && self.step.is_finite() && self.start.is_finite() && self.stop.is_finite() && self.stop >= self.start;
        if valid {
            Ok(())
        } else {
            Err(SpecError::Span { start: self.start, stop: self.stop, step: self.step })
        }
    }
}

impl SystemSpec {
    /// Parses a system file's text; `origin` names it in messages.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self, SystemFileError> {
        let origin = || origin.to_owned();
        let spec: Self = toml::from_str(text).map_err(|error| SystemFileError::Syntax { origin: origin(), error })?;
        spec.simulation.check().map_err(|error| SystemFileError::Simulation { origin: origin(), error })?;
        for (k, event) in spec.event.iter().enumerate() {
            event.check().map_err(|error| SystemFileError::Event { origin: origin(), number: k + 1, error })?;
        }
        Ok(spec)
    }

    /// The system file's text; [`SystemSpec::from_toml`] reads it back unchanged (reals
    /// are written in their shortest exact form).
    pub fn to_toml(&self) -> Result<String, SystemFileError> {
        toml::to_string(self).map_err(SystemFileError::Write)
    }
}
