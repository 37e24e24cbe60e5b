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
//!
//! The reading itself is split by version: [`Interface::parse`] reads the root element and
//! hands the rest of the document to the reader of its version (`fmi2`: `ScalarVariable`s and
//! `ModelStructure/Outputs` by index; `fmi3`: typed variable elements, `Alias`es and
//! `ModelStructure/Output` by value reference); both fill one `Reading`, which is checked
//! and resolved here into the [`Interface`].

mod fmi2;
mod fmi3;

use std::collections::HashMap;
use std::io::Read;
use std::path::Path;

use quick_xml::events::attributes::Attributes;
use quick_xml::events::{BytesStart, Event};

use crate::error::{DescriptionError, FmuFileError, FmuProblem};

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

/// The type element of a variable: its base type, `declaredType`, and whether it has a start
/// value.
struct TypeElement {
    base: BaseType,
    declared_type: Option<String>,
    has_start: bool,
}

impl TypeElement {
    /// The type element `e` of base type `base`.
    fn read(e: &BytesStart, base: BaseType) -> Result<Self, DescriptionError> {
        let declared_type = attribute(e.attributes(), b"declaredType")?;
        let has_start = attribute(e.attributes(), b"start")?.is_some();
        Ok(Self { base, declared_type, has_start })
    }
}

/// What is being read of a variable.
struct Pending {
    name: String,
    causality: Causality,
    variability: Variability,
    initial: Option<Initial>,
    value_reference: u32,
    base: Option<TypeElement>,
    /// The element that closes it: ScalarVariable (FMI 2.0) or the type's (FMI 3.0).
    element: Vec<u8>,
    is_array: bool,
}

