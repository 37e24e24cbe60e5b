//! What FMI 2.0 allows and a general master must handle, each with a small FMU of
//! `neurarm-test-fmus` (on the export layer, nothing of neurarm's robotics): a unit that discards
//! a step, outputs that depend on separate inputs, a stop time that is not a whole number of
//! steps, a unit that cannot vary its step, outputs with settable start values,
//! enumerations and strings, an interrupted run, and the error of a failed one.
//! Needs the test FMUs' library: `cargo build --release -p neurarm-test-fmus` (scripts/test does).

use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use neurarm_cosim::{run, Algorithm, BaseType, EventSpec, FmuEntry, OnDiscard, RunEnd, SimulationSpec, System, SystemSpec, Value};
use neurarm_test_fmus::{fmu3_in, fmu_in, TestModel};

fn fmu(dir: &Path, model: TestModel) -> PathBuf {
    fmu_in(dir, model).expect("test FMU packaged")
}

fn names(list: &[&str]) -> Vec<String> {
    list.iter().map(|s| s.to_string()).collect()
}

/// The column `name` of a simulation's rows.
fn column(sim: &neurarm_cosim::Simulation, name: &str) -> Vec<f64> {
    let c = sim.columns().iter().position(|c| c == name).expect("recorded");
    sim.rows().iter().map(|r| r[c]).collect()
}

#[test]
fn a_discarded_step_ends_the_run_at_the_last_point_every_unit_completed() {
    let dir = tempfile::tempdir().unwrap();
    let counter = fmu(dir.path(), TestModel::Counter);
    let hold = fmu(dir.path(), TestModel::Hold);
    let build = |retry: bool| {
        let mut s = System::new();
        // The hold steps after the counter in each sweep: when the counter discards, the hold
        // has not stepped, and every unit last completed the point 8.8 s.
        s.add_fmu("counter", &counter).unwrap().add_fmu("hold", &hold).unwrap();
        s.set("counter", "retry", Value::Boolean(retry)).unwrap();
        s.connect("counter.t_last", "hold.u").unwrap();
        s
    };
    let record = names(&["counter.count", "counter.t_last", "hold.y"]);
    let mut sim = build(false).initialize(0.0, 0.1, Algorithm::GaussSeidel, &record).unwrap();
    let end = sim.run_until(10.0).unwrap();
    let RunEnd::Discarded { unit, time, status, log } = end else { panic!("expected a discard, got {end:?}") };
    assert_eq!(unit, "counter");
    assert!((time - 8.8).abs() < 1e-9, "ended at {time}");
    assert_eq!(status.terminated, Some(true));
    assert!(status.last_successful_time.is_some_and(|t| (t - 8.8).abs() < 1e-9), "{status:?}");
    assert!(log.iter().any(|l| l.contains("the counter stops at 8.8 s")), "the FMU's reason is quoted: {log:?}");
    // The rows end at 8.8 s, consistent across units: 88 steps counted, the hold one step behind.
    let last = sim.rows().last().unwrap().to_vec();
    assert!((last[0] - 8.8).abs() < 1e-9 && last[1] == 88.0 && (last[2] - 8.8).abs() < 1e-9, "{last:?}");
    // Gauss–Seidel: the hold steps after the counter, with the counter's output at the new point.
    assert!((last[3] - 8.8).abs() < 1e-9, "{last:?}");
    assert_eq!(sim.rows().len(), 89);
    assert!(
        sim.notices().iter().any(|n| n.contains("'counter' discarded the step from t = 8.8") && n.contains("asks to end")),
        "{:?}",
        sim.notices()
    );
    let e = sim.step().unwrap_err();
    assert!(e.to_string().contains("the run has ended"), "{e}");

    // A discard that does not ask to terminate ends the run the same way, and says so.
    let mut sim = build(true).initialize(0.0, 0.1, Algorithm::Jacobi, &record).unwrap();
    let RunEnd::Discarded { status, .. } = sim.run_until(10.0).unwrap() else { panic!("expected a discard") };
    assert_eq!(status.terminated, Some(false));

    // An option makes it an error; the rows are kept all the same.
    let mut sim = build(false).initialize(0.0, 0.1, Algorithm::GaussSeidel, &record).unwrap();
    sim.on_discard(OnDiscard::Error);
    let e = sim.run_until(10.0).unwrap_err();
    assert!(e.discard.is_some() && e.unit.as_deref() == Some("counter"), "{e:?}");
    assert!(e.to_string().contains("asks to end the simulation"), "{e}");
    assert_eq!(sim.rows().len(), 89);
}

