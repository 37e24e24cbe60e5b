//! One FMU instance in safe Rust: the FMI 2.0 Co-Simulation state machine, argument checks,
//! logging and FMU states. The C APIs ([`crate::fmi2::abi`], [`crate::fmi3::abi`]) only convert pointers and catch
//! panics; every rule lives here.
//!
//! Refusals and failures:
//! * a call in a state that does not allow it, or with a bad argument (unknown value
//!   reference, wrong type, a variable that may not be set now, NaN, a tolerance that is not
//!   finite and > 0, h <= 0, a wrong communication point, a step past the stop time or to a
//!   time that is not finite, not later or beyond the time horizon, an FMU state of another
//!   instance or model, or holding numbers that are not finite),
//!   returns `Error` after logging why, and changes nothing: the instance goes on as before
//!   (as the Modelica Reference-FMUs do);
//! * a failure of the model itself (invalid parameters at initialization, a step that cannot
//!   be taken) returns `Error` and puts the instance in the error state, where the standard
//!   allows only getting values, restoring an FMU state, `fmi2Reset` and `fmi2FreeInstance`.
//!   A model call that leaves a Real output or local NaN or infinite is such a failure, named by the
//!   variable; and `fmi2GetReal` never returns `fmi2OK` with a number that is not finite.

use crate::codec::{Put, Reader, StateError};
use crate::description::{BaseType, Causality, Kind, ModelDescription, SetPhase, LOG_CATEGORIES};
use crate::model::{Discard, Model, Values};

/// `fmi2Status`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
#[repr(i32)]
pub enum Status {
    /// `fmi2OK`.
    Ok = 0,
    /// `fmi2Warning`.
    Warning = 1,
    /// `fmi2Discard`.
    Discard = 2,
    /// `fmi2Error`.
    Error = 3,
    /// `fmi2Fatal`.
    Fatal = 4,
    /// `fmi2Pending`.
    Pending = 5,
}

/// The instance's place in the FMI 2.0 Co-Simulation state machine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// After `fmi2Instantiate` or `fmi2Reset`.
    Instantiated = 1 << 0,
    /// Between `fmi2EnterInitializationMode` and `fmi2ExitInitializationMode`.
    InitializationMode = 1 << 1,
    /// Ready for `fmi2DoStep`.
    StepComplete = 1 << 2,
    /// A step returned `fmi2Discard`.
    StepFailed = 1 << 3,
    /// A step was cancelled.
    StepCanceled = 1 << 4,
    /// After `fmi2Terminate`.
    Terminated = 1 << 5,
    /// After a failure of the model.
    Error = 1 << 6,
    /// After a panic was caught: only `fmi2FreeInstance` is allowed.
    Fatal = 1 << 7,
}

/// The FMI functions that take an instance, each with the phases that allow it (FMI 2.0 CS
/// state machine, section 4.2.4).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[allow(missing_docs)]
pub enum Function {
    SetDebugLogging,
    SetupExperiment,
    EnterInitializationMode,
    ExitInitializationMode,
    Terminate,
    Reset,
    GetValues,
    SetReal,
    SetOther,
    FmuState,
    GetDirectionalDerivative,
    SetRealInputDerivatives,
    GetRealOutputDerivatives,
    DoStep,
    CancelStep,
    GetStatus,
}

const AFTER_INSTANTIATE: u16 = Phase::Instantiated as u16
    | Phase::InitializationMode as u16
    | Phase::StepComplete as u16
    | Phase::StepFailed as u16
    | Phase::StepCanceled as u16
    | Phase::Terminated as u16
    | Phase::Error as u16;
const AFTER_INIT_MODE: u16 = AFTER_INSTANTIATE & !(Phase::Instantiated as u16);

impl Function {
    /// Phases (bit mask of [`Phase`]) in which the function may be called.
    pub fn allowed(self) -> u16 {
        use Phase::*;
        match self {
            Function::SetDebugLogging | Function::Reset | Function::FmuState => AFTER_INSTANTIATE,
            Function::SetupExperiment | Function::EnterInitializationMode => Instantiated as u16,
            Function::ExitInitializationMode => InitializationMode as u16,
            Function::Terminate => StepComplete as u16 | StepFailed as u16,
            Function::GetValues | Function::GetDirectionalDerivative => AFTER_INIT_MODE,
            Function::SetReal | Function::SetOther | Function::SetRealInputDerivatives => {
                Instantiated as u16 | InitializationMode as u16 | StepComplete as u16
            }
            Function::GetRealOutputDerivatives => AFTER_INIT_MODE & !(InitializationMode as u16),
            Function::DoStep => StepComplete as u16,
            Function::CancelStep => 0,
            Function::GetStatus => StepComplete as u16 | StepFailed as u16 | Terminated as u16,
        }
    }
}

/// Which FMI version's C API drives an instance. The rules are the same (the FMI 2.0
/// Co-Simulation state machine covers FMI 3.0 Co-Simulation without event mode); only the
/// function names in log messages differ.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Api {
    /// FMI 2.0: `fmi2DoStep`, `fmi2GetReal`, …
    #[default]
    Fmi2,
    /// FMI 3.0: `fmi3DoStep`, `fmi3GetFloat64`, …
    Fmi3,
}

impl Api {
    /// The name of the function of this API that does what the FMI 2.0 function `fmi2_name`
    /// does (`fmi2SetupExperiment` is part of `fmi3EnterInitializationMode`, the status
    /// queries are results of `fmi3DoStep`); a name it does not know is returned as it is.
    pub fn name(self, fmi2_name: &str) -> &str {
        if self == Api::Fmi2 {
            return fmi2_name;
        }
        match fmi2_name {
            "fmi2SetDebugLogging" => "fmi3SetDebugLogging",
            "fmi2SetupExperiment" | "fmi2EnterInitializationMode" => "fmi3EnterInitializationMode",
            "fmi2ExitInitializationMode" => "fmi3ExitInitializationMode",
            "fmi2Terminate" => "fmi3Terminate",
            "fmi2Reset" => "fmi3Reset",
            "fmi2GetReal" => "fmi3GetFloat64",
            "fmi2SetReal" => "fmi3SetFloat64",
            "fmi2GetInteger" => "fmi3GetInt32",
            "fmi2SetInteger" => "fmi3SetInt32",
            "fmi2GetBoolean" => "fmi3GetBoolean",
            "fmi2SetBoolean" => "fmi3SetBoolean",
            "fmi2GetString" => "fmi3GetString",
            "fmi2SetString" => "fmi3SetString",
            "fmi2DoStep" | "fmi2GetRealStatus" | "fmi2GetBooleanStatus" => "fmi3DoStep",
            "fmi2GetFMUstate" => "fmi3GetFMUState",
            "fmi2SetFMUstate" => "fmi3SetFMUState",
            "fmi2FreeFMUstate" => "fmi3FreeFMUState",
            "fmi2SerializedFMUstateSize" => "fmi3SerializedFMUStateSize",
            "fmi2SerializeFMUstate" => "fmi3SerializeFMUState",
            "fmi2DeSerializeFMUstate" => "fmi3DeserializeFMUState",
            other => other,
        }
    }
}