impl Pending {
    /// Name, causality, variability, initial and value reference of a ScalarVariable (FMI
    /// 2.0) or a typed variable element (FMI 3.0).
    fn read(e: &BytesStart) -> Result<Self, DescriptionError> {
        let name =
            attribute(e.attributes(), b"name")?.ok_or(DescriptionError::MissingAttribute { element: "a variable", attribute: "name" })?;
        let unknown = |attribute: &'static str, value: &str| DescriptionError::UnknownValue {
            variable: name.clone(),
            attribute,
            value: value.to_owned(),
        };
        let causality = match attribute(e.attributes(), b"causality")?.as_deref() {
            Some("parameter") => Causality::Parameter,
            Some("calculatedParameter") => Causality::CalculatedParameter,
            Some("structuralParameter") => Causality::StructuralParameter,
            Some("input") => Causality::Input,
            Some("output") => Causality::Output,
            Some("independent") => Causality::Independent,
            Some("local") | None => Causality::Local,
            Some(other) => return Err(unknown("causality", other)),
        };
        let variability = match attribute(e.attributes(), b"variability")?.as_deref() {
            Some("constant") => Variability::Constant,
            Some("fixed") => Variability::Fixed,
            Some("tunable") => Variability::Tunable,
            Some("discrete") => Variability::Discrete,
            Some("continuous") => Variability::Continuous,
            None => Variability::Continuous,
            Some(other) => return Err(unknown("variability", other)),
        };
        let initial = match attribute(e.attributes(), b"initial")?.as_deref() {
            Some("exact") => Some(Initial::Exact),
            Some("approx") => Some(Initial::Approx),
            Some("calculated") => Some(Initial::Calculated),
            None => None,
            Some(other) => return Err(unknown("initial", other)),
        };
        let value_reference = match attribute(e.attributes(), b"valueReference")? {
            Some(t) => t.trim().parse().map_err(|_| DescriptionError::BadValueReference { variable: name.clone(), text: t })?,
            None => return Err(DescriptionError::NoValueReference { variable: name }),
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

    fn finish(self) -> Result<VariableInfo, DescriptionError> {
        let Some(TypeElement { base, declared_type, has_start }) = self.base else {
            return Err(DescriptionError::NoTypeElement { variable: self.name });
        };
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

/// The `CoSimulation` element: model identifier and capability flags.
struct CoSimulation {
    model_identifier: String,
    can_handle_variable_step: bool,
    only_once_per_process: bool,
}

/// An output and what it depends on, as `ModelStructure` gives them (1-based indices in
/// FMI 2.0, value references in FMI 3.0); `None`: no `dependencies` attribute.
type Dependencies<T> = (T, Option<Vec<T>>);

/// What the version's reader collected of a description, before it is checked.
#[derive(Default)]
struct Reading {
    co_simulation: Option<CoSimulation>,
    /// The variables read so far, in `ModelVariables` order.
    variables: Vec<VariableInfo>,
    enumerations: Vec<EnumerationInfo>,
    /// The enumeration type being read, and its items once they began.
    simple_type: Option<(String, Option<Items>)>,
    /// The variable being read.
    current: Option<Pending>,
    in_variables: bool,
    in_outputs: bool,
    /// Per `Unknown` of `ModelStructure/Outputs`: its output and dependencies by 1-based index.
    output_dependencies: Vec<Dependencies<usize>>,
    /// FMI 3.0: other names of variables (`Alias`), with the variable's position.
    aliases: Vec<(String, usize)>,
    /// FMI 3.0: per `Output` of `ModelStructure`, its output and dependencies by value
    /// reference.
    output_value_references: Vec<Dependencies<u32>>,
}

impl Reading {
    /// The `CoSimulation` element.
    fn co_simulation(&mut self, e: &BytesStart) -> Result<(), DescriptionError> {
        let model_identifier = attribute(e.attributes(), b"modelIdentifier")?
            .ok_or(DescriptionError::MissingAttribute { element: "CoSimulation", attribute: "modelIdentifier" })?;
        let can_handle_variable_step = flag(e, "canHandleVariableCommunicationStepSize")?;
        let only_once_per_process = flag(e, "canBeInstantiatedOnlyOncePerProcess")?;
        self.co_simulation = Some(CoSimulation { model_identifier, can_handle_variable_step, only_once_per_process });
        Ok(())
    }

    /// The start of a type definition (`SimpleType`, FMI 3.0's `EnumerationType`).
    fn start_type(&mut self, e: &BytesStart) -> Result<(), DescriptionError> {
        let name =
            attribute(e.attributes(), b"name")?.ok_or(DescriptionError::MissingAttribute { element: "a SimpleType", attribute: "name" })?;
        self.simple_type = Some((name, None));
        Ok(())
    }

    /// Whether an `Enumeration` element opens the items of the type definition being read.
    fn opens_items(&self, e: &BytesStart) -> bool {
        e.name().as_ref() == b"Enumeration" && self.simple_type.is_some() && self.current.is_none()
    }

    /// The items of the type definition being read begin.
    fn open_items(&mut self) {
        if let Some((_, items @ None)) = self.simple_type.as_mut() {
            *items = Some(Vec::new());
        }
    }

    /// An `Item` of the enumeration being read, if its items began.
    fn item(&mut self, e: &BytesStart) -> Result<(), DescriptionError> {
        if let Some((type_name, Some(items))) = self.simple_type.as_mut() {
            items.push(item(e, type_name)?);
        }
        Ok(())
    }

    /// The end of a type definition: an enumeration's is kept.
    fn end_type(&mut self) {
        if let Some((name, Some(items))) = self.simple_type.take() {
            self.enumerations.push(EnumerationInfo { name, items });
        }
    }

    /// Whether the end of element `name` closes the variable being read.
    fn closes_variable(&self, name: &[u8]) -> bool {
        self.current.as_ref().is_some_and(|c| c.element.as_slice() == name)
    }

    /// The end of the variable being read.
    fn end_variable(&mut self) -> Result<(), DescriptionError> {
        if let Some(p) = self.current.take() {
            self.variables.push(p.finish()?);
        }
        Ok(())
    }

    /// An `Unknown` of `ModelStructure/Outputs`: an output's 1-based index and dependencies.
    fn output_unknown(&mut self, e: &BytesStart) -> Result<(), DescriptionError> {
        let index = attribute(e.attributes(), b"index")?
            .ok_or(DescriptionError::MissingAttribute { element: "an Unknown of Outputs", attribute: "index" })?;
        let index = index.trim().parse::<usize>().map_err(|_| DescriptionError::NotANumber {
            section: "Outputs",
            attribute: "index",
            text: index,
        })?;
        let deps = dependencies(e, "an index")?;
        self.output_dependencies.push((index, deps));
        Ok(())
    }

    /// The interface the description gives, checked: FMI version, token, Co-Simulation
    /// element, unique names, value references and enumeration types, and each output's
    /// direct inputs.
    fn finish(self, root: Root) -> Result<Interface, DescriptionError> {
        let fmi_version = match root.version.as_deref() {
            Some("2.0") => FmiVersion::V2,
            Some(v) if v.starts_with("3.") => FmiVersion::V3,
            Some(v) => return Err(DescriptionError::UnsupportedVersion { version: v.to_owned() }),
            None => return Err(DescriptionError::NoVersion),
        };
        let token = root.token_attribute();
        let guid = root.guid.ok_or(DescriptionError::MissingAttribute { element: "fmiModelDescription", attribute: token })?;
        let co_simulation = self.co_simulation.ok_or(DescriptionError::NotCoSimulation)?;
        let by_name = index_names(&self.variables, self.aliases)?;
        check_variables(&self.variables, &self.enumerations, fmi_version)?;
        let mut variables = self.variables;
        let mut output_dependencies = self.output_dependencies;
        if fmi_version == FmiVersion::V3 {
            output_dependencies.extend(fmi3::by_index(&variables, self.output_value_references)?);
        }
        resolve_direct_inputs(&mut variables, output_dependencies)?;
        Ok(Interface {
            fmi_version,
            model_identifier: co_simulation.model_identifier,
            guid,
            can_handle_variable_step: co_simulation.can_handle_variable_step,
            only_once_per_process: co_simulation.only_once_per_process,
            variables,
            enumerations: self.enumerations,
            by_name,
        })
    }
}

/// The root element `fmiModelDescription`: the FMI version and the GUID (FMI 2.0) or
/// instantiation token (FMI 3.0).
struct Root {
    version: Option<String>,
    guid: Option<String>,
}

impl Root {
    /// Reads up to the root element; `None` if there is none.
    fn read(reader: &mut quick_xml::Reader<&[u8]>) -> Result<Option<Self>, DescriptionError> {
        loop {
            match next_event(reader)? {
                Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"fmiModelDescription" => {
                    let version = attribute(e.attributes(), b"fmiVersion")?;
                    let mut root = Self { version, guid: None };
                    root.guid = attribute(e.attributes(), root.token_attribute().as_bytes())?;
                    return Ok(Some(root));
                }
                Event::Eof => return Ok(None),
                _ => {}
            }
        }
    }

    /// Whether the document is read as FMI 3.0 (any 3.x); every other is read as FMI 2.0.
    fn is_fmi3(&self) -> bool {
        self.version.as_deref().is_some_and(|v| v.starts_with("3."))
    }

    /// The attribute that holds the GUID: `instantiationToken` in FMI 3.0, else `guid`.
    fn token_attribute(&self) -> &'static str {
        if self.is_fmi3() {
            "instantiationToken"
        } else {
            "guid"
        }
    }
}

/// The next event of `reader`; an XML error says where it stopped.
fn next_event<'a>(reader: &mut quick_xml::Reader<&'a [u8]>) -> Result<Event<'a>, DescriptionError> {
    reader.read_event().map_err(|error| DescriptionError::Xml { position: reader.error_position(), error })
}

