//! A model's interface as one table of variables, and the `modelDescription.xml` written
//! from it. The ABI's dispatch reads the same table, so the two cannot disagree.

use std::io::Cursor;

use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, Event};
use quick_xml::Writer;

/// FMI 2.0 causality of a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    /// Set by the environment before initialization (or while running, if tunable).
    Parameter,
    /// Set by the environment at each communication point.
    Input,
    /// Computed by the model.
    Output,
    /// Internal, visible for inspection.
    Local,
    /// The independent variable, time.
    Independent,
}

/// FMI 2.0 variability of a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variability {
    /// Never changes.
    Constant,
    /// Fixed after initialization.
    Fixed,
    /// Changes only at communication points when set by the environment.
    Tunable,
    /// Changes only at discrete instants.
    Discrete,
    /// May change continuously.
    Continuous,
}

/// Type, start value and unit of a variable.
#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    /// A real number with its unit (an entry of [`UNITS`], or "" for none).
    Real {
        /// Start value; `None` for computed outputs and the independent variable.
        start: Option<f64>,
        /// Unit name, e.g. `"N.m"`.
        unit: &'static str,
    },
    /// A 32-bit integer.
    Integer {
        /// Start value.
        start: Option<i32>,
    },
    /// A Boolean.
    Boolean {
        /// Start value.
        start: Option<bool>,
    },
    /// A string.
    String {
        /// Start value.
        start: Option<String>,
    },
}

/// The FMI base type of a variable, without start value.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BaseType {
    /// `fmi2Real`.
    Real,
    /// `fmi2Integer`.
    Integer,
    /// `fmi2Boolean`.
    Boolean,
    /// `fmi2String`.
    String,
}

impl BaseType {
    /// The XML element name.
    pub fn name(self) -> &'static str {
        match self {
            BaseType::Real => "Real",
            BaseType::Integer => "Integer",
            BaseType::Boolean => "Boolean",
            BaseType::String => "String",
        }
    }
}

/// One scalar variable of a model.
#[derive(Clone, Debug, PartialEq)]
pub struct Variable {
    /// Unique name.
    pub name: String,
    /// Value reference, unique within the variable's base type.
    pub value_reference: u32,
    /// Causality.
    pub causality: Causality,
    /// Variability.
    pub variability: Variability,
    /// Type, start and unit.
    pub kind: Kind,
    /// Human-readable description, with units in words where helpful.
    pub description: String,
    /// For outputs: the 1-based indices of the inputs this output depends on directly
    /// (`dependencies` in `ModelStructure/Outputs`); empty for none.
    pub output_dependencies: Vec<usize>,
}

impl Variable {
    /// The base type.
    pub fn base_type(&self) -> BaseType {
        match self.kind {
            Kind::Real { .. } => BaseType::Real,
            Kind::Integer { .. } => BaseType::Integer,
            Kind::Boolean { .. } => BaseType::Boolean,
            Kind::String { .. } => BaseType::String,
        }
    }

    /// Whether `fmi2Set*` may change this variable in `phase` (FMI 2.0, section 4.2.4).
    pub fn settable_in(&self, phase: SetPhase) -> bool {
        use Causality::*;
        match self.causality {
            Output | Independent | Local => false,
            Input => true,
            Parameter => match phase {
                SetPhase::Instantiated | SetPhase::Initialization => self.variability != Variability::Constant,
                SetPhase::Running => self.variability == Variability::Tunable,
            },
        }
    }
}

/// When a set call happens, for the rules on what may be set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SetPhase {
    /// After instantiation, before initialization mode.
    Instantiated,
    /// In initialization mode.
    Initialization,
    /// Between steps.
    Running,
}

/// A unit and its exponents of SI base units: kg, m, s, rad.
pub struct UnitDef {
    /// Name as used in variables.
    pub name: &'static str,
    /// Exponents of kg, m, s, rad.
    pub exponents: [i8; 4],
}

/// Every unit a neurarm model may use.
pub const UNITS: &[UnitDef] = &[
    UnitDef { name: "s", exponents: [0, 0, 1, 0] },
    UnitDef { name: "m", exponents: [0, 1, 0, 0] },
    UnitDef { name: "m/s", exponents: [0, 1, -1, 0] },
    UnitDef { name: "m/s2", exponents: [0, 1, -2, 0] },
    UnitDef { name: "kg", exponents: [1, 0, 0, 0] },
    UnitDef { name: "kg.m2", exponents: [1, 2, 0, 0] },
    UnitDef { name: "rad", exponents: [0, 0, 0, 1] },
    UnitDef { name: "rad/s", exponents: [0, 0, -1, 1] },
    UnitDef { name: "N.m", exponents: [1, 2, -2, 0] },
    UnitDef { name: "N.m.s/rad", exponents: [1, 2, -1, -1] },
    UnitDef { name: "N.m/rad", exponents: [1, 2, -2, -1] },
    UnitDef { name: "1/s", exponents: [0, 0, -1, 0] },
    UnitDef { name: "1/s2", exponents: [0, 0, -2, 0] },
];