/// Receives the instance's log messages: status, category, message.
pub type LogSink = Box<dyn Fn(Status, &str, &str) + Send>;

/// A saved FMU state (`fmi2FMUstate`), bound to the model it was taken from: restoring or
/// serialising it through an instance of another model is refused.
#[derive(Clone, Debug, PartialEq)]
pub struct Snapshot {
    /// The GUID of the model whose instance saved it.
    model: std::sync::Arc<str>,
    phase: Phase,
    time: f64,
    start_time: f64,
    values: Values,
    /// The model's own part ([`Model::save_state`]).
    internal: Vec<u8>,
}

/// The handle of an FMU state held by an instance, as the C APIs pass it (`fmi2FMUstate`,
/// `fmi3FMUState`): a number, never an address, so a handle the instance did not give out
/// (of another instance or model, freed, or made up) is found unknown without being read.
pub type StateHandle = usize;

/// The next handle any instance of this library gives out: handles are never reused, so a
/// freed one stays unknown.
static NEXT_STATE_HANDLE: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(1);

/// Why an FMU state given as a value is not one of this model's.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ForeignState {
    /// Saved by an instance of another model.
    #[error("the FMU state was saved by an instance of another model (GUID {saved_by}), this is {this} (GUID {guid})")]
    OtherModel {
        /// The GUID of the model that saved it.
        saved_by: String,
        /// This model's identifier.
        this: String,
        /// This model's GUID.
        guid: String,
    },
    /// Its values are not this model's variables.
    #[error("the FMU state does not hold this model's variables")]
    OtherVariables,
}

/// Why an FMU state of this model holds what no instance of this layer saves: numbers that
/// are not finite, or a time before its start time. The numbers are as messages show them.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum UnfitState {
    /// Its time or start time is NaN or infinite.
    #[error("the state's {what} is {value}, not a finite number")]
    NonFiniteTime {
        /// `time` or `start time`.
        what: &'static str,
        /// The value.
        value: String,
    },
    /// Its time is before its start time [s].
    #[error("the state's time {time} s is before its start time {start} s")]
    BeforeStart {
        /// The time.
        time: String,
        /// The start time.
        start: String,
    },
    /// A Real value is NaN or infinite.
    #[error("the state holds {value} for '{name}', not a finite number")]
    NonFiniteValue {
        /// The value.
        value: String,
        /// The variable.
        name: String,
    },
}

/// Why an instance could not be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum InstantiateError {
    /// `instanceName` is empty or white space only (FMI 2.0 and 3.0 ask for at least one
    /// other character).
    #[error("the instance name is empty or white space only")]
    BlankName,
    /// A Real variable's start value is NaN or infinite (the model was built from bad data).
    #[error("the start value of '{name}' is {value}, not a finite number")]
    NonFiniteStart {
        /// The variable.
        name: String,
        /// Its start value.
        value: f64,
    },
    /// The host's GUID is not the model's.
    #[error("GUID {given} does not match this FMU's {expected}: the modelDescription.xml and the binary or resources differ")]
    WrongGuid {
        /// The GUID the host passed.
        given: String,
        /// The model's.
        expected: String,
    },
}

/// One instance of a model.
pub struct Instance {
    name: String,
    guid: std::sync::Arc<str>,
    model: Box<dyn Model>,
    values: Values,
    start_values: Values,
    phase: Phase,
    start_time: f64,
    /// The stop time set by `fmi2SetupExperiment`, if it set one [s].
    stop_time: Option<f64>,
    time: f64,
    dirty: bool,
    /// The last step was discarded because the model asks to end the simulation.
    terminated: bool,
    /// For a model that cannot handle variable steps: the size of the first step [s].
    fixed_step: Option<f64>,
    log: LogSink,
    debug_logging: bool,
    categories: Vec<bool>,
    /// Variable entry by base type (in [`BaseType`] order) and value reference; value
    /// references are dense per type, so a vector beats a hash map on the hot path.
    lookup: [Vec<Entry>; 4],
    /// Value references of the Real variables a model call computes (outputs and locals): the
    /// ones checked for NaN and infinities after every call. Inputs and parameters change only
    /// through checked sets, start values and restored states.
    computed_reals: Vec<u32>,
    /// The C API driving the instance, for the function names in messages.
    api: Api,
    /// The value reference of the independent variable `time`, kept equal to the instance's
    /// time so that hosts that record it read the current time.
    time_variable: Option<u32>,
    /// The model's nominal communication step ([`ModelDescription::default_experiment`], else
    /// [`NOMINAL_STEP`]) [s].
    nominal_step: f64,
    /// The magnitude of time no step may reach [s]: below it a double resolves the nominal
    /// step to [`STEP_RESOLUTION`] of itself, so the instance can always go on stepping.
    time_horizon: f64,
    /// The FMU states the host holds, by handle; freed with the instance at the latest.
    states: std::collections::HashMap<StateHandle, Snapshot>,
}

/// The communication step assumed for a model whose description has no default experiment [s].
pub const NOMINAL_STEP: f64 = 1e-3;

/// The resolution a step of the nominal size keeps at the [`Instance`]'s time horizon: the
/// spacing of doubles there is at most this fraction of it.
pub const STEP_RESOLUTION: f64 = 1.0 / 1024.0;

/// How far apart, in units in the last place of the larger magnitude, two times may be and
/// still be one communication point: hosts compute points as `t0 + n·h` or by adding `h`, which
/// leaves them a few ulps from the FMU's own `t + h`.
pub const TIME_ULPS: f64 = 8.0;

/// The spacing of doubles at the magnitude of `t` (the unit in the last place) [s].
fn ulp(t: f64) -> f64 {
    let a = t.abs();
    if !a.is_finite() {
        return f64::INFINITY;
    }
    f64::from_bits(a.to_bits() + 1) - a
}