#[test]
fn dependencies_are_resolved_per_output_not_per_unit() {
    let dir = tempfile::tempdir().unwrap();
    let split = fmu(dir.path(), TestModel::Split);
    // a.y1 → b.u1 and b.y1 → a.u2: the units feed each other, but y1 depends on u1 only and
    // y2 on u2 only, so there is no algebraic loop: a.y1 = k u1, b.y1 = k² u1, a.y2 = k³ u1,
    // all at the same communication point, which needs a read of a before b and one after.
    for algorithm in [Algorithm::GaussSeidel, Algorithm::Jacobi] {
        let mut s = System::new();
        s.add_fmu("a", &split).unwrap().add_fmu("b", &split).unwrap().add_fmu("c", &split).unwrap();
        s.set("a", "u1", Value::Real(3.0)).unwrap().set("c", "u1", Value::Real(1.0)).unwrap();
        s.connect("a.y1", "b.u1").unwrap().connect("b.y1", "a.u2").unwrap();
        // A unit wired to itself from an output to an input that output does not depend on:
        // c.y1 → c.u2, so c.y2 = k c.y1 = k² c.u1.
        s.connect("c.y1", "c.u2").unwrap();
        let record = names(&["a.y1", "b.y1", "a.y2", "c.y2"]);
        let mut sim = s.initialize(0.0, 0.5, algorithm, &record).unwrap();
        assert_eq!(sim.run_until(1.0).unwrap(), RunEnd::Completed);
        assert_eq!(sim.rows().len(), 3);
        for row in sim.rows() {
            assert_eq!(&row[1..], &[6.0, 12.0, 24.0, 4.0], "{algorithm:?} at t = {}", row[0]);
        }
    }

    // A true loop is refused, naming the variables that close it.
    let mut s = System::new();
    s.add_fmu("a", &split).unwrap().add_fmu("b", &split).unwrap();
    s.connect("a.y1", "b.u1").unwrap().connect("b.y1", "a.u2").unwrap().connect("a.y2", "b.u2").unwrap().connect("b.y2", "a.u1").unwrap();
    let e = s.initialize(0.0, 0.1, Algorithm::GaussSeidel, &[]).err().unwrap().to_string();
    assert!(e.contains("algebraic loop: a.y1 → b.u1 ⇒ b.y1 → a.u2 ⇒ a.y2 → b.u2 ⇒ b.y2 → a.u1 ⇒ a.y1"), "{e}");
    // So is a unit wired to itself through a direct dependency.
    let mut s = System::new();
    s.add_fmu("a", &split).unwrap();
    s.connect("a.y1", "a.u1").unwrap();
    let e = s.initialize(0.0, 0.1, Algorithm::GaussSeidel, &[]).err().unwrap().to_string();
    assert!(e.contains("algebraic loop: a.y1 → a.u1 ⇒ a.y1"), "{e}");
}

