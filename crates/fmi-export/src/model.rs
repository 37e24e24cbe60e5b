//! The small trait a model implements to become an FMU, the value store the layer keeps for
//! it, and the error a model reports.

use std::fmt;
use std::ops::{Index, IndexMut};

use crate::description::{Kind, ModelDescription};
use crate::table::{BooleanVar, IntegerVar, RealVar, StringVar};

/// The current value of every variable, one vector per base type indexed by value reference.
/// A model reads and writes it through the handles its [`TableBuilder`](crate::TableBuilder)
/// gave: `values[handle]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Values {
    pub(crate) reals: Vec<f64>,
    pub(crate) integers: Vec<i32>,
    pub(crate) booleans: Vec<bool>,
    pub(crate) strings: Vec<String>,
}

impl Values {
    /// The start values of `description` (0, false or "" where a variable has none).
    pub fn start(description: &ModelDescription) -> Self {
        let mut v = Values { reals: Vec::new(), integers: Vec::new(), booleans: Vec::new(), strings: Vec::new() };
        fn put<T: Clone + Default>(slot: &mut Vec<T>, vr: u32, value: T) {
            let i = vr as usize;
            if slot.len() <= i {
                slot.resize(i + 1, T::default());
            }
            slot[i] = value;
        }
        for var in &description.variables {
            let vr = var.value_reference;
            match &var.kind {
                Kind::Real { start, .. } => put(&mut v.reals, vr, start.unwrap_or(0.0)),
                Kind::Integer { start } => put(&mut v.integers, vr, start.unwrap_or(0)),
                Kind::Enumeration { start, declared_type } => {
                    put(&mut v.integers, vr, start.or(declared_type.items.first().map(|i| i.value)).unwrap_or(0))
                }
                Kind::Boolean { start } => put(&mut v.booleans, vr, start.unwrap_or(false)),
                Kind::String { start } => put(&mut v.strings, vr, start.clone().unwrap_or_default()),
            }
        }
        v
    }

    /// Copies the values of `vars` into `out` (as many as both hold).
    pub fn read_reals(&self, vars: &[RealVar], out: &mut [f64]) {
        for (o, v) in out.iter_mut().zip(vars) {
            *o = self[*v];
        }
    }

    /// Sets `vars` to `values` (as many as both hold).
    pub fn write_reals(&mut self, vars: &[RealVar], values: &[f64]) {
        for (v, x) in vars.iter().zip(values) {
            self[*v] = *x;
        }
    }
}

macro_rules! index {
    ($handle:ty, $field:ident, $t:ty) => {
        impl Index<$handle> for Values {
            type Output = $t;
            fn index(&self, var: $handle) -> &$t {
                &self.$field[var.0 as usize]
            }
        }
        impl IndexMut<$handle> for Values {
            fn index_mut(&mut self, var: $handle) -> &mut $t {
                &mut self.$field[var.0 as usize]
            }
        }
    };
}

index!(RealVar, reals, f64);
index!(IntegerVar, integers, i32);
index!(BooleanVar, booleans, bool);
index!(StringVar, strings, String);

/// Why a model call failed. The layer logs it and returns `fmi2Error`, or `fmi2Discard` for
/// an error made by [`ModelError::discard`] or [`ModelError::terminate`] and returned from
/// [`Model::do_step`]. Any error type converts into it with `?`; [`ModelError::msg`] makes one
/// from text.
pub struct ModelError {
    error: Box<dyn std::error::Error + Send + Sync + 'static>,
    discard: Option<Discard>,
}

/// How a step that was not taken ends, for `fmi2Discard` (FMI 2.0, section 4.2.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Discard {
    /// The step could not be taken; the master may restore an earlier FMU state and try
    /// otherwise (a smaller step).
    Retry,
    /// The model asks to end the simulation (`fmi2Terminated` reads true).
    Terminate,
    /// The step was taken in full and the model asks to end the simulation at its end.
    Finish,
}

impl ModelError {
    /// An error that is just a message.
    pub fn msg(message: impl fmt::Display) -> Self {
        Self { error: message.to_string().into(), discard: None }
    }

    /// From [`Model::do_step`]: the step was not taken and nothing of it was done, but the
    /// instance is sound: `fmi2DoStep` returns `fmi2Discard`, `fmi2LastSuccessfulTime` is the
    /// step's start and `fmi2Terminated` false.
    pub fn discard(message: impl fmt::Display) -> Self {
        Self { error: message.to_string().into(), discard: Some(Discard::Retry) }
    }

    /// From [`Model::do_step`]: the model asks to end the simulation at the step's start (a
    /// stop condition was reached): `fmi2DoStep` returns `fmi2Discard`,
    /// `fmi2LastSuccessfulTime` is the step's start and `fmi2Terminated` true.
    pub fn terminate(message: impl fmt::Display) -> Self {
        Self { error: message.to_string().into(), discard: Some(Discard::Terminate) }
    }

