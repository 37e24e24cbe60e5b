//! A system written as an SSP 1.0 archive (System Structure and Parameterization, Modelica
//! Association Project): a zip holding `SystemStructure.ssd` and every FMU under `resources/`.
//!
//! # What the SSD holds
//! - One `ssd:System` named after the archive, whose `ssd:Elements` are one `ssd:Component`
//!   per unit, in declaration order (`source="resources/<file>.fmu"`,
//!   `implementation="CoSimulation"`). Two units loaded from the same file share one copy.
//! - Per component, `ssd:Connectors` in `modelDescription.xml` order, each with its type
//!   (`ssc:Real`, `ssc:Integer`, `ssc:Boolean`, ...): every Real, Integer and Boolean output
//!   (kind `output`), every *connected* input (kind `input`) and every parameter the spec sets
//!   (kind `parameter`). An input that is not connected gets no connector, even when the spec
//!   sets it: SSP only requires connectors for what connections use, and importers such as
//!   fmpy expect every input connector to be connected (and would overwrite its value).
//! - `ssd:Connections`, one per output → input pair, `*` patterns expanded as
//!   [`System::connect`](super::System::connect) does.
//! - The spec's parameters (and values of unconnected inputs) as one system-level
//!   `ssd:ParameterBinding` with an inline `ssv:ParameterSet`, under hierarchical names
//!   (`unit.variable`), so the set applies to the whole system as it stands.
//! - `ssd:DefaultExperiment` with the start and stop time. SSP 1.0 has no place for the
//!   communication step, the stepping algorithm or the recorded variables, so these go into
//!   an `ssc:Annotation` of type [`ANNOTATION_TYPE`] there:
//!   `<nr:Simulation stepSize="…" algorithm="gauss-seidel|jacobi" recordEvery="…">` with one
//!   `<nr:Record variable="unit.variable"/>` per recorded variable.

use std::collections::{BTreeMap, HashMap};
use std::io::{Cursor, Read, Write};
use std::path::{Path, PathBuf};

use quick_xml::events::{BytesDecl, BytesEnd, BytesStart, Event};
use quick_xml::Writer;

use super::{check_value, Algorithm, BaseType, SystemSpec, Value, VariableInfo};

const NS_SSD: &str = "http://ssp-standard.org/SSP1/SystemStructureDescription";
const NS_SSC: &str = "http://ssp-standard.org/SSP1/SystemStructureCommon";
const NS_SSV: &str = "http://ssp-standard.org/SSP1/SystemStructureParameterValues";

/// Namespace of the elements inside the neurarm annotation.
pub const ANNOTATION_NAMESPACE: &str = "urn:neurarm:ssp:simulation";

/// `type` of the `ssc:Annotation` in `ssd:DefaultExperiment` that holds the communication
/// step, the algorithm and the recorded variables.
pub const ANNOTATION_TYPE: &str = "neurarm.simulation";

/// Writes `out` as an SSP 1.0 archive (.ssp, a zip) of the system: SystemStructure.ssd plus every FMU under resources/.
///
/// `base` is the folder the spec's relative FMU paths are taken from. The FMUs are not
/// loaded, only their `modelDescription.xml` read: units, parameters, connections and
/// recorded variables are checked against it as [`System::from_spec`](super::System::from_spec)
/// would. The archive is written to a temporary file beside `out` and renamed over it when
/// complete, so on any error nothing is left at `out` (and an existing `out` is untouched).
pub fn write_ssp(spec: &SystemSpec, base: &Path, out: &Path) -> Result<(), String> {
    let system_name = out.file_stem().and_then(|s| s.to_str()).filter(|s| !s.is_empty()).unwrap_or("system").to_owned();
    let plan = plan(spec, base)?;
    let ssd = ssd_xml(spec, &plan, &system_name);
    write_archive(out, &ssd, &plan.resources)
}