#[test]
fn the_last_step_lands_on_the_stop_time_when_every_unit_can_vary_its_step() {
    let dir = tempfile::tempdir().unwrap();
    let counter = fmu(dir.path(), TestModel::Counter);
    let fixed = fmu(dir.path(), TestModel::FixedStep);
    let mut s = System::new();
    s.add_fmu("counter", &counter).unwrap();
    let mut sim = s.initialize(0.0, 0.3, Algorithm::GaussSeidel, &names(&["counter.t_last", "counter.count"])).unwrap();
    assert_eq!(sim.run_until(1.0).unwrap(), RunEnd::Completed);
    let times = column(&sim, "time");
    assert_eq!(times.len(), 5, "{times:?}");
    for (t, want) in times.iter().zip([0.0, 0.3, 0.6, 0.9, 1.0]) {
        assert!((t - want).abs() < 1e-12, "{times:?}");
    }
    assert_eq!(column(&sim, "counter.t_last").last(), Some(&1.0), "the FMU itself reached 1.0 s");
    assert!(sim.notices().is_empty());
    // Whole steps from there on, from the stop time reached.
    assert_eq!(sim.run_until(1.6).unwrap(), RunEnd::Completed);
    assert!((sim.time() - 1.6).abs() < 1e-12, "{}", sim.time());

    // A unit that cannot vary its step: the run ends at the last whole step, with a notice.
    let mut s = System::new();
    s.add_fmu("counter", &counter).unwrap().add_fmu("clock", &fixed).unwrap();
    let mut sim = s.initialize(0.0, 0.3, Algorithm::GaussSeidel, &names(&["clock.t_out"])).unwrap();
    assert_eq!(sim.run_until(1.0).unwrap(), RunEnd::Completed);
    assert!((sim.time() - 0.9).abs() < 1e-12 && (column(&sim, "clock.t_out").last().unwrap() - 0.9).abs() < 1e-12);
    assert!(sim.notices()[0].contains("unit 'clock' cannot take a shorter last step"), "{:?}", sim.notices());
}

#[test]
fn outputs_with_a_start_value_and_every_type_can_be_set() {
    let dir = tempfile::tempdir().unwrap();
    let hold = fmu(dir.path(), TestModel::Hold);
    let split = fmu(dir.path(), TestModel::Split);
    let mut s = System::new();
    s.add_fmu("hold", &hold).unwrap().add_fmu("split", &split).unwrap();
    // y is an output with initial="exact": FMI 2.0 lets a master set it before initialization.
    s.set("hold", "y", Value::Real(5.0)).unwrap().set("hold", "u", Value::Integer(2)).unwrap();
    let e = s.set("split", "y1", Value::Real(1.0)).unwrap_err().to_string();
    assert!(e.contains("an output cannot be set (its initial is calculated)"), "{e}");
    let e = s.set("hold", "time", Value::Real(1.0)).unwrap_err().to_string();
    assert!(e.contains("the independent variable cannot be set"), "{e}");
    let mut sim = s.initialize(0.0, 0.1, Algorithm::GaussSeidel, &names(&["hold.y"])).unwrap();
    sim.step().unwrap();
    assert_eq!(column(&sim, "hold.y"), [5.0, 2.0]);
}