/// Whether `a` and `b` are within [`TIME_ULPS`] of the larger of them.
fn same_time(a: f64, b: f64) -> bool {
    (a - b).abs() <= TIME_ULPS * ulp(a.abs().max(b.abs()))
}

/// The first power of two at which the spacing of doubles exceeds `STEP_RESOLUTION · nominal`
/// [s]: times below it resolve a step of `nominal` to that fraction.
fn time_horizon(nominal: f64) -> f64 {
    let finest = (nominal * STEP_RESOLUTION).log2().floor();
    // The spacing at 2^e is 2^(e − 52): it stays within 2^finest below 2^(finest + 53).
    2f64.powf(finest + 53.0)
}

/// What the hot get/set paths need of a variable, precomputed: its index in the description
/// and in which phases `fmi2Set*` may change it.
#[derive(Clone, Copy)]
struct Entry {
    /// Index in the description's variables; [`Entry::NONE`] for an unused value reference.
    index: u32,
    /// Bit `phase_bit(p)` set when the variable is settable in [`SetPhase`] `p`.
    settable: u8,
}

impl Entry {
    const NONE: Entry = Entry { index: u32::MAX, settable: 0 };

    fn index(self) -> Option<usize> {
        (self.index != u32::MAX).then_some(self.index as usize)
    }
}

fn phase_bit(phase: SetPhase) -> u8 {
    match phase {
        SetPhase::Instantiated => 1,
        SetPhase::Initialization => 2,
        SetPhase::Running => 4,
    }
}

/// Whether every number is finite; no early exit, so the loop vectorises (this runs on every
/// step over all Real variables).
fn all_finite(numbers: &[f64]) -> bool {
    numbers.iter().fold(0u64, |any, &v| any | not_finite_bit(v)) == 0
}

/// Whether `numbers[i]` is finite for every `i` in `at`.
fn all_finite_at(numbers: &[f64], at: &[u32]) -> bool {
    at.iter().fold(0u64, |any, &i| any | not_finite_bit(numbers[i as usize])) == 0
}

/// 1 for an infinity or NaN, else 0: such a double has all exponent bits set. An OR of these
/// vectorises where `is_finite` with an early exit does not.
fn not_finite_bit(v: f64) -> u64 {
    const EXPONENT: u64 = 0x7ff0_0000_0000_0000;
    u64::from(v.to_bits() & EXPONENT == EXPONENT)
}

/// Magic bytes at the start of a serialized FMU state.
const STATE_MAGIC: &[u8; 8] = b"F2XSTATE";
/// Version of the serialized FMU state format.
const STATE_VERSION: u32 = 1;

/// `value` for a message: as written for ordinary magnitudes, in exponent form beyond them
/// (1.7e308 rather than 309 digits).
fn show(value: f64) -> String {
    if value == 0.0 || !value.is_finite() || (1e-4..1e15).contains(&value.abs()) {
        value.to_string()
    } else {
        format!("{value:e}")
    }
}

fn phase_from(code: u8) -> Result<Phase, StateError> {
    use Phase::*;
    [Instantiated, InitializationMode, StepComplete, StepFailed, StepCanceled, Terminated, Error, Fatal]
        .into_iter()
        .find(|p| u32::from(*p as u16) == 1u32.checked_shl(code.into()).unwrap_or(0))
        .ok_or_else(|| StateError::Invalid(format!("unknown phase code {code}")))
}

impl Instance {
    /// A new instance of `model` called `name`, if `guid` is the model's GUID.
    pub fn new(name: &str, guid: &str, model: Box<dyn Model>, log: LogSink, debug_logging: bool) -> Result<Self, InstantiateError> {
        if name.trim().is_empty() {
            return Err(InstantiateError::BlankName);
        }
        let expected = model.description().guid();
        if guid != expected {
            return Err(InstantiateError::WrongGuid { given: guid.to_owned(), expected });
        }
        let description = model.description();
        let time_variable = description.variables.iter().find(|v| v.causality == Causality::Independent).map(|v| v.value_reference);
        let nominal_step =
            description.default_experiment.as_ref().map(|e| e.step_size).filter(|h| h.is_finite() && *h > 0.0).unwrap_or(NOMINAL_STEP);
        let mut lookup: [Vec<Entry>; 4] = Default::default();
        for (i, v) in description.variables.iter().enumerate() {
            let slot = &mut lookup[v.base_type().slot()];
            let vr = v.value_reference as usize;
            if slot.len() <= vr {
                slot.resize(vr + 1, Entry::NONE);
            }
            let settable = [SetPhase::Instantiated, SetPhase::Initialization, SetPhase::Running]
                .into_iter()
                .filter(|&p| v.settable_in(p))
                .fold(0, |bits, p| bits | phase_bit(p));
            slot[vr] = Entry { index: u32::try_from(i).expect("fewer than 2^32 variables"), settable };
        }
        let computed_reals = description
            .variables
            .iter()
            .filter(|v| v.base_type() == BaseType::Real && matches!(v.causality, Causality::Output | Causality::Local))
            .map(|v| v.value_reference)
            .collect();
        let values = Values::start(description);
        if let Some(vr) = values.reals.iter().position(|v| !v.is_finite()) {
            let name = lookup[BaseType::Real.slot()].get(vr).and_then(|e| e.index()).map(|i| description.variables[i].name.clone());
            return Err(InstantiateError::NonFiniteStart { name: name.unwrap_or_else(|| format!("#{vr}")), value: values.reals[vr] });
        }
        Ok(Self {
            name: name.to_owned(),
            guid: expected.into(),
            start_values: values.clone(),
            values,
            model,
            phase: Phase::Instantiated,
            start_time: 0.0,
            stop_time: None,
            time: 0.0,
            dirty: true,
            terminated: false,
            fixed_step: None,
            log,
            debug_logging,
            categories: LOG_CATEGORIES.iter().map(|_| debug_logging).collect(),
            lookup,
            computed_reals,
            api: Api::Fmi2,
            time_variable,
            nominal_step,
            time_horizon: time_horizon(nominal_step),
            states: std::collections::HashMap::new(),
        })
    }

    /// Moves the instance's time to `t` [s], and the independent variable with it.
    fn set_time(&mut self, t: f64) {
        self.time = t;
        if let Some(vr) = self.time_variable {
            self.values.reals[vr as usize] = t;
        }
    }