/// Each variable's position by name, and by the other names `aliases` give (FMI 3.0).
fn index_names(variables: &[VariableInfo], aliases: Vec<(String, usize)>) -> Result<HashMap<String, usize>, DescriptionError> {
    let mut by_name = HashMap::with_capacity(variables.len());
    for (i, v) in variables.iter().enumerate() {
        if by_name.insert(v.name.clone(), i).is_some() {
            return Err(DescriptionError::DuplicateName { name: v.name.clone() });
        }
    }
    for (alias, index) in aliases {
        if by_name.insert(alias.clone(), index).is_some() {
            return Err(DescriptionError::DuplicateAlias { alias, variable: variables[index].name.clone() });
        }
    }
    Ok(by_name)
}

/// Checks that value references are unique as the version requires and that every
/// enumeration variable's type is defined.
fn check_variables(variables: &[VariableInfo], enumerations: &[EnumerationInfo], version: FmiVersion) -> Result<(), DescriptionError> {
    let mut seen = HashMap::new();
    for v in variables {
        // FMI 3.0 value references are unique over all types (other names are Alias
        // elements); FMI 2.0 ones per access type, where variables of the same type that
        // share one are aliases.
        let class = if version == FmiVersion::V3 { BaseType::Real } else { v.base.access() };
        if let Some(first) = seen.insert((class, v.value_reference), v.base) {
            if version == FmiVersion::V3 {
                return Err(DescriptionError::DuplicateValueReference { variable: v.name.clone(), value_reference: v.value_reference });
            }
            if first != v.base {
                return Err(DescriptionError::AliasTypes {
                    variable: v.name.clone(),
                    value_reference: v.value_reference,
                    class: v.base.access(),
                    first,
                    second: v.base,
                });
            }
        }
        if v.base == BaseType::Enumeration {
            let known = v.declared_type.as_ref().is_some_and(|t| enumerations.iter().any(|e| &e.name == t));
            if !known {
                return Err(DescriptionError::UndeclaredEnumeration { variable: v.name.clone() });
            }
        }
    }
    Ok(())
}

