//! The FMI 3.0 `modelDescription.xml` of a model, written from the same table as its FMI 2.0
//! one, and the FMI 3.0 value references.
//!
//! FMI 3.0 wants value references unique over all variables, where FMI 2.0 numbers them per
//! base type (and the FMI 2.0 layer does). Here a variable's FMI 3.0 value reference is its position
//! in `ModelVariables` (time is 0), and [`Fmi3Variables`] maps it back to the base type and FMI
//! 2.0 value reference the shared instance works with.
//!
//! Types: `Real` is `Float64`, `Integer` is `Int32`, `Boolean` and `String` keep their names,
//! and an `Enumeration` is read and set as `Int64` (FMI 3.0 section 2.4.7.5). The variables are
//! scalars; the instantiation token is the FMI 2.0 GUID, so the twins of one model carry the same
//! identity.

use crate::description::BaseType;
use crate::xml::{initial, Xml};
use crate::{Causality, Kind, ModelDescription};
use quick_xml::events::BytesStart;

/// The FMI 3.0 type of a variable: the functions that read and set it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fmi3Type {
    /// `Float64` (an FMI 2.0 `Real`).
    Float64,
    /// `Int32` (an FMI 2.0 `Integer`).
    Int32,
    /// `Enumeration`, accessed with `fmi3GetInt64`/`fmi3SetInt64`.
    Enumeration,
    /// `Boolean`.
    Boolean,
    /// `String`.
    String,
}

impl Fmi3Type {
    /// The type of a variable of `kind`.
    pub fn of(kind: &Kind) -> Self {
        match kind {
            Kind::Real { .. } => Fmi3Type::Float64,
            Kind::Integer { .. } => Fmi3Type::Int32,
            Kind::Enumeration { .. } => Fmi3Type::Enumeration,
            Kind::Boolean { .. } => Fmi3Type::Boolean,
            Kind::String { .. } => Fmi3Type::String,
        }
    }

    /// The XML element name, which is also the name in `fmi3Get…`/`fmi3Set…` (but for
    /// enumerations, which use `Int64`).
    pub fn name(self) -> &'static str {
        match self {
            Fmi3Type::Float64 => "Float64",
            Fmi3Type::Int32 => "Int32",
            Fmi3Type::Enumeration => "Enumeration",
            Fmi3Type::Boolean => "Boolean",
            Fmi3Type::String => "String",
        }
    }

    /// The FMI 2.0 base type the values are kept as.
    pub fn base_type(self) -> BaseType {
        match self {
            Fmi3Type::Float64 => BaseType::Real,
            Fmi3Type::Int32 | Fmi3Type::Enumeration => BaseType::Integer,
            Fmi3Type::Boolean => BaseType::Boolean,
            Fmi3Type::String => BaseType::String,
        }
    }
}

/// The FMI 3.0 value references of a model: for each (its position in the description's
/// variables), the type and the FMI 2.0 value reference.
#[derive(Clone, Debug, PartialEq)]
pub struct Fmi3Variables {
    entries: Vec<(Fmi3Type, u32)>,
}

impl Fmi3Variables {
    /// The value references of `description`.
    pub fn new(description: &ModelDescription) -> Self {
        Self { entries: description.variables.iter().map(|v| (Fmi3Type::of(&v.kind), v.value_reference)).collect() }
    }

    /// Type and FMI 2.0 value reference of the FMI 3.0 value reference `vr`.
    pub fn get(&self, vr: u32) -> Option<(Fmi3Type, u32)> {
        self.entries.get(vr as usize).copied()
    }

    /// The FMI 3.0 value reference of the variable at `index` in the description: the index.
    pub fn value_reference(index: usize) -> u32 {
        u32::try_from(index).expect("fewer than 2^32 variables")
    }

    /// How many variables there are.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }
}

