//! An FMU's interface, read once from the `modelDescription.xml` in its archive without
//! loading its binary: the variables with their value references, base types and
//! causalities, and which inputs feed outputs directly (`ModelStructure/Outputs`). The
//! system plan, the simulation and the SSP writer all use this one reading.
//!
//! FMI 2.0 and FMI 3.0 Co-Simulation descriptions are read into the same [`Interface`]; its
//! [`Interface::fmi_version`] says which API the binary has. FMI 3.0's types map onto four
//! *access classes* the master passes values in ([`BaseType::access`]): Float64 and Float32 as
//! Real (f64), every integer type and enumerations as Integer (i64), Boolean, String. Binary
//! and Clock variables and arrays are read (so that names resolve and messages can say why)
//! but cannot be connected, recorded or set.

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
    /// An enumeration: read and set as fmi2Integer (FMI 2.0, sharing the Integer value
    /// references) or fmi3Int64 (FMI 3.0).
    Enumeration,
    /// FMI 3.0 Float64.
    Float64,
    /// FMI 3.0 Float32.
    Float32,
    /// FMI 3.0 Int8.
    Int8,
    /// FMI 3.0 UInt8.
    UInt8,
    /// FMI 3.0 Int16.
    Int16,
    /// FMI 3.0 UInt16.
    UInt16,
    /// FMI 3.0 Int32.
    Int32,
    /// FMI 3.0 UInt32.
    UInt32,
    /// FMI 3.0 Int64.
    Int64,
    /// FMI 3.0 UInt64.
    UInt64,
    /// FMI 3.0 Binary (not connectable).
    Binary,
    /// FMI 3.0 Clock (not connectable).
    Clock,
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
            BaseType::Float64 => "Float64",
            BaseType::Float32 => "Float32",
            BaseType::Int8 => "Int8",
            BaseType::UInt8 => "UInt8",
            BaseType::Int16 => "Int16",
            BaseType::UInt16 => "UInt16",
            BaseType::Int32 => "Int32",
            BaseType::UInt32 => "UInt32",
            BaseType::Int64 => "Int64",
            BaseType::UInt64 => "UInt64",
            BaseType::Binary => "Binary",
            BaseType::Clock => "Clock",
        }
    }

    /// The FMI 3.0 type of element `name` of `ModelVariables`.
    fn fmi3(name: &[u8]) -> Option<BaseType> {
        Some(match name {
            b"Float64" => BaseType::Float64,
            b"Float32" => BaseType::Float32,
            b"Int8" => BaseType::Int8,
            b"UInt8" => BaseType::UInt8,
            b"Int16" => BaseType::Int16,
            b"UInt16" => BaseType::UInt16,
            b"Int32" => BaseType::Int32,
            b"UInt32" => BaseType::UInt32,
            b"Int64" => BaseType::Int64,
            b"UInt64" => BaseType::UInt64,
            b"Boolean" => BaseType::Boolean,
            b"String" => BaseType::String,
            b"Binary" => BaseType::Binary,
            b"Enumeration" => BaseType::Enumeration,
            b"Clock" => BaseType::Clock,
            _ => return None,
        })
    }

    /// Whether connections and recordings handle this type: all but FMI 3.0's Binary and
    /// Clock.
    pub fn is_connectable(self) -> bool {
        !matches!(self, BaseType::Binary | BaseType::Clock)
    }

    /// The access class the master passes this type's values in: Real (f64) for Real,
    /// Float64 and Float32; Integer (i64) for every integer type and enumerations; else
    /// itself. Two variables of one class connect; FMI 2.0 value references are unique per
    /// class.
    pub fn access(self) -> BaseType {
        match self {
            BaseType::Real | BaseType::Float64 | BaseType::Float32 => BaseType::Real,
            BaseType::Enumeration
            | BaseType::Integer
            | BaseType::Int8
            | BaseType::UInt8
            | BaseType::Int16
            | BaseType::UInt16
            | BaseType::Int32
            | BaseType::UInt32
            | BaseType::Int64
            | BaseType::UInt64 => BaseType::Integer,
            t => t,
        }
    }

    /// The values an integer type holds (enumerations: FMI 2.0's fmi2Integer, the narrower).
    pub fn integer_range(self) -> Option<(i128, i128)> {
        Some(match self {
            BaseType::Integer | BaseType::Int32 | BaseType::Enumeration => (i32::MIN.into(), i32::MAX.into()),
            BaseType::Int8 => (i8::MIN.into(), i8::MAX.into()),
            BaseType::UInt8 => (0, u8::MAX.into()),
            BaseType::Int16 => (i16::MIN.into(), i16::MAX.into()),
            BaseType::UInt16 => (0, u16::MAX.into()),
            BaseType::UInt32 => (0, u32::MAX.into()),
            BaseType::Int64 => (i64::MIN.into(), i64::MAX.into()),
            // The master passes integers as i64: larger UInt64 values are refused when read.
            BaseType::UInt64 => (0, i64::MAX.into()),
            _ => return None,
        })
    }
}