/// Sets each output's direct inputs from `ModelStructure` (1-based indices): every input for
/// an output it leaves out or gives no `dependencies` attribute, else the inputs among its
/// dependencies.
fn resolve_direct_inputs(variables: &mut [VariableInfo], output_dependencies: Vec<Dependencies<usize>>) -> Result<(), DescriptionError> {
    let inputs: Vec<usize> = (0..variables.len()).filter(|&i| variables[i].causality == Causality::Input).collect();
    // An output not listed in ModelStructure may depend on every input.
    for v in variables.iter_mut().filter(|v| v.causality == Causality::Output) {
        v.direct_inputs = inputs.clone();
    }
    for (index, deps) in output_dependencies {
        let Some(output) = index.checked_sub(1).filter(|&i| i < variables.len()) else {
            return Err(DescriptionError::OutputIndex { index });
        };
        variables[output].direct_inputs = match deps {
            // No `dependencies` attribute: the output may depend on every input.
            None => inputs.clone(),
            Some(list) => {
                let mut direct = Vec::new();
                for d in list {
                    let Some(i) = d.checked_sub(1).filter(|&i| i < variables.len()) else {
                        return Err(DescriptionError::DependencyIndex { index: d, output: variables[output].name.clone() });
                    };
                    if variables[i].causality == Causality::Input && !direct.contains(&i) {
                        direct.push(i);
                    }
                }
                direct
            }
        };
    }
    Ok(())
}

impl Interface {
    /// Reads the interface of the FMU archive at `path` (FMI 2.0 or 3.0). Errors name the
    /// file.
    pub fn read(path: &Path) -> Result<Self, FmuFileError> {
        let fail = |problem| FmuFileError { path: path.to_owned(), problem };
        let file = std::fs::File::open(path).map_err(|e| fail(FmuProblem::Open(e)))?;
        let mut archive = zip::ZipArchive::new(file).map_err(|e| fail(FmuProblem::NotZip(e)))?;
        let mut xml = String::new();
        archive
            .by_name("modelDescription.xml")
            .map_err(|e| fail(FmuProblem::NoDescription(e)))?
            .take(MAX_DESCRIPTION_BYTES)
            .read_to_string(&mut xml)
            .map_err(|e| fail(FmuProblem::ReadDescription(e)))?;
        if xml.len() as u64 >= MAX_DESCRIPTION_BYTES {
            return Err(fail(FmuProblem::DescriptionTooLarge { limit_mib: MAX_DESCRIPTION_BYTES >> 20 }));
        }
        Self::parse(&xml).map_err(|e| fail(FmuProblem::Description(e)))
    }

