//! A model's interface as one table of variables, and the `modelDescription.xml` written
//! from it. The ABI's dispatch reads the same table, so the two cannot disagree.

use std::io::Cursor;

use quick_xml::events::{BytesEnd, BytesStart, Event};
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

impl Causality {
    /// The name `modelDescription.xml` uses.
    pub fn name(self) -> &'static str {
        match self {
            Causality::Parameter => "parameter",
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Local => "local",
            Causality::Independent => "independent",
        }
    }
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

impl Variability {
    /// The name `modelDescription.xml` uses.
    pub fn name(self) -> &'static str {
        match self {
            Variability::Constant => "constant",
            Variability::Fixed => "fixed",
            Variability::Tunable => "tunable",
            Variability::Discrete => "discrete",
            Variability::Continuous => "continuous",
        }
    }
}

/// A unit as FMI 2.0 defines one: a name, exponents of the base units kg, m, s, A, K, mol, cd,
/// rad, and `base value = factor · value + offset`; `UnitDefinitions` lists those a model uses.
/// ```
/// # use neurarm_fmi_export::description::Unit;
/// const NEWTON_METRE: Unit = Unit::new("N.m").kg(1).m(2).s(-2); // kg·m²·s⁻²
/// assert_eq!(NEWTON_METRE.exponents(), [1, 2, -2, 0, 0, 0, 0, 0]);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Unit {
    /// Name as variables refer to it, e.g. `"N.m"`.
    pub name: &'static str,
    exponents: [i8; 8],
    /// Factor to the base units (1 for a coherent SI unit).
    pub factor: f64,
    /// Offset to the base units (0 but for temperature scales).
    pub offset: f64,
}

/// Names of the SI base units in [`Unit::exponents`] order, as `BaseUnit` attributes.
pub const BASE_UNITS: [&str; 8] = ["kg", "m", "s", "A", "K", "mol", "cd", "rad"];

/// Writes the `UnitDefinitions` element of `units` (nothing for none), the same in FMI 2.0
/// and FMI 3.0: a `Unit` each with its `BaseUnit` exponents, factor and offset.
pub fn write_unit_definitions(w: &mut Writer<Cursor<Vec<u8>>>, units: &[&Unit]) {
    let ok = "writing XML to memory cannot fail";
    if units.is_empty() {
        return;
    }
    w.write_event(Event::Start(BytesStart::new("UnitDefinitions"))).expect(ok);
    for u in units {
        w.write_event(Event::Start(BytesStart::new("Unit").with_attributes([("name", u.name)]))).expect(ok);
        let mut attributes: Vec<(&str, String)> =
            BASE_UNITS.iter().zip(u.exponents()).filter(|(_, e)| *e != 0).map(|(n, e)| (*n, e.to_string())).collect();
        if u.factor != 1.0 {
            attributes.push(("factor", u.factor.to_string()));
        }
        if u.offset != 0.0 {
            attributes.push(("offset", u.offset.to_string()));
        }
        let base = BytesStart::new("BaseUnit").with_attributes(attributes.iter().map(|(n, e)| (*n, e.as_str())));
        w.write_event(Event::Empty(base)).expect(ok);
        w.write_event(Event::End(BytesEnd::new("Unit"))).expect(ok);
    }
    w.write_event(Event::End(BytesEnd::new("UnitDefinitions"))).expect(ok);
}

impl Unit {
    /// The second, the unit of time.
    pub const SECOND: Unit = Unit::new("s").s(1);

    /// A dimensionless unit called `name` (factor 1, offset 0); give it dimensions with the
    /// base-unit methods.
    pub const fn new(name: &'static str) -> Self {
        Self { name, exponents: [0; 8], factor: 1.0, offset: 0.0 }
    }

    const fn with(mut self, index: usize, exponent: i8) -> Self {
        self.exponents[index] = exponent;
        self
    }

