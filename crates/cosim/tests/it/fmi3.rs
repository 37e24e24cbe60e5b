//! FMI 3.0 Co-Simulation units in the master, alone and mixed with FMI 2.0 ones in one system:
//! each test FMU of `neurarm-test-fmus` also comes as its FMI 3.0 twin (the same model behind the
//! `fmi3*` API, value references unique over all types, enumerations read as Int64), and a
//! system gives the same rows whichever version each unit is.
//! Needs the test FMUs' library: `cargo build --release -p neurarm-test-fmus` (scripts/test does).

use std::path::{Path, PathBuf};

use neurarm_cosim::{Algorithm, BaseType, FmiVersion, RunEnd, System, Value};
use neurarm_test_fmus::{fmu3_in, fmu_in, TestModel};

/// The FMU of `model` in version `version`.
fn fmu(dir: &Path, model: TestModel, version: FmiVersion) -> PathBuf {
    match version {
        FmiVersion::V2 => fmu_in(dir, model),
        FmiVersion::V3 => fmu3_in(dir, model),
    }
    .expect("test FMU packaged")
}

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

const BOTH: [FmiVersion; 2] = [FmiVersion::V2, FmiVersion::V3];

#[test]
fn the_twins_are_read_as_fmi3_with_unique_value_references() {
    let dir = tempfile::tempdir().unwrap();
    for model in TestModel::ALL {
        let two = neurarm_cosim::Interface::read(&fmu(dir.path(), model, FmiVersion::V2)).unwrap();
        let three = neurarm_cosim::Interface::read(&fmu(dir.path(), model, FmiVersion::V3)).unwrap();
        assert_eq!((two.fmi_version, three.fmi_version), (FmiVersion::V2, FmiVersion::V3));
        assert_eq!(two.guid, three.guid, "the instantiation token is the GUID");
        assert_eq!(two.variables.len(), three.variables.len());
        for (a, b) in two.variables.iter().zip(&three.variables) {
            assert_eq!((&a.name, a.causality, a.variability, a.initial), (&b.name, b.causality, b.variability, b.initial), "{model:?}");
            assert_eq!(a.base.access(), b.base.access(), "{model:?} {}", a.name);
            assert_eq!(a.direct_inputs, b.direct_inputs, "{model:?} {}: dependencies by value reference", a.name);
        }
        let mut vrs: Vec<u32> = three.variables.iter().map(|v| v.value_reference).collect();
        vrs.sort_unstable();
        vrs.dedup();
        assert_eq!(vrs.len(), three.variables.len(), "{model:?}: FMI 3.0 value references are unique");
    }
}

#[test]
fn enumerations_strings_and_booleans_cross_between_versions() {
    let dir = tempfile::tempdir().unwrap();
    for (v1, v2) in [(FmiVersion::V3, FmiVersion::V3), (FmiVersion::V3, FmiVersion::V2), (FmiVersion::V2, FmiVersion::V3)] {
        let mut s = System::new();
        s.add_fmu("m1", &fmu(dir.path(), TestModel::Modes, v1)).unwrap();
        s.add_fmu("m2", &fmu(dir.path(), TestModel::Modes, v2)).unwrap();
        s.add_fmu("split", &fmu(dir.path(), TestModel::Split, v2)).unwrap();
        s.set("m1", "shape", Value::String("square".into())).unwrap().set("m1", "label", Value::String("arm, left".into())).unwrap();
        let e = s.set("m1", "shape", Value::Integer(4)).unwrap_err().to_string();
        assert!(e.contains("not an item of type Shape (sine = 1, square = 2, ramp = 3)"), "{e}");
        s.set("m2", "use_follow", Value::Boolean(true)).unwrap();
        s.connect("m1.active", "m2.follow").unwrap().connect("m1.status", "m2.note").unwrap();
        let e = s.connect("m1.steps", "m2.follow").unwrap_err().to_string();
        assert!(e.contains("type mismatch"), "an integer is no enumeration: {e}");
        // Reals connect across versions: Float64 to Real.
        s.connect("m1.y", "split.u1").unwrap();
        let record = names(&["m1.y", "m1.active", "m2.active", "m1.steps", "m1.status", "m2.heard", "split.y1"]);
        let mut sim = s.initialize(0.0, 0.5, Algorithm::GaussSeidel, &record).unwrap();
        let types = sim.column_types();
        assert_eq!(types[2..4], [BaseType::Enumeration, BaseType::Enumeration]);
        assert_eq!((types[4].access(), types[5], types[6]), (BaseType::Integer, BaseType::String, BaseType::String));
        assert_eq!(sim.run_until(2.0).unwrap(), RunEnd::Completed, "{v1:?} → {v2:?}");
        for (row, texts) in sim.rows().iter().zip(sim.texts()) {
            let t = row[0];
            assert_eq!(row[1], t.sin().signum(), "square wave at t = {t}");
            assert_eq!((row[2], row[3]), (2.0, 2.0), "m2 follows m1's shape through the connection ({v1:?} → {v2:?})");
            assert_eq!(row[4], (t / 0.5).round(), "steps taken");
            assert_eq!(texts, &["arm, left:square".to_owned(), "arm, left:square".to_owned()], "at t = {t}");
            assert_eq!(row[7], 2.0 * row[1], "split.y1 = k m1.y");
        }
        // A tunable enumeration changes between steps, by name.
        sim.set("m1.shape", Value::String("ramp".into())).unwrap();
        sim.step().unwrap();
        let last = sim.rows().last().unwrap();
        assert_eq!((last[2], last[3]), (3.0, 3.0));
        assert_eq!(sim.texts().last().unwrap()[1], "arm, left:ramp");
    }
}

