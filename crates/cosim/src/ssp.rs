//! A system written as an SSP 1.0 archive (System Structure and Parameterization, Modelica
//! Association Project): a zip holding `SystemStructure.ssd` and every FMU under `resources/`.
//!
//! # What the SSD holds
//! Written so that engines read it without help: fmpy (`simulate_ssp`), libcosim (the Open
//! Simulation Platform's engine, `libcosimpy`) and anything that follows SSP 1.0.
//! - One `ssd:System` named after the archive, whose `ssd:Elements` are one `ssd:Component`
//!   per unit, in declaration order (`source="resources/<file>.fmu"`,
//!   `implementation="CoSimulation"`). Two units loaded from the same file share one copy.
//! - Per component, `ssd:Connectors` in `modelDescription.xml` order, each with its type
//!   (`ssc:Real`, `ssc:Integer`, `ssc:Boolean`, `ssc:String`, `ssc:Enumeration name="…"` with
//!   the type listed in `ssd:Enumerations`; an FMI 3.0 unit's Float64 and Float32 as `ssc:Real`,
//!   its integers of every width as `ssc:Integer`; Binary, Clock and array variables get no
//!   connector): every output (kind `output`), every *connected* input (kind `input`) and every parameter the spec sets
//!   (kind `parameter`; an enumeration has none, as an `ssc:Enumeration` needs a declared
//!   type and libcosim refuses an untyped connector). An input that is not connected gets no
//!   connector, even when the spec sets it: SSP only requires connectors for what connections
//!   use, and importers such as fmpy expect every input connector to be connected (and would
//!   overwrite its value).
//! - Per component, the spec's parameters (and values of unconnected inputs) of that unit as
//!   `ssd:ParameterBindings` with one inline `ssv:ParameterSet` named after the system, under
//!   the FMU's own variable names (`q0_1`, not `arm.q0_1`). Bindings on the components are
//!   what every engine applies; libcosim, for one, ignores a system-level binding. An
//!   enumeration's value is written as `ssv:Integer` (FMI 2.0 sets it as an fmi2Integer, FMI
//!   3.0 as an Int64).
//! - `ssd:Connections`, one per output → input pair, `*` patterns expanded by
//!   [`System::connect`].
//! - `ssd:DefaultExperiment` with the start and stop time. SSP 1.0 has no place for the
//!   communication step, so it goes into annotations there, one per reader:
//!   - libcosim's, type [`OSP_ANNOTATION_TYPE`]:
//!     `<osp:Algorithm><osp:FixedStepAlgorithm baseStepSize="…"/></osp:Algorithm>` (without
//!     it, and without a step from the caller, libcosim has no master algorithm and crashes);
//!   - ours, type [`ANNOTATION_TYPE`], with the step, the stepping algorithm and the recorded
//!     variables: `<nr:Simulation stepSize="…" algorithm="gauss-seidel|jacobi"
//!     recordEvery="…">` with one `<nr:Record variable="unit.variable"/>` per recorded
//!     variable and one `<nr:Event time="…" [until="…"]>` per event of the system file, holding
//!     `<nr:Set variable="unit.variable" type="Real|Integer|Boolean|String" value="…"/>`. SSP
//!     1.0 has no events: other engines run such a system without its changes.
//!
//! What the engines make of it differs in the ordering, not in the system: see the README
//! ("SSP files in other engines") for each engine's ordering and the measured gaps.

use std::collections::{BTreeSet, HashMap};
use std::io::{Cursor, Write};
use std::path::{Path, PathBuf};

use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, Event};
use quick_xml::Writer;

use crate::error::MasterError;
use crate::interface::{BaseType, Causality, EnumerationInfo, Interface};
use crate::spec::{EventSpec, SimulationSpec, SystemSpec, Value};
use crate::system::{check_value, Setting, System};

