//! An FMU's interface, read once from the `modelDescription.xml` in its archive without
//! loading its binary: the variables with their value references, base types and
//! causalities, and which inputs feed outputs directly (`ModelStructure/Outputs`). The
//! system plan, the simulation and the SSP writer all use this one reading.

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use quick_xml::events::attributes::Attributes;
use quick_xml::events::Event;

/// A variable's base type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BaseType {
    /// fmi2Real.
    Real,
    /// fmi2Integer.
    Integer,
    /// fmi2Boolean.
    Boolean,
    /// fmi2String.
    String,
    /// An enumeration (not supported in connections).
    Enumeration,
}

impl BaseType {
    /// The element name in `modelDescription.xml` and SSP.
    pub fn name(self) -> &'static str {
        match self {
            BaseType::Real => "Real",
            BaseType::Integer => "Integer",
            BaseType::Boolean => "Boolean",
            BaseType::String => "String",
            BaseType::Enumeration => "Enumeration",
        }
    }

    /// Whether connections and recordings handle this type.
    pub fn is_connectable(self) -> bool {
        matches!(self, BaseType::Real | BaseType::Integer | BaseType::Boolean)
    }
}

/// A variable's causality.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    /// `parameter`.
    Parameter,
    /// `calculatedParameter`.
    CalculatedParameter,
    /// `input`.
    Input,
    /// `output`.
    Output,
    /// `local` (also the default when the attribute is absent).
    Local,
    /// `independent`.
    Independent,
}

impl Causality {
    /// The name as `modelDescription.xml` writes it.
    pub fn name(self) -> &'static str {
        match self {
            Causality::Parameter => "parameter",
            Causality::CalculatedParameter => "calculatedParameter",
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Local => "local",
            Causality::Independent => "independent",
        }
    }

    /// The name with its article, for messages ("an output", "a parameter").
    pub fn with_article(self) -> String {
        let name = self.name();
        let article = if name.starts_with(['a', 'e', 'i', 'o', 'u']) { "an" } else { "a" };
        format!("{article} {name}")
    }
}

/// A variable of an FMU.
#[derive(Clone, Debug, PartialEq)]
pub struct VariableInfo {
    /// Name.
    pub name: String,
    /// Value reference.
    pub value_reference: u32,
    /// Base type.
    pub base: BaseType,
    /// Causality.
    pub causality: Causality,
}

/// What the master needs to know of an FMU before loading it.
#[derive(Clone, Debug, PartialEq)]
pub struct Interface {
    /// `modelIdentifier` of the Co-Simulation interface.
    pub model_identifier: String,
    /// The variables in `ModelVariables` order.
    pub variables: Vec<VariableInfo>,
    /// Value references of the inputs that some output depends on directly.
    pub feedthrough_inputs: Vec<u32>,
    by_name: HashMap<String, usize>,
}

impl Interface {
    /// Reads the interface of the FMU archive at `path`. Messages name the file.
    pub fn read(path: &Path) -> Result<Self, String> {
        let fail = |why: String| format!("cannot load {}: {why}", path.display());
        let file = std::fs::File::open(path).map_err(|e| fail(e.to_string()))?;
        let mut archive = zip::ZipArchive::new(file).map_err(|e| fail(format!("it is not an FMU (not a zip archive: {e})")))?;
        let mut xml = String::new();
        archive
            .by_name("modelDescription.xml")
            .map_err(|e| fail(format!("it is not an FMU (no modelDescription.xml: {e})")))?
            .read_to_string(&mut xml)
            .map_err(|e| fail(format!("reading modelDescription.xml: {e}")))?;
        Self::parse(&xml).map_err(|e| fail(format!("modelDescription.xml: {e}")))
    }