    /// The same instance, naming the functions of `api` in its messages.
    pub fn with_api(mut self, api: Api) -> Self {
        self.api = api;
        self
    }

    /// The C API driving the instance.
    pub fn api(&self) -> Api {
        self.api
    }

    /// The instance name.
    pub fn name(&self) -> &str {
        &self.name
    }

    /// The current phase.
    pub fn phase(&self) -> Phase {
        self.phase
    }

    /// The current communication point [s].
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Logs an error and returns `Error`.
    pub fn error(&self, message: &str) -> Status {
        (self.log)(Status::Error, "logStatusError", message);
        Status::Error
    }

    /// Logs a call trace if `logCalls` is on.
    pub fn trace(&self, message: impl FnOnce() -> String) {
        if self.debug_logging && self.categories[2] {
            (self.log)(Status::Ok, "logCalls", &message());
        }
    }

    /// After a caught panic: only freeing is possible.
    pub fn set_fatal(&mut self) {
        self.phase = Phase::Fatal;
    }

    /// Checks that `function` (named `name` in messages) may be called now.
    pub fn check_phase(&self, name: &str, function: Function) -> Result<(), Status> {
        let name = self.api.name(name);
        if function.allowed() & self.phase as u16 != 0 {
            Ok(())
        } else {
            Err(self.error(&format!("{name}: illegal call sequence: not allowed in state {:?}", self.phase)))
        }
    }

    /// `fmi2SetDebugLogging`.
    pub fn set_debug_logging(&mut self, on: bool, categories: &[&str]) -> Status {
        if let Err(s) = self.check_phase("fmi2SetDebugLogging", Function::SetDebugLogging) {
            return s;
        }
        let mut chosen = vec![categories.is_empty(); LOG_CATEGORIES.len()];
        for c in categories {
            match LOG_CATEGORIES.iter().position(|x| x.name == *c) {
                Some(i) => chosen[i] = true,
                None => {
                    let known: Vec<&str> = LOG_CATEGORIES.iter().map(|x| x.name).collect();
                    return self.error(&format!(
                        "{}: unknown log category '{c}' (known: {})",
                        self.api.name("fmi2SetDebugLogging"),
                        known.join(", ")
                    ));
                }
            }
        }
        self.debug_logging = on;
        for (enabled, chosen) in self.categories.iter_mut().zip(chosen) {
            if chosen {
                *enabled = on;
            }
        }
        Status::Ok
    }

    /// `fmi2SetupExperiment`.
    pub fn setup_experiment(&mut self, tolerance: Option<f64>, start_time: f64, stop_time: Option<f64>) -> Status {
        if let Err(s) = self.check_phase("fmi2SetupExperiment", Function::SetupExperiment) {
            return s;
        }
        if !start_time.is_finite() {
            return self.error(&format!("{}: start time {start_time} is not finite", self.api.name("fmi2SetupExperiment")));
        }
        if start_time.abs() >= self.time_horizon {
            return self.error(&format!(
                "{}: start time {} s is beyond ±{} s, where {}",
                self.api.name("fmi2SetupExperiment"),
                show(start_time),
                show(self.time_horizon),
                self.horizon_reason()
            ));
        }
        if let Some(stop) = stop_time {
            if !(stop >= start_time) {
                return self
                    .error(&format!("{}: stop time {stop} is before start time {start_time}", self.api.name("fmi2SetupExperiment")));
            }
            if !stop.is_finite() {
                return self.error(&format!(
                    "{}: stop time {stop} is not finite (leave it undefined for no stop time)",
                    self.api.name("fmi2SetupExperiment")
                ));
            }
        }
        if let Some(t) = tolerance {
            if !(t.is_finite() && t > 0.0) {
                return self.error(&format!("{}: tolerance {} must be finite and > 0", self.api.name("fmi2SetupExperiment"), show(t)));
            }
            self.trace(|| format!("{}: tolerance {t} ignored (fixed-step model)", self.api.name("fmi2SetupExperiment")));
        }
        self.start_time = start_time;
        self.stop_time = stop_time;
        self.set_time(start_time);
        Status::Ok
    }

    /// `fmi2EnterInitializationMode`.
    pub fn enter_initialization_mode(&mut self) -> Status {
        if let Err(s) = self.check_phase("fmi2EnterInitializationMode", Function::EnterInitializationMode) {
            return s;
        }
        self.phase = Phase::InitializationMode;
        Status::Ok
    }

    /// `fmi2ExitInitializationMode`: the model reads its parameters and computes its outputs.
    pub fn exit_initialization_mode(&mut self) -> Status {
        if let Err(s) = self.check_phase("fmi2ExitInitializationMode", Function::ExitInitializationMode) {
            return s;
        }
        match self.model.initialize(&mut self.values, self.start_time) {
            Ok(()) => {
                if let Some(why) = self.non_finite_real() {
                    self.phase = Phase::Error;
                    return self.error(&format!("{}: {why}", self.api.name("fmi2ExitInitializationMode")));
                }
                self.dirty = false;
                self.set_time(self.start_time);
                self.phase = Phase::StepComplete;
                Status::Ok
            }
            Err(e) => {
                self.phase = Phase::Error;
                self.error(&format!("{}: {e}", self.api.name("fmi2ExitInitializationMode")))
            }
        }
    }

    /// `fmi2Terminate`.
    pub fn terminate(&mut self) -> Status {
        if let Err(s) = self.check_phase("fmi2Terminate", Function::Terminate) {
            return s;
        }
        self.phase = Phase::Terminated;
        match self.model.terminate(&self.values) {
            Ok(()) => Status::Ok,
            Err(e) => self.error(&format!("{}: {e}", self.api.name("fmi2Terminate"))),
        }
    }

    /// `fmi2Reset`: start values back, the model as after instantiation.
    pub fn reset(&mut self) -> Status {
        if let Err(s) = self.check_phase("fmi2Reset", Function::Reset) {
            return s;
        }
        self.model.reset();
        self.values = self.start_values.clone();
        self.phase = Phase::Instantiated;
        self.start_time = 0.0;
        self.stop_time = None;
        self.set_time(0.0);
        self.dirty = true;
        self.terminated = false;
        self.fixed_step = None;
        Status::Ok
    }

    fn index_of(&self, base: BaseType, vr: u32) -> Option<usize> {
        self.lookup[base.slot()].get(vr as usize).and_then(|e| e.index())
    }

