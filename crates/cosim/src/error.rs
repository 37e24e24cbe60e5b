//! What went wrong, where and when.
//!
//! [`MasterError`] is the error of building, loading and running a system: it names the unit,
//! the variable and the time. The steps before it have their own: reading an FMU's interface
//! ([`FmuFileError`], [`DescriptionError`]) and checking a system file ([`SpecError`],
//! [`SystemFileError`]). Where one of them ends in a `MasterError` (adding a unit to a system,
//! say), its text becomes the message.
//!
//! Each error's text already holds its cause's (the zip, XML or TOML error), so none returns it
//! again from `source()`: a chain printed link by link says it once.

use std::fmt;
use std::path::PathBuf;

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
    /// Set when the unit discarded a step (`fmi2Discard`, `fmi3Discard`) rather than failed.
    pub discard: Option<Box<DiscardedStep>>,
}

/// What a unit said when it discarded a step (`fmi2DoStep` returned `fmi2Discard`, or
/// `fmi3DoStep` `fmi3Discard`).
#[derive(Clone, Debug, PartialEq)]
pub struct DiscardedStep {
    /// `fmi2LastSuccessfulTime` (FMI 3.0: `fmi3DoStep`'s `lastSuccessfulTime`) [s], if the unit
    /// could say.
    pub last_successful_time: Option<f64>,
    /// `fmi2Terminated` (FMI 3.0: `terminateSimulation`): the unit asks to end the simulation,
    /// if it could say.
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

impl From<SpecError> for MasterError {
    /// A `[simulation]` table or an event that cannot run, as the master reports it.
    fn from(e: SpecError) -> Self {
        MasterError::new(e.to_string())
    }
}

/// An FMU archive that cannot be read or unpacked: the file and why.
#[derive(Debug, thiserror::Error)]
#[error("cannot load {}: {problem}", .path.display())]
pub struct FmuFileError {
    /// The `.fmu` file.
    pub path: PathBuf,
    /// What is wrong with it.
    pub problem: FmuProblem,
}

/// What is wrong with an FMU archive.
#[derive(Debug, thiserror::Error)]
pub enum FmuProblem {
    /// The file cannot be opened.
    #[error("{0}")]
    Open(std::io::Error),
    /// It is no zip archive.
    #[error("it is not an FMU (not a zip archive: {0})")]
    NotZip(zip::result::ZipError),
    /// It holds no `modelDescription.xml`.
    #[error("it is not an FMU (no modelDescription.xml: {0})")]
    NoDescription(zip::result::ZipError),
    /// `modelDescription.xml` cannot be read (or is no UTF-8).
    #[error("reading modelDescription.xml: {0}")]
    ReadDescription(std::io::Error),
    /// `modelDescription.xml` is larger than the master reads.
    #[error("modelDescription.xml is larger than {limit_mib} MiB")]
    DescriptionTooLarge {
        /// The largest size read [MiB].
        limit_mib: u64,
    },
    /// `modelDescription.xml` is not a description the master can use.
    #[error("modelDescription.xml: {0}")]
    Description(DescriptionError),
    /// An entry of the archive cannot be read.
    #[error("{0}")]
    Entry(zip::result::ZipError),
    /// The archive would unpack to more than the master allows.
    #[error("it would unpack to {total} bytes, more than the {limit_gib} GiB allowed")]
    TooLarge {
        /// The unpacked size [bytes].
        total: u64,
        /// The largest unpacked size allowed [GiB].
        limit_gib: u64,
    },
    /// No temporary folder to unpack into.
    #[error("temporary folder: {0}")]
    TempDir(std::io::Error),
    /// Unpacking failed.
    #[error("unpacking: {0}")]
    Unpack(zip::result::ZipError),
}

/// A `modelDescription.xml` (FMI 2.0 or 3.0) that the master cannot use: what is wrong, naming
/// the variable, type or element concerned.
#[derive(Debug, thiserror::Error)]
pub enum DescriptionError {
    /// Not well-formed XML.
    #[error("at byte {position}: {error}")]
    Xml {
        /// Where the reader stopped [bytes from the start].
        position: u64,
        /// The XML reader's error.
        error: quick_xml::Error,
    },
    /// An attribute that cannot be read.
    #[error("{0}")]
    Attribute(quick_xml::events::attributes::AttrError),
    /// An attribute value with a bad escape.
    #[error("{0}")]
    Escape(quick_xml::Error),
    /// No `fmiModelDescription` element, or one without `fmiVersion`.
    #[error("no fmiModelDescription element with an fmiVersion")]
    NoVersion,
    /// An FMI version other than 2.0 and 3.x.
    #[error("fmiVersion is {version}; only FMI 2.0 and 3.0 are supported")]
    UnsupportedVersion {
        /// The `fmiVersion` given.
        version: String,
    },
    /// No `CoSimulation` element.
    #[error("not a Co-Simulation FMU (no CoSimulation element)")]
    NotCoSimulation,
    /// An element without an attribute it needs; `element` says which (with its article).
    #[error("{element} has no {attribute}")]
    MissingAttribute {
        /// The element ("CoSimulation", "an Alias", ...).
        element: &'static str,
        /// The attribute missing.
        attribute: &'static str,
    },
    /// A Boolean attribute with another value.
    #[error("{attribute} is '{value}', not a Boolean")]
    NotABoolean {
        /// The attribute.
        attribute: &'static str,
        /// Its value.
        value: String,
    },
    /// A variable's causality, variability or initial of no known value.
    #[error("variable '{variable}': unknown {attribute} '{value}'")]
    UnknownValue {
        /// The variable.
        variable: String,
        /// "causality", "variability" or "initial".
        attribute: &'static str,
        /// The value given.
        value: String,
    },
    /// A variable without a `valueReference`.
    #[error("variable '{variable}' has no valueReference")]
    NoValueReference {
        /// The variable.
        variable: String,
    },
    /// A `valueReference` that is no number.
    #[error("variable '{variable}': valueReference '{text}' is not a number")]
    BadValueReference {
        /// The variable.
        variable: String,
        /// The attribute's text.
        text: String,
    },
    /// An FMI 2.0 `ScalarVariable` without a type element.
    #[error("variable '{variable}' has no type element")]
    NoTypeElement {
        /// The variable.
        variable: String,
    },
    /// An enumeration item without a name.
    #[error("an item of type '{type_name}' has no name")]
    ItemWithoutName {
        /// The enumeration type.
        type_name: String,
    },
    /// An enumeration item without a value.
    #[error("item '{item}' of type '{type_name}' has no value")]
    ItemWithoutValue {
        /// The item.
        item: String,
        /// The enumeration type.
        type_name: String,
    },
    /// An enumeration item whose value is no integer.
    #[error("item '{item}' of type '{type_name}': value '{value}' is not an integer")]
    ItemNotInteger {
        /// The item.
        item: String,
        /// The enumeration type.
        type_name: String,
        /// The value's text.
        value: String,
    },
    /// A number of `ModelStructure` that is no number.
    #[error("{section}: {attribute} '{text}' is not a number")]
    NotANumber {
        /// "ModelStructure" (FMI 3.0) or "Outputs" (FMI 2.0).
        section: &'static str,
        /// "valueReference" or "index".
        attribute: &'static str,
        /// The attribute's text.
        text: String,
    },
    /// An entry of a `dependencies` list that is no number.
    #[error("dependencies: '{text}' is not {expected}")]
    BadDependency {
        /// The entry.
        text: String,
        /// "a value reference" (FMI 3.0) or "an index" (FMI 2.0).
        expected: &'static str,
    },
    /// Two variables of one name.
    #[error("two variables are named '{name}'")]
    DuplicateName {
        /// The name.
        name: String,
    },
    /// An FMI 3.0 `Alias` with the name of another variable.
    #[error("two variables are named '{alias}' (an Alias of '{variable}')")]
    DuplicateAlias {
        /// The alias.
        alias: String,
        /// The variable it is another name of.
        variable: String,
    },
    /// An FMI 3.0 value reference used by two variables.
    #[error("variable '{variable}': value reference {value_reference} is used twice")]
    DuplicateValueReference {
        /// The second variable.
        variable: String,
        /// The value reference.
        value_reference: u32,
    },
    /// An FMI 2.0 value reference shared by variables of two types of one access class
    /// (aliases have one type).
    #[error(
        "variable '{variable}': value reference {value_reference} of type {} is used twice, by an {} and an {} (aliases have one type)",
        .class.name(), .first.name(), .second.name()
    )]
    AliasTypes {
        /// The second variable.
        variable: String,
        /// The value reference.
        value_reference: u32,
        /// The access class both are passed in.
        class: crate::interface::BaseType,
        /// The first variable's type.
        first: crate::interface::BaseType,
        /// The second variable's type.
        second: crate::interface::BaseType,
    },
    /// An enumeration variable whose type is not in `TypeDefinitions`.
    #[error("enumeration variable '{variable}' has no declared type in TypeDefinitions")]
    UndeclaredEnumeration {
        /// The variable.
        variable: String,
    },
    /// An FMI 3.0 `Output` of `ModelStructure` whose value reference is no variable's.
    #[error("ModelStructure: Output {value_reference} is not a value reference of a variable")]
    UnknownOutput {
        /// The value reference.
        value_reference: u32,
    },
    /// An FMI 3.0 dependency whose value reference is no variable's.
    #[error("ModelStructure: dependency {value_reference} is not a value reference of a variable")]
    UnknownDependency {
        /// The value reference.
        value_reference: u32,
    },
    /// An FMI 2.0 `Unknown` of `Outputs` whose index is no variable's.
    #[error("Outputs: index {index} is not a variable")]
    OutputIndex {
        /// The 1-based index.
        index: usize,
    },
    /// An FMI 2.0 dependency whose index is no variable's.
    #[error("Outputs: dependency {index} of '{output}' is not a variable")]
    DependencyIndex {
        /// The 1-based index.
        index: usize,
        /// The output it was given for.
        output: String,
    },
}