    /// Parses the text of a `modelDescription.xml`: FMI 2.0 Co-Simulation only.
    pub fn parse(xml: &str) -> Result<Self, String> {
        let mut reader = quick_xml::Reader::from_str(xml);
        let mut version = None;
        let mut model_identifier = None;
        let mut variables: Vec<VariableInfo> = Vec::new();
        // The ScalarVariable being read: (name, causality, value reference, base type once seen).
        let mut current: Option<(String, Causality, u32, Option<BaseType>)> = None;
        let mut in_outputs = false;
        // Per output in ModelStructure/Outputs: its 1-based dependencies, None when absent.
        let mut output_dependencies: Vec<Option<Vec<usize>>> = Vec::new();
        loop {
            let event = reader.read_event().map_err(|e| format!("at byte {}: {e}", reader.error_position()))?;
            match event {
                Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"fmiModelDescription" => {
                    version = attribute(e.attributes(), b"fmiVersion")?;
                }
                Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"CoSimulation" => {
                    model_identifier = Some(attribute(e.attributes(), b"modelIdentifier")?.ok_or("CoSimulation has no modelIdentifier")?);
                }
                Event::Start(e) if e.name().as_ref() == b"ScalarVariable" => {
                    let name = attribute(e.attributes(), b"name")?.ok_or("a ScalarVariable has no name")?;
                    let causality = match attribute(e.attributes(), b"causality")?.as_deref() {
                        Some("parameter") => Causality::Parameter,
                        Some("calculatedParameter") => Causality::CalculatedParameter,
                        Some("input") => Causality::Input,
                        Some("output") => Causality::Output,
                        Some("independent") => Causality::Independent,
                        _ => Causality::Local,
                    };
                    let vr = match attribute(e.attributes(), b"valueReference")? {
                        Some(t) => t.trim().parse().map_err(|_| format!("variable '{name}': valueReference '{t}' is not a number"))?,
                        None => return Err(format!("variable '{name}' has no valueReference")),
                    };
                    current = Some((name, causality, vr, None));
                }
                Event::Start(e) | Event::Empty(e) if current.as_ref().is_some_and(|c| c.3.is_none()) => {
                    let base = match e.name().as_ref() {
                        b"Real" => Some(BaseType::Real),
                        b"Integer" => Some(BaseType::Integer),
                        b"Boolean" => Some(BaseType::Boolean),
                        b"String" => Some(BaseType::String),
                        b"Enumeration" => Some(BaseType::Enumeration),
                        _ => None,
                    };
                    if let Some(c) = current.as_mut() {
                        c.3 = base;
                    }
                }
                Event::End(e) if e.name().as_ref() == b"ScalarVariable" => {
                    let (name, causality, value_reference, base) = current.take().ok_or("unbalanced ScalarVariable")?;
                    let base = base.ok_or_else(|| format!("variable '{name}' has no type element"))?;
                    variables.push(VariableInfo { name, value_reference, base, causality });
                }
                Event::Start(e) if e.name().as_ref() == b"Outputs" => in_outputs = true,
                Event::End(e) if e.name().as_ref() == b"Outputs" => in_outputs = false,
                Event::Start(e) | Event::Empty(e) if in_outputs && e.name().as_ref() == b"Unknown" => {
                    let deps = match attribute(e.attributes(), b"dependencies")? {
                        None => None,
                        Some(text) => Some(
                            text.split_whitespace()
                                .map(|t| t.parse::<usize>().map_err(|_| format!("dependencies: '{t}' is not an index")))
                                .collect::<Result<Vec<_>, _>>()?,
                        ),
                    };
                    output_dependencies.push(deps);
                }
                Event::Eof => break,
                _ => {}
            }
        }
        match version.as_deref() {
            Some("2.0") => {}
            Some(v) => return Err(format!("fmiVersion is {v}; only FMI 2.0 is supported")),
            None => return Err("no fmiModelDescription element with an fmiVersion".into()),
        }
        let model_identifier = model_identifier.ok_or("not a Co-Simulation FMU (no CoSimulation element)")?;
        let mut by_name = HashMap::with_capacity(variables.len());
        for (i, v) in variables.iter().enumerate() {
            if by_name.insert(v.name.clone(), i).is_some() {
                return Err(format!("two variables are named '{}'", v.name));
            }
        }
        let inputs: Vec<u32> = variables.iter().filter(|v| v.causality == Causality::Input).map(|v| v.value_reference).collect();
        let mut feedthrough_inputs: Vec<u32> = Vec::new();
        for deps in output_dependencies {
            let listed: Vec<u32> = match deps {
                // No `dependencies` attribute: the output may depend on every input.
                None => inputs.clone(),
                Some(list) => list
                    .iter()
                    .filter_map(|&i| variables.get(i.wrapping_sub(1)))
                    .filter(|v| v.causality == Causality::Input)
                    .map(|v| v.value_reference)
                    .collect(),
            };
            for vr in listed {
                if !feedthrough_inputs.contains(&vr) {
                    feedthrough_inputs.push(vr);
                }
            }
        }
        Ok(Self { model_identifier, variables, feedthrough_inputs, by_name })
    }