    fn resolve(&self, function: &str, vr: u32, base: BaseType) -> Result<usize, Status> {
        let function = self.api.name(function);
        match self.index_of(base, vr) {
            Some(i) => Ok(i),
            None => {
                let other = [BaseType::Real, BaseType::Integer, BaseType::Boolean, BaseType::String]
                    .into_iter()
                    .find(|&t| self.index_of(t, vr).is_some())
                    .map(BaseType::name);
                Err(self.error(&match other {
                    Some(t) => format!("{function}: value reference {vr} is a {t} variable, not {}", base.name()),
                    None => format!("{function}: unknown value reference {vr}"),
                }))
            }
        }
    }

    fn refresh(&mut self, function: &str) -> Result<(), Status> {
        let function = self.api.name(function);
        if self.dirty && self.phase != Phase::Instantiated {
            // In initialization mode the outputs are initial unknowns: computed by the same
            // initialisation that leaving the mode runs, from the values set so far.
            let computed = if self.phase == Phase::InitializationMode {
                self.model.initialize(&mut self.values, self.start_time)
            } else {
                self.model.update_outputs(&mut self.values, self.time)
            };
            if let Err(e) = computed {
                return Err(self.error(&format!("{function}: {e}")));
            }
            if let Some(why) = self.non_finite_real() {
                return Err(self.error(&format!("{function}: {why}")));
            }
            self.dirty = false;
        }
        Ok(())
    }

    /// Reads variables of base type `base` through `read`, after the phase and reference checks.
    fn get<T>(&mut self, function: &str, base: BaseType, vrs: &[u32], out: &mut [T], read: impl Fn(&Values, usize) -> T) -> Status {
        if let Err(s) = self.check_phase(function, Function::GetValues) {
            return s;
        }
        if let Err(s) = self.refresh(function) {
            return s;
        }
        let table = &self.lookup[base.slot()];
        if !vrs.iter().all(|&vr| table.get(vr as usize).is_some_and(|e| e.index != u32::MAX)) {
            for &vr in vrs {
                if let Err(s) = self.resolve(function, vr, base) {
                    return s;
                }
            }
        }
        for (o, &vr) in out.iter_mut().zip(vrs) {
            *o = read(&self.values, vr as usize);
        }
        Status::Ok
    }

    /// `fmi2GetReal`: a value that is not a finite number (left by a failed model call) is
    /// refused by name, never returned with `fmi2OK`.
    pub fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Status {
        match self.get("fmi2GetReal", BaseType::Real, vrs, out, |v, i| v.reals[i]) {
            Status::Ok if all_finite(out) => Status::Ok,
            Status::Ok => match vrs.iter().find(|&&vr| !self.values.reals[vr as usize].is_finite()) {
                Some(&vr) => self.error(&format!(
                    "{}: '{}' is {}, not a finite number: the model call that computed it failed",
                    self.api.name("fmi2GetReal"),
                    self.real_name(vr),
                    show(self.values.reals[vr as usize])
                )),
                None => Status::Ok,
            },
            s => s,
        }
    }
    /// `fmi2GetInteger`.
    pub fn get_integer(&mut self, vrs: &[u32], out: &mut [i32]) -> Status {
        self.get("fmi2GetInteger", BaseType::Integer, vrs, out, |v, i| v.integers[i])
    }
    /// `fmi2GetBoolean`.
    pub fn get_boolean(&mut self, vrs: &[u32], out: &mut [bool]) -> Status {
        self.get("fmi2GetBoolean", BaseType::Boolean, vrs, out, |v, i| v.booleans[i])
    }
    /// `fmi2GetString`.
    pub fn get_string(&mut self, vrs: &[u32], out: &mut [String]) -> Status {
        self.get("fmi2GetString", BaseType::String, vrs, out, |v, i| v.strings[i].clone())
    }

    /// Checks that every reference may be set now; sets nothing.
    fn check_settable(&self, function: &str, base: BaseType, vrs: &[u32]) -> Result<(), Status> {
        let function = self.api.name(function);
        let which = if base == BaseType::Real { Function::SetReal } else { Function::SetOther };
        self.check_phase(function, which)?;
        let phase = match self.phase {
            Phase::Instantiated => SetPhase::Instantiated,
            Phase::InitializationMode => SetPhase::Initialization,
            _ => SetPhase::Running,
        };
        let bit = phase_bit(phase);
        let table = &self.lookup[base.slot()];
        if vrs.iter().all(|&vr| table.get(vr as usize).is_some_and(|e| e.settable & bit != 0)) {
            return Ok(());
        }
        // The slow path names the first reference that fails.
        let variables = &self.model.description().variables;
        for &vr in vrs {
            let var = &variables[self.resolve(function, vr, base)?];
            if !var.settable_in(phase) {
                return Err(self.error(&format!(
                    "{function}: '{}' ({:?}, {:?}) cannot be set in state {:?}",
                    var.name, var.causality, var.variability, self.phase
                )));
            }
        }
        Ok(())
    }

    /// `fmi2SetReal`: all values are checked (settable now, finite) before any is set.
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Status {
        if let Err(s) = self.check_settable("fmi2SetReal", BaseType::Real, vrs) {
            return s;
        }
        if !all_finite(values) {
            let (vr, v) = vrs.iter().zip(values).find(|(_, v)| !v.is_finite()).expect("one is not finite");
            let index = self.index_of(BaseType::Real, *vr).expect("checked above");
            let name = &self.model.description().variables[index].name;
            return self.error(&format!("{}: {v} for '{name}' is not a finite number; nothing was set", self.api.name("fmi2SetReal")));
        }
        for (&vr, &v) in vrs.iter().zip(values) {
            self.values.reals[vr as usize] = v;
        }
        self.dirty = true;
        Status::Ok
    }

    /// Sets variables of a non-real base type after the checks; `slot` picks the storage.
    fn set<T: Clone>(&mut self, function: &str, base: BaseType, vrs: &[u32], values: &[T], slot: fn(&mut Values) -> &mut Vec<T>) -> Status {
        if let Err(s) = self.check_settable(function, base, vrs) {
            return s;
        }
        let storage = slot(&mut self.values);
        for (&vr, v) in vrs.iter().zip(values) {
            storage[vr as usize].clone_from(v);
        }
        self.dirty = true;
        Status::Ok
    }