    /// Parses the text of a `modelDescription.xml` of an FMI 2.0 or FMI 3.0 Co-Simulation
    /// FMU. A version other than 2.0 and 3.x is read as FMI 2.0, then refused.
    pub fn parse(xml: &str) -> Result<Self, DescriptionError> {
        let mut reader = quick_xml::Reader::from_str(xml);
        let Some(root) = Root::read(&mut reader)? else { return Err(DescriptionError::NoVersion) };
        let mut reading = Reading::default();
        if root.is_fmi3() {
            fmi3::read(&mut reader, &mut reading)?;
        } else {
            fmi2::read(&mut reader, &mut reading)?;
        }
        reading.finish(root)
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
fn item(e: &BytesStart, type_name: &str) -> Result<(String, i64), DescriptionError> {
    let name = attribute(e.attributes(), b"name")?.ok_or_else(|| DescriptionError::ItemWithoutName { type_name: type_name.to_owned() })?;
    let Some(value) = attribute(e.attributes(), b"value")? else {
        return Err(DescriptionError::ItemWithoutValue { item: name, type_name: type_name.to_owned() });
    };
    match value.trim().parse() {
        Ok(v) => Ok((name, v)),
        Err(_) => Err(DescriptionError::ItemNotInteger { item: name, type_name: type_name.to_owned(), value }),
    }
}

/// The `dependencies` attribute of `e`, a list of numbers (`expected` says what each is, for
/// messages); `None` when absent.
fn dependencies<T: std::str::FromStr>(e: &BytesStart, expected: &'static str) -> Result<Option<Vec<T>>, DescriptionError> {
    let Some(text) = attribute(e.attributes(), b"dependencies")? else { return Ok(None) };
    let list =
        text.split_whitespace().map(|t| t.parse::<T>().map_err(|_| DescriptionError::BadDependency { text: t.to_owned(), expected }));
    list.collect::<Result<Vec<_>, _>>().map(Some)
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

/// The Boolean attribute `name` of `e` (false when absent).
fn flag(e: &BytesStart, name: &'static str) -> Result<bool, DescriptionError> {
    match attribute(e.attributes(), name.as_bytes())?.as_deref().map(str::trim) {
        None | Some("false") | Some("0") => Ok(false),
        Some("true") | Some("1") => Ok(true),
        Some(other) => Err(DescriptionError::NotABoolean { attribute: name, value: other.to_owned() }),
    }
}

/// The value of attribute `key`, unescaped, if present.
fn attribute(attrs: Attributes, key: &[u8]) -> Result<Option<String>, DescriptionError> {
    for a in attrs {
        let a = a.map_err(DescriptionError::Attribute)?;
        if a.key.as_ref() == key {
            return Ok(Some(a.unescape_value().map_err(DescriptionError::Escape)?.into_owned()));
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn other_versions_and_model_exchange_are_refused() {
        let xml = fmi2::tests::XML;
        let e = Interface::parse(&xml.replace(r#"fmiVersion="2.0""#, r#"fmiVersion="1.0""#)).unwrap_err().to_string();
        assert!(e.contains("only FMI 2.0 and 3.0"), "{e}");
        let e = Interface::parse(&xml.replace(r#"<CoSimulation modelIdentifier="M"/>"#, r#"<ModelExchange modelIdentifier="M"/>"#))
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a Co-Simulation FMU"), "{e}");
        let e = Interface::parse(&xml.replace(r#"name="w""#, r#"name="u""#)).unwrap_err().to_string();
        assert!(e.contains("two variables are named 'u'"), "{e}");
        let e = Interface::parse("<fmiModelDescription/>").unwrap_err().to_string();
        assert_eq!(e, "no fmiModelDescription element with an fmiVersion");
    }
}