    /// A variable by name.
    pub fn get(&self, name: &str) -> Option<&VariableInfo> {
        self.by_name.get(name).map(|&i| &self.variables[i])
    }

    /// Whether some output depends directly on an input.
    pub fn has_feedthrough(&self) -> bool {
        !self.feedthrough_inputs.is_empty()
    }

    /// The names of the outputs, in `ModelVariables` order.
    pub fn outputs(&self) -> impl Iterator<Item = &str> {
        self.variables.iter().filter(|v| v.causality == Causality::Output).map(|v| v.name.as_str())
    }
}

fn attribute(attrs: Attributes, key: &[u8]) -> Result<Option<String>, String> {
    for a in attrs {
        let a = a.map_err(|e| e.to_string())?;
        if a.key.as_ref() == key {
            return Ok(Some(a.unescape_value().map_err(|e| e.to_string())?.into_owned()));
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    const XML: &str = r#"<?xml version="1.0"?>
<fmiModelDescription fmiVersion="2.0" modelName="M" guid="{x}">
  <CoSimulation modelIdentifier="M"/>
  <ModelVariables>
    <ScalarVariable name="u" valueReference="0" causality="input"><Real start="0"/></ScalarVariable>
    <ScalarVariable name="w" valueReference="1" causality="input"><Real start="0"/></ScalarVariable>
    <ScalarVariable name="y" valueReference="2" causality="output"><Real/></ScalarVariable>
    <ScalarVariable name="z" valueReference="3" causality="output"><Real/></ScalarVariable>
    <ScalarVariable name="on" valueReference="0" causality="parameter" variability="tunable"><Boolean start="true"/></ScalarVariable>
  </ModelVariables>
  <ModelStructure><Outputs><Unknown index="3" dependencies="2"/><Unknown index="4" dependencies=""/></Outputs></ModelStructure>
</fmiModelDescription>"#;

    #[test]
    fn variables_types_and_feedthrough_are_read() {
        let i = Interface::parse(XML).unwrap();
        assert_eq!(i.model_identifier, "M");
        assert_eq!(i.variables.len(), 5);
        assert_eq!(i.get("on").map(|v| (v.base, v.causality)), Some((BaseType::Boolean, Causality::Parameter)));
        assert_eq!(i.feedthrough_inputs, [1], "y depends on w (index 2) only; z on nothing");
        assert_eq!(i.outputs().collect::<Vec<_>>(), ["y", "z"]);
        // An absent dependencies attribute means every input.
        let all = Interface::parse(&XML.replace(r#"<Unknown index="3" dependencies="2"/>"#, r#"<Unknown index="3"/>"#)).unwrap();
        assert_eq!(all.feedthrough_inputs, [0, 1]);
    }

    #[test]
    fn other_versions_and_model_exchange_are_refused() {
        let e = Interface::parse(&XML.replace(r#"fmiVersion="2.0""#, r#"fmiVersion="3.0""#)).unwrap_err();
        assert!(e.contains("only FMI 2.0"), "{e}");
        let e = Interface::parse(&XML.replace(r#"<CoSimulation modelIdentifier="M"/>"#, r#"<ModelExchange modelIdentifier="M"/>"#))
            .unwrap_err();
        assert!(e.contains("not a Co-Simulation FMU"), "{e}");
        let e = Interface::parse(&XML.replace(r#"name="w""#, r#"name="u""#)).unwrap_err();
        assert!(e.contains("two variables are named 'u'"), "{e}");
    }
}