/// A `[simulation]` table or an event that cannot run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SpecError {
    /// Times or step out of range.
    #[error("[simulation] needs a positive step and stop ≥ start (got start {start}, stop {stop}, step {step})")]
    Span {
        /// Start time [s].
        start: f64,
        /// Stop time [s].
        stop: f64,
        /// Communication step [s].
        step: f64,
    },
    /// An event at no finite time.
    #[error("an event's time must be finite, not {time}")]
    EventTime {
        /// The event's time [s].
        time: f64,
    },
    /// A ramp that does not end at a finite time after its start.
    #[error("the ramp from t = {time} s must end at a finite time after it, not until = {until}")]
    RampEnd {
        /// The ramp's start [s].
        time: f64,
        /// Its end as given [s].
        until: f64,
    },
    /// An event that sets nothing.
    #[error("the event at t = {time} s sets nothing: give set = {{ \"unit.variable\" = value }}")]
    EmptyEvent {
        /// The event's time [s].
        time: f64,
    },
}

/// A system file that cannot be read or written; `origin` names the file.
#[derive(Debug, thiserror::Error)]
pub enum SystemFileError {
    /// Not TOML, or not a system file's fields.
    #[error("{origin}: {}", .error.to_string().trim_end())]
    Syntax {
        /// The file.
        origin: String,
        /// The TOML reader's error.
        error: toml::de::Error,
    },
    /// A `[simulation]` table that cannot run.
    #[error("{origin}: {error}")]
    Simulation {
        /// The file.
        origin: String,
        /// What is wrong.
        error: SpecError,
    },
    /// An `[[event]]` that cannot run.
    #[error("{origin}: event {number}: {error}")]
    Event {
        /// The file.
        origin: String,
        /// The event's number in the file, from 1.
        number: usize,
        /// What is wrong.
        error: SpecError,
    },
    /// The system cannot be written as TOML.
    #[error("writing the system file: {0}")]
    Write(toml::ser::Error),
}