/// The FMI version of an FMU.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum FmiVersion {
    /// FMI 2.0.
    V2,
    /// FMI 3.0.
    V3,
}

impl FmiVersion {
    /// The prefix of the API's function names: "fmi2" or "fmi3".
    pub fn prefix(self) -> &'static str {
        match self {
            FmiVersion::V2 => "fmi2",
            FmiVersion::V3 => "fmi3",
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
    /// `structuralParameter` (FMI 3.0).
    StructuralParameter,
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
            Causality::StructuralParameter => "structuralParameter",
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
    /// An FMI 3.0 array (it has `Dimension` elements): not connectable, recordable or settable.
    pub is_array: bool,
}

impl VariableInfo {
    /// Whether a master may set this variable after instantiation, before initialization:
    /// inputs, and variables that are not constant and have `initial` exact or approx
    /// (parameters, and outputs or locals given a start value) (FMI 2.0, section 4.2.4).
    pub fn settable_before_initialization(&self) -> bool {
        !self.is_array && self.base.is_connectable() && self.settable_class()
    }

    fn settable_class(&self) -> bool {
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
    /// FMI 2.0 or 3.0.
    pub fmi_version: FmiVersion,
    /// `modelIdentifier` of the Co-Simulation interface.
    pub model_identifier: String,
    /// The GUID (FMI 2.0) or `instantiationToken` (FMI 3.0).
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
    /// The element that closes it: ScalarVariable (FMI 2.0) or the type's (FMI 3.0).
    element: Vec<u8>,
    is_array: bool,
}

impl Pending {
    /// Name, causality, variability, initial and value reference of a ScalarVariable (FMI
    /// 2.0) or a typed variable element (FMI 3.0).
    fn read(e: &quick_xml::events::BytesStart) -> Result<Self, String> {
        let name = attribute(e.attributes(), b"name")?.ok_or("a variable has no name")?;
        let causality = match attribute(e.attributes(), b"causality")?.as_deref() {
            Some("parameter") => Causality::Parameter,
            Some("calculatedParameter") => Causality::CalculatedParameter,
            Some("structuralParameter") => Causality::StructuralParameter,
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
            Some("continuous") => Variability::Continuous,
            None => Variability::Continuous,
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
        Ok(Self {
            name,
            causality,
            variability,
            initial,
            value_reference,
            base: None,
            element: e.name().as_ref().to_vec(),
            is_array: false,
        })
    }

    fn finish(self) -> Result<VariableInfo, String> {
        let (base, declared_type, has_start) = self.base.ok_or_else(|| format!("variable '{}' has no type element", self.name))?;
        // FMI 3.0: variables other than Float32/64 are discrete unless they say otherwise.
        let variability = if self.element.as_slice() != b"ScalarVariable"
            && self.variability == Variability::Continuous
            && !matches!(base, BaseType::Float64 | BaseType::Float32)
        {
            Variability::Discrete
        } else {
            self.variability
        };
        let initial = self.initial.unwrap_or_else(|| default_initial(self.causality, variability, has_start));
        Ok(VariableInfo {
            name: self.name,
            value_reference: self.value_reference,
            base,
            causality: self.causality,
            variability,
            initial,
            declared_type,
            direct_inputs: Vec::new(),
            is_array: self.is_array,
        })
    }
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
        // FMI 3.0: the same by value reference.
        let mut aliases: Vec<(String, usize)> = Vec::new();
        let mut output_vr_dependencies: Vec<(u32, Option<Vec<u32>>)> = Vec::new();
        let mut is_fmi3 = false;
        let mut in_variables = false;
        loop {
            let event = reader.read_event().map_err(|e| format!("at byte {}: {e}", reader.error_position()))?;
            let empty = matches!(event, Event::Empty(_));
            match event {
                Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"fmiModelDescription" => {
                    version = attribute(e.attributes(), b"fmiVersion")?;
                    is_fmi3 = version.as_deref().is_some_and(|v| v.starts_with("3."));
                    guid = attribute(e.attributes(), if is_fmi3 { &b"instantiationToken"[..] } else { &b"guid"[..] })?;
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
                Event::Start(e) if e.name().as_ref() == b"SimpleType" || (is_fmi3 && e.name().as_ref() == b"EnumerationType") => {
                    let name = attribute(e.attributes(), b"name")?.ok_or("a SimpleType has no name")?;
                    simple_type = Some((name, None));
                }
                Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"Enumeration" && simple_type.is_some() && current.is_none() => {
                    if let Some(t) = simple_type.as_mut() {
                        t.1 = Some(Vec::new());
                    }
                }
                Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"Item" && is_fmi3 => {
                    // FMI 3.0 items sit directly in the EnumerationType.
                    if let Some((_, items @ None)) = simple_type.as_mut() {
                        *items = Some(Vec::new());
                    }
                    if let Some((type_name, Some(items))) = simple_type.as_mut() {
                        items.push(item(&e, type_name)?);
                    }
                }
                Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"Item" => {
                    if let Some((type_name, Some(items))) = simple_type.as_mut() {
                        items.push(item(&e, type_name)?);
                    }
                }
                Event::End(e) if e.name().as_ref() == b"SimpleType" || (is_fmi3 && e.name().as_ref() == b"EnumerationType") => {
                    if let Some((name, Some(items))) = simple_type.take() {
                        enumerations.push(EnumerationInfo { name, items });
                    }
                }
                Event::Start(e) if !is_fmi3 && e.name().as_ref() == b"ScalarVariable" => current = Some(Pending::read(&e)?),
                // FMI 3.0: a variable is its type's element, directly in ModelVariables.
                Event::Start(e) | Event::Empty(e) if in_variables && current.is_none() && is_fmi3 => {
                    let Some(base) = BaseType::fmi3(e.name().as_ref()) else { continue };
                    let mut p = Pending::read(&e)?;
                    let declared = attribute(e.attributes(), b"declaredType")?;
                    let has_start = attribute(e.attributes(), b"start")?.is_some();
                    p.base = Some((base, declared, has_start));
                    if empty {
                        variables.push(p.finish()?);
                    } else {
                        current = Some(p);
                    }
                }
                Event::Start(e) | Event::Empty(e) if is_fmi3 && current.is_some() && e.name().as_ref() == b"Dimension" => {
                    if let Some(c) = current.as_mut() {
                        c.is_array = true;
                    }
                }
                // FMI 3.0: another name of the variable being read (same value reference).
                Event::Start(e) | Event::Empty(e) if is_fmi3 && current.is_some() && e.name().as_ref() == b"Alias" => {
                    let name = attribute(e.attributes(), b"name")?.ok_or("an Alias has no name")?;
                    aliases.push((name, variables.len()));
                }
                Event::Start(e) | Event::Empty(e) if is_fmi3 && current.is_some() && e.name().as_ref() == b"Start" => {
                    if let Some((_, _, has_start)) = current.as_mut().and_then(|c| c.base.as_mut()) {
                        *has_start = true;
                    }
                }
                Event::Start(e) | Event::Empty(e) if !is_fmi3 && current.as_ref().is_some_and(|c| c.base.is_none()) => {
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
                Event::End(e) if current.as_ref().is_some_and(|c| c.element.as_slice() == e.name().as_ref()) => {
                    let p = current.take().ok_or("unbalanced variable")?;
                    variables.push(p.finish()?);
                }
                Event::Start(e) if e.name().as_ref() == b"ModelVariables" => in_variables = true,
                Event::End(e) if e.name().as_ref() == b"ModelVariables" => in_variables = false,
                // FMI 3.0: outputs by value reference, dependencies as value references.
                Event::Start(e) | Event::Empty(e) if is_fmi3 && e.name().as_ref() == b"Output" => {
                    let vr = attribute(e.attributes(), b"valueReference")?.ok_or("an Output of ModelStructure has no valueReference")?;
                    let vr = vr.trim().parse::<u32>().map_err(|_| format!("ModelStructure: valueReference '{vr}' is not a number"))?;
                    let deps = match attribute(e.attributes(), b"dependencies")? {
                        None => None,
                        Some(text) => Some(
                            text.split_whitespace()
                                .map(|t| t.parse::<u32>().map_err(|_| format!("dependencies: '{t}' is not a value reference")))
                                .collect::<Result<Vec<_>, _>>()?,
                        ),
                    };
                    output_vr_dependencies.push((vr, deps));
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
        let fmi_version = match version.as_deref() {
            Some("2.0") => FmiVersion::V2,
            Some(v) if v.starts_with("3.") => FmiVersion::V3,
            Some(v) => return Err(format!("fmiVersion is {v}; only FMI 2.0 and 3.0 are supported")),
            None => return Err("no fmiModelDescription element with an fmiVersion".into()),
        };
        let guid = guid.ok_or(if is_fmi3 { "fmiModelDescription has no instantiationToken" } else { "fmiModelDescription has no guid" })?;
        let (model_identifier, can_handle_variable_step, only_once_per_process) =
            co_simulation.ok_or("not a Co-Simulation FMU (no CoSimulation element)")?;
        let mut by_name = HashMap::with_capacity(variables.len());
        for (i, v) in variables.iter().enumerate() {
            if by_name.insert(v.name.clone(), i).is_some() {
                return Err(format!("two variables are named '{}'", v.name));
            }
        }
        for (alias, index) in aliases {
            if by_name.insert(alias.clone(), index).is_some() {
                return Err(format!("two variables are named '{alias}' (an Alias of '{}')", variables[index].name));
            }
        }
        let mut seen = HashMap::new();
        for v in &variables {
            // FMI 3.0 value references are unique over all types (other names are Alias
            // elements); FMI 2.0 ones per access type, where variables of the same type that
            // share one are aliases.
            let class = if is_fmi3 { BaseType::Real } else { v.base.access() };
            if let Some(first) = seen.insert((class, v.value_reference), v.base) {
                if is_fmi3 {
                    return Err(format!("variable '{}': value reference {} is used twice", v.name, v.value_reference));
                }
                if first != v.base {
                    return Err(format!(
                        "variable '{}': value reference {} of type {} is used twice, by an {} and an {} (aliases have one type)",
                        v.name,
                        v.value_reference,
                        v.base.access().name(),
                        first.name(),
                        v.base.name()
                    ));
                }
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
        if is_fmi3 {
            let index_of = |vr: u32| variables.iter().position(|v| v.value_reference == vr).map(|i| i + 1);
            for (vr, deps) in output_vr_dependencies {
                let index = index_of(vr).ok_or_else(|| format!("ModelStructure: Output {vr} is not a value reference of a variable"))?;
                let deps = match deps {
                    None => None,
                    Some(list) => Some(
                        list.into_iter()
                            .map(|d| {
                                index_of(d).ok_or_else(|| format!("ModelStructure: dependency {d} is not a value reference of a variable"))
                            })
                            .collect::<Result<Vec<_>, _>>()?,
                    ),
                };
                output_dependencies.push((index, deps));
            }
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
        Ok(Self { fmi_version, model_identifier, guid, can_handle_variable_step, only_once_per_process, variables, enumerations, by_name })
    }

    /// A variable by name (or by one of its FMI 3.0 `Alias` names).
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

/// An enumeration item of type `type_name`.
fn item(e: &quick_xml::events::BytesStart, type_name: &str) -> Result<(String, i64), String> {
    let name = attribute(e.attributes(), b"name")?.ok_or_else(|| format!("an item of type '{type_name}' has no name"))?;
    let value = attribute(e.attributes(), b"value")?.ok_or_else(|| format!("item '{name}' of type '{type_name}' has no value"))?;
    let value = value.trim().parse().map_err(|_| format!("item '{name}' of type '{type_name}': value '{value}' is not an integer"))?;
    Ok((name, value))
}

/// The largest `modelDescription.xml` read (FMUs with 10⁵ variables stay far below it).
const MAX_DESCRIPTION_BYTES: u64 = 256 << 20;

/// The default of `initial` (FMI 2.0, table in section 2.2.7): exact for parameters and
/// constants, calculated for calculated parameters, outputs and locals; none for inputs and
/// the independent variable. A start value on an output or local without an `initial` is taken
/// as approx, which the standard's table allows and exporters that omit the attribute mean.
fn default_initial(causality: Causality, variability: Variability, has_start: bool) -> Initial {
    match causality {
        Causality::Parameter | Causality::StructuralParameter => Initial::Exact,
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
        assert!(e.contains("value reference 0 of type Integer is used twice, by an Enumeration and an Integer"), "{e}");
        // Two variables of one type sharing a value reference are aliases (FMI 2.0, 2.2.7).
        let aliased = xml.replace(
            r#"<ScalarVariable name="c" valueReference="5""#,
            r#"<ScalarVariable name="z_alias" valueReference="3" causality="local" initial="calculated"><Real/></ScalarVariable>
    <ScalarVariable name="c" valueReference="5""#,
        );
        let i = Interface::parse(&aliased).unwrap();
        assert_eq!((i.get("z_alias").unwrap().value_reference, i.get("z").unwrap().value_reference), (3, 3));
        let e = Interface::parse(&xml.replace(r#"declaredType="Mode""#, r#"declaredType="Gear""#)).unwrap_err();
        assert!(e.contains("no declared type"), "{e}");
    }

    #[test]
    fn other_versions_and_model_exchange_are_refused() {
        let e = Interface::parse(&XML.replace(r#"fmiVersion="2.0""#, r#"fmiVersion="1.0""#)).unwrap_err();
        assert!(e.contains("only FMI 2.0 and 3.0"), "{e}");
        let e = Interface::parse(&XML.replace(r#"<CoSimulation modelIdentifier="M"/>"#, r#"<ModelExchange modelIdentifier="M"/>"#))
            .unwrap_err();
        assert!(e.contains("not a Co-Simulation FMU"), "{e}");
        let e = Interface::parse(&XML.replace(r#"name="w""#, r#"name="u""#)).unwrap_err();
        assert!(e.contains("two variables are named 'u'"), "{e}");
    }

    /// An FMI 3.0 description with every kind of variable the reader must tell apart.
    const XML3: &str = r#"<?xml version="1.0"?>
<fmiModelDescription fmiVersion="3.0" modelName="F" instantiationToken="{t}">
  <CoSimulation modelIdentifier="F" canHandleVariableCommunicationStepSize="true"/>
  <TypeDefinitions>
    <Float64Type name="Angle" unit="rad"/>
    <EnumerationType name="Option"><Item name="one" value="1"/><Item name="two" value="2"/></EnumerationType>
  </TypeDefinitions>
  <ModelVariables>
    <Float64 name="time" valueReference="0" causality="independent" variability="continuous"/>
    <Float32 name="f32_in" valueReference="1" causality="input" start="0"/>
    <Float32 name="f32_out" valueReference="2" causality="output"/>
    <Float64 name="k" valueReference="5" causality="parameter" variability="tunable" start="2" declaredType="Angle"/>
    <Int8 name="i8_in" valueReference="11" causality="input" start="0"/>
    <UInt64 name="u64_out" valueReference="26" causality="output"/>
    <Boolean name="b_in" valueReference="27" causality="input" start="false"/>
    <String name="s_in" valueReference="29" causality="input"><Start value="Set me!"/></String>
    <Binary name="bin_in" valueReference="31" causality="input"><Start value="666f6f"/></Binary>
    <Enumeration name="e_in" declaredType="Option" valueReference="33" causality="input" start="1"/>
    <Float64 name="v" valueReference="40" causality="output"><Dimension start="3"/></Float64>
    <Int32 name="n" valueReference="41" causality="structuralParameter" variability="fixed" start="3"/>
  </ModelVariables>
  <ModelStructure>
    <Output valueReference="2" dependencies="1"/>
    <Output valueReference="26" dependencies=""/>
    <Output valueReference="40"/>
  </ModelStructure>
</fmiModelDescription>"#;

    #[test]
    fn fmi3_types_value_references_and_dependencies_are_read() {
        let i = Interface::parse(XML3).unwrap();
        assert_eq!((i.fmi_version, i.guid.as_str(), i.can_handle_variable_step), (FmiVersion::V3, "{t}", true));
        let bases: Vec<BaseType> = i.variables.iter().map(|v| v.base).collect();
        use BaseType::*;
        assert_eq!(bases, [Float64, Float32, Float32, Float64, Int8, UInt64, Boolean, String, Binary, Enumeration, Float64, Int32]);
        assert_eq!(i.get("f32_out").unwrap().direct_inputs, [1], "dependencies are value references: 1 is f32_in");
        assert!(i.get("u64_out").unwrap().direct_inputs.is_empty());
        let inputs: Vec<usize> = (0..i.variables.len()).filter(|&k| i.variables[k].causality == Causality::Input).collect();
        assert_eq!(i.get("v").unwrap().direct_inputs, inputs, "no dependencies attribute: every input");
        assert_eq!(i.enumeration_of(i.get("e_in").unwrap()).unwrap().items, [("one".to_owned(), 1), ("two".to_owned(), 2)]);
        // Variables that are not Float default to discrete; a String's start is an element.
        assert_eq!(i.get("i8_in").unwrap().variability, Variability::Discrete);
        assert_eq!(i.get("f32_in").unwrap().variability, Variability::Continuous);
        assert_eq!(i.get("n").unwrap().causality, Causality::StructuralParameter);
        // Arrays, Binary and Clock variables are read but cannot be set or connected.
        assert!(i.get("v").unwrap().is_array && !i.get("k").unwrap().is_array);
        assert!(!i.get("bin_in").unwrap().settable_before_initialization() && i.get("s_in").unwrap().settable_before_initialization());
        assert!(!Binary.is_connectable() && !Clock.is_connectable() && UInt64.is_connectable());
        assert_eq!((Float32.access(), UInt64.access(), Enumeration.access()), (Real, Integer, Integer));
        // Value references are unique over all types in FMI 3.0.
        let e = Interface::parse(&XML3.replace(r#"name="b_in" valueReference="27""#, r#"name="b_in" valueReference="26""#)).unwrap_err();
        assert!(e.contains("'b_in': value reference 26 is used twice"), "{e}");
        // An Alias element is another name of its variable; names stay unique.
        let k = r#"start="2" declaredType="Angle"/>"#;
        let aliased = XML3.replace(k, r#"start="2" declaredType="Angle"><Alias name="k_deg" displayUnit="deg"/></Float64>"#);
        let i = Interface::parse(&aliased).unwrap();
        assert_eq!(i.get("k_deg"), i.get("k"));
        assert_eq!((i.variables.len(), i.index("k_deg"), i.get("i8_in").unwrap().value_reference), (12, i.index("k"), 11));
        let e = Interface::parse(&aliased.replace("k_deg", "n")).unwrap_err();
        assert!(e.contains("two variables are named 'n' (an Alias of 'k')"), "{e}");
        let e = Interface::parse(
            &XML3.replace(r#"<Output valueReference="2" dependencies="1"/>"#, r#"<Output valueReference="2" dependencies="99"/>"#),
        )
        .unwrap_err();
        assert!(e.contains("dependency 99 is not a value reference"), "{e}");
        let e = Interface::parse(&XML3.replace(r#" instantiationToken="{t}""#, "")).unwrap_err();
        assert!(e.contains("no instantiationToken"), "{e}");
    }
}