const NS_SSD: &str = "http://ssp-standard.org/SSP1/SystemStructureDescription";
const NS_SSC: &str = "http://ssp-standard.org/SSP1/SystemStructureCommon";
const NS_SSV: &str = "http://ssp-standard.org/SSP1/SystemStructureParameterValues";
/// The Open Simulation Platform's annotations (libcosim).
const NS_OSP: &str = "http://opensimulationplatform.com/SSP/OSPAnnotations";
/// `type` of the `ssc:Annotation` in `ssd:DefaultExperiment` that libcosim reads its master
/// algorithm and communication step from.
pub const OSP_ANNOTATION_TYPE: &str = "com.opensimulationplatform";

/// Namespace of the elements inside the simulation annotation (named after the crate's first
/// name, which SSP files already written carry).
pub const ANNOTATION_NAMESPACE: &str = "urn:fmi2-cosim:ssp:simulation";

/// `type` of the `ssc:Annotation` in `ssd:DefaultExperiment` that holds the communication
/// step, the algorithm and the recorded variables.
pub const ANNOTATION_TYPE: &str = "fmi2-cosim.simulation";

/// Writes `out` as an SSP 1.0 archive (.ssp, a zip) of the system a spec describes:
/// SystemStructure.ssd plus every FMU under resources/.
///
/// `base` is the folder the spec's relative FMU paths are taken from. The FMUs are not
/// loaded, only their `modelDescription.xml` read, and the system is checked as
/// [`System::from_spec`] checks it. See [`write_system`]. The spec's events go into our
/// annotation (SSP 1.0 has no events: other engines ignore them).
pub fn write_ssp(spec: &SystemSpec, base: &Path, out: &Path) -> Result<(), MasterError> {
    for (k, event) in spec.event.iter().enumerate() {
        event.check().map_err(|e| MasterError::new(format!("event {}: {e}", k + 1)))?;
    }
    write_with_events(&System::from_spec(spec, base)?, &spec.simulation, &spec.event, out)
}

/// Writes `out` as an SSP 1.0 archive of `system`, simulated as `simulation` says. The
/// archive is written to a temporary file beside `out` and renamed over it when complete, so
/// on any error nothing is left at `out` (and an existing `out` is untouched).
pub fn write_system(system: &System, simulation: &SimulationSpec, out: &Path) -> Result<(), MasterError> {
    write_with_events(system, simulation, &[], out)
}

fn write_with_events(system: &System, simulation: &SimulationSpec, events: &[EventSpec], out: &Path) -> Result<(), MasterError> {
    simulation.check()?;
    system.recordable(&simulation.record)?;
    let system_name = out.file_stem().and_then(|s| s.to_str()).filter(|s| !s.is_empty()).unwrap_or("system").to_owned();
    let sources = sources(system)?;
    let ssd = ssd_xml(system, simulation, events, &sources, &system_name);
    let mut resources: Vec<(PathBuf, String)> = Vec::new();
    for (u, source) in system.units().iter().zip(&sources) {
        if !resources.iter().any(|(_, s)| s == source) {
            resources.push((u.path.clone(), source.clone()));
        }
    }
    write_archive(out, &ssd, &resources)
}

/// The path in the archive of each unit's FMU, `resources/<file>.fmu`; units loaded from the
/// same file share one.
fn sources(system: &System) -> Result<Vec<String>, MasterError> {
    let mut by_file: HashMap<PathBuf, String> = HashMap::new();
    let mut sources: Vec<String> = Vec::new();
    for u in system.units() {
        let canonical = std::fs::canonicalize(&u.path).map_err(|e| MasterError::new(format!("{}: {e}", u.path.display())).unit(&u.name))?;
        let source = match by_file.get(&canonical) {
            Some(s) => s.clone(),
            None => {
                let s = resource_name(&u.path, |candidate| sources.iter().any(|r| r == candidate));
                by_file.insert(canonical, s.clone());
                s
            }
        };
        sources.push(source);
    }
    Ok(sources)
}

/// `resources/<name>.fmu` for `path`: its file stem with anything but letters, digits, '.',
/// '-' and '_' replaced by '_' (so the name is a plain relative URI), made unique with a
/// counter if `taken`.
fn resource_name(path: &Path, taken: impl Fn(&str) -> bool) -> String {
    let stem = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    let mut clean: String = stem.chars().map(|c| if c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '_') { c } else { '_' }).collect();
    if clean.is_empty() || clean.starts_with('.') {
        clean.insert(0, '_');
    }
    let mut candidate = format!("resources/{clean}.fmu");
    let mut n = 2;
    while taken(&candidate) {
        candidate = format!("resources/{clean}-{n}.fmu");
        n += 1;
    }
    candidate
}

