//! A system is checked and written without loading any FMU binary; only `initialize` loads.
//! The FMU here is the Van der Pol example (nothing of neurarm's robotics in it), and a copy of
//! it whose archive holds its `modelDescription.xml` alone.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

use neurarm_cosim::{Algorithm, SimulationSpec, System, Value};

/// A copy of the FMU at `fmu` with nothing but its `modelDescription.xml`.
fn description_only(fmu: &Path, out: &Path) -> PathBuf {
    let mut archive = zip::ZipArchive::new(std::fs::File::open(fmu).unwrap()).unwrap();
    let mut xml = String::new();
    archive.by_name("modelDescription.xml").unwrap().read_to_string(&mut xml).unwrap();
    let mut zip = zip::ZipWriter::new(std::fs::File::create(out).unwrap());
    zip.start_file("modelDescription.xml", zip::write::SimpleFileOptions::default()).unwrap();
    zip.write_all(xml.as_bytes()).unwrap();
    zip.finish().unwrap();
    out.to_owned()
}

fn simulation(record: &[&str]) -> SimulationSpec {
    SimulationSpec {
        start: 0.0,
        stop: 1.0,
        step: 0.01,
        algorithm: Algorithm::Jacobi,
        record: record.iter().map(|s| s.to_string()).collect(),
        record_every: 1,
        on_discard: neurarm_cosim::OnDiscard::Stop,
    }
}

#[test]
fn a_system_is_checked_and_written_before_anything_is_loaded() {
    let dir = tempfile::tempdir().unwrap();
    let fmu = van_der_pol::package::fmu_in(dir.path()).unwrap();
    let hollow = description_only(&fmu, &dir.path().join("Hollow.fmu"));

    let mut system = System::new();
    system.add_fmu("a", &hollow).unwrap().add_fmu("b", &fmu).unwrap();
    system.set("a", "mu", Value::Integer(2)).unwrap().set("a", "mu", Value::Real(0.5)).unwrap();
    system.connect("a.x", "b.u").unwrap();
    // b.v → a.v is refused (a.v is an output), and so is the whole pattern: nothing is added.
    let e = system.connect("b.*", "a.*").unwrap_err();
    assert!(e.to_string().contains("must end at an input"), "{e}");
    assert_eq!(system.links().len(), 1);
    system.connect("b.x", "a.u").unwrap();
    assert_eq!(system.settings().len(), 1, "setting a variable again replaces its value");
    assert_eq!(system.settings()[0].value, Value::Real(0.5));
    assert_eq!(system.links().len(), 2);

    // Written as SSP from the interfaces alone: both FMUs go in, connectors as connected.
    let out = dir.path().join("pair.ssp");
    neurarm_cosim::ssp::write_system(&system, &simulation(&["a.x", "b.x"]), &out).unwrap();
    let mut ssp = zip::ZipArchive::new(std::fs::File::open(&out).unwrap()).unwrap();
    let mut ssd = String::new();
    ssp.by_name("SystemStructure.ssd").unwrap().read_to_string(&mut ssd).unwrap();
    assert!(ssd.contains(r#"<ssd:Connection startElement="a" startConnector="x" endElement="b" endConnector="u"/>"#), "{ssd}");
    // The setting is bound on its component, under the FMU's own name.
    let a = ssd.find(r#"<ssd:Component name="a""#).unwrap();
    let mu = ssd.find(r#"<ssv:Parameter name="mu">"#).expect("mu bound");
    assert!(a < mu && mu < ssd.find(r#"<ssd:Component name="b""#).unwrap(), "{ssd}");
    assert!(ssd.contains(r#"<ssv:Real value="0.5"/>"#), "{ssd}");
    let mut names: Vec<&str> = ssp.file_names().collect();
    names.sort_unstable();
    assert_eq!(names, ["SystemStructure.ssd", "resources/Hollow.fmu", "resources/VanDerPol.fmu"]);

    // A recorded variable that does not exist is refused by the writer as by the simulation.
    let e = neurarm_cosim::ssp::write_system(&system, &simulation(&["b.y"]), &out).unwrap_err();
    assert_eq!((e.unit.as_deref(), e.variable.as_deref()), (Some("b"), Some("y")));

    // Only initialize loads the binaries, and the one without a binary fails by name.
    let e = system.initialize(0.0, 0.01, Algorithm::Jacobi, &[]).err().expect("Hollow.fmu has no binary");
    assert_eq!(e.unit.as_deref(), Some("a"), "{e}");
}

#[test]
fn the_same_checked_system_runs() {
    let dir = tempfile::tempdir().unwrap();
    let fmu = van_der_pol::package::fmu_in(dir.path()).unwrap();
    let mut system = System::new();
    system.add_fmu("osc", &fmu).unwrap();
    system.set("osc", "mu", Value::Real(0.0)).unwrap().set("osc", "x0", Value::Real(1.0)).unwrap();
    let mut sim = system.initialize(0.0, 0.01, Algorithm::GaussSeidel, &["osc.x".into(), "osc.v".into()]).unwrap();
    assert_eq!(sim.run_until(3.0).unwrap(), neurarm_cosim::RunEnd::Completed);
    // Alone and unforced, with mu = 0: x = cos t, v = −sin t, integrated by the FMU's RK4.
    for row in sim.rows() {
        assert!((row[1] - row[0].cos()).abs() < 1e-9 && (row[2] + row[0].sin()).abs() < 1e-9, "{row:?}");
    }
    assert_eq!(sim.rows().len(), 301);
    // Between steps, an unconnected input can be set and a tunable parameter changed.
    sim.set("osc.u", Value::Real(1.0)).unwrap();
    let e = sim.set("osc.x0", Value::Real(2.0)).unwrap_err();
    assert_eq!(e.variable.as_deref(), Some("x0"), "a fixed parameter cannot change now: {e}");
}