    /// From [`Model::do_step`] after taking the whole step (outputs written): the model asks
    /// to end the simulation at the step's end (it reached its own end, as a replayed log
    /// does). FMI 2.0: `fmi2DoStep` returns `fmi2Discard` with `fmi2LastSuccessfulTime` the
    /// step's end and `fmi2Terminated` true (the Reference-FMUs' convention); FMI 3.0:
    /// `fmi3OK` with `terminateSimulation`.
    pub fn finish(message: impl fmt::Display) -> Self {
        Self { error: message.to_string().into(), discard: Some(Discard::Finish) }
    }

    /// Whether this is a discarded step rather than a failure, and of which kind.
    pub fn discarded(&self) -> Option<Discard> {
        self.discard
    }

    /// The underlying error.
    pub fn inner(&self) -> &(dyn std::error::Error + Send + Sync + 'static) {
        &*self.error
    }
}

impl<E: std::error::Error + Send + Sync + 'static> From<E> for ModelError {
    fn from(e: E) -> Self {
        Self { error: Box::new(e), discard: None }
    }
}

impl fmt::Display for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.error.fmt(f)
    }
}

impl fmt::Debug for ModelError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(&self.error, f)
    }
}

/// A model behind an FMU. The layer owns the [`Values`]: it writes inputs and parameters into
/// them, checked, and reads outputs from them; the model reads and writes them in its calls.
/// Errors are logged by the layer and turned into `fmi2Error`.
pub trait Model: Send {
    /// The model's interface, fixed for the life of the instance.
    fn description(&self) -> &ModelDescription;

    /// Leaves initialization mode: read parameters and inputs from `values`, set up the
    /// internal state at `start_time` [s] and write the initial outputs.
    fn initialize(&mut self, values: &mut Values, start_time: f64) -> Result<(), ModelError>;

    /// Recomputes outputs that depend directly on inputs, after inputs changed at the
    /// communication point `time` [s]. The default does nothing (no direct feedthrough).
    fn update_outputs(&mut self, _values: &mut Values, _time: f64) -> Result<(), ModelError> {
        Ok(())
    }

    /// Advances from `time` by `step` [s] with the inputs in `values`, writing the outputs.
    /// A step the model cannot or will not take returns [`ModelError::discard`] or
    /// [`ModelError::terminate`] (`fmi2Discard`) and leaves the state as it was; a step taken
    /// after which the model asks to end returns [`ModelError::finish`]; any other error is a
    /// failure (`fmi2Error`).
    fn do_step(&mut self, values: &mut Values, time: f64, step: f64) -> Result<(), ModelError>;

    /// The simulation ends (`fmi2Terminate`): a model may hand over what it made (write a
    /// file it was asked for). An error is logged and returned as `fmi2Error`; the instance is
    /// terminated either way. The default does nothing.
    fn terminate(&mut self, _values: &Values) -> Result<(), ModelError> {
        Ok(())
    }

    /// Back to the state right after instantiation (the layer restores the start values).
    fn reset(&mut self);

    /// Appends the internal state not held in [`Values`] to `out`.
    fn save_state(&self, out: &mut Vec<u8>);

    /// Restores a state written by [`Model::save_state`], with `values` already restored.
    /// Must reject malformed bytes without changing anything.
    fn load_state(&mut self, values: &Values, bytes: &[u8]) -> Result<(), ModelError>;
}

/// A model without state of its own: its outputs are a function of its inputs, its
/// parameters and the time, so initialising, stepping and updating all just compute them,
/// and there is nothing to save (the layer keeps the time in its FMU state). Every
/// `StaticModel` is a [`Model`].
pub trait StaticModel: Send {
    /// The model's interface, fixed for the life of the instance.
    fn description(&self) -> &ModelDescription;

    /// Writes the outputs at the communication point `time` [s] from the inputs and
    /// parameters in `values`.
    fn compute(&mut self, values: &mut Values, time: f64) -> Result<(), ModelError>;
}

impl<T: StaticModel> Model for T {
    fn description(&self) -> &ModelDescription {
        StaticModel::description(self)
    }
    fn initialize(&mut self, values: &mut Values, start_time: f64) -> Result<(), ModelError> {
        self.compute(values, start_time)
    }
    fn update_outputs(&mut self, values: &mut Values, time: f64) -> Result<(), ModelError> {
        self.compute(values, time)
    }
    fn do_step(&mut self, values: &mut Values, time: f64, step: f64) -> Result<(), ModelError> {
        self.compute(values, time + step)
    }
    fn reset(&mut self) {}
    fn save_state(&self, _out: &mut Vec<u8>) {}
    fn load_state(&mut self, _values: &Values, bytes: &[u8]) -> Result<(), ModelError> {
        Ok(crate::codec::Reader::new(bytes).finish()?)
    }
}

/// Makes a model from the FMU's `resources/` folder (which may not exist, for an FMU without
/// resources; `None` when the host passed no resource location). The layer checks the GUID
/// the host passes against the returned model's description.
pub type ModelFactory = fn(resources: Option<&std::path::Path>) -> Result<Box<dyn Model>, ModelError>;