/// An xs:double: the shortest text that reads back as the same number.
fn xs_double(x: f64) -> String {
    if x.is_nan() {
        "NaN".into()
    } else if x.is_infinite() {
        if x > 0.0 { "INF" } else { "-INF" }.into()
    } else {
        format!("{x:?}")
    }
}

/// The `ssv:` element and value text of a parameter of type `base`. An enumeration is set as
/// an integer (`fmi2SetInteger`, `fmi3SetInt64`), and an ssv:Enumeration would need its item's
/// name.
fn parameter_value(base: BaseType, value: &Value) -> (&'static str, String) {
    match (base, value) {
        (b, Value::Integer(i)) if b.access() == BaseType::Real => ("ssv:Real", xs_double(*i as f64)),
        (_, Value::Real(x)) => ("ssv:Real", xs_double(*x)),
        (_, Value::Integer(i)) => ("ssv:Integer", i.to_string()),
        (_, Value::Boolean(b)) => ("ssv:Boolean", b.to_string()),
        (_, Value::String(s)) => ("ssv:String", s.clone()),
    }
}

/// The SSP 1.0 connector type of `base`: FMI 3.0's types by their class (Float64 and
/// Float32 as Real, every integer type as Integer).
fn ssp_type(base: BaseType) -> &'static str {
    match base {
        BaseType::Enumeration => "Enumeration",
        b => b.access().name(),
    }
}

/// An XML writer into memory, which cannot fail.
struct Xml(Writer<Cursor<Vec<u8>>>);

impl Xml {
    const OK: &'static str = "writing XML to memory cannot fail";

    fn start(&mut self, e: BytesStart) {
        self.0.write_event(Event::Start(e)).expect(Self::OK);
    }

    fn end(&mut self, name: &str) {
        self.0.write_event(Event::End(BytesEnd::new(name))).expect(Self::OK);
    }

    fn empty(&mut self, e: BytesStart) {
        self.0.write_event(Event::Empty(e)).expect(Self::OK);
    }
}

/// The text of `SystemStructure.ssd`: the system's components and connections, the
/// enumeration types its connectors use, and the default experiment.
fn ssd_xml(system: &System, simulation: &SimulationSpec, events: &[EventSpec], sources: &[String], system_name: &str) -> String {
    let mut w = Xml(Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2));
    w.0.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None))).expect(Xml::OK);
    write_header(&mut w, system_name);
    w.start(BytesStart::new("ssd:System").with_attributes([("name", system_name)]));
    let mut enumerations: Vec<&EnumerationInfo> = Vec::new();
    w.start(BytesStart::new("ssd:Elements"));
    for (index, (_, source)) in system.units().iter().zip(sources).enumerate() {
        write_component(&mut w, system, index, source, system_name, &mut enumerations);
    }
    w.end("ssd:Elements");
    write_connections(&mut w, system);
    w.end("ssd:System");
    write_enumerations(&mut w, &enumerations);
    write_default_experiment(&mut w, simulation, events);
    w.end("ssd:SystemStructureDescription");
    let mut text = String::from_utf8(w.0.into_inner().into_inner()).expect("the XML is built from UTF-8 text");
    text.push('\n');
    text
}

/// The root element's start: the namespaces, the system's name and the tool.
fn write_header(w: &mut Xml, system_name: &str) {
    let tool = concat!("neurarm-cosim ", env!("CARGO_PKG_VERSION"));
    w.start(BytesStart::new("ssd:SystemStructureDescription").with_attributes([
        ("xmlns:ssd", NS_SSD),
        ("xmlns:ssc", NS_SSC),
        ("xmlns:ssv", NS_SSV),
        ("xmlns:osp", NS_OSP),
        ("version", "1.0"),
        ("name", system_name),
        ("generationTool", tool),
    ]));
}