/// The (output, input) variable pairs a connection from `from_var` of one unit to `to_var`
/// of another stands for, given the names of the source's outputs. With a `*` in both names,
/// every output whose name has the text before and after the `*` (sorted by name), mapped to
/// the target name with the same text in place of its `*`; with none, the one pair as given.
/// `from` and `to` are the full names, for messages.
pub(super) fn expand_connection<'a>(
    from: &str,
    to: &str,
    from_var: &str,
    to_var: &str,
    outputs: impl IntoIterator<Item = &'a str>,
) -> Result<Vec<(String, String)>, String> {
    match (from_var.split_once('*'), to_var.split_once('*')) {
        (Some((fp, fs)), Some((tp, ts))) => {
            let mut names: Vec<&str> = outputs.into_iter().filter(|n| n.len() >= fp.len() + fs.len() && n.starts_with(fp) && n.ends_with(fs)).collect();
            names.sort_unstable();
            names.dedup();
            if names.is_empty() {
                return Err(format!("no output matches '{from_var}'"));
            }
            Ok(names.into_iter().map(|n| (n.to_owned(), format!("{tp}{}{ts}", &n[fp.len()..n.len() - fs.len()]))).collect())
        }
        (None, None) => Ok(vec![(from_var.to_owned(), to_var.to_owned())]),
        _ => Err(format!("'{from}' → '{to}': use '*' in both names or in neither")),
    }
}

/// The variables of an FMU, read from the `modelDescription.xml` inside it.
struct Interface {
    /// Variables in `ModelVariables` order.
    order: Vec<String>,
    variables: HashMap<String, VariableInfo>,
}

impl Interface {
    fn get(&self, name: &str) -> Option<&VariableInfo> {
        self.variables.get(name)
    }
}

/// One unit as it goes into the SSD.
struct Component {
    name: String,
    /// Path inside the archive, `resources/<file>.fmu`.
    source: String,
    interface: Interface,
    /// Inputs that a connection sets.
    connected_inputs: Vec<String>,
}

/// One resolved connection.
struct Link {
    from_unit: usize,
    from_var: String,
    to_unit: usize,
    to_var: String,
}

/// Everything checked and resolved, ready to write.
struct Plan {
    components: Vec<Component>,
    links: Vec<Link>,
    /// (hierarchical name, base type of the variable, value).
    parameters: Vec<(String, BaseType, Value)>,
    /// (file to copy, path inside the archive).
    resources: Vec<(PathBuf, String)>,
}