#[test]
fn dependencies_by_value_reference_are_resolved_per_output() {
    let dir = tempfile::tempdir().unwrap();
    // As the FMI 2.0 test: a.y1 → b.u1, b.y1 → a.u2, c.y1 → c.u2 is no algebraic loop.
    for versions in
        [[FmiVersion::V3; 3], [FmiVersion::V3, FmiVersion::V2, FmiVersion::V3], [FmiVersion::V2, FmiVersion::V3, FmiVersion::V2]]
    {
        for algorithm in [Algorithm::GaussSeidel, Algorithm::Jacobi] {
            let mut s = System::new();
            for (name, v) in ["a", "b", "c"].into_iter().zip(versions) {
                s.add_fmu(name, &fmu(dir.path(), TestModel::Split, v)).unwrap();
            }
            s.set("a", "u1", Value::Real(3.0)).unwrap().set("c", "u1", Value::Real(1.0)).unwrap();
            s.connect("a.y1", "b.u1").unwrap().connect("b.y1", "a.u2").unwrap().connect("c.y1", "c.u2").unwrap();
            let mut sim = s.initialize(0.0, 0.5, algorithm, &names(&["a.y1", "b.y1", "a.y2", "c.y2"])).unwrap();
            assert_eq!(sim.run_until(1.0).unwrap(), RunEnd::Completed);
            for row in sim.rows() {
                assert_eq!(&row[1..], &[6.0, 12.0, 24.0, 4.0], "{versions:?} {algorithm:?} at t = {}", row[0]);
            }
        }
    }
    let split = fmu(dir.path(), TestModel::Split, FmiVersion::V3);
    let mut s = System::new();
    s.add_fmu("a", &split).unwrap();
    s.connect("a.y1", "a.u1").unwrap();
    let e = s.initialize(0.0, 0.1, Algorithm::GaussSeidel, &[]).err().unwrap().to_string();
    assert!(e.contains("algebraic loop: a.y1 → a.u1 ⇒ a.y1"), "{e}");
}

#[test]
fn an_fmi3_unit_that_asks_to_end_ends_the_run_with_its_reason() {
    let dir = tempfile::tempdir().unwrap();
    for version in BOTH {
        let counter = fmu(dir.path(), TestModel::Counter, version);
        let hold = fmu(dir.path(), TestModel::Hold, FmiVersion::V2);
        let mut s = System::new();
        s.add_fmu("counter", &counter).unwrap().add_fmu("hold", &hold).unwrap();
        s.connect("counter.t_last", "hold.u").unwrap();
        let mut sim = s.initialize(0.0, 0.1, Algorithm::GaussSeidel, &names(&["counter.count", "hold.y"])).unwrap();
        let end = sim.run_until(10.0).unwrap();
        let RunEnd::Discarded { unit, time, status, log } = end else { panic!("{version:?}: expected a discard, got {end:?}") };
        assert_eq!(unit, "counter");
        assert!((time - 8.8).abs() < 1e-9, "{version:?} ended at {time}");
        assert_eq!(status.terminated, Some(true), "{version:?}");
        assert!(log.iter().any(|l| l.contains("the counter stops at 8.8 s")), "{version:?}: the FMU's reason is quoted: {log:?}");
        let last = sim.rows().last().unwrap();
        assert_eq!((last[1], sim.rows().len()), (88.0, 89), "{version:?}");
        // The run cannot go on; the error names the version's function.
        let e = sim.step().unwrap_err().to_string();
        assert!(e.contains(&format!("{}DoStep", version.prefix())), "{e}");
    }
}

