//! The co-simulation master against loops with known discrete solutions, and its errors.
//! Needs the FMU binary: `cargo build --release -p neurarm-fmu` (scripts/test builds it).

use std::path::{Path, PathBuf};

use neurarm::export::export_fmu;
use neurarm_cosim::{run, Algorithm, System, SystemSpec, Value};
use neurarm_models::{FmuSpec, GainSpec, IntegratorSpec, ModelSpec};

fn fmu(dir: &Path, identifier: &str, model: ModelSpec) -> PathBuf {
    let path = dir.join(format!("{identifier}.fmu"));
    export_fmu(&FmuSpec { identifier: identifier.into(), model }, &[], &path).unwrap();
    path
}

struct Blocks {
    _dir: tempfile::TempDir,
    integrator: PathBuf,
    gain: PathBuf,
}

fn blocks() -> Blocks {
    let dir = tempfile::tempdir().unwrap();
    let integrator = fmu(dir.path(), "Integrator", ModelSpec::Integrator(IntegratorSpec { y0: 0.0 }));
    let gain = fmu(dir.path(), "Gain", ModelSpec::Gain(GainSpec { k: 1.0 }));
    Blocks { _dir: dir, integrator, gain }
}

/// y' = −a y as an integrator and a gain k = −a in a loop: with the input held over each
/// step, y_n = y0 (1 − a h)^n under either algorithm (one state, a static block).
#[test]
fn integrator_gain_loop_is_the_discrete_exponential() {
    let b = blocks();
    let (a, h, y0) = (2.0, 0.01, 1.5);
    for algorithm in [Algorithm::GaussSeidel, Algorithm::Jacobi] {
        let mut s = System::new();
        s.add_fmu("int", &b.integrator).unwrap().add_fmu("gain", &b.gain).unwrap();
        s.set("int", "y0", Value::Real(y0)).unwrap().set("gain", "k", Value::Real(-a)).unwrap();
        s.connect("int.y", "gain.u").unwrap().connect("gain.y", "int.u").unwrap();
        let mut sim = s.initialize(0.0, h, algorithm, &["int.y".into(), "gain.y".into()]).unwrap();
        assert_eq!(sim.run_until(2.0).unwrap(), neurarm_cosim::RunEnd::Completed);
        assert_eq!(sim.rows().len(), 201);
        for (n, row) in sim.rows().iter().enumerate() {
            let expected = y0 * (1.0 - a * h).powi(n as i32);
            assert!((row[0] - n as f64 * h).abs() < 1e-12);
            assert!((row[1] - expected).abs() <= 1e-12 * y0, "{algorithm:?} step {n}: {} vs {expected}", row[1]);
            assert!((row[2] + a * row[1]).abs() <= 1e-12 * y0, "the gain's output follows its input");
        }
        // And the continuous solution, to first order in h.
        let last = sim.rows().last().unwrap();
        assert!((last[1] - y0 * (-a * 2.0f64).exp()).abs() < 0.05 * y0);
    }
}

/// Two integrators and a gain: y1' = −a y2, y2' = y1 (an oscillator). Gauss–Seidel (order
/// int1, int2, gain) is symplectic Euler, which keeps y1² + a y2² − a h y1 y2 exactly;
/// Jacobi is explicit Euler, which multiplies y1² + a y2² by (1 + a h²) every step.
#[test]
fn gauss_seidel_and_jacobi_differ_as_theory_says() {
    let b = blocks();
    let (a, h) = (4.0, 0.02);
    let mut results = Vec::new();
    for algorithm in [Algorithm::GaussSeidel, Algorithm::Jacobi] {
        let mut s = System::new();
        s.add_fmu("int1", &b.integrator).unwrap().add_fmu("int2", &b.integrator).unwrap().add_fmu("gain", &b.gain).unwrap();
        s.set("int2", "y0", Value::Real(1.0)).unwrap().set("gain", "k", Value::Real(-a)).unwrap();
        s.connect("int1.y", "int2.u").unwrap().connect("int2.y", "gain.u").unwrap().connect("gain.y", "int1.u").unwrap();
        let mut sim = s.initialize(0.0, h, algorithm, &["int1.y".into(), "int2.y".into()]).unwrap();
        assert_eq!(sim.step_order(), ["int1", "int2", "gain"]);
        assert_eq!(sim.run_until(10.0).unwrap(), neurarm_cosim::RunEnd::Completed);
        results.push(sim.take_rows());
    }
    let (gs, jacobi) = (&results[0], &results[1]);
    // The recurrences, computed here independently of any FMU.
    let (mut g1, mut g2, mut j1, mut j2) = (0.0f64, 1.0f64, 0.0f64, 1.0f64);
    for n in 0..gs.len() {
        assert!((gs[n][1] - g1).abs() < 1e-12 && (gs[n][2] - g2).abs() < 1e-12, "GS step {n}");
        assert!((jacobi[n][1] - j1).abs() < 1e-12 && (jacobi[n][2] - j2).abs() < 1e-12, "Jacobi step {n}");
        g1 -= a * h * g2;
        g2 += h * g1;
        let (n1, n2) = (j1 - a * h * j2, j2 + h * j1);
        j1 = n1;
        j2 = n2;
    }
    let steps = (gs.len() - 1) as i32;
    let modified = |r: &Vec<f64>| r[1] * r[1] + a * r[2] * r[2] - a * h * r[1] * r[2];
    let energy = |r: &Vec<f64>| r[1] * r[1] + a * r[2] * r[2];
    assert!((modified(gs.last().unwrap()) - modified(&gs[0])).abs() < 1e-12);
    let growth = energy(jacobi.last().unwrap()) / energy(&jacobi[0]);
    assert!((growth / (1.0 + a * h * h).powi(steps) - 1.0).abs() < 1e-10, "Jacobi growth {growth}");
    assert!(growth > 1.3, "explicit Euler visibly gains energy over 500 steps");
}

