//! The PlanarArm FMU through its C ABI, loaded with dlopen as a host would: exported symbols,
//! the state machine, argument checks, FMU states, reset and threads.

use crate::common;

use std::ffi::{c_int, CString};

use common::*;
use neurarm_models::FmuSpec;
use neurarm_physics::config::ArmConfig;

fn arm_fmu() -> Fmu {
    Fmu::new(&FmuSpec::planar_arm("PlanarArm", ArmConfig::default()))
}

#[test]
fn reports_version_and_platform() {
    let fmu = arm_fmu();
    // SAFETY: both functions take nothing and return a static NUL-terminated string.
    unsafe {
        assert_eq!(std::ffi::CStr::from_ptr((fmu.api.fmi2GetVersion)()).to_str().unwrap(), "2.0");
        assert_eq!(std::ffi::CStr::from_ptr((fmu.api.fmi2GetTypesPlatform)()).to_str().unwrap(), "default");
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    Instantiated,
    Initialization,
    StepComplete,
    Terminated,
    Error,
}
const PHASES: [Phase; 5] = [Phase::Instantiated, Phase::Initialization, Phase::StepComplete, Phase::Terminated, Phase::Error];

fn bring_to(fmu: &Fmu, phase: Phase) -> Instance {
    let i = fmu.instance();
    if phase == Phase::Instantiated {
        return i;
    }
    assert_eq!(i.setup(), OK);
    assert_eq!(i.enter(), OK);
    if phase == Phase::Error {
        // An invalid parameter makes initialization fail: the model's own error.
        assert_eq!(i.set_real(&[fmu.vr("mass_1")], &[-1.0]), OK);
        assert_eq!(i.exit(), ERROR);
        assert!(i.log.contains("links[0].mass_kg"), "{}", i.log.dump());
        i.log.take();
        return i;
    }
    if phase == Phase::Initialization {
        return i;
    }
    assert_eq!(i.exit(), OK);
    if phase == Phase::Terminated {
        assert_eq!(i.terminate(), OK);
    }
    i
}

/// From `phase`, the normal sequence still works: the instance was not broken by a refusal.
fn still_works(fmu: &Fmu, i: &Instance, phase: Phase) {
    let mut phase = phase;
    if matches!(phase, Phase::Terminated | Phase::Error) {
        assert_eq!(i.reset(), OK, "{}", i.log.dump());
        phase = Phase::Instantiated;
    }
    if phase == Phase::Instantiated {
        assert_eq!(i.setup(), OK);
        assert_eq!(i.enter(), OK);
        phase = Phase::Initialization;
    }
    if phase == Phase::Initialization {
        assert_eq!(i.exit(), OK, "{}", i.log.dump());
    }
    let mut t = f64::NAN;
    assert_eq!(i.get_real_status(2, &mut t), OK);
    assert_eq!(i.set_real(&[fmu.vr("tau_1")], &[2.0]), OK);
    assert_eq!(i.step(t, 1e-3), OK, "{}", i.log.dump());
    assert!(i.get_real(&[fmu.vr("qd_1")]).unwrap()[0] > 0.0);
}

#[test]
fn illegal_call_table() {
    use Phase::*;
    let fmu = arm_fmu();
    let tau = fmu.vr("tau_1");
    let q = fmu.vr("q_1");
    type Call = Box<dyn Fn(&Instance) -> c_int>;
    // Allowed phases from the FMI 2.0 co-simulation state table, written out here rather than
    // taken from the implementation.
    let table: Vec<(&str, Vec<Phase>, Call)> = vec![
        ("fmi2SetupExperiment", vec![Instantiated], Box::new(|i| i.setup())),
        ("fmi2EnterInitializationMode", vec![Instantiated], Box::new(|i| i.enter())),
        ("fmi2ExitInitializationMode", vec![Initialization], Box::new(|i| i.exit())),
        ("fmi2Terminate", vec![StepComplete], Box::new(|i| i.terminate())),
        ("fmi2DoStep", vec![StepComplete], Box::new(|i| i.step(0.0, 1e-3))),
        ("fmi2GetReal", vec![Initialization, StepComplete, Terminated, Error], Box::new(move |i| i.get_real(&[q]).err().unwrap_or(OK))),
        ("fmi2SetReal", vec![Instantiated, Initialization, StepComplete], Box::new(move |i| i.set_real(&[tau], &[1.0]))),
        ("fmi2GetRealStatus", vec![StepComplete, Terminated], Box::new(|i| i.get_real_status(2, &mut 0.0))),
        ("fmi2GetBooleanStatus", vec![StepComplete, Terminated], Box::new(|i| i.get_boolean_status(3, &mut 7))),
        (
            "fmi2GetFMUstate",
            PHASES.to_vec(),
            Box::new(|i| {
                let mut s = std::ptr::null_mut();
                let r = i.get_fmu_state(&mut s);
                i.free_fmu_state(&mut s);
                r
            }),
        ),
        ("fmi2SetDebugLogging", PHASES.to_vec(), Box::new(|i| i.set_debug_logging(true, &[]))),
        ("fmi2Reset", PHASES.to_vec(), Box::new(|i| i.reset())),
    ];
    let mut cells = 0;
    for (name, allowed, call) in &table {
        for phase in PHASES {
            let i = bring_to(&fmu, phase);
            let status = call(&i);
            if allowed.contains(&phase) {
                assert_eq!(status, OK, "{name} in {phase:?}: {}", i.log.dump());
            } else {
                assert_eq!(status, ERROR, "{name} in {phase:?} should be refused");
                let log = i.log.take();
                assert!(
                    log.iter().any(|(s, cat, m)| *s == ERROR
                        && cat == "logStatusError"
                        && m.contains(name)
                        && m.contains("illegal call sequence")),
                    "{name} in {phase:?}: log {log:?}"
                );
                still_works(&fmu, &i, phase);
            }
            cells += 1;
        }
    }
    assert_eq!(cells, 60);
}

#[test]
fn unsupported_functions_return_error_and_log() {
    let fmu = arm_fmu();
    let i = bring_to(&fmu, Phase::StepComplete);
    let vr = [fmu.vr("q_1")];
    let mut out = [0.0];
    let order = [1];
    // SAFETY: `i.c` is live (an `Instance`); every array is a local of the length passed,
    // writable where the function writes, and outlives the call.
    unsafe {
        assert_eq!((i.api.fmi2GetDirectionalDerivative)(i.c, vr.as_ptr(), 1, vr.as_ptr(), 1, out.as_ptr(), out.as_mut_ptr()), ERROR);
        assert_eq!((i.api.fmi2SetRealInputDerivatives)(i.c, vr.as_ptr(), 1, order.as_ptr(), out.as_ptr()), ERROR);
        assert_eq!((i.api.fmi2GetRealOutputDerivatives)(i.c, vr.as_ptr(), 1, order.as_ptr(), out.as_mut_ptr()), ERROR);
        assert_eq!((i.api.fmi2CancelStep)(i.c), ERROR);
        let mut s = 0;
        assert_eq!((i.api.fmi2GetStatus)(i.c, 0, &mut s), ERROR);
        assert_eq!((i.api.fmi2GetIntegerStatus)(i.c, 0, &mut s), ERROR);
        let mut p = std::ptr::null();
        assert_eq!((i.api.fmi2GetStringStatus)(i.c, 1, &mut p), ERROR);
    }
    let log = i.log.take();
    assert_eq!(log.len(), 7, "{log:?}");
    // fmi2CancelStep is only allowed while a step is in progress, which never happens here.
    assert!(
        log.iter().all(|(s, _, m)| *s == ERROR && (m.contains("not supported") || m.starts_with("fmi2CancelStep: illegal call sequence"))),
        "{log:?}"
    );
    still_works(&fmu, &i, Phase::StepComplete);
}

#[test]
fn instantiate_rejects_bad_arguments_with_a_logged_reason() {
    let fmu = arm_fmu();
    let guid = fmu.guid();
    let uri = fmu.resource_uri();
    let cases: Vec<(&str, String, String, &str)> = vec![
        ("", guid.clone(), uri.clone(), "instance name is NULL, empty"),
        (" \t", guid.clone(), uri.clone(), "white space only"),
        ("a", "{00000000-0000-0000-0000-000000000000}".into(), uri.clone(), "does not match"),
        ("a", guid.clone(), "http://example.org/resources".into(), "not a file URI"),
        ("a", guid.clone(), "file:relative/resources".into(), "not an absolute path"),
        ("a", guid.clone(), "file://otherhost/resources".into(), "remote host"),
        ("a", guid.clone(), format!("{uri}/missing"), "does not exist"),
    ];
    for (name, g, u, why) in cases {
        let (c, log, _cb) = fmu.instantiate_with(name, &g, &u);
        assert!(c.is_null(), "accepted {name:?} {g} {u}");
        assert!(log.contains(why), "expected {why:?} in {}", log.dump());
    }
    // The other forms hosts write for the same folder all instantiate.
    let folder = fmu.resources().display().to_string();
    let encoded = folder.replace('/', "%2F").replacen("%2F", "/", 1);
    for form in [format!("file:{folder}"), format!("file://localhost{folder}"), format!("FILE://{folder}"), format!("file://{encoded}")] {
        let (c, log, _cb) = fmu.instantiate_with("a", &guid, &form);
        assert!(!c.is_null(), "refused {form}: {}", log.dump());
        // SAFETY: `c` is a component just instantiated, freed once, used no more.
        unsafe { (fmu.api.fmi2FreeInstance)(c) };
    }
    // A resources folder without a spec file, and one with a corrupt spec.
    let empty = tempfile::tempdir().unwrap();
    let (c, log, _cb) = fmu.instantiate_with("a", &guid, &format!("file://{}", empty.path().display()));
    assert!(c.is_null() && log.contains("cannot read") && log.contains("neurarm.toml"), "{}", log.dump());
    std::fs::write(empty.path().join("neurarm.toml"), "identifier = 3").unwrap();
    let (c, log, _cb) = fmu.instantiate_with("a", &guid, &format!("file://{}", empty.path().display()));
    assert!(c.is_null() && log.contains("neurarm.toml"), "{}", log.dump());

    // NULL pointers and the wrong model type.
    let name = CString::new("a").unwrap();
    let g = CString::new(guid.clone()).unwrap();
    let u = CString::new(uri.clone()).unwrap();
    let (c, log, cb) = fmu.instantiate_with("probe", &guid, &uri);
    // SAFETY: `c` is NULL or a component just instantiated, freed once, used no more.
    unsafe { (fmu.api.fmi2FreeInstance)(c) };
    let api = &fmu.api;
    // SAFETY: every pointer passed is NULL (which the FMU must refuse) or a live local: the
    // strings are NUL-terminated, `no_logger` and `*cb` valid callbacks, `cb` with the
    // environment `log`. Each call is refused, so no component is made.
    unsafe {
        assert!((api.fmi2Instantiate)(name.as_ptr(), 1, g.as_ptr(), u.as_ptr(), std::ptr::null(), 0, 0).is_null());
        let no_logger = Callbacks {
            logger: None,
            allocate: std::ptr::null(),
            free: std::ptr::null(),
            step_finished: std::ptr::null(),
            environment: std::ptr::null_mut(),
        };
        assert!((api.fmi2Instantiate)(name.as_ptr(), 1, g.as_ptr(), u.as_ptr(), &no_logger, 0, 0).is_null());
        log.take();
        assert!((api.fmi2Instantiate)(std::ptr::null(), 1, g.as_ptr(), u.as_ptr(), &*cb, 0, 0).is_null());
        assert!((api.fmi2Instantiate)(name.as_ptr(), 1, std::ptr::null(), u.as_ptr(), &*cb, 0, 0).is_null());
        assert!((api.fmi2Instantiate)(name.as_ptr(), 1, g.as_ptr(), std::ptr::null(), &*cb, 0, 0).is_null());
        assert!((api.fmi2Instantiate)(name.as_ptr(), 0, g.as_ptr(), u.as_ptr(), &*cb, 0, 0).is_null());
    }
    let messages = log.dump();
    for why in ["instance name is NULL", "GUID is NULL", "resource location is NULL", "supports only fmi2CoSimulation"] {
        assert!(messages.contains(why), "{why:?} not in {messages}");
    }
}

#[test]
fn resource_locations_in_both_uri_forms_and_percent_encoded() {
    let spec = FmuSpec::planar_arm("PlanarArm", ArmConfig::default());
    let fmu = Fmu::new(&spec);
    let spaced = fmu.dir.path().join("with space");
    std::fs::create_dir(&spaced).unwrap();
    std::fs::write(spaced.join("neurarm.toml"), spec.to_toml()).unwrap();
    let encoded = spaced.display().to_string().replace(' ', "%20");
    for uri in [
        fmu.resource_uri(),
        format!("file:{}", fmu.resources().display()),
        format!("file://localhost{}", fmu.resources().display()),
        format!("{}/", fmu.resource_uri()),
        format!("file://{encoded}"),
    ] {
        let (c, log, _cb) = fmu.instantiate_with("a", &fmu.guid(), &uri);
        assert!(!c.is_null(), "{uri}: {}", log.dump());
        // SAFETY: `c` is a component just instantiated, freed once, used no more.
        unsafe { (fmu.api.fmi2FreeInstance)(c) };
    }
}

#[test]
fn bad_value_arguments_are_refused_and_change_nothing() {
    let fmu = arm_fmu();
    let i = bring_to(&fmu, Phase::StepComplete);
    let (tau, q, mass, seed) = (fmu.vr("tau_1"), fmu.vr("q_1"), fmu.vr("mass_1"), fmu.vr("noise_seed"));
    assert_eq!(i.set_real(&[tau], &[1.5]), OK);

    // Unknown reference, and a reference of another type.
    assert_eq!(i.get_real(&[99_999]).unwrap_err(), ERROR);
    assert!(i.log.contains("unknown value reference 99999"));
    let mut v = 0;
    let bogus = fmu.vr("x");
    assert_eq!(i.get_integer(&[bogus], std::slice::from_mut(&mut v)), ERROR);
    assert!(i.log.contains("is a Real variable, not Integer"), "{}", i.log.dump());
    assert_eq!(i.get_integer(&[seed], std::slice::from_mut(&mut v)), OK);

    // Outputs and fixed parameters cannot be set while running.
    assert_eq!(i.set_real(&[q], &[1.0]), ERROR);
    assert!(i.log.contains("'q_1'"));
    assert_eq!(i.set_real(&[mass], &[3.0]), ERROR);
    assert!(i.log.contains("'mass_1'"));

    // NaN and infinity: refused, and the valid value before it in the same call is not set.
    for bad in [f64::NAN, f64::INFINITY] {
        let tau2 = fmu.vr("tau_2");
        assert_eq!(i.set_real(&[tau2, tau], &[0.7, bad]), ERROR);
        assert!(i.log.contains("not a finite number"));
        assert_eq!(i.get_real(&[tau2, tau]).unwrap(), vec![0.0, 1.5]);
    }

    // NULL arrays with n > 0.
    // SAFETY: `i.c` is live; each call passes one NULL array, which the FMU must refuse before
    // reading, and one temporary array of the 1 element passed, which outlives the call.
    assert_eq!(unsafe { (i.api.fmi2SetReal)(i.c, std::ptr::null(), 1, [1.0].as_ptr()) }, ERROR);
    // SAFETY: as above.
    assert_eq!(unsafe { (i.api.fmi2GetReal)(i.c, [q].as_ptr(), 1, std::ptr::null_mut()) }, ERROR);

    // Step size and communication point.
    for h in [0.0, -1e-3, f64::NAN] {
        assert_eq!(i.step(0.0, h), ERROR);
    }
    assert!(i.log.contains("must be finite and > 0"));
    assert_eq!(i.step(0.5, 1e-3), ERROR);
    assert!(i.log.contains("differs from the FMU's time 0"), "{}", i.log.dump());
    // Still at t = 0, still working.
    still_works(&fmu, &i, Phase::StepComplete);
    assert_eq!(i.set_debug_logging(true, &[&CString::new("nonsense").unwrap()]), ERROR);
    assert!(i.log.contains("unknown log category 'nonsense'"));
}

#[test]
fn debug_logging_categories_switch_call_traces() {
    let fmu = arm_fmu();
    let i = bring_to(&fmu, Phase::StepComplete);
    i.log.take();
    i.step(0.0, 1e-3);
    let quiet = i.log.take();
    assert!(quiet.is_empty(), "quiet by default: {quiet:?}");
    let cat = CString::new("logCalls").unwrap();
    assert_eq!(i.set_debug_logging(true, &[&cat]), OK);
    i.step(1e-3, 1e-3);
    let log = i.log.take();
    assert!(log.iter().any(|(_, c, m)| c == "logCalls" && m == "fmi2DoStep"), "{log:?}");
    assert_eq!(i.set_debug_logging(false, &[]), OK);
    i.log.take();
    i.step(2e-3, 1e-3);
    assert!(i.log.take().is_empty());
}

fn outputs(fmu: &Fmu, i: &Instance) -> Vec<f64> {
    let vrs: Vec<u32> =
        ["q_1", "q_2", "q_3", "q_4", "qd_1", "qd_2", "qd_3", "qd_4", "x", "y", "xd", "yd"].iter().map(|n| fmu.vr(n)).collect();
    i.get_real(&vrs).unwrap()
}

/// Steps from `t0` for `steps` steps of 1 ms with a time-varying torque; returns the outputs.
fn run(fmu: &Fmu, i: &Instance, t0_step: usize, steps: usize) -> Vec<f64> {
    let tau: Vec<u32> = (1..=4).map(|j| fmu.vr(&format!("tau_{j}"))).collect();
    for k in t0_step..t0_step + steps {
        let t = k as f64 * 1e-3;
        let u = [3.0 * (3.0 * t).sin(), -1.8, 1.0 * (5.0 * t).cos(), 0.5];
        assert_eq!(i.set_real(&tau, &u), OK);
        assert_eq!(i.step(t, 1e-3), OK, "{}", i.log.dump());
    }
    outputs(fmu, i)
}

#[test]
fn fmu_state_restores_bit_identically_also_through_serialization() {
    let mut config = ArmConfig::default();
    config.hardware.q_noise_std_rad = 1e-3; // the noise stream must be restored too
    config.hardware.seed = 5;
    let fmu = Fmu::new(&FmuSpec::planar_arm("PlanarArm", config));
    let i = bring_to(&fmu, Phase::StepComplete);
    let meas = fmu.vr("q_meas_1");
    run(&fmu, &i, 0, 300);
    let mut saved = std::ptr::null_mut();
    assert_eq!(i.get_fmu_state(&mut saved), OK);
    let mut reference = run(&fmu, &i, 300, 500);
    reference.push(i.get_real(&[meas]).unwrap()[0]);

    assert_eq!(i.set_fmu_state(saved), OK);
    let mut again = run(&fmu, &i, 300, 500);
    again.push(i.get_real(&[meas]).unwrap()[0]);
    assert_eq!(reference.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), again.iter().map(|v| v.to_bits()).collect::<Vec<_>>());

    // Serialize, free, deserialize into a fresh instance.
    let mut size = 0;
    assert_eq!(i.serialized_fmu_state_size(saved, &mut size), OK);
    let mut bytes = vec![0u8; size];
    assert_eq!(i.serialize_fmu_state(saved, &mut bytes), OK);
    assert_eq!(i.serialize_fmu_state(saved, &mut bytes[..size - 1]), ERROR);
    assert_eq!(i.free_fmu_state(&mut saved), OK);
    assert!(saved.is_null());
    let other = fmu.instance();
    let mut restored = std::ptr::null_mut();
    assert_eq!(other.deserialize_fmu_state(&bytes, &mut restored), OK);
    assert_eq!(other.set_fmu_state(restored), OK);
    let mut third = run(&fmu, &other, 300, 500);
    third.push(other.get_real(&[meas]).unwrap()[0]);
    assert_eq!(reference.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), third.iter().map(|v| v.to_bits()).collect::<Vec<_>>());

    // Corrupt buffers: truncated, one byte altered anywhere, empty, foreign.
    let reject = |b: &[u8], why: &str| {
        let mut s = std::ptr::null_mut();
        assert_eq!(other.deserialize_fmu_state(b, &mut s), ERROR, "{why}");
        assert!(s.is_null(), "{why}: a state was allocated");
    };
    for cut in [0, 1, 8, 20, size / 2, size - 1] {
        reject(&bytes[..cut], "truncated");
    }
    for at in (0..size).step_by(7) {
        let mut b = bytes.clone();
        b[at] ^= 0x40;
        reject(&b, "altered");
    }
    assert!(other.log.contains("checksum mismatch"));
    let three = Fmu::new(&FmuSpec::planar_arm("PlanarArm", {
        let mut c = ArmConfig::default();
        c.arm.links.truncate(3);
        c.arm.friction.truncate(3);
        c
    }));
    let foreign = three.instance();
    reject_foreign(&foreign, &bytes);
    other.free_fmu_state(&mut restored);
}