fn plan(spec: &SystemSpec, base: &Path) -> Result<Plan, String> {
    let s = &spec.simulation;
    let valid = s.step > 0.0 && s.step.is_finite() && s.start.is_finite() && s.stop.is_finite() && s.stop >= s.start;
    if !valid {
        return Err(format!("[simulation] needs a positive step and stop ≥ start (got start {}, stop {}, step {})", s.start, s.stop, s.step));
    }
    if spec.fmu.is_empty() {
        return Err("the system has no FMU".into());
    }
    let mut components: Vec<Component> = Vec::new();
    let mut resources: Vec<(PathBuf, String)> = Vec::new();
    // Canonical path of each copied FMU → its path in the archive.
    let mut copied: HashMap<PathBuf, String> = HashMap::new();
    let mut parameters = Vec::new();
    for f in &spec.fmu {
        if f.name.is_empty() || f.name.contains('.') {
            return Err(format!("FMU '{}': a unit name must be non-empty and hold no '.'", f.name));
        }
        if components.iter().any(|c| c.name == f.name) {
            return Err(format!("FMU '{}': two units have this name", f.name));
        }
        let path = base.join(&f.path);
        let interface = read_interface(&path).map_err(|e| format!("FMU '{}': {e}", f.name))?;
        let canonical = std::fs::canonicalize(&path).map_err(|e| format!("FMU '{}': {}: {e}", f.name, path.display()))?;
        let source = match copied.get(&canonical) {
            Some(s) => s.clone(),
            None => {
                let s = resource_name(&path, |candidate| resources.iter().any(|(_, r)| r == candidate));
                copied.insert(canonical.clone(), s.clone());
                resources.push((path.clone(), s.clone()));
                s
            }
        };
        for (k, v) in &f.parameters {
            let info = interface.get(k).ok_or_else(|| format!("FMU '{}', variable '{k}': no such variable in {}", f.name, path.display()))?;
            check_value(info, v).map_err(|m| format!("FMU '{}', variable '{k}': {m}", f.name))?;
            if !matches!(info.causality, "parameter" | "input") {
                return Err(format!("FMU '{}', variable '{k}': {} cannot be set; only parameters and inputs", f.name, with_article(info.causality)));
            }
            parameters.push((format!("{}.{k}", f.name), info.base, v.clone()));
        }
        components.push(Component { name: f.name.clone(), source, interface, connected_inputs: Vec::new() });
    }

    fn unit_index(components: &[Component], name: &str) -> Result<usize, String> {
        components.iter().position(|c| c.name == name).ok_or_else(|| format!("FMU '{name}': no unit of this name in the system"))
    }
    fn split(full: &str) -> Result<(&str, &str), String> {
        full.split_once('.').ok_or_else(|| format!("'{full}' must be written as unit.variable"))
    }
    let mut links: Vec<Link> = Vec::new();
    for c in &spec.connection {
        let ((fu, fv), (tu, tv)) = (split(&c.from)?, split(&c.to)?);
        let (fi, ti) = (unit_index(&components, fu)?, unit_index(&components, tu)?);
        let source = &components[fi].interface;
        let outputs = source.order.iter().filter(|n| source.variables[n.as_str()].causality == "output").map(String::as_str);
        let pairs = expand_connection(&c.from, &c.to, fv, tv, outputs).map_err(|e| format!("FMU '{fu}': {e}"))?;
        for (fv, tv) in pairs {
            let src = components[fi].interface.get(&fv).ok_or_else(|| format!("FMU '{fu}', variable '{fv}': no such variable in the FMU"))?;
            let dst = components[ti].interface.get(&tv).ok_or_else(|| format!("FMU '{tu}', variable '{tv}': no such variable in the FMU"))?;
            if src.causality != "output" {
                return Err(format!("FMU '{fu}', variable '{fv}': a connection must start at an output, not {}", with_article(src.causality)));
            }
            if dst.causality != "input" {
                return Err(format!("FMU '{tu}', variable '{tv}': a connection must end at an input, not {}", with_article(dst.causality)));
            }
            if src.base != dst.base || matches!(src.base, BaseType::String | BaseType::Enumeration) {
                return Err(format!(
                    "FMU '{tu}', variable '{tv}': type mismatch: {fu}.{fv} is {:?}, {tu}.{tv} is {:?} (Real, Integer and Boolean connect to their own type)",
                    src.base, dst.base
                ));
            }
            if links.iter().any(|l| l.to_unit == ti && l.to_var == tv) {
                return Err(format!("FMU '{tu}', variable '{tv}': this input is already connected"));
            }
            components[ti].connected_inputs.push(tv.clone());
            links.push(Link { from_unit: fi, from_var: fv, to_unit: ti, to_var: tv });
        }
    }

    for full in &s.record {
        let (u, v) = split(full)?;
        let info = components[unit_index(&components, u)?].interface.get(v).ok_or_else(|| format!("FMU '{u}', variable '{v}': no such variable to record"))?;
        if matches!(info.base, BaseType::String | BaseType::Enumeration) {
            return Err(format!("FMU '{u}', variable '{v}': only Real, Integer and Boolean variables can be recorded"));
        }
    }
    Ok(Plan { components, links, parameters, resources })
}

