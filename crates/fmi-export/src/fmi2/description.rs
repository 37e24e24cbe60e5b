//! The FMI 2.0 `modelDescription.xml` of a [`ModelDescription`].

use quick_xml::events::BytesStart;

use crate::description::{Causality, Kind, ModelDescription, Variable};
use crate::xml::{initial, Xml};

/// The FMI 2.0 `modelDescription.xml` of `d` with `guid` (empty while the GUID is computed
/// from it).
pub(crate) fn to_xml_with_guid(d: &ModelDescription, guid: &str) -> String {
    let mut x = Xml::new();
    x.start(BytesStart::new("fmiModelDescription").with_attributes([
        ("fmiVersion", "2.0"),
        ("modelName", d.model_name.as_str()),
        ("guid", guid),
        ("description", d.description.as_str()),
        ("generationTool", d.generation_tool.as_str()),
        ("variableNamingConvention", "flat"),
        ("numberOfEventIndicators", "0"),
    ]));
    x.empty(BytesStart::new("CoSimulation").with_attributes([
        ("modelIdentifier", d.model_identifier.as_str()),
        ("canHandleVariableCommunicationStepSize", if d.can_handle_variable_step { "true" } else { "false" }),
        ("canGetAndSetFMUstate", "true"),
        ("canSerializeFMUstate", "true"),
        ("canNotUseMemoryManagementFunctions", "true"),
    ]));
    x.unit_definitions(&d.units());
    x.type_definitions(d, "SimpleType", Some("Enumeration"));
    x.log_categories(str::to_owned);
    x.default_experiment(d.default_experiment.as_ref());
    model_variables(&mut x, d);
    model_structure(&mut x, d);
    x.end("fmiModelDescription");
    x.finish()
}

/// `ModelVariables`: a `ScalarVariable` per variable, with its type element.
fn model_variables(x: &mut Xml, d: &ModelDescription) {
    x.start(BytesStart::new("ModelVariables"));
    for v in &d.variables {
        let vr = v.value_reference.to_string();
        let mut sv = BytesStart::new("ScalarVariable").with_attributes([
            ("name", v.name.as_str()),
            ("valueReference", vr.as_str()),
            ("description", v.description.as_str()),
            ("causality", v.causality.name()),
            ("variability", v.variability.name()),
        ]);
        if let Some(initial) = initial(v) {
            sv.push_attribute(("initial", initial));
        }
        x.start(sv);
        let mut t = match &v.kind {
            Kind::Enumeration { declared_type, .. } => {
                BytesStart::new("Enumeration").with_attributes([("declaredType", declared_type.name.as_str())])
            }
            _ => BytesStart::new(v.base_type().name()),
        };
        if let Some(unit) = v.kind.unit() {
            t.push_attribute(("unit", unit.name));
        }
        if let Some(start) = v.kind.start_text() {
            t.push_attribute(("start", start.as_str()));
        }
        x.empty(t);
        x.end("ScalarVariable");
    }
    x.end("ModelVariables");
}

/// `ModelStructure`: outputs with their direct dependencies, and the outputs calculated in
/// initialization. Indices are 1-based positions in `ModelVariables`.
fn model_structure(x: &mut Xml, d: &ModelDescription) {
    let outputs: Vec<(usize, &Variable)> =
        d.variables.iter().enumerate().filter(|(_, v)| v.causality == Causality::Output).map(|(i, v)| (i + 1, v)).collect();
    x.start(BytesStart::new("ModelStructure"));
    if !outputs.is_empty() {
        x.start(BytesStart::new("Outputs"));
        for (index, v) in &outputs {
            let deps = v.output_dependencies.iter().map(usize::to_string).collect::<Vec<_>>().join(" ");
            let kinds = vec!["dependent"; v.output_dependencies.len()].join(" ");
            let index = index.to_string();
            let mut u = BytesStart::new("Unknown").with_attributes([("index", index.as_str()), ("dependencies", deps.as_str())]);
            u.push_attribute(("dependenciesKind", kinds.as_str()));
            x.empty(u);
        }
        x.end("Outputs");
    }
    // Outputs without initial="exact" are calculated in initialization from parameters (and,
    // with direct feedthrough, inputs); no dependencies attribute means "may depend on all".
    let calculated: Vec<usize> = outputs.iter().filter(|(_, v)| !v.is_exact()).map(|(i, _)| *i).collect();
    if !calculated.is_empty() {
        x.start(BytesStart::new("InitialUnknowns"));
        for index in &calculated {
            let index = index.to_string();
            x.empty(BytesStart::new("Unknown").with_attributes([("index", index.as_str())]));
        }
        x.end("InitialUnknowns");
    }
    x.end("ModelStructure");
}