#[test]
fn errors_name_the_unit_and_variable() {
    let b = blocks();
    let mut s = System::new();
    s.add_fmu("int", &b.integrator).unwrap().add_fmu("gain", &b.gain).unwrap();

    let e = s.connect("int.z", "gain.u").err().unwrap();
    assert_eq!((e.unit.as_deref(), e.variable.as_deref()), (Some("int"), Some("z")));
    assert!(e.to_string().contains("no such variable"), "{e}");

    let e = s.connect("int.y", "gain.k").err().unwrap();
    assert!(e.to_string().contains("must end at an input, not a parameter"), "{e}");
    let e = s.connect("int.u", "gain.u").err().unwrap();
    assert!(e.to_string().contains("must start at an output"), "{e}");

    let e = s.set("gain", "k", Value::Boolean(true)).err().unwrap();
    assert!(e.to_string().contains("type mismatch") && e.variable.as_deref() == Some("k"), "{e}");
    let e = s.set("gain", "y", Value::Real(1.0)).err().unwrap();
    assert!(e.to_string().contains("an output cannot be set"), "{e}");
    let e = s.set("nobody", "k", Value::Real(1.0)).err().unwrap();
    assert_eq!(e.unit.as_deref(), Some("nobody"));
    let e = s.add_fmu("int", &b.integrator).err().unwrap();
    assert!(e.to_string().contains("two units"), "{e}");
    let e = s.add_fmu("x", Path::new("/nonexistent/X.fmu")).err().unwrap();
    assert!(e.to_string().contains("cannot load"), "{e}");

    s.connect("int.y", "gain.u").unwrap();
    let e = s.connect("int.y", "gain.u").err().unwrap();
    assert!(e.to_string().contains("already connected"), "{e}");
}

#[test]
fn an_algebraic_loop_is_refused_by_name() {
    let b = blocks();
    let mut s = System::new();
    s.add_fmu("g1", &b.gain).unwrap().add_fmu("g2", &b.gain).unwrap();
    s.connect("g1.y", "g2.u").unwrap().connect("g2.y", "g1.u").unwrap();
    let e = s.initialize(0.0, 0.1, Algorithm::GaussSeidel, &[]).err().unwrap();
    let text = e.to_string();
    assert!(text.contains("algebraic loop") && text.contains("g1") && text.contains("g2"), "{text}");
}

/// A unit failing mid-run: the error names it, the time and the FMU's own reason, and the
/// rows recorded before the failure are kept.
#[test]
fn a_failing_step_keeps_the_recording() {
    let b = blocks();
    let dir = b.integrator.parent().unwrap();
    let text = r#"
[[fmu]]
name = "int"
path = "Integrator.fmu"
parameters = { y0 = 1e307 }

[[fmu]]
name = "gain"
path = "Gain.fmu"
parameters = { k = 1.0 }

[[connection]]
from = "int.y"
to = "gain.u"

[[connection]]
from = "gain.y"
to = "int.u"

[simulation]
stop = 10.0
step = 1.0
record = ["int.y"]
"#;
    let spec = SystemSpec::from_toml(text, "system.toml").unwrap();
    let outcome = run(&spec, dir, None).unwrap();
    let e = outcome.error.expect("y overflows after a few steps");
    assert_eq!(e.unit.as_deref(), Some("int"));
    assert_eq!(e.time, Some(4.0), "y doubles each step and overflows in the fifth: {e}");
    assert!(e.log.iter().any(|l| l.contains("overflowed")), "the FMU's reason is quoted: {e}");
    assert_eq!(outcome.rows.len() as f64, e.time.unwrap() + 1.0, "rows up to the failing step");
    assert!(outcome.rows.iter().all(|r| r[1].is_finite()));
}

