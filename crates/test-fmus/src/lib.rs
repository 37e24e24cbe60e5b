//! Small FMI 2.0 and 3.0 Co-Simulation FMUs on `neurarm-fmi-export` for testing masters: each exercises one
//! thing the standard allows and a general master must handle. One binary serves them all; an
//! FMU's `resources/model.txt` names its model. [`fmu_in`] packages one, [`fmu3_in`] its FMI 3.0
//! twin (the same binary, which exports both APIs).
//!
//! - [`TestModel::Counter`]: counts its steps; a step from `stop_at` [s] on returns
//!   `fmi2Discard` with `fmi2Terminated` true (or false with `retry`), as a model that reaches
//!   its own end condition does.
//! - [`TestModel::Split`]: two channels `y1 = k u1`, `y2 = k u2`, each output depending
//!   directly on its own input only, so two units can feed each other without an algebraic
//!   loop.
//! - [`TestModel::Modes`]: an Enumeration parameter and input, an Enumeration output, String
//!   parameter, input and outputs, an Integer output and a Boolean parameter.
//! - [`TestModel::Hold`]: a sample-and-hold whose output has a start value
//!   (`initial="exact"`) the environment may set.
//! - [`TestModel::FixedStep`]: a clock that cannot handle variable communication steps.

pub mod package;

use std::path::Path;

use neurarm_fmi_export::codec::{Put, Reader};
use neurarm_fmi_export::{
    BooleanVar, Causality, EnumerationType, IntegerVar, Model, ModelDescription, ModelError, RealVar, StaticModel, StringVar, TableBuilder,
    Unit, Values, Variability,
};

pub use package::{built_library, fmu3_in, fmu_in, PackageError};

/// The models of this crate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TestModel {
    /// Counts steps; discards the step from `stop_at` on.
    Counter,
    /// Two channels with separate direct feedthrough.
    Split,
    /// Enumerations, strings, integers and Booleans.
    Modes,
    /// Sample-and-hold with a settable initial output.
    Hold,
    /// A clock stepping at one fixed communication step only.
    FixedStep,
}

impl TestModel {
    /// Every model.
    pub const ALL: [TestModel; 5] = [TestModel::Counter, TestModel::Split, TestModel::Modes, TestModel::Hold, TestModel::FixedStep];

    /// The model identifier (also the name in `resources/model.txt`).
    pub fn identifier(self) -> &'static str {
        match self {
            TestModel::Counter => "Counter",
            TestModel::Split => "Split",
            TestModel::Modes => "Modes",
            TestModel::Hold => "Hold",
            TestModel::FixedStep => "FixedStep",
        }
    }

    /// The model of identifier `name`.
    pub fn named(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|m| m.identifier() == name)
    }

    /// A new instance's model.
    pub fn build(self) -> Result<Box<dyn Model>, ModelError> {
        Ok(match self {
            TestModel::Counter => Box::new(Counter::new()?),
            TestModel::Split => Box::new(Split::new()?),
            TestModel::Modes => Box::new(Modes::new()?),
            TestModel::Hold => Box::new(Hold::new()?),
            TestModel::FixedStep => Box::new(FixedStep::new()?),
        })
    }

    /// What it computes, for the FMU's documentation page.
    pub fn equations_html(self) -> &'static str {
        match self {
            TestModel::Counter => {
                "<p><code>count</code> counts the steps taken; <code>t_last</code> is the time reached. A step from \
                 <code>t ≥ stop_at</code> returns fmi2Discard: fmi2Terminated is true, or false when <code>retry</code>.</p>"
            }
            TestModel::Split => "<p><code>y1 = k u1</code> (depends on u1 only), <code>y2 = k u2</code> (on u2 only).</p>",
            TestModel::Modes => {
                "<p><code>y</code> is sin t, the sign of sin t, or t mod 1 as the shape (<code>follow</code> if \
                 <code>use_follow</code>, else <code>shape</code>) says; <code>active</code> is that shape, \
                 <code>status</code> = label:shape, <code>heard</code> echoes the string input <code>note</code>, \
                 <code>steps</code> counts the steps.</p>"
            }
            TestModel::Hold => {
                "<p><code>y</code> starts at its start value; each step sets it to the input <code>u</code> at the step's start.</p>"
            }
            TestModel::FixedStep => "<p><code>t_out</code> is the time reached; every step must have the first step's size.</p>",
        }
    }
}

const SECOND: Unit = Unit::SECOND;

/// Counts steps and ends the simulation at `stop_at`.
struct Counter {
    description: ModelDescription,
    count: IntegerVar,
    t_last: RealVar,
    stop_at: RealVar,
    retry: BooleanVar,
    finish: BooleanVar,
    steps: i32,
}

