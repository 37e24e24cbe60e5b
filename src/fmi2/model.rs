//! The small trait a model implements to become an FMU, and the value store the layer keeps
//! for it.

use super::description::{Kind, ModelDescription};

/// The current value of every variable, one vector per base type indexed by value reference.
#[derive(Clone, Debug, PartialEq)]
pub struct Values {
    /// `fmi2Real` values.
    pub reals: Vec<f64>,
    /// `fmi2Integer` values.
    pub integers: Vec<i32>,
    /// `fmi2Boolean` values.
    pub booleans: Vec<bool>,
    /// `fmi2String` values.
    pub strings: Vec<String>,
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
                Kind::Boolean { start } => put(&mut v.booleans, vr, start.unwrap_or(false)),
                Kind::String { start } => put(&mut v.strings, vr, start.clone().unwrap_or_default()),
            }
        }
        v
    }
}

/// A model behind an FMU. The layer owns the [`Values`]: it writes inputs and parameters into
/// them, checked, and reads outputs from them; the model reads and writes them in its calls.
/// Errors are returned as messages, which the layer logs and turns into `fmi2Error`.
pub trait Model: Send {
    /// The model's interface, fixed for the life of the instance.
    fn description(&self) -> &ModelDescription;

    /// Leaves initialization mode: read parameters and inputs from `values`, set up the
    /// internal state at `start_time` [s] and write the initial outputs.
    fn initialize(&mut self, values: &mut Values, start_time: f64) -> Result<(), String>;

    /// Recomputes outputs that depend directly on inputs, after inputs changed. The default
    /// does nothing (no direct feedthrough).
    fn update_outputs(&mut self, _values: &mut Values) -> Result<(), String> {
        Ok(())
    }

    /// Advances from `time` by `step` [s] with the inputs in `values`, writing the outputs.
    fn do_step(&mut self, values: &mut Values, time: f64, step: f64) -> Result<(), String>;

    /// Back to the state right after instantiation (the layer restores the start values).
    fn reset(&mut self);

    /// Appends the internal state not held in [`Values`] to `out`.
    fn save_state(&self, out: &mut Vec<u8>);

    /// Restores a state written by [`Model::save_state`], with `values` already restored.
    /// Must reject malformed bytes without changing anything.
    fn load_state(&mut self, values: &Values, bytes: &[u8]) -> Result<(), String>;
}

/// A model without state: its outputs are a function of its inputs and parameters alone, so
/// initialising, stepping and updating all just compute them, and there is no state to save.
/// Every `StaticModel` is a [`Model`].
pub trait StaticModel: Send {
    /// The model's interface, fixed for the life of the instance.
    fn description(&self) -> &ModelDescription;

    /// Writes the outputs from the inputs and parameters in `values`.
    fn compute(&mut self, values: &mut Values);
}

impl<T: StaticModel> Model for T {
    fn description(&self) -> &ModelDescription {
        StaticModel::description(self)
    }
    fn initialize(&mut self, values: &mut Values, _start_time: f64) -> Result<(), String> {
        self.compute(values);
        Ok(())
    }
    fn update_outputs(&mut self, values: &mut Values) -> Result<(), String> {
        self.compute(values);
        Ok(())
    }
    fn do_step(&mut self, values: &mut Values, _time: f64, _step: f64) -> Result<(), String> {
        self.compute(values);
        Ok(())
    }
    fn reset(&mut self) {}
    fn save_state(&self, _out: &mut Vec<u8>) {}
    fn load_state(&mut self, _values: &Values, bytes: &[u8]) -> Result<(), String> {
        super::codec::Reader::new(bytes).finish()
    }
}

/// Makes a model from the FMU's `resources/` folder. The GUID is checked by the layer against
/// the returned model's description.
pub type ModelFactory = fn(resources: &std::path::Path) -> Result<Box<dyn Model>, String>;