fn reject_foreign(i: &Instance, bytes: &[u8]) {
    let mut s = std::ptr::null_mut();
    assert_eq!(i.deserialize_fmu_state(bytes, &mut s), ERROR);
    assert!(i.log.contains("belongs to another model"), "{}", i.log.dump());
}

#[test]
fn reset_brings_back_start_values() {
    let fmu = arm_fmu();
    let i = fmu.instance();
    let (q0, q, tau) = (fmu.vr("q0_1"), fmu.vr("q_1"), fmu.vr("tau_1"));
    assert_eq!(i.set_real(&[q0, tau], &[0.7, 2.5]), OK);
    i.initialize();
    assert_eq!(i.get_real(&[q]).unwrap(), vec![0.7]);
    run(&fmu, &i, 0, 100);
    assert_eq!(i.reset(), OK);
    assert_eq!(i.setup(), OK);
    assert_eq!(i.enter(), OK);
    assert_eq!(i.get_real(&[q0, tau]).unwrap(), vec![0.0, 0.0]);
    assert_eq!(i.exit(), OK);
    assert_eq!(i.get_real(&[q]).unwrap(), vec![0.0]);
    // And the run after reset equals a fresh instance's.
    let fresh = bring_to(&fmu, Phase::StepComplete);
    assert_eq!(run(&fmu, &i, 0, 200), run(&fmu, &fresh, 0, 200));
}

