//! What went wrong, where and when.

use std::fmt;

/// An error of the master. `unit` names the FMU (as named in the system), `variable` the
/// variable if one is concerned, `time` the communication point [s] if the simulation had
/// started; `log` holds the FMU's own messages logged during the failing call.
#[derive(Clone, Debug, PartialEq)]
pub struct MasterError {
    /// The unit concerned.
    pub unit: Option<String>,
    /// The variable concerned.
    pub variable: Option<String>,
    /// Communication point [s].
    pub time: Option<f64>,
    /// What happened.
    pub message: String,
    /// Messages the FMU logged in the failing call.
    pub log: Vec<String>,
    /// Set when the unit discarded a step (`fmi2Discard`) rather than failed.
    pub discard: Option<Box<DiscardedStep>>,
}

/// What a unit said when it discarded a step (`fmi2DoStep` returned `fmi2Discard`).
#[derive(Clone, Debug, PartialEq)]
pub struct DiscardedStep {
    /// `fmi2LastSuccessfulTime` [s], if the unit could say.
    pub last_successful_time: Option<f64>,
    /// `fmi2Terminated`: the unit asks to end the simulation, if it could say.
    pub terminated: Option<bool>,
}

impl MasterError {
    /// An error with only a message.
    pub fn new(message: impl Into<String>) -> Self {
        Self { unit: None, variable: None, time: None, message: message.into(), log: Vec::new(), discard: None }
    }

    /// The same error, concerning unit `unit`.
    pub fn unit(mut self, unit: &str) -> Self {
        self.unit = Some(unit.to_owned());
        self
    }

    /// The same error, concerning variable `variable`.
    pub fn variable(mut self, variable: &str) -> Self {
        self.variable = Some(variable.to_owned());
        self
    }

    /// The same error, at communication point `time` [s].
    pub fn at(mut self, time: f64) -> Self {
        self.time = Some(time);
        self
    }
}

impl fmt::Display for MasterError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.unit, &self.variable) {
            (Some(u), Some(v)) => write!(f, "FMU '{u}', variable '{v}'")?,
            (Some(u), None) => write!(f, "FMU '{u}'")?,
            (None, Some(v)) => write!(f, "variable '{v}'")?,
            (None, None) => write!(f, "system")?,
        }
        if let Some(t) = self.time {
            write!(f, " at t = {t} s")?;
        }
        write!(f, ": {}", self.message)?;
        for line in &self.log {
            write!(f, "\n  FMU log: {line}")?;
        }
        Ok(())
    }
}

impl std::error::Error for MasterError {}