#[test]
fn bad_system_files_are_refused_with_the_reason() {
    let e = SystemSpec::from_toml("[[fmu]]\nname = 'a'\npath = 'A.fmu'\n[simulation]\nstop = 1\nstep = -1\n", "s.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("s.toml") && e.contains("positive step"), "{e}");
    let e = SystemSpec::from_toml("[[fmu]]\nname = 'a'\npath = 'A.fmu'\nspeed = 3\n[simulation]\nstop = 1\nstep = 1\n", "s.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("speed"), "{e}");
}

/// A gain k·u feeding an integrator, u and k changed only by events: u ramps from 0 to 1
/// over [1, 2] s, k steps from 1 to 2 at 3 s. With values held over each step the integral
/// is the left Riemann sum of k·u: h² Σ j (j < 100) over the ramp, then 1 and 2 s·(k u).
#[test]
fn events_set_and_ramp_tunable_parameters_and_free_inputs() {
    let b = blocks();
    let text = format!(
        r#"
[[fmu]]
name = "gain"
path = "{gain}"
[[fmu]]
name = "int"
path = "{int}"
[[connection]]
from = "gain.y"
to = "int.u"
[simulation]
stop = 4.0
step = 0.01
record = ["int.y", "gain.u", "gain.k"]
[[event]]
time = 3.0
set = {{ "gain.k" = 2 }}
[[event]]
time = 1.0
until = 2.0
set = {{ "gain.u" = 1.0 }}
"#,
        gain = b.gain.display(),
        int = b.integrator.display()
    );
    let spec = SystemSpec::from_toml(&text, "events.toml").unwrap();
    assert_eq!(SystemSpec::from_toml(&spec.to_toml().unwrap(), "again").unwrap(), spec, "events round-trip through TOML");
    let outcome = run(&spec, Path::new("."), None).unwrap();
    assert!(outcome.error.is_none(), "{:?}", outcome.error);
    let at = |t: f64| outcome.rows.iter().find(|r| (r[0] - t).abs() < 1e-9).unwrap().clone();
    assert_eq!(at(1.0)[2], 0.0, "the ramp starts from the value at its start");
    assert!((at(1.5)[2] - 0.5).abs() < 1e-12 && at(2.5)[2] == 1.0, "{:?} {:?}", at(1.5), at(2.5));
    assert_eq!((at(2.99)[3], at(3.0)[3]), (1.0, 2.0), "the step change at its time");
    let expected = 1e-4 * 4950.0 + 1.0 + 2.0;
    let last = outcome.rows.last().unwrap();
    assert!((last[0] - 4.0).abs() < 1e-12 && (last[1] - expected).abs() < 1e-9, "y(4) = {} vs {expected}", last[1]);
}

#[test]
fn events_on_what_cannot_change_while_running_are_refused_before_the_run() {
    let b = blocks();
    let mut s = System::new();
    s.add_fmu("gain", &b.gain).unwrap().add_fmu("int", &b.integrator).unwrap();
    s.connect("gain.y", "int.u").unwrap();
    let event = |time: f64, until: Option<f64>, name: &str, value: Value| neurarm_cosim::EventSpec {
        time,
        until,
        set: [(name.to_owned(), value)].into(),
    };
    for (e, wanted) in [
        (event(1.0, None, "int.y0", Value::Real(2.0)), "only a tunable parameter can change while running"),
        (event(1.0, None, "int.u", Value::Real(2.0)), "this input is connected"),
        (event(1.0, None, "int.y", Value::Real(2.0)), "only tunable parameters and unconnected inputs"),
        (event(1.0, None, "gain.kk", Value::Real(2.0)), "kk"),
        (event(1.0, Some(0.5), "gain.k", Value::Real(2.0)), "must end at a finite time after it"),
        (event(1.0, None, "gain.k", Value::Boolean(true)), "gain"),
    ] {
        let mut sim = s.clone().initialize(0.0, 0.1, Algorithm::GaussSeidel, &[]).unwrap();
        let err = sim.schedule(&[e]).unwrap_err().to_string();
        assert!(err.contains("event 1") && err.contains(wanted), "{err}");
    }
}