impl Counter {
    fn new() -> Result<Self, ModelError> {
        let mut b = TableBuilder::new();
        let count = b.integer("count", Causality::Output, Variability::Discrete, None, "Steps taken");
        let t_last = b.output("t_last", SECOND, "Time reached", &[]);
        let stop_at = b.parameter("stop_at", SECOND, 8.8, "A step from this time on is discarded");
        let retry = b.boolean("retry", Causality::Parameter, Variability::Fixed, Some(false), "Discard without asking to terminate");
        let finish = b.boolean(
            "finish",
            Causality::Parameter,
            Variability::Fixed,
            Some(false),
            "Take the step that reaches stop_at, then ask to end (instead of discarding the next)",
        );
        let description = ModelDescription::new("Counter", "Counts steps; discards the step from stop_at on", b.finish())?;
        Ok(Self { description, count, t_last, stop_at, retry, finish, steps: 0 })
    }
}

impl Model for Counter {
    fn description(&self) -> &ModelDescription {
        &self.description
    }
    fn initialize(&mut self, values: &mut Values, start: f64) -> Result<(), ModelError> {
        self.steps = 0;
        values[self.count] = 0;
        values[self.t_last] = start;
        Ok(())
    }
    fn do_step(&mut self, values: &mut Values, time: f64, step: f64) -> Result<(), ModelError> {
        let stop_at = values[self.stop_at];
        if time >= stop_at - 1e-9 * stop_at.abs().max(1.0) {
            let why = format!("the counter stops at {stop_at} s");
            return Err(if values[self.retry] { ModelError::discard(why) } else { ModelError::terminate(why) });
        }
        self.steps += 1;
        values[self.count] = self.steps;
        values[self.t_last] = time + step;
        let end = time + step;
        if values[self.finish] && end >= stop_at - 1e-9 * stop_at.abs().max(1.0) {
            return Err(ModelError::finish(format!("the counter reached {stop_at} s")));
        }
        Ok(())
    }
    fn reset(&mut self) {
        self.steps = 0;
    }
    fn save_state(&self, out: &mut Vec<u8>) {
        out.put_u32(self.steps as u32);
    }
    fn load_state(&mut self, _values: &Values, bytes: &[u8]) -> Result<(), ModelError> {
        let mut r = Reader::new(bytes);
        let steps = r.u32()? as i32;
        r.finish()?;
        self.steps = steps;
        Ok(())
    }
}

/// Two channels, each output depending on its own input only.
struct Split {
    description: ModelDescription,
    u: [RealVar; 2],
    y: [RealVar; 2],
    k: RealVar,
}

impl Split {
    fn new() -> Result<Self, ModelError> {
        let mut b = TableBuilder::new();
        let u1 = b.input("u1", None, 0.0, "Input of channel 1");
        let u2 = b.input("u2", None, 0.0, "Input of channel 2");
        let y1 = b.output("y1", None, "k u1", &[u1]);
        let y2 = b.output("y2", None, "k u2", &[u2]);
        let k = b.tunable("k", None, 2.0, "Gain of both channels");
        let description = ModelDescription::new("Split", "Two channels with separate direct feedthrough", b.finish())?;
        Ok(Self { description, u: [u1, u2], y: [y1, y2], k })
    }
}

impl StaticModel for Split {
    fn description(&self) -> &ModelDescription {
        &self.description
    }
    fn compute(&mut self, values: &mut Values, _time: f64) -> Result<(), ModelError> {
        for c in 0..2 {
            values[self.y[c]] = values[self.k] * values[self.u[c]];
        }
        Ok(())
    }
}

/// The shapes of [`Modes`].
fn shape_type() -> EnumerationType {
    EnumerationType::new("Shape", &[("sine", "sin t"), ("square", "sign of sin t"), ("ramp", "t mod 1")])
}

/// Enumerations, strings, integers and Booleans.
struct Modes {
    description: ModelDescription,
    shape: IntegerVar,
    follow: IntegerVar,
    use_follow: BooleanVar,
    label: StringVar,
    note: StringVar,
    y: RealVar,
    active: IntegerVar,
    status: StringVar,
    heard: StringVar,
    steps: IntegerVar,
    taken: i32,
}

impl Modes {
    fn new() -> Result<Self, ModelError> {
        let shapes = shape_type();
        let mut b = TableBuilder::new();
        let shape = b.enumeration("shape", Causality::Parameter, Variability::Tunable, &shapes, Some(1), "Shape of y");
        let follow = b.enumeration("follow", Causality::Input, Variability::Discrete, &shapes, Some(1), "Shape to use when use_follow");
        let use_follow =
            b.boolean("use_follow", Causality::Parameter, Variability::Fixed, Some(false), "Take the shape from the input follow");
        let label = b.string("label", Causality::Parameter, Variability::Fixed, Some("modes".into()), "Prefix of status");
        let note = b.string("note", Causality::Input, Variability::Discrete, Some(String::new()), "Echoed as heard");
        let y = b.output("y", None, "The shape at the time reached", &[]);
        let active = b.enumeration("active", Causality::Output, Variability::Discrete, &shapes, None, "The shape in use");
        let status = b.string("status", Causality::Output, Variability::Discrete, None, "label:shape");
        let heard = b.string("heard", Causality::Output, Variability::Discrete, None, "The input note");
        let steps = b.integer("steps", Causality::Output, Variability::Discrete, None, "Steps taken");
        let description = ModelDescription::new("Modes", "Enumerations, strings, integers and Booleans", b.finish())?;
        Ok(Self { description, shape, follow, use_follow, label, note, y, active, status, heard, steps, taken: 0 })
    }