/// The `ssd:Component` of unit `index`, loaded from `source` in the archive: its connectors
/// and parameter bindings. The enumeration types its connectors use are added to
/// `enumerations`.
fn write_component<'a>(
    w: &mut Xml,
    system: &'a System,
    index: usize,
    source: &str,
    system_name: &str,
    enumerations: &mut Vec<&'a EnumerationInfo>,
) {
    let c = &system.units()[index];
    w.start(BytesStart::new("ssd:Component").with_attributes([
        ("name", c.name.as_str()),
        ("type", "application/x-fmu-sharedlibrary"),
        ("source", source),
        ("implementation", "CoSimulation"),
    ]));
    let connectors = connectors(system, index);
    if !connectors.is_empty() {
        write_connectors(w, &c.interface, &connectors, enumerations);
    }
    let settings: Vec<&Setting> = system.settings().iter().filter(|s| s.unit == index).collect();
    if !settings.is_empty() {
        write_parameter_bindings(w, &c.interface, &settings, system_name);
    }
    w.end("ssd:Component");
}

/// The connectors of unit `index`, in `modelDescription.xml` order: name, kind and type of
/// every output, every connected input and every parameter set (but an enumeration's).
fn connectors(system: &System, index: usize) -> Vec<(&str, &'static str, BaseType)> {
    let set: BTreeSet<&str> = system.settings().iter().filter(|s| s.unit == index).map(|s| s.variable.as_str()).collect();
    let connected = |name: &str| system.links().iter().any(|l| l.to_unit == index && l.to_variable == name);
    let variables = &system.units()[index].interface.variables;
    variables
        .iter()
        .filter_map(|v| {
            let kind = match v.causality {
                _ if v.is_array || !v.base.is_connectable() => return None,
                Causality::Output => "output",
                Causality::Input if connected(&v.name) => "input",
                // An ssc:Enumeration needs a declared enumeration type, and libcosim refuses
                // an untyped connector: the binding sets it without one.
                Causality::Parameter if set.contains(v.name.as_str()) && v.base != BaseType::Enumeration => "parameter",
                _ => return None,
            };
            Some((v.name.as_str(), kind, v.base))
        })
        .collect()
}

/// `ssd:Connectors` of a component with interface `interface`; an enumeration connector names
/// its type, which is added to `enumerations`.
fn write_connectors<'a>(
    w: &mut Xml,
    interface: &'a Interface,
    connectors: &[(&str, &str, BaseType)],
    enumerations: &mut Vec<&'a EnumerationInfo>,
) {
    w.start(BytesStart::new("ssd:Connectors"));
    for &(name, kind, base) in connectors {
        w.start(BytesStart::new("ssd:Connector").with_attributes([("name", name), ("kind", kind)]));
        let mut t = BytesStart::new(format!("ssc:{}", ssp_type(base)));
        // An enumeration connector names its type, listed in ssd:Enumerations.
        if let Some(e) = interface.get(name).and_then(|v| interface.enumeration_of(v)).filter(|_| base == BaseType::Enumeration) {
            t.push_attribute(("name", e.name.as_str()));
            if !enumerations.iter().any(|x: &&EnumerationInfo| x.name == e.name) {
                enumerations.push(e);
            }
        }
        w.empty(t);
        w.end("ssd:Connector");
    }
    w.end("ssd:Connectors");
}

/// `ssd:ParameterBindings` of a component with interface `interface`: one inline
/// `ssv:ParameterSet` named after the system with the values `settings` set, as the master
/// sets them.
fn write_parameter_bindings(w: &mut Xml, interface: &Interface, settings: &[&Setting], system_name: &str) {
    w.start(BytesStart::new("ssd:ParameterBindings"));
    w.start(BytesStart::new("ssd:ParameterBinding"));
    w.start(BytesStart::new("ssd:ParameterValues"));
    w.start(BytesStart::new("ssv:ParameterSet").with_attributes([("version", "1.0"), ("name", system_name)]));
    w.start(BytesStart::new("ssv:Parameters"));
    for setting in settings {
        let info = interface.get(&setting.variable);
        let base = info.map_or(BaseType::Real, |v| v.base);
        // As the master sets it: an enumeration item given by name is its value.
        let value = info.and_then(|v| check_value(interface, v, &setting.value).ok()).unwrap_or_else(|| setting.value.clone());
        let (element, text) = parameter_value(base, &value);
        w.start(BytesStart::new("ssv:Parameter").with_attributes([("name", setting.variable.as_str())]));
        w.empty(BytesStart::new(element).with_attributes([("value", text.as_str())]));
        w.end("ssv:Parameter");
    }
    w.end("ssv:Parameters");
    w.end("ssv:ParameterSet");
    w.end("ssd:ParameterValues");
    w.end("ssd:ParameterBinding");
    w.end("ssd:ParameterBindings");
}

