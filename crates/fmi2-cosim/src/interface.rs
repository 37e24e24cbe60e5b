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
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BaseType {
    /// fmi2Real.
    Real,
    /// fmi2Integer.
    Integer,
    /// fmi2Boolean.
    Boolean,
    /// fmi2String.
    String,
    /// An enumeration: read and set as fmi2Integer, sharing the Integer value references.
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

    /// Whether connections and recordings handle this type (all FMI 2.0 types do).
    pub fn is_connectable(self) -> bool {
        true
    }

    /// The type whose `fmi2Get*`/`fmi2Set*` functions and value references this type uses:
    /// Integer for an enumeration, else itself.
    pub fn access(self) -> BaseType {
        match self {
            BaseType::Enumeration => BaseType::Integer,
            t => t,
        }
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

/// A variable's variability.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variability {
    /// `constant`.
    Constant,
    /// `fixed`.
    Fixed,
    /// `tunable`.
    Tunable,
    /// `discrete`.
    Discrete,
    /// `continuous` (also the default when the attribute is absent).
    Continuous,
}

/// A variable's `initial` attribute, or its default from causality and variability (FMI 2.0,
/// section 2.2.7).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Initial {
    /// `exact`: the start value is the initial value.
    Exact,
    /// `approx`: the start value is a guess for an iteration.
    Approx,
    /// `calculated`: computed from other variables during initialization.
    Calculated,
    /// No initial attribute applies (inputs, the independent variable).
    None,
}

/// A variable of an FMU.
#[derive(Clone, Debug, PartialEq)]
pub struct VariableInfo {
    /// Name.
    pub name: String,
    /// Value reference (unique per [`BaseType::access`] type).
    pub value_reference: u32,
    /// Base type.
    pub base: BaseType,
    /// Causality.
    pub causality: Causality,
    /// Variability.
    pub variability: Variability,
    /// `initial`, given or defaulted.
    pub initial: Initial,
    /// The `declaredType` of the type element, if any (an enumeration's type).
    pub declared_type: Option<String>,
    /// For an output: the positions in [`Interface::variables`] of the inputs it depends on
    /// directly (`ModelStructure/Outputs`; every input when the FMU does not say).
    pub direct_inputs: Vec<usize>,
}

impl VariableInfo {
    /// Whether a master may set this variable after instantiation, before initialization:
    /// inputs, and variables that are not constant and have `initial` exact or approx
    /// (parameters, and outputs or locals given a start value) (FMI 2.0, section 4.2.4).
    pub fn settable_before_initialization(&self) -> bool {
        self.causality == Causality::Input
            || (self.variability != Variability::Constant
                && matches!(self.initial, Initial::Exact | Initial::Approx)
                && self.causality != Causality::Independent)
    }
}

/// An enumeration type of `TypeDefinitions`.
#[derive(Clone, Debug, PartialEq)]
pub struct EnumerationInfo {
    /// The type's name.
    pub name: String,
    /// Its items: name and value.
    pub items: Vec<(String, i64)>,
}

/// What the master needs to know of an FMU before loading it.
#[derive(Clone, Debug, PartialEq)]
pub struct Interface {
    /// `modelIdentifier` of the Co-Simulation interface.
    pub model_identifier: String,
    /// The GUID.
    pub guid: String,
    /// `canHandleVariableCommunicationStepSize`.
    pub can_handle_variable_step: bool,
    /// `canBeInstantiatedOnlyOncePerProcess`.
    pub only_once_per_process: bool,
    /// The variables in `ModelVariables` order.
    pub variables: Vec<VariableInfo>,
    /// The enumeration types of `TypeDefinitions`.
    pub enumerations: Vec<EnumerationInfo>,
    by_name: HashMap<String, usize>,
}