    /// Writes the outputs at `time` [s].
    fn outputs(&self, values: &mut Values, time: f64) {
        let shape = if values[self.use_follow] { values[self.follow] } else { values[self.shape] };
        values[self.y] = match shape {
            1 => time.sin(),
            2 => time.sin().signum(),
            _ => time.rem_euclid(1.0),
        };
        values[self.active] = shape;
        let name = shape_type().item(shape).map_or("?", |i| i.name.as_str()).to_owned();
        values[self.status] = format!("{}:{name}", values[self.label]);
        values[self.heard] = values[self.note].clone();
        values[self.steps] = self.taken;
    }
}

impl Model for Modes {
    fn description(&self) -> &ModelDescription {
        &self.description
    }
    fn initialize(&mut self, values: &mut Values, start: f64) -> Result<(), ModelError> {
        self.taken = 0;
        self.outputs(values, start);
        Ok(())
    }
    fn do_step(&mut self, values: &mut Values, time: f64, step: f64) -> Result<(), ModelError> {
        self.taken += 1;
        self.outputs(values, time + step);
        Ok(())
    }
    fn reset(&mut self) {
        self.taken = 0;
    }
    fn save_state(&self, out: &mut Vec<u8>) {
        out.put_u32(self.taken as u32);
    }
    fn load_state(&mut self, _values: &Values, bytes: &[u8]) -> Result<(), ModelError> {
        let mut r = Reader::new(bytes);
        let taken = r.u32()? as i32;
        r.finish()?;
        self.taken = taken;
        Ok(())
    }
}

/// Sample-and-hold: `y` starts at its (settable) start value.
struct Hold {
    description: ModelDescription,
    u: RealVar,
    y: RealVar,
}

impl Hold {
    fn new() -> Result<Self, ModelError> {
        let mut b = TableBuilder::new();
        let u = b.input("u", None, 0.0, "Sampled at each step's start");
        let y = b.output_with_start("y", None, 0.0, "The held value; its start value may be set", &[]);
        let description = ModelDescription::new("Hold", "Sample-and-hold with a settable initial output", b.finish())?;
        Ok(Self { description, u, y })
    }
}

impl Model for Hold {
    fn description(&self) -> &ModelDescription {
        &self.description
    }
    fn initialize(&mut self, _values: &mut Values, _start: f64) -> Result<(), ModelError> {
        // y keeps the start value the environment set (initial="exact").
        Ok(())
    }
    fn do_step(&mut self, values: &mut Values, _time: f64, _step: f64) -> Result<(), ModelError> {
        values[self.y] = values[self.u];
        Ok(())
    }
    fn reset(&mut self) {}
    fn save_state(&self, _out: &mut Vec<u8>) {}
    fn load_state(&mut self, _values: &Values, bytes: &[u8]) -> Result<(), ModelError> {
        Ok(Reader::new(bytes).finish()?)
    }
}

/// A clock that steps at one communication step size only.
struct FixedStep {
    description: ModelDescription,
    t_out: RealVar,
}

impl FixedStep {
    fn new() -> Result<Self, ModelError> {
        let mut b = TableBuilder::new();
        let t_out = b.output("t_out", SECOND, "Time reached", &[]);
        let description =
            ModelDescription::new("FixedStep", "A clock at one fixed communication step", b.finish())?.with_fixed_communication_step();
        Ok(Self { description, t_out })
    }
}

impl StaticModel for FixedStep {
    fn description(&self) -> &ModelDescription {
        &self.description
    }
    fn compute(&mut self, values: &mut Values, time: f64) -> Result<(), ModelError> {
        values[self.t_out] = time;
        Ok(())
    }
}

/// Name of the file in `resources/` that names the model.
pub const MODEL_FILE: &str = "model.txt";

fn factory(resources: Option<&Path>) -> Result<Box<dyn Model>, ModelError> {
    let dir = resources.ok_or_else(|| ModelError::msg("no resource location: resources/model.txt names the model"))?;
    let path = dir.join(MODEL_FILE);
    let text = std::fs::read_to_string(&path).map_err(|e| ModelError::msg(format!("{}: {e}", path.display())))?;
    let model =
        TestModel::named(text.trim()).ok_or_else(|| ModelError::msg(format!("{}: unknown model '{}'", path.display(), text.trim())))?;
    model.build()
}

neurarm_fmi_export::export_fmi2!(factory);
neurarm_fmi_export::export_fmi3!(factory);