#[test]
fn enumerations_and_strings_are_set_connected_and_recorded() {
    let dir = tempfile::tempdir().unwrap();
    let modes = fmu(dir.path(), TestModel::Modes);
    let split = fmu(dir.path(), TestModel::Split);
    let mut s = System::new();
    s.add_fmu("m1", &modes).unwrap().add_fmu("m2", &modes).unwrap().add_fmu("split", &split).unwrap();
    // An enumeration takes an item's name or value; anything else is refused, naming the items.
    s.set("m1", "shape", Value::String("square".into())).unwrap().set("m1", "label", Value::String("arm, left".into())).unwrap();
    let e = s.set("m1", "shape", Value::Integer(4)).unwrap_err().to_string();
    assert!(e.contains("not an item of type Shape (sine = 1, square = 2, ramp = 3)"), "{e}");
    let e = s.set("m1", "shape", Value::String("triangle".into())).unwrap_err().to_string();
    assert!(e.contains("not an item"), "{e}");
    s.set("m2", "use_follow", Value::Boolean(true)).unwrap();
    s.connect("m1.active", "m2.follow").unwrap().connect("m1.status", "m2.note").unwrap();
    let e = s.connect("m1.steps", "m2.follow").unwrap_err().to_string();
    assert!(e.contains("type mismatch"), "an Integer is no enumeration: {e}");
    let e = s.connect("m1.status", "split.u1").unwrap_err().to_string();
    assert!(e.contains("type mismatch"), "{e}");

    let record = names(&["m1.y", "m1.active", "m2.active", "m1.steps", "m1.status", "m2.heard"]);
    let mut sim = s.initialize(0.0, 0.5, Algorithm::GaussSeidel, &record).unwrap();
    assert_eq!(
        sim.column_types(),
        [
            BaseType::Real,
            BaseType::Real,
            BaseType::Enumeration,
            BaseType::Enumeration,
            BaseType::Integer,
            BaseType::String,
            BaseType::String
        ]
    );
    assert_eq!(sim.run_until(2.0).unwrap(), RunEnd::Completed);
    for (row, texts) in sim.rows().iter().zip(sim.texts()) {
        let t = row[0];
        assert_eq!(row[1], t.sin().signum(), "square wave at t = {t}");
        assert_eq!((row[2], row[3]), (2.0, 2.0), "m2 follows m1's shape through the connection");
        assert_eq!(row[4], (t / 0.5).round(), "steps taken");
        assert!(row[5].is_nan() && row[6].is_nan(), "String columns hold NaN in the numbers");
        assert_eq!(texts, &["arm, left:square".to_owned(), "arm, left:square".to_owned()], "at t = {t}");
    }
    // A tunable enumeration changes between steps, by name.
    sim.set("m1.shape", Value::String("ramp".into())).unwrap();
    sim.step().unwrap();
    let last = sim.rows().last().unwrap();
    assert_eq!((last[2], last[3]), (3.0, 3.0));
    assert_eq!(sim.texts().last().unwrap()[1], "arm, left:ramp");
}

#[test]
fn a_raised_interrupt_flag_ends_the_run_with_the_rows_so_far() {
    let dir = tempfile::tempdir().unwrap();
    let counter = fmu(dir.path(), TestModel::Counter);
    let spec = SystemSpec {
        fmu: vec![FmuEntry {
            name: "counter".into(),
            path: counter.display().to_string(),
            parameters: [("stop_at".to_owned(), Value::Real(1e9))].into(),
        }],
        connection: Vec::new(),
        simulation: SimulationSpec {
            start: 0.0,
            stop: 1e6,
            step: 1e-3,
            algorithm: Algorithm::GaussSeidel,
            record: names(&["counter.count"]),
            record_every: 1,
            on_discard: OnDiscard::Stop,
        },
        event: Vec::new(),
    };
    let flag = Arc::new(AtomicBool::new(false));
    let raiser = {
        let flag = flag.clone();
        std::thread::spawn(move || {
            std::thread::sleep(std::time::Duration::from_millis(200));
            flag.store(true, std::sync::atomic::Ordering::SeqCst);
        })
    };
    let outcome = run(&spec, Path::new("/"), Some(flag)).unwrap();
    raiser.join().unwrap();
    let Some(RunEnd::Interrupted { time }) = outcome.end else { panic!("expected an interrupt, got {:?}", outcome.end) };
    let last = outcome.rows.last().unwrap();
    assert!(last[0] == time && time > 0.0 && time < 1e6, "ended at {time}");
    assert_eq!(last[1], (time / 1e-3).round(), "every step up to the interrupt is recorded");
    assert!(outcome.error.is_none());
}

