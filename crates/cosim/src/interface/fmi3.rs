//! The FMI 3.0 reader: `TypeDefinitions/EnumerationType`s (items directly inside), variables
//! as their type's element directly in `ModelVariables` (`Float64`, `Int8`, ..., `Binary`,
//! `Clock`), with `Dimension` (an array), `Alias` (another name) and `Start` children, and
//! `ModelStructure/Output`s whose outputs and dependencies are value references, unique over
//! all types.

use quick_xml::events::{BytesStart, Event};

use super::{attribute, dependencies, next_event, BaseType, Dependencies, DescriptionError, Pending, Reading, TypeElement, VariableInfo};

/// Reads the rest of an FMI 3.0 description after its root element into `r`.
pub(super) fn read(reader: &mut quick_xml::Reader<&[u8]>, r: &mut Reading) -> Result<(), DescriptionError> {
    loop {
        let event = next_event(reader)?;
        let empty = matches!(event, Event::Empty(_));
        match event {
            Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"CoSimulation" => r.co_simulation(&e)?,
            Event::Start(e) if is_type_definition(&e) => r.start_type(&e)?,
            Event::Start(e) | Event::Empty(e) if r.opens_items(&e) => r.open_items(),
            // FMI 3.0 items sit directly in the EnumerationType.
            Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"Item" => {
                r.open_items();
                r.item(&e)?;
            }
            Event::End(e) if matches!(e.name().as_ref(), b"SimpleType" | b"EnumerationType") => r.end_type(),
            // A variable is its type's element, directly in ModelVariables.
            Event::Start(e) | Event::Empty(e) if r.in_variables && r.current.is_none() => variable(r, &e, empty)?,
            Event::Start(e) | Event::Empty(e) if r.current.is_some() && is_variable_child(&e) => variable_child(r, &e)?,
            Event::End(e) if r.closes_variable(e.name().as_ref()) => r.end_variable()?,
            Event::Start(e) if e.name().as_ref() == b"ModelVariables" => r.in_variables = true,
            Event::End(e) if e.name().as_ref() == b"ModelVariables" => r.in_variables = false,
            Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"Output" => output(r, &e)?,
            Event::Start(e) if e.name().as_ref() == b"Outputs" => r.in_outputs = true,
            Event::End(e) if e.name().as_ref() == b"Outputs" => r.in_outputs = false,
            Event::Start(e) | Event::Empty(e) if r.in_outputs && e.name().as_ref() == b"Unknown" => r.output_unknown(&e)?,
            Event::Eof => return Ok(()),
            _ => {}
        }
    }
}

/// Whether `e` starts a type definition (an `EnumerationType`, or a `SimpleType` as FMI 2.0
/// has).
fn is_type_definition(e: &BytesStart) -> bool {
    matches!(e.name().as_ref(), b"SimpleType" | b"EnumerationType")
}