    /// `fmi2SetInteger`: an enumeration variable takes only its type's item values.
    pub fn set_integer(&mut self, vrs: &[u32], values: &[i32]) -> Status {
        let variables = &self.model.description().variables;
        for (&vr, &value) in vrs.iter().zip(values) {
            let Some(index) = self.index_of(BaseType::Integer, vr) else { continue };
            if let Kind::Enumeration { declared_type, .. } = &variables[index].kind {
                if declared_type.item(value).is_none() {
                    let items: Vec<String> = declared_type.items.iter().map(|i| format!("{} = {}", i.name, i.value)).collect();
                    let name = &variables[index].name;
                    return self.error(&format!(
                        "{}: {value} is not an item of '{name}' (type {}: {}); nothing was set",
                        self.api.name("fmi2SetInteger"),
                        declared_type.name,
                        items.join(", ")
                    ));
                }
            }
        }
        self.set("fmi2SetInteger", BaseType::Integer, vrs, values, |v| &mut v.integers)
    }

    /// `fmi2SetBoolean`.
    pub fn set_boolean(&mut self, vrs: &[u32], values: &[bool]) -> Status {
        self.set("fmi2SetBoolean", BaseType::Boolean, vrs, values, |v| &mut v.booleans)
    }

    /// `fmi2SetString`.
    pub fn set_string(&mut self, vrs: &[u32], values: &[String]) -> Status {
        self.set("fmi2SetString", BaseType::String, vrs, values, |v| &mut v.strings)
    }

    /// `fmi2DoStep` from `current` [s] by `step` [s].
    pub fn do_step(&mut self, current: f64, step: f64) -> Status {
        if let Err(s) = self.check_phase("fmi2DoStep", Function::DoStep) {
            return s;
        }
        if let Err(s) = self.check_step(current, step) {
            return s;
        }
        if !self.model.description().can_handle_variable_step {
            match self.fixed_step {
                Some(h) if (step - h).abs() > 1e-9 * h => {
                    return self.error(&format!(
                        "{}: this FMU steps only at its first communication step size {h} s (canHandleVariableCommunicationStepSize is false), not {step} s", self.api.name("fmi2DoStep")
                    ));
                }
                Some(_) => {}
                None => self.fixed_step = Some(step),
            }
        }
        match self.model.do_step(&mut self.values, current, step) {
            Ok(()) => {
                if let Some(why) = self.non_finite_real() {
                    self.phase = Phase::Error;
                    return self.error(&format!("{} at t = {current} s: {why}", self.api.name("fmi2DoStep")));
                }
                self.set_time(current + step);
                self.dirty = false;
                Status::Ok
            }
            Err(e) => match e.discarded() {
                Some(Discard::Finish) => {
                    // The step was taken: the time moves to its end, the last successful one.
                    if let Some(why) = self.non_finite_real() {
                        self.phase = Phase::Error;
                        return self.error(&format!("{} at t = {current} s: {why}", self.api.name("fmi2DoStep")));
                    }
                    self.set_time(current + step);
                    self.dirty = false;
                    self.phase = Phase::StepFailed;
                    self.terminated = true;
                    (self.log)(
                        Status::Discard,
                        "logStatusWarning",
                        &format!("{} to t = {} s: the model asks to end the simulation: {e}", self.api.name("fmi2DoStep"), self.time),
                    );
                    Status::Discard
                }
                Some(kind) => {
                    // Nothing of the step was done: the time stays at its start, which is
                    // the last successful time.
                    self.phase = Phase::StepFailed;
                    self.terminated = kind == Discard::Terminate;
                    let what = if self.terminated { "the model asks to end the simulation" } else { "step discarded" };
                    (self.log)(
                        Status::Discard,
                        "logStatusWarning",
                        &format!("{} at t = {current} s: {what}: {e}", self.api.name("fmi2DoStep")),
                    );
                    Status::Discard
                }
                None => {
                    self.phase = Phase::Error;
                    self.error(&format!("{} at t = {current} s: {e}", self.api.name("fmi2DoStep")))
                }
            },
        }
    }

    /// Checks the arguments of `fmi2DoStep`: a finite step > 0 from the FMU's own time (within
    /// [`TIME_ULPS`]), ending at a later time within the time horizon, and not past the stop
    /// time of `fmi2SetupExperiment` (beyond [`TIME_ULPS`]: FMI 2.0 section 4.2.2 and FMI 3.0
    /// make computing past it an error).
    fn check_step(&self, current: f64, step: f64) -> Result<(), Status> {
        let function = self.api.name("fmi2DoStep");
        if !(step.is_finite() && step > 0.0) {
            return Err(self.error(&format!("{function}: communication step size {} must be finite and > 0", show(step))));
        }
        if !current.is_finite() || !same_time(current, self.time) {
            return Err(self.error(&format!(
                "{function}: currentCommunicationPoint {} differs from the FMU's time {}",
                show(current),
                show(self.time)
            )));
        }
        let end = current + step;
        if !(end.is_finite() && end > current) {
            return Err(self.error(&format!(
                "{function}: a step of {} s from t = {} s ends at {}, not at a later time a double can hold",
                show(step),
                show(current),
                show(end)
            )));
        }
        if end.abs() >= self.time_horizon {
            return Err(self.error(&format!(
                "{function}: a step of {} s from t = {} s would end at {} s, beyond {} s, where {}; the time stays at {} s",
                show(step),
                show(current),
                show(end),
                show(self.time_horizon),
                self.horizon_reason(),
                show(self.time)
            )));
        }
        if let Some(stop) = self.stop_time {
            if end > stop && !same_time(end, stop) {
                return Err(self.error(&format!(
                    "{function}: at t = {} s a step of {} s was requested, past the stop time {} s set at initialization (by {} s)",
                    show(current),
                    show(step),
                    show(stop),
                    show(end - stop)
                )));
            }
        }
        Ok(())
    }

    /// Why times beyond the horizon are refused, for messages.
    fn horizon_reason(&self) -> String {
        format!(
            "a double no longer resolves this FMU's step of {} s to 1/{} of itself (the instance could not go on)",
            show(self.nominal_step),
            (1.0 / STEP_RESOLUTION) as u32
        )
    }

    /// The name of the Real variable `vr`, for messages.
    fn real_name(&self, vr: u32) -> String {
        match self.index_of(BaseType::Real, vr) {
            Some(i) => self.model.description().variables[i].name.clone(),
            None => format!("value reference {vr}"),
        }
    }