/// What is being read of a ScalarVariable.
struct Pending {
    name: String,
    causality: Causality,
    variability: Variability,
    initial: Option<Initial>,
    value_reference: u32,
    base: Option<(BaseType, Option<String>, bool)>,
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
            .take(MAX_DESCRIPTION_BYTES)
            .read_to_string(&mut xml)
            .map_err(|e| fail(format!("reading modelDescription.xml: {e}")))?;
        if xml.len() as u64 >= MAX_DESCRIPTION_BYTES {
            return Err(fail(format!("modelDescription.xml is larger than {} MiB", MAX_DESCRIPTION_BYTES >> 20)));
        }
        Self::parse(&xml).map_err(|e| fail(format!("modelDescription.xml: {e}")))
    }

    /// Parses the text of a `modelDescription.xml`: FMI 2.0 Co-Simulation only.
    pub fn parse(xml: &str) -> Result<Self, String> {
        let mut reader = quick_xml::Reader::from_str(xml);
        let mut version = None;
        let mut guid = None;
        let mut co_simulation: Option<(String, bool, bool)> = None;
        let mut variables: Vec<VariableInfo> = Vec::new();
        let mut enumerations: Vec<EnumerationInfo> = Vec::new();
        // The SimpleType being read, and its items once its Enumeration element was seen.
        let mut simple_type: Option<(String, Option<Items>)> = None;
        let mut current: Option<Pending> = None;
        let mut in_outputs = false;
        // Per output in ModelStructure/Outputs: its 1-based index and dependencies (None:
        // the attribute is absent).
        let mut output_dependencies: Vec<(usize, Option<Vec<usize>>)> = Vec::new();
        loop {
            let event = reader.read_event().map_err(|e| format!("at byte {}: {e}", reader.error_position()))?;
            match event {
                Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"fmiModelDescription" => {
                    version = attribute(e.attributes(), b"fmiVersion")?;
                    guid = attribute(e.attributes(), b"guid")?;
                }
                Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"CoSimulation" => {
                    let id = attribute(e.attributes(), b"modelIdentifier")?.ok_or("CoSimulation has no modelIdentifier")?;
                    let variable = flag(
                        attribute(e.attributes(), b"canHandleVariableCommunicationStepSize")?,
                        "canHandleVariableCommunicationStepSize",
                    )?;
                    let once =
                        flag(attribute(e.attributes(), b"canBeInstantiatedOnlyOncePerProcess")?, "canBeInstantiatedOnlyOncePerProcess")?;
                    co_simulation = Some((id, variable, once));
                }
                Event::Start(e) if e.name().as_ref() == b"SimpleType" => {
                    let name = attribute(e.attributes(), b"name")?.ok_or("a SimpleType has no name")?;
                    simple_type = Some((name, None));
                }
                Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"Enumeration" && simple_type.is_some() && current.is_none() => {
                    if let Some(t) = simple_type.as_mut() {
                        t.1 = Some(Vec::new());
                    }
                }
                Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"Item" => {
                    if let Some((type_name, Some(items))) = simple_type.as_mut() {
                        let name =
                            attribute(e.attributes(), b"name")?.ok_or_else(|| format!("an item of type '{type_name}' has no name"))?;
                        let value = attribute(e.attributes(), b"value")?
                            .ok_or_else(|| format!("item '{name}' of type '{type_name}' has no value"))?;
                        let value = value
                            .trim()
                            .parse()
                            .map_err(|_| format!("item '{name}' of type '{type_name}': value '{value}' is not an integer"))?;
                        items.push((name, value));
                    }
                }
                Event::End(e) if e.name().as_ref() == b"SimpleType" => {
                    if let Some((name, Some(items))) = simple_type.take() {
                        enumerations.push(EnumerationInfo { name, items });
                    }
                }
                Event::Start(e) if e.name().as_ref() == b"ScalarVariable" => {
                    let name = attribute(e.attributes(), b"name")?.ok_or("a ScalarVariable has no name")?;
                    let causality = match attribute(e.attributes(), b"causality")?.as_deref() {
                        Some("parameter") => Causality::Parameter,
                        Some("calculatedParameter") => Causality::CalculatedParameter,
                        Some("input") => Causality::Input,
                        Some("output") => Causality::Output,
                        Some("independent") => Causality::Independent,
                        Some("local") | None => Causality::Local,
                        Some(other) => return Err(format!("variable '{name}': unknown causality '{other}'")),
                    };
                    let variability = match attribute(e.attributes(), b"variability")?.as_deref() {
                        Some("constant") => Variability::Constant,
                        Some("fixed") => Variability::Fixed,
                        Some("tunable") => Variability::Tunable,
                        Some("discrete") => Variability::Discrete,
                        Some("continuous") | None => Variability::Continuous,
                        Some(other) => return Err(format!("variable '{name}': unknown variability '{other}'")),
                    };
                    let initial = match attribute(e.attributes(), b"initial")?.as_deref() {
                        Some("exact") => Some(Initial::Exact),
                        Some("approx") => Some(Initial::Approx),
                        Some("calculated") => Some(Initial::Calculated),
                        None => None,
                        Some(other) => return Err(format!("variable '{name}': unknown initial '{other}'")),
                    };
                    let value_reference = match attribute(e.attributes(), b"valueReference")? {
                        Some(t) => t.trim().parse().map_err(|_| format!("variable '{name}': valueReference '{t}' is not a number"))?,
                        None => return Err(format!("variable '{name}' has no valueReference")),
                    };
                    current = Some(Pending { name, causality, variability, initial, value_reference, base: None });
                }
                Event::Start(e) | Event::Empty(e) if current.as_ref().is_some_and(|c| c.base.is_none()) => {
                    let base = match e.name().as_ref() {
                        b"Real" => Some(BaseType::Real),
                        b"Integer" => Some(BaseType::Integer),
                        b"Boolean" => Some(BaseType::Boolean),
                        b"String" => Some(BaseType::String),
                        b"Enumeration" => Some(BaseType::Enumeration),
                        _ => None,
                    };
                    if let (Some(c), Some(base)) = (current.as_mut(), base) {
                        let declared = attribute(e.attributes(), b"declaredType")?;
                        let has_start = attribute(e.attributes(), b"start")?.is_some();
                        c.base = Some((base, declared, has_start));
                    }
                }
                Event::End(e) if e.name().as_ref() == b"ScalarVariable" => {
                    let p = current.take().ok_or("unbalanced ScalarVariable")?;
                    let (base, declared_type, has_start) = p.base.ok_or_else(|| format!("variable '{}' has no type element", p.name))?;
                    let initial = p.initial.unwrap_or_else(|| default_initial(p.causality, p.variability, has_start));
                    variables.push(VariableInfo {
                        name: p.name,
                        value_reference: p.value_reference,
                        base,
                        causality: p.causality,
                        variability: p.variability,
                        initial,
                        declared_type,
                        direct_inputs: Vec::new(),
                    });
                }
                Event::Start(e) if e.name().as_ref() == b"Outputs" => in_outputs = true,
                Event::End(e) if e.name().as_ref() == b"Outputs" => in_outputs = false,
                Event::Start(e) | Event::Empty(e) if in_outputs && e.name().as_ref() == b"Unknown" => {
                    let index = attribute(e.attributes(), b"index")?.ok_or("an Unknown of Outputs has no index")?;
                    let index = index.trim().parse::<usize>().map_err(|_| format!("Outputs: index '{index}' is not a number"))?;
                    let deps = match attribute(e.attributes(), b"dependencies")? {
                        None => None,
                        Some(text) => Some(
                            text.split_whitespace()
                                .map(|t| t.parse::<usize>().map_err(|_| format!("dependencies: '{t}' is not an index")))
                                .collect::<Result<Vec<_>, _>>()?,
                        ),
                    };
                    output_dependencies.push((index, deps));
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
        let guid = guid.ok_or("fmiModelDescription has no guid")?;
        let (model_identifier, can_handle_variable_step, only_once_per_process) =
            co_simulation.ok_or("not a Co-Simulation FMU (no CoSimulation element)")?;
        let mut by_name = HashMap::with_capacity(variables.len());
        for (i, v) in variables.iter().enumerate() {
            if by_name.insert(v.name.clone(), i).is_some() {
                return Err(format!("two variables are named '{}'", v.name));
            }
        }
        let mut seen = std::collections::HashSet::new();
        for v in &variables {
            if !seen.insert((v.base.access(), v.value_reference)) {
                return Err(format!(
                    "variable '{}': value reference {} of type {} is used twice",
                    v.name,
                    v.value_reference,
                    v.base.access().name()
                ));
            }
            if v.base == BaseType::Enumeration {
                let known = v.declared_type.as_ref().is_some_and(|t| enumerations.iter().any(|e| &e.name == t));
                if !known {
                    return Err(format!("enumeration variable '{}' has no declared type in TypeDefinitions", v.name));
                }
            }
        }
        let inputs: Vec<usize> = (0..variables.len()).filter(|&i| variables[i].causality == Causality::Input).collect();
        // An output not listed in ModelStructure may depend on every input.
        for v in variables.iter_mut().filter(|v| v.causality == Causality::Output) {
            v.direct_inputs = inputs.clone();
        }
        for (index, deps) in output_dependencies {
            let Some(output) = index.checked_sub(1).filter(|&i| i < variables.len()) else {
                return Err(format!("Outputs: index {index} is not a variable"));
            };
            variables[output].direct_inputs = match deps {
                // No `dependencies` attribute: the output may depend on every input.
                None => inputs.clone(),
                Some(list) => {
                    let mut direct = Vec::new();
                    for d in list {
                        let Some(i) = d.checked_sub(1).filter(|&i| i < variables.len()) else {
                            return Err(format!("Outputs: dependency {d} of '{}' is not a variable", variables[output].name));
                        };
                        if variables[i].causality == Causality::Input && !direct.contains(&i) {
                            direct.push(i);
                        }
                    }
                    direct
                }
            };
        }
        Ok(Self { model_identifier, guid, can_handle_variable_step, only_once_per_process, variables, enumerations, by_name })
    }

    /// A variable by name.
    pub fn get(&self, name: &str) -> Option<&VariableInfo> {
        self.by_name.get(name).map(|&i| &self.variables[i])
    }

    /// The position of variable `name` in [`Interface::variables`].
    pub fn index(&self, name: &str) -> Option<usize> {
        self.by_name.get(name).copied()
    }

    /// Whether some output depends directly on an input.
    pub fn has_feedthrough(&self) -> bool {
        self.variables.iter().any(|v| !v.direct_inputs.is_empty())
    }

    /// The names of the outputs, in `ModelVariables` order.
    pub fn outputs(&self) -> impl Iterator<Item = &str> {
        self.variables.iter().filter(|v| v.causality == Causality::Output).map(|v| v.name.as_str())
    }

    /// The enumeration type of an enumeration variable.
    pub fn enumeration_of(&self, variable: &VariableInfo) -> Option<&EnumerationInfo> {
        let name = variable.declared_type.as_ref()?;
        self.enumerations.iter().find(|e| &e.name == name)
    }
}

/// An enumeration's items: name and value.
type Items = Vec<(String, i64)>;

/// The largest `modelDescription.xml` read (FMUs with 10⁵ variables stay far below it).
const MAX_DESCRIPTION_BYTES: u64 = 256 << 20;

/// The default of `initial` (FMI 2.0, table in section 2.2.7): exact for parameters and
/// constants, calculated for calculated parameters, outputs and locals; none for inputs and
/// the independent variable. A start value on an output or local without an `initial` is taken
/// as approx, which the standard's table allows and exporters that omit the attribute mean.
fn default_initial(causality: Causality, variability: Variability, has_start: bool) -> Initial {
    match causality {
        Causality::Parameter => Initial::Exact,
        Causality::CalculatedParameter => Initial::Calculated,
        Causality::Input | Causality::Independent => Initial::None,
        Causality::Output | Causality::Local if variability == Variability::Constant => Initial::Exact,
        Causality::Output | Causality::Local if has_start => Initial::Approx,
        Causality::Output | Causality::Local => Initial::Calculated,
    }
}

fn flag(value: Option<String>, name: &str) -> Result<bool, String> {
    match value.as_deref().map(str::trim) {
        None | Some("false") | Some("0") => Ok(false),
        Some("true") | Some("1") => Ok(true),
        Some(other) => Err(format!("{name} is '{other}', not a Boolean")),
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
    fn variables_types_and_dependencies_are_read() {
        let i = Interface::parse(XML).unwrap();
        assert_eq!((i.model_identifier.as_str(), i.guid.as_str(), i.can_handle_variable_step), ("M", "{x}", false));
        assert_eq!(i.variables.len(), 5);
        let on = i.get("on").unwrap();
        assert_eq!(
            (on.base, on.causality, on.variability, on.initial),
            (BaseType::Boolean, Causality::Parameter, Variability::Tunable, Initial::Exact)
        );
        assert_eq!(i.get("y").unwrap().direct_inputs, [1], "y depends on w (index 2) only");
        assert!(i.get("z").unwrap().direct_inputs.is_empty(), "z on nothing");
        assert_eq!(i.outputs().collect::<Vec<_>>(), ["y", "z"]);
        // An absent dependencies attribute means every input.
        let all = Interface::parse(&XML.replace(r#"<Unknown index="3" dependencies="2"/>"#, r#"<Unknown index="3"/>"#)).unwrap();
        assert_eq!(all.get("y").unwrap().direct_inputs, [0, 1]);
        // So does an output that ModelStructure leaves out.
        let none = Interface::parse(&XML.replace(r#"<Unknown index="4" dependencies=""/>"#, "")).unwrap();
        assert_eq!(none.get("z").unwrap().direct_inputs, [0, 1]);
    }

    #[test]
    fn enumerations_initial_and_settable_variables_are_read() {
        let xml = XML
            .replace(r#"<CoSimulation modelIdentifier="M"/>"#, r#"<CoSimulation modelIdentifier="M" canHandleVariableCommunicationStepSize="true"/>
  <TypeDefinitions><SimpleType name="Mode"><Enumeration><Item name="slow" value="1"/><Item name="fast" value="7"/></Enumeration></SimpleType></TypeDefinitions>"#)
            .replace(
                r#"<ScalarVariable name="z" valueReference="3" causality="output"><Real/></ScalarVariable>"#,
                r#"<ScalarVariable name="z" valueReference="3" causality="output" initial="exact"><Real start="2"/></ScalarVariable>
    <ScalarVariable name="mode" valueReference="0" causality="parameter" variability="fixed"><Enumeration declaredType="Mode" start="7"/></ScalarVariable>
    <ScalarVariable name="k" valueReference="1" causality="parameter" variability="constant"><Integer start="3"/></ScalarVariable>
    <ScalarVariable name="c" valueReference="5" causality="calculatedParameter" variability="fixed"><Real/></ScalarVariable>"#,
            );
        let i = Interface::parse(&xml).unwrap();
        assert!(i.can_handle_variable_step);
        let mode = i.get("mode").unwrap();
        assert_eq!(
            (mode.base, mode.base.access(), mode.declared_type.as_deref()),
            (BaseType::Enumeration, BaseType::Integer, Some("Mode"))
        );
        assert_eq!(i.enumeration_of(mode).unwrap().items, [("slow".to_owned(), 1), ("fast".to_owned(), 7)]);
        let settable: Vec<&str> = i.variables.iter().filter(|v| v.settable_before_initialization()).map(|v| v.name.as_str()).collect();
        assert_eq!(settable, ["u", "w", "z", "mode", "on"], "inputs, parameters and the exact output; not y, the constant or c");
        // Integer and Enumeration share value references: mode (0) collides with an Integer 0.
        let e = Interface::parse(&xml.replace(r#"name="k" valueReference="1""#, r#"name="k" valueReference="0""#)).unwrap_err();
        assert!(e.contains("value reference 0 of type Integer is used twice"), "{e}");
        let e = Interface::parse(&xml.replace(r#"declaredType="Mode""#, r#"declaredType="Gear""#)).unwrap_err();
        assert!(e.contains("no declared type"), "{e}");
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