/// A log category the model declares.
#[derive(Clone, Debug, PartialEq)]
pub struct LogCategory {
    /// Name passed to `fmi2SetDebugLogging`.
    pub name: &'static str,
    /// What it reports.
    pub description: &'static str,
}

/// The categories every neurarm FMU declares.
pub const LOG_CATEGORIES: &[LogCategory] = &[
    LogCategory { name: "logStatusError", description: "Calls that return fmi2Error or fmi2Fatal, and why" },
    LogCategory { name: "logStatusWarning", description: "Calls that return fmi2Warning, and why" },
    LogCategory { name: "logCalls", description: "Every FMI call with its arguments (verbose)" },
];

/// Start, stop and step the model suggests to a master.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DefaultExperiment {
    /// Start time [s].
    pub start_time: f64,
    /// Stop time [s].
    pub stop_time: f64,
    /// Communication step [s].
    pub step_size: f64,
}

/// A model's complete interface.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelDescription {
    /// Model name.
    pub model_name: String,
    /// Model identifier: the name of the shared library in `binaries/`.
    pub model_identifier: String,
    /// One-line description.
    pub description: String,
    /// Suggested experiment.
    pub default_experiment: DefaultExperiment,
    /// The variables, in `ModelVariables` order.
    pub variables: Vec<Variable>,
}

impl ModelDescription {
    /// A checked description of the model `identifier` (also its name) with the project's
    /// default experiment: 0 to 10 s at a 1 ms communication step.
    pub fn new(identifier: &str, description: String, variables: Vec<Variable>) -> Result<Self, String> {
        let d = Self {
            model_name: identifier.to_owned(),
            model_identifier: identifier.to_owned(),
            description,
            default_experiment: DefaultExperiment { start_time: 0.0, stop_time: 10.0, step_size: 1e-3 },
            variables,
        };
        d.check()?;
        Ok(d)
    }

    /// The GUID: a UUID (v5) of the model description with an empty GUID, so any change of
    /// the interface or of a start value gives a new one.
    pub fn guid(&self) -> String {
        let xml = self.xml_with_guid("");
        let namespace = uuid::Uuid::from_bytes(*b"neurarm.fmi2.v1\0");
        format!("{{{}}}", uuid::Uuid::new_v5(&namespace, xml.as_bytes()))
    }

    /// `modelDescription.xml`.
    pub fn to_xml(&self) -> String {
        self.xml_with_guid(&self.guid())
    }

    /// Checks the table: unique names, value references unique per type, start values where
    /// FMI requires them and nowhere it forbids them, dependencies pointing at inputs.
    pub fn check(&self) -> Result<(), String> {
        let mut names = std::collections::HashSet::new();
        let mut refs = std::collections::HashSet::new();
        for v in &self.variables {
            if !names.insert(v.name.as_str()) {
                return Err(format!("variable name '{}' repeated", v.name));
            }
            if !refs.insert((v.base_type(), v.value_reference)) {
                return Err(format!("value reference {} of '{}' repeated", v.value_reference, v.name));
            }
            let has_start = match &v.kind {
                Kind::Real { start, unit } => {
                    if !unit.is_empty() && !UNITS.iter().any(|u| u.name == *unit) {
                        return Err(format!("unit '{unit}' of '{}' is not defined", v.name));
                    }
                    start.is_some()
                }
                Kind::Integer { start } => start.is_some(),
                Kind::Boolean { start } => start.is_some(),
                Kind::String { start } => start.is_some(),
            };
            let needs_start = matches!(v.causality, Causality::Parameter | Causality::Input);
            let forbids_start = matches!(v.causality, Causality::Output | Causality::Independent);
            if needs_start && !has_start {
                return Err(format!("'{}' needs a start value", v.name));
            }
            if forbids_start && has_start {
                return Err(format!("'{}' must not have a start value", v.name));
            }
            for &d in &v.output_dependencies {
                let ok = self.variables.get(d.wrapping_sub(1)).is_some_and(|x| x.causality == Causality::Input);
                if v.causality != Causality::Output || !ok {
                    return Err(format!("'{}' lists dependency {d}, which is not an input", v.name));
                }
            }
        }
        Ok(())
    }