    /// After a model call: every Real output and local must be a finite number; the first that
    /// is not is named in the returned reason.
    fn non_finite_real(&self) -> Option<String> {
        let reals = &self.values.reals;
        if all_finite_at(reals, &self.computed_reals) {
            return None;
        }
        let vr = self.computed_reals.iter().map(|&vr| vr as usize).find(|&vr| !reals[vr].is_finite())?;
        Some(format!("the model computed {} for '{}', not a finite number", show(self.values.reals[vr]), self.real_name(vr as u32)))
    }

    /// Refuses an FMU state with times or Real values that are not finite numbers, or a time
    /// before the start time: no instance of this layer saves such a state.
    fn check_snapshot(&self, snapshot: &Snapshot) -> Result<(), UnfitState> {
        for (what, t) in [("time", snapshot.time), ("start time", snapshot.start_time)] {
            if !t.is_finite() {
                return Err(UnfitState::NonFiniteTime { what, value: show(t) });
            }
        }
        if snapshot.time < snapshot.start_time {
            return Err(UnfitState::BeforeStart { time: show(snapshot.time), start: show(snapshot.start_time) });
        }
        match snapshot.values.reals.iter().position(|v| !v.is_finite()) {
            Some(vr) => Err(UnfitState::NonFiniteValue { value: show(snapshot.values.reals[vr]), name: self.real_name(vr as u32) }),
            None => Ok(()),
        }
    }

    /// `fmi2GetRealStatus(fmi2LastSuccessfulTime)` [s].
    pub fn last_successful_time(&self) -> Result<f64, Status> {
        self.check_phase("fmi2GetRealStatus", Function::GetStatus)?;
        Ok(self.time)
    }

    /// `fmi2GetBooleanStatus(fmi2Terminated)`: whether the last step was discarded because
    /// the model asks to end the simulation ([`crate::ModelError::terminate`]).
    pub fn terminated_status(&self) -> Result<bool, Status> {
        self.check_phase("fmi2GetBooleanStatus", Function::GetStatus)?;
        Ok(self.terminated)
    }

    /// `fmi2GetFMUstate` as a value. Refused after a failed call left a Real output or local
    /// that is not a finite number: such a state could not be restored (found by fuzzing: the
    /// state was saved, then refused by `fmi2DeSerializeFMUstate`).
    pub fn get_state(&self) -> Result<Snapshot, Status> {
        self.check_phase("fmi2GetFMUstate", Function::FmuState)?;
        if let Some(problem) = self.non_finite_real() {
            return Err(self.error(&format!(
                "{}: {problem}, left by a failed call; a state holding it could not be restored, so none is saved (restore an earlier state or reset)", self.api.name("fmi2GetFMUstate")
            )));
        }
        let mut internal = Vec::new();
        self.model.save_state(&mut internal);
        Ok(Snapshot {
            model: self.guid.clone(),
            phase: self.phase,
            time: self.time,
            start_time: self.start_time,
            values: self.values.clone(),
            internal,
        })
    }

    /// Refuses a state saved by an instance of another model, or one whose values do not have
    /// this model's shape.
    fn check_owner(&self, snapshot: &Snapshot) -> Result<(), ForeignState> {
        if snapshot.model != self.guid {
            return Err(ForeignState::OtherModel {
                saved_by: snapshot.model.to_string(),
                this: self.description().model_identifier.clone(),
                guid: self.guid.to_string(),
            });
        }
        let (a, b) = (&snapshot.values, &self.start_values);
        if (a.reals.len(), a.integers.len(), a.booleans.len(), a.strings.len())
            != (b.reals.len(), b.integers.len(), b.booleans.len(), b.strings.len())
        {
            return Err(ForeignState::OtherVariables);
        }
        Ok(())
    }

    /// `fmi2SetFMUstate` from a value.
    pub fn set_state(&mut self, snapshot: &Snapshot) -> Status {
        if let Err(s) = self.check_phase("fmi2SetFMUstate", Function::FmuState) {
            return s;
        }
        if let Err(e) = self.check_owner(snapshot) {
            return self.error(&format!("{}: {e}", self.api.name("fmi2SetFMUstate")));
        }
        if let Err(e) = self.check_snapshot(snapshot) {
            return self.error(&format!("{}: {e}", self.api.name("fmi2SetFMUstate")));
        }
        if let Err(e) = self.model.load_state(&snapshot.values, &snapshot.internal) {
            return self.error(&format!("{}: {e}", self.api.name("fmi2SetFMUstate")));
        }
        self.values = snapshot.values.clone();
        self.phase = snapshot.phase;
        self.start_time = snapshot.start_time;
        self.set_time(snapshot.time);
        self.dirty = false;
        self.terminated = false;
        Status::Ok
    }

    /// The state behind `handle`, if this instance gave it out and it was not freed.
    fn held_state(&self, function: &str, handle: StateHandle) -> Result<&Snapshot, Status> {
        self.states.get(&handle).ok_or_else(|| {
            self.error(&format!(
                "{}: {handle:#x} is not an FMU state of this instance: a state is used with the instance that saved or \
                 deserialized it, until it or its instance is freed (serialize it to move it to another instance)",
                self.api.name(function)
            ))
        })
    }

    /// Keeps `snapshot` under `reuse` (a handle this instance gave out, overwritten) or a new
    /// handle; returns the handle.
    fn hold_state(&mut self, function: &str, snapshot: Snapshot, reuse: Option<StateHandle>) -> Result<StateHandle, Status> {
        let handle = match reuse {
            Some(handle) => {
                self.held_state(function, handle)?;
                handle
            }
            None => NEXT_STATE_HANDLE.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
        };
        self.states.insert(handle, snapshot);
        Ok(handle)
    }

    /// `fmi2GetFMUstate`: the state saved under a new handle, or under `reuse` (a state this
    /// instance gave out), which is overwritten.
    pub fn save_state(&mut self, reuse: Option<StateHandle>) -> Result<StateHandle, Status> {
        let snapshot = self.get_state()?;
        self.hold_state("fmi2GetFMUstate", snapshot, reuse)
    }

    /// `fmi2SetFMUstate` by handle.
    pub fn restore_state(&mut self, handle: StateHandle) -> Status {
        if let Err(s) = self.check_phase("fmi2SetFMUstate", Function::FmuState) {
            return s;
        }
        // The instance holds its states; one is taken out while it is restored, and put back.
        let Some(snapshot) = self.states.remove(&handle) else {
            return self.held_state("fmi2SetFMUstate", handle).err().unwrap_or(Status::Error);
        };
        let status = self.set_state(&snapshot);
        self.states.insert(handle, snapshot);
        status
    }