#[test]
fn a_unit_that_takes_its_last_step_and_asks_to_end_ends_the_run_after_that_step() {
    // The counter takes the step to 8.8 s and asks to end there (FMI 3.0: fmi3OK with
    // terminateSimulation; FMI 2.0: fmi2Discard with fmi2LastSuccessfulTime 8.8). A second
    // counter stepped after it in the sweep still takes that step, and its row is recorded
    // even where record_every would skip it.
    let dir = tempfile::tempdir().unwrap();
    for (first, second) in [(FmiVersion::V2, FmiVersion::V3), (FmiVersion::V3, FmiVersion::V2), (FmiVersion::V3, FmiVersion::V3)] {
        for algorithm in [Algorithm::GaussSeidel, Algorithm::Jacobi] {
            let mut s = System::new();
            s.add_fmu("a", &fmu(dir.path(), TestModel::Counter, first)).unwrap();
            s.add_fmu("b", &fmu(dir.path(), TestModel::Counter, second)).unwrap();
            s.set("a", "finish", Value::Boolean(true)).unwrap().set("b", "stop_at", Value::Real(100.0)).unwrap();
            let mut sim = s.initialize(0.0, 0.1, algorithm, &names(&["a.count", "b.count", "a.t_last"])).unwrap();
            sim.record_every(3);
            let end = sim.run_until(10.0).unwrap();
            let RunEnd::EndRequested { unit, time } = end else { panic!("{first:?}/{second:?}: expected an end request, got {end:?}") };
            assert_eq!(unit, "a");
            assert!((time - 8.8).abs() < 1e-9, "ended at {time}");
            let last = sim.rows().last().unwrap().to_vec();
            assert_eq!((last[1], last[2]), (88.0, 88.0), "{first:?}/{second:?} {algorithm:?}: both units took the last step");
            assert!((last[0] - 8.8).abs() < 1e-9 && (last[3] - 8.8).abs() < 1e-12, "{last:?}");
            assert!(sim.notices().iter().any(|n| n.contains("unit 'a' completed the step to t = 8.8") && n.contains("asks to end")));
            let e = sim.step().unwrap_err().to_string();
            assert!(e.contains("asked to end the simulation at t = 8.8"), "{e}");
        }
    }
}

#[test]
fn an_fmi3_unit_that_cannot_vary_its_step_and_start_values_are_honoured() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = System::new();
    s.add_fmu("counter", &fmu(dir.path(), TestModel::Counter, FmiVersion::V3)).unwrap();
    s.add_fmu("clock", &fmu(dir.path(), TestModel::FixedStep, FmiVersion::V3)).unwrap();
    s.add_fmu("hold", &fmu(dir.path(), TestModel::Hold, FmiVersion::V3)).unwrap();
    // An output with initial="exact" is set before initialization, as in FMI 2.0.
    s.set("hold", "y", Value::Real(5.0)).unwrap().set("hold", "u", Value::Integer(2)).unwrap();
    let e = s.set("hold", "time", Value::Real(1.0)).unwrap_err().to_string();
    assert!(e.contains("the independent variable cannot be set"), "{e}");
    let mut sim = s.initialize(0.0, 0.3, Algorithm::GaussSeidel, &names(&["clock.t_out", "hold.y"])).unwrap();
    assert_eq!(sim.run_until(1.0).unwrap(), RunEnd::Completed);
    assert!((sim.time() - 0.9).abs() < 1e-12);
    assert!(sim.notices()[0].contains("unit 'clock' cannot take a shorter last step"), "{:?}", sim.notices());
    let hold: Vec<f64> = sim.rows().iter().map(|r| r[2]).collect();
    assert_eq!(hold, [5.0, 2.0, 2.0, 2.0]);
}

#[test]
fn a_call_an_fmi3_unit_refuses_names_its_fmi3_function_and_reason() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = System::new();
    s.add_fmu("counter", &fmu(dir.path(), TestModel::Counter, FmiVersion::V3)).unwrap();
    // NaN passes the master's type check; the FMU refuses it and says why.
    s.set("counter", "stop_at", Value::Real(f64::NAN)).unwrap();
    let e = s.initialize(0.0, 0.1, Algorithm::GaussSeidel, &[]).err().expect("refused").to_string();
    assert!(e.contains("fmi3SetFloat64 returned Error"), "{e}");
    assert!(e.to_lowercase().contains("nan"), "the FMU's reason is quoted: {e}");
}

#[test]
fn a_mixed_system_is_written_to_ssp_with_ssp_types() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = System::new();
    s.add_fmu("m1", &fmu(dir.path(), TestModel::Modes, FmiVersion::V3)).unwrap();
    s.add_fmu("split", &fmu(dir.path(), TestModel::Split, FmiVersion::V2)).unwrap();
    s.connect("m1.y", "split.u1").unwrap();
    let simulation = neurarm_cosim::SimulationSpec {
        start: 0.0,
        stop: 1.0,
        step: 0.5,
        algorithm: Algorithm::GaussSeidel,
        record: names(&["split.y1"]),
        record_every: 1,
        on_discard: neurarm_cosim::OnDiscard::Stop,
    };
    let out = dir.path().join("mixed.ssp");
    neurarm_cosim::ssp::write_system(&s, &simulation, &out).unwrap();
    let mut archive = zip::ZipArchive::new(std::fs::File::open(&out).unwrap()).unwrap();
    let mut ssd = String::new();
    std::io::Read::read_to_string(&mut archive.by_name("SystemStructure.ssd").unwrap(), &mut ssd).unwrap();
    assert!(
        !ssd.contains("ssc:Float") && !ssd.contains("ssc:Int32") && !ssd.contains("ssc:Int64"),
        "SSP 1.0 has no FMI 3.0 type names: {ssd}"
    );
    assert!(ssd.contains(r#"<ssd:Connector name="y" kind="output">"#), "{ssd}");
    assert!(ssd.contains("<ssc:Real/>") && ssd.contains("ssc:Enumeration"), "{ssd}");
    assert!(archive.file_names().any(|n| n.ends_with("Modes.fmi3.fmu")), "the FMI 3.0 FMU is packed");
}