    /// With kilogram to the power `e`.
    pub const fn kg(self, e: i8) -> Self {
        self.with(0, e)
    }
    /// With metre to the power `e`.
    pub const fn m(self, e: i8) -> Self {
        self.with(1, e)
    }
    /// With second to the power `e`.
    pub const fn s(self, e: i8) -> Self {
        self.with(2, e)
    }
    /// With ampere to the power `e`.
    pub const fn ampere(self, e: i8) -> Self {
        self.with(3, e)
    }
    /// With kelvin to the power `e`.
    pub const fn kelvin(self, e: i8) -> Self {
        self.with(4, e)
    }
    /// With mole to the power `e`.
    pub const fn mol(self, e: i8) -> Self {
        self.with(5, e)
    }
    /// With candela to the power `e`.
    pub const fn cd(self, e: i8) -> Self {
        self.with(6, e)
    }
    /// With radian to the power `e`.
    pub const fn rad(self, e: i8) -> Self {
        self.with(7, e)
    }
    /// With `factor` and `offset` to the base units.
    pub const fn scaled(mut self, factor: f64, offset: f64) -> Self {
        self.factor = factor;
        self.offset = offset;
        self
    }

    /// Exponents of kg, m, s, A, K, mol, cd, rad.
    pub const fn exponents(&self) -> [i8; 8] {
        self.exponents
    }
}

/// Type, start value and unit of a variable.
#[derive(Clone, Debug, PartialEq)]
pub enum Kind {
    /// A real number, with its unit if it has one.
    Real {
        /// Start value; `None` for computed outputs and the independent variable.
        start: Option<f64>,
        /// Unit; `None` for a plain number.
        unit: Option<Unit>,
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
    /// An enumeration: one of the items of a declared type. Its values are read and set with
    /// `fmi2GetInteger`/`fmi2SetInteger` and share the Integer value references.
    Enumeration {
        /// The declared type, listed in `TypeDefinitions`.
        declared_type: EnumerationType,
        /// Start value: one of the items' values.
        start: Option<i32>,
    },
}

/// An enumeration type (`TypeDefinitions/SimpleType/Enumeration`): named items with their
/// integer values.
#[derive(Clone, Debug, PartialEq)]
pub struct EnumerationType {
    /// The type's name, which variables give as `declaredType`.
    pub name: String,
    /// The items: name, value, description.
    pub items: Vec<EnumerationItem>,
}

/// One item of an [`EnumerationType`].
#[derive(Clone, Debug, PartialEq)]
pub struct EnumerationItem {
    /// Name, unique in the type.
    pub name: String,
    /// Value, unique in the type.
    pub value: i32,
    /// What it means.
    pub description: String,
}

impl EnumerationType {
    /// A type called `name` whose items are `items` (name, description), valued 1, 2, ….
    pub fn new(name: impl Into<String>, items: &[(&str, &str)]) -> Self {
        let items = items
            .iter()
            .zip(1..)
            .map(|(&(n, d), value)| EnumerationItem { name: n.to_owned(), value, description: d.to_owned() })
            .collect();
        Self { name: name.into(), items }
    }

    /// The item of value `value`, if any.
    pub fn item(&self, value: i32) -> Option<&EnumerationItem> {
        self.items.iter().find(|i| i.value == value)
    }
}

impl Kind {
    /// The start value as `modelDescription.xml` writes it, if there is one.
    pub fn start_text(&self) -> Option<String> {
        match self {
            Kind::Real { start, .. } => start.map(|s| s.to_string()),
            Kind::Integer { start } => start.map(|s| s.to_string()),
            Kind::Boolean { start } => start.map(|s| s.to_string()),
            Kind::String { start } => start.clone(),
            Kind::Enumeration { start, .. } => start.map(|s| s.to_string()),
        }
    }

    /// The unit of a real, if any.
    pub fn unit(&self) -> Option<&Unit> {
        match self {
            Kind::Real { unit, .. } => unit.as_ref(),
            _ => None,
        }
    }
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

    /// Position in per-type arrays: Real, Integer, Boolean, String.
    pub(crate) fn slot(self) -> usize {
        self as usize
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
            Kind::Enumeration { .. } => BaseType::Integer,
        }
    }