    fn xml_with_guid(&self, guid: &str) -> String {
        let mut w = Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2);
        let ok = "writing XML to memory cannot fail";
        w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None))).expect(ok);
        let version = concat!("neurarm ", env!("CARGO_PKG_VERSION"));
        let root = BytesStart::new("fmiModelDescription").with_attributes([
            ("fmiVersion", "2.0"),
            ("modelName", self.model_name.as_str()),
            ("guid", guid),
            ("description", self.description.as_str()),
            ("generationTool", version),
            ("variableNamingConvention", "flat"),
            ("numberOfEventIndicators", "0"),
        ]);
        w.write_event(Event::Start(root)).expect(ok);
        w.write_event(Event::Empty(BytesStart::new("CoSimulation").with_attributes([
            ("modelIdentifier", self.model_identifier.as_str()),
            ("canHandleVariableCommunicationStepSize", "true"),
            ("canGetAndSetFMUstate", "true"),
            ("canSerializeFMUstate", "true"),
            ("canNotUseMemoryManagementFunctions", "true"),
        ])))
        .expect(ok);

        let used: Vec<&UnitDef> = UNITS
            .iter()
            .filter(|u| self.variables.iter().any(|v| matches!(v.kind, Kind::Real { unit, .. } if unit == u.name)))
            .collect();
        if !used.is_empty() {
            w.write_event(Event::Start(BytesStart::new("UnitDefinitions"))).expect(ok);
            for u in used {
                w.write_event(Event::Start(BytesStart::new("Unit").with_attributes([("name", u.name)]))).expect(ok);
                let exps: Vec<(&str, String)> = ["kg", "m", "s", "rad"]
                    .iter()
                    .zip(u.exponents)
                    .filter(|(_, e)| *e != 0)
                    .map(|(n, e)| (*n, e.to_string()))
                    .collect();
                let base = BytesStart::new("BaseUnit").with_attributes(exps.iter().map(|(n, e)| (*n, e.as_str())));
                w.write_event(Event::Empty(base)).expect(ok);
                w.write_event(Event::End(BytesEnd::new("Unit"))).expect(ok);
            }
            w.write_event(Event::End(BytesEnd::new("UnitDefinitions"))).expect(ok);
        }

        w.write_event(Event::Start(BytesStart::new("LogCategories"))).expect(ok);
        for c in LOG_CATEGORIES {
            let e = BytesStart::new("Category").with_attributes([("name", c.name), ("description", c.description)]);
            w.write_event(Event::Empty(e)).expect(ok);
        }
        w.write_event(Event::End(BytesEnd::new("LogCategories"))).expect(ok);

        let de = &self.default_experiment;
        let (start, stop, step) = (de.start_time.to_string(), de.stop_time.to_string(), de.step_size.to_string());
        w.write_event(Event::Empty(BytesStart::new("DefaultExperiment").with_attributes([
            ("startTime", start.as_str()),
            ("stopTime", stop.as_str()),
            ("stepSize", step.as_str()),
        ])))
        .expect(ok);

        w.write_event(Event::Start(BytesStart::new("ModelVariables"))).expect(ok);
        for v in &self.variables {
            let vr = v.value_reference.to_string();
            let mut sv = BytesStart::new("ScalarVariable").with_attributes([
                ("name", v.name.as_str()),
                ("valueReference", vr.as_str()),
                ("description", v.description.as_str()),
                ("causality", causality_name(v.causality)),
                ("variability", variability_name(v.variability)),
            ]);
            match v.causality {
                Causality::Parameter => sv.push_attribute(("initial", "exact")),
                Causality::Output => sv.push_attribute(("initial", "calculated")),
                _ => {}
            }
            w.write_event(Event::Start(sv)).expect(ok);
            let mut t = BytesStart::new(v.base_type().name());
            match &v.kind {
                Kind::Real { start, unit } => {
                    if !unit.is_empty() {
                        t.push_attribute(("unit", *unit));
                    }
                    if let Some(s) = start {
                        t.push_attribute(("start", s.to_string().as_str()));
                    }
                }
                Kind::Integer { start } => {
                    if let Some(s) = start {
                        t.push_attribute(("start", s.to_string().as_str()));
                    }
                }
                Kind::Boolean { start } => {
                    if let Some(s) = start {
                        t.push_attribute(("start", if *s { "true" } else { "false" }));
                    }
                }
                Kind::String { start } => {
                    if let Some(s) = start {
                        t.push_attribute(("start", s.as_str()));
                    }
                }
            }
            w.write_event(Event::Empty(t)).expect(ok);
            w.write_event(Event::End(BytesEnd::new("ScalarVariable"))).expect(ok);
        }
        w.write_event(Event::End(BytesEnd::new("ModelVariables"))).expect(ok);

        // ModelStructure indices are 1-based positions in ModelVariables.
        let outputs: Vec<(usize, &Variable)> =
            self.variables.iter().enumerate().filter(|(_, v)| v.causality == Causality::Output).map(|(i, v)| (i + 1, v)).collect();
        w.write_event(Event::Start(BytesStart::new("ModelStructure"))).expect(ok);
        if !outputs.is_empty() {
            w.write_event(Event::Start(BytesStart::new("Outputs"))).expect(ok);
            for (index, v) in &outputs {
                let deps = v.output_dependencies.iter().map(usize::to_string).collect::<Vec<_>>().join(" ");
                let kinds = vec!["dependent"; v.output_dependencies.len()].join(" ");
                let index = index.to_string();
                let mut u = BytesStart::new("Unknown").with_attributes([("index", index.as_str()), ("dependencies", deps.as_str())]);
                u.push_attribute(("dependenciesKind", kinds.as_str()));
                w.write_event(Event::Empty(u)).expect(ok);
            }
            w.write_event(Event::End(BytesEnd::new("Outputs"))).expect(ok);
            // Every output is calculated during initialization from parameters (and, with
            // direct feedthrough, inputs); no dependencies attribute means "may depend on all".
            w.write_event(Event::Start(BytesStart::new("InitialUnknowns"))).expect(ok);
            for (index, _) in &outputs {
                let index = index.to_string();
                w.write_event(Event::Empty(BytesStart::new("Unknown").with_attributes([("index", index.as_str())]))).expect(ok);
            }
            w.write_event(Event::End(BytesEnd::new("InitialUnknowns"))).expect(ok);
        }
        w.write_event(Event::End(BytesEnd::new("ModelStructure"))).expect(ok);
        w.write_event(Event::End(BytesEnd::new("fmiModelDescription"))).expect(ok);
        let mut text = String::from_utf8(w.into_inner().into_inner()).expect("XML is UTF-8");
        text.push('\n');
        text
    }
}