/// `ssd:Connections`, one per output → input pair (none if nothing is connected).
fn write_connections(w: &mut Xml, system: &System) {
    if system.links().is_empty() {
        return;
    }
    w.start(BytesStart::new("ssd:Connections"));
    for l in system.links() {
        w.empty(BytesStart::new("ssd:Connection").with_attributes([
            ("startElement", system.units()[l.from_unit].name.as_str()),
            ("startConnector", l.from_variable.as_str()),
            ("endElement", system.units()[l.to_unit].name.as_str()),
            ("endConnector", l.to_variable.as_str()),
        ]));
    }
    w.end("ssd:Connections");
}

/// `ssd:Enumerations`: the enumeration types the connectors use (none if none does).
fn write_enumerations(w: &mut Xml, enumerations: &[&EnumerationInfo]) {
    if enumerations.is_empty() {
        return;
    }
    w.start(BytesStart::new("ssd:Enumerations"));
    for e in enumerations {
        w.start(BytesStart::new("ssc:Enumeration").with_attributes([("name", e.name.as_str())]));
        for (name, value) in &e.items {
            let value = value.to_string();
            w.empty(BytesStart::new("ssc:Item").with_attributes([("name", name.as_str()), ("value", value.as_str())]));
        }
        w.end("ssc:Enumeration");
    }
    w.end("ssd:Enumerations");
}

/// `ssd:DefaultExperiment`: start and stop time, and the communication step in libcosim's
/// annotation and ours (with the algorithm, the recorded variables and the events).
fn write_default_experiment(w: &mut Xml, s: &SimulationSpec, events: &[EventSpec]) {
    let (t0, t1, h, every) = (xs_double(s.start), xs_double(s.stop), xs_double(s.step), s.record_every.max(1).to_string());
    w.start(BytesStart::new("ssd:DefaultExperiment").with_attributes([("startTime", t0.as_str()), ("stopTime", t1.as_str())]));
    w.start(BytesStart::new("ssd:Annotations"));
    // libcosim's step: it matches the literal prefix `osp:`, not the namespace.
    w.start(BytesStart::new("ssc:Annotation").with_attributes([("type", OSP_ANNOTATION_TYPE)]));
    w.start(BytesStart::new("osp:Algorithm"));
    w.empty(BytesStart::new("osp:FixedStepAlgorithm").with_attributes([("baseStepSize", h.as_str())]));
    w.end("osp:Algorithm");
    w.end("ssc:Annotation");
    w.start(BytesStart::new("ssc:Annotation").with_attributes([("type", ANNOTATION_TYPE)]));
    let simulation = BytesStart::new("nr:Simulation").with_attributes([
        ("xmlns:nr", ANNOTATION_NAMESPACE),
        ("stepSize", h.as_str()),
        ("algorithm", s.algorithm.name()),
        ("recordEvery", every.as_str()),
    ]);
    if s.record.is_empty() && events.is_empty() {
        w.empty(simulation);
    } else {
        w.start(simulation);
        for r in &s.record {
            w.empty(BytesStart::new("nr:Record").with_attributes([("variable", r.as_str())]));
        }
        for e in events {
            write_event(w, e);
        }
        w.end("nr:Simulation");
    }
    w.end("ssc:Annotation");
    w.end("ssd:Annotations");
    w.end("ssd:DefaultExperiment");
}