    /// `fmi2FreeFMUstate`: forgets the state behind `handle`.
    pub fn free_state(&mut self, handle: StateHandle) -> Status {
        if let Err(s) = self.check_phase("fmi2FreeFMUstate", Function::FmuState) {
            return s;
        }
        match self.held_state("fmi2FreeFMUstate", handle) {
            Ok(_) => {
                self.states.remove(&handle);
                Status::Ok
            }
            Err(s) => s,
        }
    }

    /// `fmi2SerializeFMUstate` by handle.
    pub fn serialize_state(&self, handle: StateHandle) -> Result<Vec<u8>, Status> {
        self.check_phase("fmi2SerializeFMUstate", Function::FmuState)?;
        self.serialize(self.held_state("fmi2SerializeFMUstate", handle)?)
    }

    /// `fmi2DeSerializeFMUstate`: the state read from `bytes` under a new handle, or under
    /// `reuse` (a state this instance gave out), which is overwritten.
    pub fn deserialize_state(&mut self, bytes: &[u8], reuse: Option<StateHandle>) -> Result<StateHandle, Status> {
        if let Some(handle) = reuse {
            self.check_phase("fmi2DeSerializeFMUstate", Function::FmuState)?;
            self.held_state("fmi2DeSerializeFMUstate", handle)?;
        }
        let snapshot = self.deserialize(bytes)?;
        self.hold_state("fmi2DeSerializeFMUstate", snapshot, reuse)
    }

    /// How many FMU states the instance holds for the host.
    pub fn states_held(&self) -> usize {
        self.states.len()
    }

    /// `fmi2SerializeFMUstate`: magic, version, GUID, payload, CRC-32.
    pub fn serialize(&self, snapshot: &Snapshot) -> Result<Vec<u8>, Status> {
        self.check_phase("fmi2SerializeFMUstate", Function::FmuState)?;
        if let Err(e) = self.check_owner(snapshot) {
            return Err(self.error(&format!("{}: {e}", self.api.name("fmi2SerializeFMUstate"))));
        }
        let mut out = Vec::new();
        out.extend_from_slice(STATE_MAGIC);
        out.put_u32(STATE_VERSION);
        out.put_bytes(self.guid.as_bytes());
        let mut p = Vec::new();
        p.put_u8((snapshot.phase as u16).trailing_zeros() as u8);
        p.put_f64(snapshot.time);
        p.put_f64(snapshot.start_time);
        p.put_f64s(&snapshot.values.reals);
        p.put_u32(snapshot.values.integers.len() as u32);
        for &i in &snapshot.values.integers {
            p.put_u32(i as u32);
        }
        p.put_u32(snapshot.values.booleans.len() as u32);
        for &b in &snapshot.values.booleans {
            p.put_u8(b as u8);
        }
        p.put_u32(snapshot.values.strings.len() as u32);
        for s in &snapshot.values.strings {
            p.put_bytes(s.as_bytes());
        }
        p.put_bytes(&snapshot.internal);
        out.put_u64(p.len() as u64);
        out.extend_from_slice(&p);
        let crc = crc32fast::hash(&out);
        out.put_u32(crc);
        Ok(out)
    }

    /// `fmi2DeSerializeFMUstate`: rejects a buffer that is truncated, altered, of another
    /// format version or of another model.
    pub fn deserialize(&self, bytes: &[u8]) -> Result<Snapshot, Status> {
        self.check_phase("fmi2DeSerializeFMUstate", Function::FmuState)?;
        self.decode(bytes).map_err(|e| self.error(&format!("{}: {e}", self.api.name("fmi2DeSerializeFMUstate"))))
    }

    fn decode(&self, bytes: &[u8]) -> Result<Snapshot, StateError> {
        let invalid = |m: String| StateError::Invalid(m);
        if bytes.len() < STATE_MAGIC.len() + 4 || &bytes[..8] != STATE_MAGIC {
            return Err(invalid("not an FMU state of this FMU's kind (bad magic bytes)".into()));
        }
        let (body, crc) = bytes.split_at(bytes.len() - 4);
        if crc32fast::hash(body).to_le_bytes() != crc {
            return Err(invalid("checksum mismatch: the state is truncated or altered".into()));
        }
        let mut r = Reader::new(&body[8..]);
        let version = r.u32()?;
        if version != STATE_VERSION {
            return Err(invalid(format!("state format version {version}, this FMU reads version {STATE_VERSION}")));
        }
        let guid = r.bytes()?;
        if guid != self.guid.as_bytes() {
            return Err(invalid(format!("the state belongs to another model (GUID {})", String::from_utf8_lossy(guid))));
        }
        let len = r.u64()?;
        let payload = r.take(usize::try_from(len).map_err(|_| invalid("payload length too large".into()))?)?;
        r.finish()?;
        let mut p = Reader::new(payload);
        let phase = phase_from(p.u8()?)?;
        let time = p.f64()?;
        let start_time = p.f64()?;
        let shape = &self.start_values;
        let reals = p.f64s(shape.reals.len())?;
        let n = p.count("integers", shape.integers.len())?;
        let integers = (0..n).map(|_| p.u32().map(|v| v as i32)).collect::<Result<_, _>>()?;
        let n = p.count("booleans", shape.booleans.len())?;
        let booleans = (0..n)
            .map(|_| match p.u8()? {
                0 => Ok(false),
                1 => Ok(true),
                b => Err(invalid(format!("invalid Boolean byte {b}"))),
            })
            .collect::<Result<_, _>>()?;
        let n = p.count("strings", shape.strings.len())?;
        let strings = (0..n)
            .map(|_| String::from_utf8(p.bytes()?.to_vec()).map_err(|_| invalid("a string is not UTF-8".into())))
            .collect::<Result<_, _>>()?;
        let internal = p.bytes()?.to_vec();
        p.finish()?;
        if phase == Phase::Fatal {
            return Err(invalid("a state saved in the fatal state cannot be restored".into()));
        }
        let values = Values { reals, integers, booleans, strings };
        let snapshot = Snapshot { model: self.guid.clone(), phase, time, start_time, values, internal };
        self.check_snapshot(&snapshot).map_err(|e| invalid(e.to_string()))?;
        Ok(snapshot)
    }

    /// The model's description.
    pub fn description(&self) -> &ModelDescription {
        self.model.description()
    }
}