#[test]
fn eight_instances_in_eight_threads_equal_one_alone() {
    let fmu = arm_fmu();
    let alone = {
        let i = bring_to(&fmu, Phase::StepComplete);
        run(&fmu, &i, 0, 2000)
    };
    let fmu = std::sync::Arc::new(fmu);
    let handles: Vec<_> = (0..8)
        .map(|_| {
            let fmu = fmu.clone();
            std::thread::spawn(move || {
                let i = bring_to(&fmu, Phase::StepComplete);
                run(&fmu, &i, 0, 2000)
            })
        })
        .collect();
    for h in handles {
        assert_eq!(h.join().unwrap(), alone);
    }
}

#[test]
fn get_status_reports_time_and_not_terminated() {
    let fmu = arm_fmu();
    let i = bring_to(&fmu, Phase::StepComplete);
    run(&fmu, &i, 0, 10);
    let mut t = 0.0;
    let mut b = 7;
    assert_eq!(i.get_real_status(2, &mut t), OK);
    assert_eq!(i.get_boolean_status(3, &mut b), OK);
    assert_eq!(i.get_real_status(0, &mut t), ERROR);
    assert!((t - 0.01).abs() < 1e-15);
    assert_eq!(b, 0);
}

#[test]
fn variable_communication_steps_match_the_in_process_arm() {
    // canHandleVariableCommunicationStepSize: any positive step, each split into RK4
    // sub-steps of at most internal_step; compare with the in-process simulator.
    let fmu = arm_fmu();
    let i = bring_to(&fmu, Phase::StepComplete);
    let (mut sim, _) = ArmConfig::default().build().unwrap();
    let mut state = neurarm_physics::arm::ArmState::at_rest(vec![0.0; 4]);
    let tau: Vec<u32> = (1..=4).map(|j| fmu.vr(&format!("tau_{j}"))).collect();
    let q: Vec<u32> = (1..=4).map(|j| fmu.vr(&format!("q_{j}"))).collect();
    let mut t = 0.0;
    for (k, h) in [1e-3, 2.5e-3, 1e-4, 0.0173, 3e-6, 0.05, 1e-3].iter().cycle().take(70).enumerate() {
        let u = [2.5 * (k as f64).sin(), -1.5, 0.8, -0.35];
        assert_eq!(i.set_real(&tau, &u), OK);
        assert_eq!(i.step(t, *h), OK, "{}", i.log.dump());
        sim.step(&mut state, &u, *h).unwrap();
        t += h;
    }
    assert_eq!(i.get_real(&q).unwrap(), state.q);
}