/// An `nr:Event` of our annotation: its time (and a ramp's end) and the values it sets.
fn write_event(w: &mut Xml, e: &EventSpec) {
    let (time, until) = (xs_double(e.time), e.until.map(xs_double));
    let mut element = BytesStart::new("nr:Event").with_attributes([("time", time.as_str())]);
    if let Some(u) = &until {
        element.push_attribute(("until", u.as_str()));
    }
    w.start(element);
    for (variable, value) in &e.set {
        let (kind, text) = match value {
            Value::Real(x) => ("Real", xs_double(*x)),
            Value::Integer(i) => ("Integer", i.to_string()),
            Value::Boolean(b) => ("Boolean", b.to_string()),
            Value::String(t) => ("String", t.clone()),
        };
        w.empty(BytesStart::new("nr:Set").with_attributes([("variable", variable.as_str()), ("type", kind), ("value", text.as_str())]));
    }
    w.end("nr:Event");
}

/// Writes the zip to a temporary file beside `out`, then renames it over `out`.
fn write_archive(out: &Path, ssd: &str, resources: &[(PathBuf, String)]) -> Result<(), MasterError> {
    let fail = |e: &dyn std::fmt::Display| MasterError::new(format!("writing {}: {e}", out.display()));
    let dir = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    // Readable by all (0644 less the umask), as a plain file would be, not a temporary 0600.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o644));
    let tmp = builder.prefix(".neurarm-cosim-").suffix(".ssp.tmp").tempfile_in(dir).map_err(|e| fail(&e))?;
    let mut zip = zip::ZipWriter::new(tmp.reopen().map_err(|e| fail(&e))?);
    let deflated = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    // An FMU is a zip already: stored as it is.
    let stored = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored).large_file(true);
    zip.start_file("SystemStructure.ssd", deflated).map_err(|e| fail(&e))?;
    zip.write_all(ssd.as_bytes()).map_err(|e| fail(&e))?;
    for (path, name) in resources {
        let mut file = std::fs::File::open(path).map_err(|e| MasterError::new(format!("{}: {e}", path.display())))?;
        zip.start_file(name.as_str(), stored).map_err(|e| fail(&e))?;
        std::io::copy(&mut file, &mut zip)
            .map_err(|e| MasterError::new(format!("copying {} into {}: {e}", path.display(), out.display())))?;
    }
    zip.finish().map_err(|e| fail(&e))?.sync_all().map_err(|e| fail(&e))?;
    tmp.persist(out).map_err(|e| fail(&e.error))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn doubles_read_back_exactly() {
        for x in [1.5, -2.0, 0.01, 1e307, 1e-300, 0.1 + 0.2] {
            assert_eq!(xs_double(x).parse::<f64>().unwrap(), x);
        }
        assert_eq!(xs_double(f64::INFINITY), "INF");
        assert_eq!(xs_double(f64::NEG_INFINITY), "-INF");
    }

    #[test]
    fn parameter_values_take_the_variables_type() {
        assert_eq!(parameter_value(BaseType::Real, &Value::Integer(-2)), ("ssv:Real", "-2.0".into()));
        assert_eq!(parameter_value(BaseType::Real, &Value::Real(0.5)), ("ssv:Real", "0.5".into()));
        assert_eq!(parameter_value(BaseType::Integer, &Value::Integer(7)), ("ssv:Integer", "7".into()));
        // FMI 2.0 and 3.0 set an enumeration as an integer; libcosim reads no ssv:Enumeration.
        assert_eq!(parameter_value(BaseType::Enumeration, &Value::Integer(3)), ("ssv:Integer", "3".into()));
        assert_eq!(parameter_value(BaseType::Boolean, &Value::Boolean(false)), ("ssv:Boolean", "false".into()));
        assert_eq!(parameter_value(BaseType::String, &Value::String("a".into())), ("ssv:String", "a".into()));
    }

    #[test]
    fn resource_names_are_plain_and_unique() {
        let taken = ["resources/My_Arm.fmu".to_owned()];
        assert_eq!(resource_name(Path::new("/x/My Arm.fmu"), |c| taken.contains(&c.to_owned())), "resources/My_Arm-2.fmu");
        assert_eq!(resource_name(Path::new("Gain.fmu"), |_| false), "resources/Gain.fmu");
    }
}