/// The type of variable element `name` of `ModelVariables`, if it is one.
fn base_type(name: &[u8]) -> Option<BaseType> {
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

/// An element of `ModelVariables`: a variable if it is a type's element (read whole if
/// `empty`, else until its end), else skipped.
fn variable(r: &mut Reading, e: &BytesStart, empty: bool) -> Result<(), DescriptionError> {
    let Some(base) = base_type(e.name().as_ref()) else { return Ok(()) };
    let mut p = Pending::read(e)?;
    p.base = Some(TypeElement::read(e, base)?);
    if empty {
        r.variables.push(p.finish()?);
    } else {
        r.current = Some(p);
    }
    Ok(())
}

/// Whether `e`, inside a variable, says something of it: `Dimension`, `Alias` or `Start`.
fn is_variable_child(e: &BytesStart) -> bool {
    matches!(e.name().as_ref(), b"Dimension" | b"Alias" | b"Start")
}

/// An element inside the variable being read: `Dimension` makes it an array, `Alias` gives
/// it another name, `Start` a start value (a String's or Binary's).
fn variable_child(r: &mut Reading, e: &BytesStart) -> Result<(), DescriptionError> {
    let Some(current) = r.current.as_mut() else { return Ok(()) };
    match e.name().as_ref() {
        b"Dimension" => current.is_array = true,
        b"Alias" => {
            let name =
                attribute(e.attributes(), b"name")?.ok_or(DescriptionError::MissingAttribute { element: "an Alias", attribute: "name" })?;
            r.aliases.push((name, r.variables.len()));
        }
        b"Start" => {
            if let Some(t) = current.base.as_mut() {
                t.has_start = true;
            }
        }
        _ => {}
    }
    Ok(())
}

/// An `Output` of `ModelStructure`: an output's value reference and its dependencies'.
fn output(r: &mut Reading, e: &BytesStart) -> Result<(), DescriptionError> {
    let vr = attribute(e.attributes(), b"valueReference")?
        .ok_or(DescriptionError::MissingAttribute { element: "an Output of ModelStructure", attribute: "valueReference" })?;
    let vr = vr.trim().parse::<u32>().map_err(|_| DescriptionError::NotANumber {
        section: "ModelStructure",
        attribute: "valueReference",
        text: vr,
    })?;
    let deps = dependencies(e, "a value reference")?;
    r.output_value_references.push((vr, deps));
    Ok(())
}

/// The outputs and dependencies `by_value_reference` gives as 1-based indices into
/// `variables`, as FMI 2.0 gives them.
pub(super) fn by_index(
    variables: &[VariableInfo],
    by_value_reference: Vec<Dependencies<u32>>,
) -> Result<Vec<Dependencies<usize>>, DescriptionError> {
    let index_of = |vr: u32| variables.iter().position(|v| v.value_reference == vr).map(|i| i + 1);
    let mut by_index = Vec::with_capacity(by_value_reference.len());
    for (vr, deps) in by_value_reference {
        let index = index_of(vr).ok_or(DescriptionError::UnknownOutput { value_reference: vr })?;
        let deps = match deps {
            None => None,
            Some(list) => Some(
                list.into_iter()
                    .map(|d| index_of(d).ok_or(DescriptionError::UnknownDependency { value_reference: d }))
                    .collect::<Result<Vec<_>, _>>()?,
            ),
        };
        by_index.push((index, deps));
    }
    Ok(by_index)
}

#[cfg(test)]
mod tests {
    use super::super::*;

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
    }

    #[test]
    fn fmi3_names_value_references_and_token_are_checked() {
        let parse_err = |xml: &str| Interface::parse(xml).unwrap_err().to_string();
        // Value references are unique over all types in FMI 3.0.
        let e = parse_err(&XML3.replace(r#"name="b_in" valueReference="27""#, r#"name="b_in" valueReference="26""#));
        assert!(e.contains("'b_in': value reference 26 is used twice"), "{e}");
        // An Alias element is another name of its variable; names stay unique.
        let k = r#"start="2" declaredType="Angle"/>"#;
        let aliased = XML3.replace(k, r#"start="2" declaredType="Angle"><Alias name="k_deg" displayUnit="deg"/></Float64>"#);
        let i = Interface::parse(&aliased).unwrap();
        assert_eq!(i.get("k_deg"), i.get("k"));
        assert_eq!((i.variables.len(), i.index("k_deg"), i.get("i8_in").unwrap().value_reference), (12, i.index("k"), 11));
        let e = parse_err(&aliased.replace("k_deg", "n"));
        assert!(e.contains("two variables are named 'n' (an Alias of 'k')"), "{e}");
        let e = parse_err(
            &XML3.replace(r#"<Output valueReference="2" dependencies="1"/>"#, r#"<Output valueReference="2" dependencies="99"/>"#),
        );
        assert!(e.contains("dependency 99 is not a value reference"), "{e}");
        let e = parse_err(
            &XML3.replace(r#"<Output valueReference="2" dependencies="1"/>"#, r#"<Output valueReference="2" dependencies="x"/>"#),
        );
        assert_eq!(e, "dependencies: 'x' is not a value reference");
        let e = parse_err(&XML3.replace(r#" instantiationToken="{t}""#, ""));
        assert!(e.contains("no instantiationToken"), "{e}");
    }
}