/// Gauss–Seidel passes a unit's new outputs through every chain of direct feedthrough before
/// the next unit steps. Here the order is clock, hold, t, c (the cycle t → c → hold → t is cut
/// at the hold, which has no feedthrough), and the hold reads t's output through c: it must
/// see the clock's new time, `hold.y(t_n) = 4 t_n`, although t and c step after it.
#[test]
fn gauss_seidel_passes_new_values_through_feedthrough_chains_before_the_next_unit_steps() {
    let dir = tempfile::tempdir().unwrap();
    let counter = fmu(dir.path(), TestModel::Counter);
    let split = fmu(dir.path(), TestModel::Split);
    let hold = fmu(dir.path(), TestModel::Hold);
    let mut s = System::new();
    s.add_fmu("clock", &counter).unwrap().add_fmu("t", &split).unwrap().add_fmu("c", &split).unwrap().add_fmu("hold", &hold).unwrap();
    s.connect("clock.t_last", "t.u1").unwrap().connect("t.y1", "c.u1").unwrap().connect("c.y1", "hold.u").unwrap();
    s.connect("hold.y", "t.u2").unwrap();
    let mut sim = s.initialize(0.0, 0.25, Algorithm::GaussSeidel, &names(&["hold.y"])).unwrap();
    assert_eq!(sim.step_order(), ["clock", "hold", "t", "c"]);
    assert_eq!(sim.run_until(2.0).unwrap(), RunEnd::Completed);
    for row in sim.rows().iter().skip(1) {
        assert_eq!(row[1], 4.0 * row[0], "at t = {}", row[0]);
    }
}

/// The standard lets a variable carry `<Annotations>` and a model description carry
/// `<VendorAnnotations>` and tool-specific attributes; the `fmi` crate's own parser refuses some
/// of these, so the master must not depend on it to load an FMU.
#[test]
fn an_fmu_with_annotations_loads_and_runs() {
    use std::io::{Read, Write};
    let dir = tempfile::tempdir().unwrap();
    let split = fmu(dir.path(), TestModel::Split);
    let annotated = dir.path().join("Annotated.fmu");
    let mut source = zip::ZipArchive::new(std::fs::File::open(&split).unwrap()).unwrap();
    let mut out = zip::ZipWriter::new(std::fs::File::create(&annotated).unwrap());
    for i in 0..source.len() {
        let mut entry = source.by_index(i).unwrap();
        let mut bytes = Vec::new();
        entry.read_to_end(&mut bytes).unwrap();
        if entry.name() == "modelDescription.xml" {
            let xml = String::from_utf8(bytes).unwrap();
            let xml = xml
                .replacen(
                    "<Real start=\"0\"/>",
                    "<Real start=\"0\"/>\n      <Annotations><Tool name=\"org.example\"><x/></Tool></Annotations>",
                    1,
                )
                .replace("<ModelVariables>", "<VendorAnnotations><Tool name=\"org.example\"/></VendorAnnotations>\n  <ModelVariables>")
                .replacen("causality=\"input\"", "causality=\"input\" canHandleMultipleSetPerTimeInstant=\"true\"", 1);
            assert!(xml.contains("<Annotations>") && xml.contains("canHandleMultipleSetPerTimeInstant"), "{xml}");
            bytes = xml.into_bytes();
        }
        out.start_file(entry.name(), zip::write::SimpleFileOptions::default()).unwrap();
        out.write_all(&bytes).unwrap();
    }
    out.finish().unwrap();
    let mut s = System::new();
    s.add_fmu("a", &annotated).unwrap();
    s.set("a", "u1", Value::Real(2.0)).unwrap();
    let mut sim = s.initialize(0.0, 0.5, Algorithm::GaussSeidel, &names(&["a.y1"])).unwrap();
    assert_eq!(sim.run_until(1.0).unwrap(), RunEnd::Completed);
    assert_eq!(column(&sim, "a.y1"), [4.0, 4.0, 4.0]);
}