/// The FMI 3.0 `modelDescription.xml` of `d`.
pub fn to_xml(d: &ModelDescription) -> String {
    let token = d.guid();
    let mut x = Xml::new();
    x.start(BytesStart::new("fmiModelDescription").with_attributes([
        ("fmiVersion", "3.0"),
        ("modelName", d.model_name.as_str()),
        ("instantiationToken", token.as_str()),
        ("description", d.description.as_str()),
        ("generationTool", d.generation_tool.as_str()),
        ("variableNamingConvention", "flat"),
    ]));
    x.empty(BytesStart::new("CoSimulation").with_attributes([
        ("modelIdentifier", d.model_identifier.as_str()),
        ("canGetAndSetFMUState", "true"),
        ("canSerializeFMUState", "true"),
        ("canHandleVariableCommunicationStepSize", if d.can_handle_variable_step { "true" } else { "false" }),
        ("hasEventMode", "false"),
    ]));
    x.unit_definitions(&d.units());
    x.type_definitions(d, "EnumerationType", None);
    x.log_categories(|description| description.replace("fmi2", "fmi3"));
    x.default_experiment(d.default_experiment.as_ref());
    model_variables(&mut x, d);
    model_structure(&mut x, d);
    x.end("fmiModelDescription");
    x.finish()
}

/// `ModelVariables`: an element of the variable's FMI 3.0 type per variable.
fn model_variables(x: &mut Xml, d: &ModelDescription) {
    x.start(BytesStart::new("ModelVariables"));
    for (index, v) in d.variables.iter().enumerate() {
        let vr = Fmi3Variables::value_reference(index).to_string();
        let kind = Fmi3Type::of(&v.kind);
        let mut e = BytesStart::new(kind.name()).with_attributes([
            ("name", v.name.as_str()),
            ("valueReference", vr.as_str()),
            ("description", v.description.as_str()),
            ("causality", v.causality.name()),
            ("variability", v.variability.name()),
        ]);
        if let Kind::Enumeration { declared_type, .. } = &v.kind {
            e.push_attribute(("declaredType", declared_type.name.as_str()));
        }
        if let Some(initial) = initial(v) {
            e.push_attribute(("initial", initial));
        }
        if let Some(unit) = v.kind.unit() {
            e.push_attribute(("unit", unit.name));
        }
        match (&v.kind, v.kind.start_text()) {
            // A String's start value is a child element in FMI 3.0 (strings may be arrays).
            (Kind::String { .. }, Some(text)) => {
                x.start(e);
                x.empty(BytesStart::new("Start").with_attributes([("value", text.as_str())]));
                x.end(kind.name());
            }
            (_, start) => {
                if let Some(start) = start {
                    e.push_attribute(("start", start.as_str()));
                }
                x.empty(e);
            }
        }
    }
    x.end("ModelVariables");
}

/// `ModelStructure` by value reference (FMI 2.0: 1-based indices): each output with the
/// inputs it depends on directly (none when empty), then the outputs calculated in
/// initialization.
fn model_structure(x: &mut Xml, d: &ModelDescription) {
    x.start(BytesStart::new("ModelStructure"));
    let outputs: Vec<(usize, &crate::Variable)> =
        d.variables.iter().enumerate().filter(|(_, v)| v.causality == Causality::Output).collect();
    for (index, v) in &outputs {
        let vr = Fmi3Variables::value_reference(*index).to_string();
        // output_dependencies are 1-based indices; the value reference is the 0-based index.
        let deps = v.output_dependencies.iter().map(|i| (i - 1).to_string()).collect::<Vec<_>>().join(" ");
        let mut e = BytesStart::new("Output").with_attributes([("valueReference", vr.as_str()), ("dependencies", deps.as_str())]);
        if !v.output_dependencies.is_empty() {
            let kinds = vec!["dependent"; v.output_dependencies.len()].join(" ");
            e.push_attribute(("dependenciesKind", kinds.as_str()));
        }
        x.empty(e);
    }
    // Outputs without initial="exact" are computed in initialization mode (from parameters
    // and, with direct feedthrough, inputs): no dependencies attribute, "may depend on all".
    for (index, _) in outputs.iter().filter(|(_, v)| !v.is_exact()) {
        let vr = Fmi3Variables::value_reference(*index).to_string();
        x.empty(BytesStart::new("InitialUnknown").with_attributes([("valueReference", vr.as_str())]));
    }
    x.end("ModelStructure");
}