fn causality_name(c: Causality) -> &'static str {
    match c {
        Causality::Parameter => "parameter",
        Causality::Input => "input",
        Causality::Output => "output",
        Causality::Local => "local",
        Causality::Independent => "independent",
    }
}

fn variability_name(v: Variability) -> &'static str {
    match v {
        Variability::Constant => "constant",
        Variability::Fixed => "fixed",
        Variability::Tunable => "tunable",
        Variability::Discrete => "discrete",
        Variability::Continuous => "continuous",
    }
}

/// Builds a variable table, numbering value references per base type in order of addition.
#[derive(Debug, Default)]
pub struct TableBuilder {
    variables: Vec<Variable>,
    counts: [u32; 4],
}

impl TableBuilder {
    /// An empty table with `time` (the independent variable) first.
    pub fn new() -> Self {
        let mut b = Self::default();
        b.push("time", Causality::Independent, Variability::Continuous, Kind::Real { start: None, unit: "s" }, "Simulation time");
        b
    }

    /// Adds a variable and returns its value reference.
    pub fn push(
        &mut self,
        name: impl Into<String>,
        causality: Causality,
        variability: Variability,
        kind: Kind,
        description: impl Into<String>,
    ) -> u32 {
        let slot = match kind {
            Kind::Real { .. } => 0,
            Kind::Integer { .. } => 1,
            Kind::Boolean { .. } => 2,
            Kind::String { .. } => 3,
        };
        let vr = self.counts[slot];
        self.counts[slot] += 1;
        self.variables.push(Variable {
            name: name.into(),
            value_reference: vr,
            causality,
            variability,
            kind,
            description: description.into(),
            output_dependencies: Vec::new(),
        });
        vr
    }

    /// Adds a real input with its start value [unit].
    pub fn input(&mut self, name: impl Into<String>, unit: &'static str, start: f64, description: impl Into<String>) -> u32 {
        self.push(name, Causality::Input, Variability::Continuous, Kind::Real { start: Some(start), unit }, description)
    }

    /// Adds a real output [unit] that depends directly on the inputs named in `depends_on`.
    pub fn output(&mut self, name: impl Into<String>, unit: &'static str, description: impl Into<String>, depends_on: &[u32]) -> u32 {
        let vr = self.push(name, Causality::Output, Variability::Continuous, Kind::Real { start: None, unit }, description);
        let deps: Vec<usize> = depends_on
            .iter()
            .map(|&input_vr| {
                1 + self
                    .variables
                    .iter()
                    .position(|v| v.causality == Causality::Input && v.base_type() == BaseType::Real && v.value_reference == input_vr)
                    .expect("dependency on a real input added earlier")
            })
            .collect();
        self.variables.last_mut().expect("just pushed").output_dependencies = deps;
        vr
    }

    /// Adds a fixed real parameter [unit].
    pub fn parameter(&mut self, name: impl Into<String>, unit: &'static str, start: f64, description: impl Into<String>) -> u32 {
        self.push(name, Causality::Parameter, Variability::Fixed, Kind::Real { start: Some(start), unit }, description)
    }

    /// The finished table.
    pub fn finish(self) -> Vec<Variable> {
        self.variables
    }
}
