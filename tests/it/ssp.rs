//! SSP export of a system: the archive's entries and the SystemStructure.ssd inside.
//! Needs the FMU binary: `cargo build --release -p neurarm-fmu` (scripts/test builds it).

use std::collections::BTreeMap;
use std::io::Read;
use std::path::{Path, PathBuf};

use neurarm::export::export_fmu;
use neurarm_cosim::ssp::write_ssp;
use neurarm_cosim::{ConnectionSpec, FmuEntry, SimulationSpec, SystemSpec, Value};
use neurarm_models::{FmuSpec, GainSpec, IntegratorSpec, ModelSpec};

fn fmu(dir: &Path, identifier: &str, model: ModelSpec) -> PathBuf {
    let path = dir.join(format!("{identifier}.fmu"));
    export_fmu(&FmuSpec { identifier: identifier.into(), model }, &[], &path).unwrap();
    path
}

fn entry(name: &str, path: &str, parameters: &[(&str, Value)]) -> FmuEntry {
    FmuEntry {
        name: name.into(),
        path: path.into(),
        parameters: parameters.iter().map(|(k, v)| (k.to_string(), v.clone())).collect::<BTreeMap<_, _>>(),
    }
}

fn connection(from: &str, to: &str) -> ConnectionSpec {
    ConnectionSpec { from: from.into(), to: to.into() }
}

/// y' = −2 y as an integrator (y0 = 1.5) and a gain (k = −2) in a loop.
fn loop_spec(integrator: &str) -> SystemSpec {
    SystemSpec {
        fmu: vec![entry("int", integrator, &[("y0", Value::Real(1.5))]), entry("gain", "Gain.fmu", &[("k", Value::Integer(-2))])],
        connection: vec![connection("int.y", "gain.u"), connection("gain.y*", "int.u*")],
        simulation: SimulationSpec {
            start: 0.0,
            stop: 2.0,
            step: 0.01,
            algorithm: Default::default(),
            record: vec!["int.y".into(), "gain.y".into()],
            record_every: 1,
            on_discard: neurarm_cosim::OnDiscard::Stop,
        },
        event: Vec::new(),
    }
}

fn names(archive: &mut zip::ZipArchive<std::fs::File>) -> Vec<String> {
    let mut v: Vec<String> = archive.file_names().map(str::to_owned).collect();
    v.sort();
    v
}