    /// Whether the variable has `initial="exact"`: a parameter, or an output given a start
    /// value (which the environment may set before initialization).
    pub fn is_exact(&self) -> bool {
        match self.causality {
            Causality::Parameter => true,
            Causality::Output | Causality::Local => self.kind.start_text().is_some(),
            _ => false,
        }
    }

    /// Whether `fmi2Set*` may change this variable in `phase` (FMI 2.0, section 4.2.4).
    pub fn settable_in(&self, phase: SetPhase) -> bool {
        use Causality::*;
        match self.causality {
            // FMI 2.0 (4.2.4): before and in initialization mode, a variable with
            // initial="exact" may be set; an output or local with a start value is one.
            Output | Local => self.is_exact() && phase != SetPhase::Running && self.variability != Variability::Constant,
            Independent => false,
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

/// A log category the layer declares.
#[derive(Clone, Debug, PartialEq)]
pub struct LogCategory {
    /// Name passed to `fmi2SetDebugLogging`.
    pub name: &'static str,
    /// What it reports.
    pub description: &'static str,
}

/// The categories every FMU of this layer declares.
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

/// Why a variable table cannot describe an FMU.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum DescriptionError {
    /// Two variables have the same name.
    #[error("variable name '{0}' repeated")]
    RepeatedName(String),
    /// Two variables of one base type have the same value reference.
    #[error("value reference {value_reference} of '{name}' repeated")]
    RepeatedValueReference {
        /// The second variable with it.
        name: String,
        /// The value reference.
        value_reference: u32,
    },
    /// A parameter or input without a start value.
    #[error("'{0}' needs a start value")]
    MissingStart(String),
    /// An output or the independent variable with a start value.
    #[error("'{0}' must not have a start value")]
    ForbiddenStart(String),
    /// An output dependency that is not an input, or a dependency listed by a non-output.
    #[error("'{name}' lists dependency {index}, which is not an input")]
    BadDependency {
        /// The variable listing it.
        name: String,
        /// The 1-based index listed.
        index: usize,
    },
    /// An enumeration type without items, with repeated names or values, or two types of
    /// one name with different items.
    #[error("enumeration type '{0}': {1}")]
    BadEnumeration(String, &'static str),
    /// An enumeration start value that is none of its type's items.
    #[error("'{0}' starts at {1}, which is not an item of its enumeration type")]
    BadEnumerationStart(String, i32),
    /// Two units of the same name with different definitions.
    #[error("unit '{0}' is declared twice with different definitions")]
    UnitConflict(&'static str),
    /// A model identifier that is no C identifier.
    #[error("model identifier '{0}' must start with a letter or '_' and hold only ASCII letters, digits and '_'")]
    BadIdentifier(String),
}

/// A model's complete interface.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelDescription {
    /// Model name.
    pub model_name: String,
    /// Model identifier: the name of the shared library in `binaries/` and a C identifier.
    pub model_identifier: String,
    /// One-line description.
    pub description: String,
    /// `generationTool`: what made the FMU, e.g. `"mytool 1.2"`.
    pub generation_tool: String,
    /// Suggested experiment, if any.
    pub default_experiment: Option<DefaultExperiment>,
    /// The variables, in `ModelVariables` order.
    pub variables: Vec<Variable>,
    /// `canHandleVariableCommunicationStepSize`: true unless the model steps only at one fixed
    /// communication step ([`ModelDescription::with_fixed_communication_step`]), which the
    /// layer then enforces.
    pub can_handle_variable_step: bool,
}

impl ModelDescription {
    /// A checked description of the model `identifier` (also its name), generated by this
    /// crate and with no default experiment; set those fields to change them.
    pub fn new(identifier: &str, description: impl Into<String>, variables: Vec<Variable>) -> Result<Self, DescriptionError> {
        let d = Self {
            model_name: identifier.to_owned(),
            model_identifier: identifier.to_owned(),
            description: description.into(),
            generation_tool: concat!("neurarm-fmi-export ", env!("CARGO_PKG_VERSION")).to_owned(),
            default_experiment: None,
            variables,
            can_handle_variable_step: true,
        };
        d.check()?;
        Ok(d)
    }

    /// The same description generated by `tool`.
    pub fn with_generation_tool(mut self, tool: impl Into<String>) -> Self {
        self.generation_tool = tool.into();
        self
    }

    /// The same description suggesting `experiment`.
    pub fn with_default_experiment(mut self, experiment: DefaultExperiment) -> Self {
        self.default_experiment = Some(experiment);
        self
    }

    /// The same description for a model that can only step at one communication step size:
    /// `canHandleVariableCommunicationStepSize="false"`; the layer refuses a step of another
    /// size than the first.
    pub fn with_fixed_communication_step(mut self) -> Self {
        self.can_handle_variable_step = false;
        self
    }

    /// The enumeration types the variables use, each once, in order of first use.
    pub fn enumeration_types(&self) -> Vec<&EnumerationType> {
        let mut used: Vec<&EnumerationType> = Vec::new();
        for v in &self.variables {
            if let Kind::Enumeration { declared_type, .. } = &v.kind {
                if !used.iter().any(|t| t.name == declared_type.name) {
                    used.push(declared_type);
                }
            }
        }
        used
    }

    /// The GUID: a UUID (v5) of the model description with an empty GUID, so any change of
    /// the interface or of a start value gives a new one.
    pub fn guid(&self) -> String {
        let xml = crate::fmi2::description::to_xml_with_guid(self, "");
        // A fixed namespace: other bytes would change the GUID of every FMU.
        let namespace = uuid::Uuid::from_bytes(*b"fmi2-export.guid");
        format!("{{{}}}", uuid::Uuid::new_v5(&namespace, xml.as_bytes()))
    }

    /// `modelDescription.xml`.
    pub fn to_xml(&self) -> String {
        crate::fmi2::description::to_xml_with_guid(self, &self.guid())
    }

    /// The units the variables use, each once, in order of first use.
    pub fn units(&self) -> Vec<&Unit> {
        let mut used: Vec<&Unit> = Vec::new();
        for u in self.variables.iter().filter_map(|v| v.kind.unit()) {
            if !used.iter().any(|x| x.name == u.name) {
                used.push(u);
            }
        }
        used
    }

    /// Checks the table: a C identifier, unique names, value references unique per type,
    /// start values where FMI requires them and nowhere it forbids them, dependencies
    /// pointing at inputs, one definition per unit name.
    pub fn check(&self) -> Result<(), DescriptionError> {
        check_identifier(&self.model_identifier)?;
        let mut names = std::collections::HashSet::new();
        let mut refs = std::collections::HashSet::new();
        let mut units: Vec<&Unit> = Vec::new();
        let mut enumerations: Vec<&EnumerationType> = Vec::new();
        for v in &self.variables {
            if !names.insert(v.name.as_str()) {
                return Err(DescriptionError::RepeatedName(v.name.clone()));
            }
            if !refs.insert((v.base_type(), v.value_reference)) {
                return Err(DescriptionError::RepeatedValueReference { name: v.name.clone(), value_reference: v.value_reference });
            }
            if let Some(u) = v.kind.unit() {
                match units.iter().find(|x| x.name == u.name) {
                    Some(x) if *x != u => return Err(DescriptionError::UnitConflict(u.name)),
                    Some(_) => {}
                    None => units.push(u),
                }
            }
            if let Kind::Enumeration { declared_type: t, start } = &v.kind {
                check_enumeration(t)?;
                match enumerations.iter().find(|x| x.name == t.name) {
                    Some(x) if *x != t => {
                        return Err(DescriptionError::BadEnumeration(t.name.clone(), "declared twice with different items"))
                    }
                    Some(_) => {}
                    None => enumerations.push(t),
                }
                if let Some(value) = start.filter(|&s| t.item(s).is_none()) {
                    return Err(DescriptionError::BadEnumerationStart(v.name.clone(), value));
                }
            }
            let has_start = v.kind.start_text().is_some();
            let needs_start = matches!(v.causality, Causality::Parameter | Causality::Input);
            // An output may have a start value: it then has initial="exact".
            let forbids_start = v.causality == Causality::Independent;
            if needs_start && !has_start {
                return Err(DescriptionError::MissingStart(v.name.clone()));
            }
            if forbids_start && has_start {
                return Err(DescriptionError::ForbiddenStart(v.name.clone()));
            }
            for &d in &v.output_dependencies {
                let ok = self.variables.get(d.wrapping_sub(1)).is_some_and(|x| x.causality == Causality::Input);
                if v.causality != Causality::Output || !ok {
                    return Err(DescriptionError::BadDependency { name: v.name.clone(), index: d });
                }
            }
        }
        Ok(())
    }
}

fn check_enumeration(t: &EnumerationType) -> Result<(), DescriptionError> {
    let bad = |why| Err(DescriptionError::BadEnumeration(t.name.clone(), why));
    if t.name.is_empty() {
        return bad("the type has no name");
    }
    if t.items.is_empty() {
        return bad("it has no items");
    }
    for (k, item) in t.items.iter().enumerate() {
        if item.name.is_empty() {
            return bad("an item has no name");
        }
        if t.items[..k].iter().any(|x| x.name == item.name) {
            return bad("two items have the same name");
        }
        if t.items[..k].iter().any(|x| x.value == item.value) {
            return bad("two items have the same value");
        }
    }
    Ok(())
}

/// A model identifier must be usable as a C identifier and a file name.
pub fn check_identifier(id: &str) -> Result<(), DescriptionError> {
    let mut chars = id.chars();
    let ok = chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_') && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
    if ok {
        Ok(())
    } else {
        Err(DescriptionError::BadIdentifier(id.to_owned()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::table::TableBuilder;

    const NEWTON_METRE: Unit = Unit::new("N.m").kg(1).m(2).s(-2);

    #[test]
    fn unit_definitions_are_the_units_used_each_once() {
        let mut b = TableBuilder::new();
        let u = b.input("tau", NEWTON_METRE, 0.0, "torque");
        b.output("y", NEWTON_METRE, "twice", &[u]);
        b.parameter("k", None, 2.0, "plain number");
        let d = ModelDescription::new("Twice", "y = 2 tau", b.finish()).unwrap();
        let xml = d.to_xml();
        let defs = &xml[xml.find("<UnitDefinitions>").unwrap()..xml.find("</UnitDefinitions>").unwrap()];
        assert_eq!(defs.matches("<Unit ").count(), 2, "s (time) and N.m: {defs}");
        assert!(defs.contains(r#"<Unit name="N.m">"#) && defs.contains(r#"<BaseUnit kg="1" m="2" s="-2"/>"#), "{defs}");
        assert!(defs.contains(r#"<Unit name="s">"#) && defs.contains(r#"<BaseUnit s="1"/>"#), "{defs}");
        assert!(!xml.contains("DefaultExperiment"), "none unless the model suggests one");
    }

    #[test]
    fn a_unit_name_with_two_definitions_is_refused() {
        let mut b = TableBuilder::new();
        b.parameter("a", Unit::new("N.m").kg(1).m(2).s(-2), 1.0, "");
        b.parameter("b", Unit::new("N.m").kg(1).m(1).s(-2), 1.0, "");
        assert_eq!(ModelDescription::new("Two", "", b.finish()).unwrap_err(), DescriptionError::UnitConflict("N.m"));
    }

    #[test]
    fn scaled_units_write_factor_and_offset() {
        let mut b = TableBuilder::new();
        b.parameter("t", Unit::new("degC").kelvin(1).scaled(1.0, 273.15), 20.0, "temperature");
        let xml = ModelDescription::new("Temp", "", b.finish()).unwrap().to_xml();
        assert!(xml.contains(r#"<BaseUnit K="1" offset="273.15"/>"#), "{xml}");
    }

    #[test]
    fn identifiers_must_be_c_identifiers() {
        for bad in ["", "1abc", "a-b", "a b", "ä"] {
            assert!(ModelDescription::new(bad, "", TableBuilder::new().finish()).is_err(), "{bad:?}");
        }
        assert!(ModelDescription::new("_Arm2", "", TableBuilder::new().finish()).is_ok());
    }
}
