//! The FMI 2.0 reader: `TypeDefinitions/SimpleType`s (enumerations' items inside an
//! `Enumeration` element), `ScalarVariable`s with their type element, and
//! `ModelStructure/Outputs` whose outputs and dependencies are 1-based indices into
//! `ModelVariables`. Value references are unique per access class; variables of one type that
//! share one are aliases (checked in the parent module).

use quick_xml::events::{BytesStart, Event};

use super::{next_event, BaseType, DescriptionError, Pending, Reading, TypeElement};

/// Reads the rest of an FMI 2.0 description after its root element into `r`.
pub(super) fn read(reader: &mut quick_xml::Reader<&[u8]>, r: &mut Reading) -> Result<(), DescriptionError> {
    loop {
        match next_event(reader)? {
            Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"CoSimulation" => r.co_simulation(&e)?,
            Event::Start(e) if e.name().as_ref() == b"SimpleType" => r.start_type(&e)?,
            Event::Start(e) | Event::Empty(e) if r.opens_items(&e) => r.open_items(),
            Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"Item" => r.item(&e)?,
            Event::End(e) if e.name().as_ref() == b"SimpleType" => r.end_type(),
            Event::Start(e) if e.name().as_ref() == b"ScalarVariable" => r.current = Some(Pending::read(&e)?),
            Event::Start(e) | Event::Empty(e) if r.current.as_ref().is_some_and(|c| c.base.is_none()) => type_element(r, &e)?,
            Event::End(e) if r.closes_variable(e.name().as_ref()) => r.end_variable()?,
            Event::Start(e) if e.name().as_ref() == b"ModelVariables" => r.in_variables = true,
            Event::End(e) if e.name().as_ref() == b"ModelVariables" => r.in_variables = false,
            Event::Start(e) if e.name().as_ref() == b"Outputs" => r.in_outputs = true,
            Event::End(e) if e.name().as_ref() == b"Outputs" => r.in_outputs = false,
            Event::Start(e) | Event::Empty(e) if r.in_outputs && e.name().as_ref() == b"Unknown" => r.output_unknown(&e)?,
            Event::Eof => return Ok(()),
            _ => {}
        }
    }
}

/// The type element of the `ScalarVariable` being read (other elements in it are skipped).
fn type_element(r: &mut Reading, e: &BytesStart) -> Result<(), DescriptionError> {
    let base = match e.name().as_ref() {
        b"Real" => BaseType::Real,
        b"Integer" => BaseType::Integer,
        b"Boolean" => BaseType::Boolean,
        b"String" => BaseType::String,
        b"Enumeration" => BaseType::Enumeration,
        _ => return Ok(()),
    };
    if let Some(c) = r.current.as_mut() {
        c.base = Some(TypeElement::read(e, base)?);
    }
    Ok(())
}

#[cfg(test)]
pub(super) mod tests {
    use super::super::*;

    pub(in crate::interface) const XML: &str = r#"<?xml version="1.0"?>
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
        let e = Interface::parse(&xml.replace(r#"name="k" valueReference="1""#, r#"name="k" valueReference="0""#)).unwrap_err().to_string();
        assert!(e.contains("value reference 0 of type Integer is used twice, by an Enumeration and an Integer"), "{e}");
        // Two variables of one type sharing a value reference are aliases (FMI 2.0, 2.2.7).
        let aliased = xml.replace(
            r#"<ScalarVariable name="c" valueReference="5""#,
            r#"<ScalarVariable name="z_alias" valueReference="3" causality="local" initial="calculated"><Real/></ScalarVariable>
    <ScalarVariable name="c" valueReference="5""#,
        );
        let i = Interface::parse(&aliased).unwrap();
        assert_eq!((i.get("z_alias").unwrap().value_reference, i.get("z").unwrap().value_reference), (3, 3));
        let e = Interface::parse(&xml.replace(r#"declaredType="Mode""#, r#"declaredType="Gear""#)).unwrap_err().to_string();
        assert!(e.contains("no declared type"), "{e}");
    }

    #[test]
    fn bad_attributes_name_the_variable_or_element() {
        let cases = [
            (
                r#"name="y" valueReference="2" causality="output""#,
                r#"name="y" valueReference="2" causality="out""#,
                "variable 'y': unknown causality 'out'",
            ),
            (r#"name="y" valueReference="2""#, r#"name="y" valueReference="two""#, "variable 'y': valueReference 'two' is not a number"),
            (
                r#"<Real/></ScalarVariable>
    <ScalarVariable name="z""#,
                r#"</ScalarVariable>
    <ScalarVariable name="z""#,
                "variable 'y' has no type element",
            ),
            (
                r#"<CoSimulation modelIdentifier="M"/>"#,
                r#"<CoSimulation modelIdentifier="M" canHandleVariableCommunicationStepSize="yes"/>"#,
                "canHandleVariableCommunicationStepSize is 'yes', not a Boolean",
            ),
            (
                r#"<Unknown index="3" dependencies="2"/>"#,
                r#"<Unknown index="3" dependencies="9"/>"#,
                "Outputs: dependency 9 of 'y' is not a variable",
            ),
            (r#" guid="{x}""#, "", "fmiModelDescription has no guid"),
        ];
        for (from, to, expected) in cases {
            assert!(XML.contains(from), "{from}");
            let e = Interface::parse(&XML.replace(from, to)).unwrap_err();
            assert_eq!(e.to_string(), expected);
        }
    }
}