#[test]
fn an_integrator_gain_loop_becomes_an_ssp() {
    let dir = tempfile::tempdir().unwrap();
    fmu(dir.path(), "Integrator", ModelSpec::Integrator(IntegratorSpec { y0: 0.0 }));
    fmu(dir.path(), "Gain", ModelSpec::Gain(GainSpec { k: 1.0 }));
    let out = dir.path().join("loop.ssp");
    write_ssp(&loop_spec("Integrator.fmu"), dir.path(), &out).unwrap();

    let mut archive = zip::ZipArchive::new(std::fs::File::open(&out).unwrap()).unwrap();
    assert_eq!(names(&mut archive), ["SystemStructure.ssd", "resources/Gain.fmu", "resources/Integrator.fmu"]);
    // The FMUs go in byte for byte.
    for name in ["Gain", "Integrator"] {
        let mut inside = Vec::new();
        archive.by_name(&format!("resources/{name}.fmu")).unwrap().read_to_end(&mut inside).unwrap();
        assert_eq!(inside, std::fs::read(dir.path().join(format!("{name}.fmu"))).unwrap(), "{name}.fmu");
    }
    let mut ssd = String::new();
    archive.by_name("SystemStructure.ssd").unwrap().read_to_string(&mut ssd).unwrap();

    for needle in [
        r#"xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription""#,
        r#"version="1.0" name="loop""#,
        r#"<ssd:Component name="int" type="application/x-fmu-sharedlibrary" source="resources/Integrator.fmu" implementation="CoSimulation">"#,
        r#"<ssd:Component name="gain" type="application/x-fmu-sharedlibrary" source="resources/Gain.fmu" implementation="CoSimulation">"#,
        r#"<ssd:Connection startElement="int" startConnector="y" endElement="gain" endConnector="u"/>"#,
        // The wildcard, expanded.
        r#"<ssd:Connection startElement="gain" startConnector="y" endElement="int" endConnector="u"/>"#,
        r#"<ssd:Connector name="u" kind="input">"#,
        r#"<ssd:Connector name="y" kind="output">"#,
        r#"<ssd:Connector name="y0" kind="parameter">"#,
        r#"<ssd:Connector name="k" kind="parameter">"#,
        "<ssc:Real/>",
        // On the components, under the FMUs' own names; the integer given for a Real goes in
        // as a Real. The set is named after the system.
        r#"<ssv:ParameterSet version="1.0" name="loop">"#,
        r#"<ssv:Parameter name="y0">"#,
        r#"<ssv:Real value="1.5"/>"#,
        r#"<ssv:Parameter name="k">"#,
        r#"<ssv:Real value="-2.0"/>"#,
        r#"<ssd:DefaultExperiment startTime="0.0" stopTime="2.0">"#,
        // libcosim's step, and ours with the algorithm and what to record.
        r#"xmlns:osp="http://opensimulationplatform.com/SSP/OSPAnnotations""#,
        r#"<ssc:Annotation type="com.opensimulationplatform">"#,
        r#"<osp:FixedStepAlgorithm baseStepSize="0.01"/>"#,
        r#"stepSize="0.01" algorithm="gauss-seidel" recordEvery="1""#,
        r#"<nr:Record variable="int.y"/>"#,
    ] {
        assert!(ssd.contains(needle), "SystemStructure.ssd lacks {needle}:\n{ssd}");
    }
    assert_eq!(ssd.matches("<ssd:Connection ").count(), 2, "{ssd}");
    assert_eq!(ssd.matches("<ssd:Component ").count(), 2, "{ssd}");
    // Elements come in the standard's order: in a component its connectors, then its bindings;
    // elements, then connections; each unit's parameters in its own component, none at the system.
    let at = |s: &str| ssd.find(s).unwrap();
    let (int, gain) = (at(r#"<ssd:Component name="int""#), at(r#"<ssd:Component name="gain""#));
    assert!(int < at(r#"name="y0""#) && at(r#"name="y0""#) < gain && gain < at(r#"<ssv:Parameter name="k""#));
    assert!(at("</ssd:Connectors>") < at("<ssd:ParameterBindings>"));
    assert!(at("<ssd:Elements>") < at("<ssd:ParameterBindings>") && at("</ssd:Elements>") < at("<ssd:Connections>"));
    assert_eq!(ssd.matches("<ssd:ParameterBindings>").count(), 2, "{ssd}");
    assert!(at("</ssd:System>") < at("<ssd:DefaultExperiment"));
    // Nothing but the archive is left in the folder.
    let mut left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    left.sort();
    assert_eq!(left, ["Gain.fmu", "Integrator.fmu", "loop.ssp"]);
}

/// Two units from one file share one copy; names that need escaping are escaped.
#[test]
fn shared_fmus_are_copied_once_and_text_is_escaped() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("my blocks")).unwrap();
    fmu(&dir.path().join("my blocks"), "Integrator", ModelSpec::Integrator(IntegratorSpec { y0: 0.0 }));
    fmu(dir.path(), "Gain", ModelSpec::Gain(GainSpec { k: 1.0 }));
    let mut spec = loop_spec("my blocks/Integrator.fmu");
    spec.fmu.push(entry("a&b", "my blocks/Integrator.fmu", &[]));
    spec.connection.push(connection("int.y", "a&b.u"));
    let out = dir.path().join("two.ssp");
    write_ssp(&spec, dir.path(), &out).unwrap();
    let mut archive = zip::ZipArchive::new(std::fs::File::open(&out).unwrap()).unwrap();
    assert_eq!(names(&mut archive), ["SystemStructure.ssd", "resources/Gain.fmu", "resources/Integrator.fmu"]);
    let mut ssd = String::new();
    archive.by_name("SystemStructure.ssd").unwrap().read_to_string(&mut ssd).unwrap();
    assert!(
        ssd.contains(r#"<ssd:Component name="a&amp;b" type="application/x-fmu-sharedlibrary" source="resources/Integrator.fmu""#),
        "{ssd}"
    );
    assert!(ssd.contains(r#"endElement="a&amp;b" endConnector="u""#), "{ssd}");
}

#[test]
fn a_missing_fmu_is_named_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    fmu(dir.path(), "Gain", ModelSpec::Gain(GainSpec { k: 1.0 }));
    let out = dir.path().join("loop.ssp");
    let e = write_ssp(&loop_spec("NoSuch.fmu"), dir.path(), &out).unwrap_err().to_string();
    assert!(e.contains("NoSuch.fmu") && e.contains("'int'"), "{e}");
    assert!(!out.exists());
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(left, ["Gain.fmu"], "no temporary file is left behind");

    // An earlier archive at `out` survives a failed export untouched.
    std::fs::write(&out, b"previous").unwrap();
    write_ssp(&loop_spec("NoSuch.fmu"), dir.path(), &out).unwrap_err();
    assert_eq!(std::fs::read(&out).unwrap(), b"previous");
}

#[test]
fn bad_systems_are_refused_by_unit_and_variable() {
    let dir = tempfile::tempdir().unwrap();
    fmu(dir.path(), "Integrator", ModelSpec::Integrator(IntegratorSpec { y0: 0.0 }));
    fmu(dir.path(), "Gain", ModelSpec::Gain(GainSpec { k: 1.0 }));
    let out = dir.path().join("bad.ssp");
    let check = |spec: SystemSpec, expected: &[&str]| {
        let e = write_ssp(&spec, dir.path(), &out).unwrap_err().to_string();
        for x in expected {
            assert!(e.contains(x), "'{x}' not in: {e}");
        }
        assert!(!out.exists());
    };

    let mut s = loop_spec("Integrator.fmu");
    s.fmu[1].parameters.insert("kk".into(), Value::Real(1.0));
    check(s, &["'gain'", "'kk'", "no such variable", "Gain.fmu"]);

    let mut s = loop_spec("Integrator.fmu");
    s.fmu[1].parameters.insert("k".into(), Value::Boolean(true));
    check(s, &["'gain'", "'k'", "type mismatch"]);

    let mut s = loop_spec("Integrator.fmu");
    s.fmu[1].parameters.insert("y".into(), Value::Real(1.0));
    check(s, &["'gain'", "'y'", "an output cannot be set"]);

    let mut s = loop_spec("Integrator.fmu");
    s.connection.push(connection("int.y", "gain.u"));
    check(s, &["'gain'", "'u'", "already connected"]);

    let mut s = loop_spec("Integrator.fmu");
    s.connection = vec![connection("int.q_*", "gain.q_*")];
    check(s, &["'int'", "no output matches 'q_*'"]);

    let mut s = loop_spec("Integrator.fmu");
    s.connection = vec![connection("int.u", "gain.u")];
    check(s, &["'int'", "must start at an output"]);

    let mut s = loop_spec("Integrator.fmu");
    s.connection = vec![connection("nobody.y", "gain.u")];
    check(s, &["'nobody'", "no unit"]);

    let mut s = loop_spec("Integrator.fmu");
    s.fmu[1].name = "int".into();
    check(s, &["'int'", "two units"]);

    let mut s = loop_spec("Integrator.fmu");
    s.simulation.record.push("gain.z".into());
    check(s, &["'gain'", "'z'"]);

    // Not an FMU at all.
    std::fs::write(dir.path().join("Text.fmu"), "hello").unwrap();
    check(loop_spec("Text.fmu"), &["'int'", "Text.fmu", "not an FMU"]);
}

#[test]
fn events_go_into_our_annotation() {
    let dir = tempfile::tempdir().unwrap();
    fmu(dir.path(), "Integrator", ModelSpec::Integrator(IntegratorSpec { y0: 0.0 }));
    fmu(dir.path(), "Gain", ModelSpec::Gain(GainSpec { k: 1.0 }));
    let mut spec = loop_spec("Integrator.fmu");
    spec.event.push(neurarm_cosim::EventSpec { time: 0.5, until: Some(1.5), set: [("gain.k".to_owned(), Value::Real(0.25))].into() });
    let out = dir.path().join("events.ssp");
    write_ssp(&spec, dir.path(), &out).unwrap();
    let mut archive = zip::ZipArchive::new(std::fs::File::open(&out).unwrap()).unwrap();
    let mut ssd = String::new();
    archive.by_name("SystemStructure.ssd").unwrap().read_to_string(&mut ssd).unwrap();
    let compact: String = ssd.lines().map(str::trim).collect();
    assert!(
        compact.contains(r#"<nr:Event time="0.5" until="1.5"><nr:Set variable="gain.k" type="Real" value="0.25"/></nr:Event>"#),
        "{ssd}"
    );
    spec.event[0].until = Some(0.1);
    let e = write_ssp(&spec, dir.path(), &dir.path().join("bad.ssp")).unwrap_err().to_string();
    assert!(e.contains("event 1") && e.contains("until"), "{e}");
    assert!(!dir.path().join("bad.ssp").exists());
}
