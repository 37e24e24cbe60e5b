//! The XML writing both versions' `modelDescription.xml` share: a writer that cannot fail (it
//! writes to memory) and the elements FMI 2.0 and 3.0 write alike.

use std::io::Cursor;

use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, Event};
use quick_xml::Writer;

use crate::description::{write_unit_definitions, Causality, DefaultExperiment, ModelDescription, Unit, Variable, LOG_CATEGORIES};

const IN_MEMORY: &str = "writing XML to memory cannot fail";

/// An indented XML document in memory, opened with its declaration.
pub(crate) struct Xml(Writer<Cursor<Vec<u8>>>);

impl Xml {
    /// A document holding the XML declaration only.
    pub(crate) fn new() -> Self {
        let mut w = Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2);
        w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None))).expect(IN_MEMORY);
        Self(w)
    }

    /// Opens element `e`.
    pub(crate) fn start(&mut self, e: BytesStart) {
        self.0.write_event(Event::Start(e)).expect(IN_MEMORY);
    }

    /// Writes the empty element `e`.
    pub(crate) fn empty(&mut self, e: BytesStart) {
        self.0.write_event(Event::Empty(e)).expect(IN_MEMORY);
    }

    /// Closes element `name`.
    pub(crate) fn end(&mut self, name: &str) {
        self.0.write_event(Event::End(BytesEnd::new(name))).expect(IN_MEMORY);
    }

    /// `UnitDefinitions` of `units` (nothing for none).
    pub(crate) fn unit_definitions(&mut self, units: &[&Unit]) {
        write_unit_definitions(&mut self.0, units);
    }

    /// `LogCategories`, each description passed through `describe` (FMI 3.0 renames the
    /// functions it names).
    pub(crate) fn log_categories(&mut self, describe: impl Fn(&str) -> String) {
        self.start(BytesStart::new("LogCategories"));
        for c in LOG_CATEGORIES {
            let description = describe(c.description);
            self.empty(BytesStart::new("Category").with_attributes([("name", c.name), ("description", description.as_str())]));
        }
        self.end("LogCategories");
    }

    /// `TypeDefinitions` of `d`'s enumeration types (nothing for none): per type an element
    /// `named` carrying its name, holding its `Item`s directly or inside an element `inner`.
    pub(crate) fn type_definitions(&mut self, d: &ModelDescription, named: &str, inner: Option<&str>) {
        let enumerations = d.enumeration_types();
        if enumerations.is_empty() {
            return;
        }
        self.start(BytesStart::new("TypeDefinitions"));
        for t in enumerations {
            self.start(BytesStart::new(named).with_attributes([("name", t.name.as_str())]));
            if let Some(inner) = inner {
                self.start(BytesStart::new(inner));
            }
            for item in &t.items {
                let value = item.value.to_string();
                self.empty(BytesStart::new("Item").with_attributes([
                    ("name", item.name.as_str()),
                    ("value", value.as_str()),
                    ("description", item.description.as_str()),
                ]));
            }
            if let Some(inner) = inner {
                self.end(inner);
            }
            self.end(named);
        }
        self.end("TypeDefinitions");
    }

    /// `DefaultExperiment`, if the model declares one.
    pub(crate) fn default_experiment(&mut self, experiment: Option<&DefaultExperiment>) {
        if let Some(de) = experiment {
            let (start, stop, step) = (de.start_time.to_string(), de.stop_time.to_string(), de.step_size.to_string());
            self.empty(BytesStart::new("DefaultExperiment").with_attributes([
                ("startTime", start.as_str()),
                ("stopTime", stop.as_str()),
                ("stepSize", step.as_str()),
            ]));
        }
    }

    /// The document as text, with a final newline.
    pub(crate) fn finish(self) -> String {
        let mut text = String::from_utf8(self.0.into_inner().into_inner()).expect("XML is UTF-8");
        text.push('\n');
        text
    }
}

/// The `initial` attribute of `v`, the same rule in both versions: parameters and outputs
/// (or locals) with a start value are exact, other outputs calculated.
pub(crate) fn initial(v: &Variable) -> Option<&'static str> {
    match v.causality {
        Causality::Parameter => Some("exact"),
        Causality::Output | Causality::Local if v.is_exact() => Some("exact"),
        Causality::Output => Some("calculated"),
        _ => None,
    }
}