fn with_article(causality: &str) -> String {
    let article = if causality.starts_with(['a', 'e', 'i', 'o', 'u']) { "an" } else { "a" };
    format!("{article} {causality}")
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

/// Reads the variables of the FMU at `path` from its `modelDescription.xml`. Messages name
/// the file.
fn read_interface(path: &Path) -> Result<Interface, String> {
    let file = std::fs::File::open(path).map_err(|e| format!("cannot open {}: {e}", path.display()))?;
    let mut archive = zip::ZipArchive::new(file).map_err(|e| format!("{} is not an FMU (not a zip archive: {e})", path.display()))?;
    let mut xml = String::new();
    archive
        .by_name("modelDescription.xml")
        .map_err(|e| format!("{} is not an FMU (no modelDescription.xml: {e})", path.display()))?
        .read_to_string(&mut xml)
        .map_err(|e| format!("{}: reading modelDescription.xml: {e}", path.display()))?;
    parse_interface(&xml).map_err(|e| format!("{}: modelDescription.xml: {e}", path.display()))
}

fn parse_interface(xml: &str) -> Result<Interface, String> {
    use quick_xml::events::attributes::Attributes;
    fn attribute(attrs: Attributes, key: &[u8]) -> Result<Option<String>, String> {
        for a in attrs {
            let a = a.map_err(|e| e.to_string())?;
            if a.key.as_ref() == key {
                return Ok(Some(a.unescape_value().map_err(|e| e.to_string())?.into_owned()));
            }
        }
        Ok(None)
    }
    let mut reader = quick_xml::Reader::from_str(xml);
    let mut version = None;
    let mut co_simulation = false;
    let mut order = Vec::new();
    let mut variables = HashMap::new();
    // The ScalarVariable being read: (name, causality, value reference, base type once seen).
    let mut current: Option<(String, &'static str, u32, Option<BaseType>)> = None;
    loop {
        let event = reader.read_event().map_err(|e| format!("at byte {}: {e}", reader.error_position()))?;
        match event {
            Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"fmiModelDescription" => {
                version = attribute(e.attributes(), b"fmiVersion")?;
            }
            Event::Start(e) | Event::Empty(e) if e.name().as_ref() == b"CoSimulation" => co_simulation = true,
            Event::Start(e) if e.name().as_ref() == b"ScalarVariable" => {
                let name = attribute(e.attributes(), b"name")?.ok_or("a ScalarVariable has no name")?;
                let causality = match attribute(e.attributes(), b"causality")?.as_deref() {
                    Some("parameter") => "parameter",
                    Some("calculatedParameter") => "calculatedParameter",
                    Some("input") => "input",
                    Some("output") => "output",
                    Some("independent") => "independent",
                    _ => "local",
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
                if variables.insert(name.clone(), VariableInfo { value_reference, base, causality }).is_some() {
                    return Err(format!("two variables are named '{name}'"));
                }
                order.push(name);
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
    if !co_simulation {
        return Err("not a Co-Simulation FMU (no CoSimulation element)".into());
    }
    Ok(Interface { order, variables })
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

fn type_name(base: BaseType) -> &'static str {
    match base {
        BaseType::Real => "Real",
        BaseType::Integer => "Integer",
        BaseType::Boolean => "Boolean",
        BaseType::String => "String",
        BaseType::Enumeration => "Enumeration",
    }
}

/// The text of `SystemStructure.ssd`.
fn ssd_xml(spec: &SystemSpec, plan: &Plan, system_name: &str) -> String {
    let ok = "writing XML to memory cannot fail";
    let mut w = Writer::new_with_indent(Cursor::new(Vec::new()), b' ', 2);
    let start = |w: &mut Writer<Cursor<Vec<u8>>>, e: BytesStart| w.write_event(Event::Start(e)).expect(ok);
    let end = |w: &mut Writer<Cursor<Vec<u8>>>, name: &str| w.write_event(Event::End(BytesEnd::new(name))).expect(ok);
    let empty = |w: &mut Writer<Cursor<Vec<u8>>>, e: BytesStart| w.write_event(Event::Empty(e)).expect(ok);

    w.write_event(Event::Decl(BytesDecl::new("1.0", Some("UTF-8"), None))).expect(ok);
    let tool = concat!("neurarm ", env!("CARGO_PKG_VERSION"));
    start(
        &mut w,
        BytesStart::new("ssd:SystemStructureDescription").with_attributes([
            ("xmlns:ssd", NS_SSD),
            ("xmlns:ssc", NS_SSC),
            ("xmlns:ssv", NS_SSV),
            ("version", "1.0"),
            ("name", system_name),
            ("generationTool", tool),
        ]),
    );
    start(&mut w, BytesStart::new("ssd:System").with_attributes([("name", system_name)]));

    if !plan.parameters.is_empty() {
        start(&mut w, BytesStart::new("ssd:ParameterBindings"));
        start(&mut w, BytesStart::new("ssd:ParameterBinding"));
        start(&mut w, BytesStart::new("ssd:ParameterValues"));
        start(&mut w, BytesStart::new("ssv:ParameterSet").with_attributes([("version", "1.0"), ("name", "parameters")]));
        start(&mut w, BytesStart::new("ssv:Parameters"));
        for (name, base, value) in &plan.parameters {
            start(&mut w, BytesStart::new("ssv:Parameter").with_attributes([("name", name.as_str())]));
            let text = match value {
                Value::Real(x) => xs_double(*x),
                Value::Integer(i) if *base == BaseType::Real => xs_double(*i as f64),
                Value::Integer(i) => i.to_string(),
                Value::Boolean(b) => b.to_string(),
                Value::String(s) => s.clone(),
            };
            empty(&mut w, BytesStart::new(format!("ssv:{}", type_name(*base))).with_attributes([("value", text.as_str())]));
            end(&mut w, "ssv:Parameter");
        }
        end(&mut w, "ssv:Parameters");
        end(&mut w, "ssv:ParameterSet");
        end(&mut w, "ssd:ParameterValues");
        end(&mut w, "ssd:ParameterBinding");
        end(&mut w, "ssd:ParameterBindings");
    }

    start(&mut w, BytesStart::new("ssd:Elements"));
    for c in &plan.components {
        start(
            &mut w,
            BytesStart::new("ssd:Component").with_attributes([
                ("name", c.name.as_str()),
                ("type", "application/x-fmu-sharedlibrary"),
                ("source", c.source.as_str()),
                ("implementation", "CoSimulation"),
            ]),
        );
        let set: BTreeMap<&str, ()> =
            plan.parameters.iter().filter_map(|(n, _, _)| n.strip_prefix(c.name.as_str()).and_then(|r| r.strip_prefix('.'))).map(|v| (v, ())).collect();
        let connectors: Vec<(&str, &str, BaseType)> = c
            .interface
            .order
            .iter()
            .filter_map(|name| {
                let v = &c.interface.variables[name];
                let kind = match v.causality {
                    "output" if matches!(v.base, BaseType::Real | BaseType::Integer | BaseType::Boolean) => "output",
                    "input" if c.connected_inputs.contains(name) => "input",
                    "parameter" if set.contains_key(name.as_str()) => "parameter",
                    _ => return None,
                };
                Some((name.as_str(), kind, v.base))
            })
            .collect();
        if !connectors.is_empty() {
            start(&mut w, BytesStart::new("ssd:Connectors"));
            for (name, kind, base) in connectors {
                start(&mut w, BytesStart::new("ssd:Connector").with_attributes([("name", name), ("kind", kind)]));
                // An ssc:Enumeration needs a declared enumeration type; it is left untyped.
                if base != BaseType::Enumeration {
                    empty(&mut w, BytesStart::new(format!("ssc:{}", type_name(base))));
                }
                end(&mut w, "ssd:Connector");
            }
            end(&mut w, "ssd:Connectors");
        }
        end(&mut w, "ssd:Component");
    }
    end(&mut w, "ssd:Elements");

    if !plan.links.is_empty() {
        start(&mut w, BytesStart::new("ssd:Connections"));
        for l in &plan.links {
            empty(
                &mut w,
                BytesStart::new("ssd:Connection").with_attributes([
                    ("startElement", plan.components[l.from_unit].name.as_str()),
                    ("startConnector", l.from_var.as_str()),
                    ("endElement", plan.components[l.to_unit].name.as_str()),
                    ("endConnector", l.to_var.as_str()),
                ]),
            );
        }
        end(&mut w, "ssd:Connections");
    }
    end(&mut w, "ssd:System");

    let s = &spec.simulation;
    let (t0, t1, h, every) = (xs_double(s.start), xs_double(s.stop), xs_double(s.step), s.record_every.max(1).to_string());
    start(&mut w, BytesStart::new("ssd:DefaultExperiment").with_attributes([("startTime", t0.as_str()), ("stopTime", t1.as_str())]));
    start(&mut w, BytesStart::new("ssd:Annotations"));
    start(&mut w, BytesStart::new("ssc:Annotation").with_attributes([("type", ANNOTATION_TYPE)]));
    let algorithm = match s.algorithm {
        Algorithm::GaussSeidel => "gauss-seidel",
        Algorithm::Jacobi => "jacobi",
    };
    let simulation = BytesStart::new("nr:Simulation").with_attributes([
        ("xmlns:nr", ANNOTATION_NAMESPACE),
        ("stepSize", h.as_str()),
        ("algorithm", algorithm),
        ("recordEvery", every.as_str()),
    ]);
    if s.record.is_empty() {
        empty(&mut w, simulation);
    } else {
        start(&mut w, simulation);
        for r in &s.record {
            empty(&mut w, BytesStart::new("nr:Record").with_attributes([("variable", r.as_str())]));
        }
        end(&mut w, "nr:Simulation");
    }
    end(&mut w, "ssc:Annotation");
    end(&mut w, "ssd:Annotations");
    end(&mut w, "ssd:DefaultExperiment");
    end(&mut w, "ssd:SystemStructureDescription");

    let mut text = String::from_utf8(w.into_inner().into_inner()).expect("the XML is built from UTF-8 text");
    text.push('\n');
    text
}

/// Writes the zip to a temporary file beside `out`, then renames it over `out`.
fn write_archive(out: &Path, ssd: &str, resources: &[(PathBuf, String)]) -> Result<(), String> {
    let fail = |e: &dyn std::fmt::Display| format!("writing {}: {e}", out.display());
    let dir = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let tmp =
        tempfile::Builder::new().permissions(crate::table::readable_file()).prefix(".neurarm-").suffix(".ssp.tmp").tempfile_in(dir).map_err(|e| fail(&e))?;
    let mut zip = zip::ZipWriter::new(tmp.reopen().map_err(|e| fail(&e))?);
    let deflated = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    // An FMU is a zip already: stored as it is.
    let stored = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored).large_file(true);
    zip.start_file("SystemStructure.ssd", deflated).map_err(|e| fail(&e))?;
    zip.write_all(ssd.as_bytes()).map_err(|e| fail(&e))?;
    for (path, name) in resources {
        let mut file = std::fs::File::open(path).map_err(|e| format!("{}: {e}", path.display()))?;
        zip.start_file(name.as_str(), stored).map_err(|e| fail(&e))?;
        std::io::copy(&mut file, &mut zip).map_err(|e| format!("copying {} into {}: {e}", path.display(), out.display()))?;
    }
    zip.finish().map_err(|e| fail(&e))?.sync_all().map_err(|e| fail(&e))?;
    tmp.persist(out).map_err(|e| fail(&e.error))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wildcards_expand_like_connect() {
        let outputs = ["q_1", "q_2", "qd_1", "tau_1", "q_"];
        let pairs = expand_connection("a.q_*", "b.x_*_in", "q_*", "x_*_in", outputs).unwrap();
        assert_eq!(pairs, [("q_".to_owned(), "x__in".to_owned()), ("q_1".to_owned(), "x_1_in".to_owned()), ("q_2".to_owned(), "x_2_in".to_owned())]);
        let e = expand_connection("a.z*", "b.z*", "z*", "z*", outputs).unwrap_err();
        assert!(e.contains("no output matches 'z*'"), "{e}");
        let e = expand_connection("a.q_*", "b.u", "q_*", "u", outputs).unwrap_err();
        assert!(e.contains("in both names or in neither"), "{e}");
        assert_eq!(expand_connection("a.y", "b.u", "y", "u", outputs).unwrap(), [("y".to_owned(), "u".to_owned())]);
    }

    #[test]
    fn doubles_read_back_exactly() {
        for x in [1.5, -2.0, 0.01, 1e307, 1e-300, 0.1 + 0.2] {
            assert_eq!(xs_double(x).parse::<f64>().unwrap(), x);
        }
        assert_eq!(xs_double(f64::INFINITY), "INF");
        assert_eq!(xs_double(f64::NEG_INFINITY), "-INF");
    }

    #[test]
    fn resource_names_are_plain_and_unique() {
        let taken = ["resources/My_Arm.fmu".to_owned()];
        assert_eq!(resource_name(Path::new("/x/My Arm.fmu"), |c| taken.contains(&c.to_owned())), "resources/My_Arm-2.fmu");
        assert_eq!(resource_name(Path::new("Gain.fmu"), |_| false), "resources/Gain.fmu");
    }
}