/// Enumerations in SSP: connectors name their type, listed once in ssd:Enumerations; an item
/// set by name is bound as the integer the master sets.
#[test]
fn enumerations_are_written_to_ssp_with_their_types() {
    use std::io::Read;
    let dir = tempfile::tempdir().unwrap();
    let modes = fmu(dir.path(), TestModel::Modes);
    let mut s = System::new();
    s.add_fmu("m1", &modes).unwrap().add_fmu("m2", &modes).unwrap();
    s.set("m1", "shape", Value::String("square".into())).unwrap();
    s.connect("m1.active", "m2.follow").unwrap();
    let simulation = SimulationSpec {
        start: 0.0,
        stop: 1.0,
        step: 0.1,
        algorithm: Algorithm::GaussSeidel,
        record: Vec::new(),
        record_every: 1,
        on_discard: OnDiscard::Stop,
    };
    let out = dir.path().join("modes.ssp");
    neurarm_cosim::ssp::write_system(&s, &simulation, &out).unwrap();
    let mut ssd = String::new();
    zip::ZipArchive::new(std::fs::File::open(&out).unwrap())
        .unwrap()
        .by_name("SystemStructure.ssd")
        .unwrap()
        .read_to_string(&mut ssd)
        .unwrap();
    assert_eq!(ssd.matches(r#"<ssc:Enumeration name="Shape"/>"#).count(), 3, "m1.active, m2.active, m2.follow: {ssd}");
    assert_eq!(ssd.matches(r#"<ssc:Enumeration name="Shape">"#).count(), 1, "{ssd}");
    assert!(ssd.contains(r#"<ssc:Item name="square" value="2"/>"#), "{ssd}");
    let binding = &ssd[ssd.find(r#"<ssv:Parameter name="shape">"#).expect("bound")..];
    assert!(binding.starts_with("<ssv:Parameter name=\"shape\">\n") && binding.contains(r#"<ssv:Integer value="2"/>"#), "{binding}");
}

/// A run that fails mid-way says where: the unit, the variable when one is concerned, and the
/// communication point, in the fields and in the text.
#[test]
fn a_failed_step_names_the_unit_the_variable_and_the_time() {
    let dir = tempfile::tempdir().unwrap();
    for (version, split) in [("fmi2", fmu(dir.path(), TestModel::Split)), ("fmi3", fmu3_in(dir.path(), TestModel::Split).unwrap())] {
        let mut s = System::new();
        s.add_fmu("split", &split).unwrap();
        let mut sim = s.initialize(0.0, 0.1, Algorithm::GaussSeidel, &names(&["split.y1"])).unwrap();
        // NaN passes the master's type check; the FMU refuses it when the event sets it.
        let nan = EventSpec { time: 0.5, until: None, set: [("split.k".to_owned(), Value::Real(f64::NAN))].into() };
        sim.schedule(&[nan]).unwrap();
        let e = sim.run_until(1.0).unwrap_err();
        assert_eq!((e.unit.as_deref(), e.variable.as_deref(), e.time), (Some("split"), Some("k"), Some(0.5)), "{version}: {e:?}");
        let text = e.to_string();
        assert!(text.starts_with("FMU 'split', variable 'k' at t = 0.5 s: setting Real(NaN) refused: "), "{version}: {text}");
        assert_eq!(sim.rows().len(), 5, "{version}: the rows up to the failing point are kept");
    }

    // A step that fails concerns no variable: the unit and the step's start time.
    let counter = fmu(dir.path(), TestModel::Counter);
    let mut s = System::new();
    s.add_fmu("counter", &counter).unwrap();
    let mut sim = s.initialize(0.0, 0.5, Algorithm::Jacobi, &[]).unwrap();
    sim.on_discard(OnDiscard::Error);
    let e = sim.run_until(10.0).unwrap_err();
    assert_eq!((e.unit.as_deref(), e.variable.as_deref()), (Some("counter"), None), "{e:?}");
    assert!(e.time.is_some_and(|t| (t - 9.0).abs() < 1e-9), "the step from 9 s reaches past stop_at = 8.8 s: {e:?}");
    assert!(e.to_string().starts_with("FMU 'counter' at t = 9 s: "), "{e}");
}
