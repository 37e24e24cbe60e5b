//! Values that parse but make no physical sense, refused through the C ABI with a logged
//! reason (issue 14's fuzzing findings; each test failed before its fix): resources that ask
//! for sizes that cannot be allocated, steps past the stop time or beyond the work one step
//! may do, times and tolerances that are not usable, FMU states holding NaN or infinities
//! with a valid checksum, and model results that are not finite.

use crate::common;

use common::*;
use neurarm_models::{FmuSpec, GainSpec, JointControllerSpec, ModelSpec, TaskSpaceControllerSpec, SPEC_FILE};
use neurarm_physics::arm::ArmParams;
use neurarm_physics::config::ArmConfig;
use neurarm_physics::control::TaskSpaceGains;

fn gain_fmu() -> Fmu {
    Fmu::new(&FmuSpec { identifier: "Gain".into(), model: ModelSpec::Gain(GainSpec { k: 2.0 }) })
}

/// Instantiates the FMU binary on a resources folder holding `spec_text` and `files`; the
/// factory reads the spec before the GUID is checked, so any GUID does for a refusal.
fn instantiate_spec(spec_text: &str, files: &[(&str, &[u8])]) -> (bool, String) {
    let fmu = gain_fmu();
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join(SPEC_FILE), spec_text).unwrap();
    for (name, bytes) in files {
        std::fs::write(dir.path().join(name), bytes).unwrap();
    }
    let (c, log, _cb) = fmu.instantiate_with("a", "{none}", &format!("file://{}", dir.path().display()));
    if !c.is_null() {
        // SAFETY: `c` is a component just instantiated, freed once, used no more.
        unsafe { (fmu.api.fmi2FreeInstance)(c) };
    }
    (!c.is_null(), log.dump())
}

fn joint_controller(joints: &str) -> String {
    format!("identifier = \"J\"\n[model]\nkind = \"JointController\"\njoints = {joints}\nkp = 1.0\nkd = 0.0\nuse_sequence = true\n")
}

#[test]
fn resources_asking_for_more_joints_than_the_limit_are_refused_by_name() {
    // 2^32 joints aborted the host on a 17 GB allocation; 10^6 took over 10 s.
    for joints in ["4294967296", "1000000", "65"] {
        let (made, log) = instantiate_spec(&joint_controller(joints), &[]);
        assert!(!made && log.contains(&format!("{joints} joints: an arm may have at most 64")), "{joints}: {log}");
    }
    let spec = |identifier: &str, model: ModelSpec| FmuSpec { identifier: identifier.into(), model }.to_toml();
    let mut long = ArmConfig::default();
    long.arm.links = vec![long.arm.links[0].clone(); 65];
    long.arm.friction = vec![long.arm.friction[0]; 65];
    let arm = FmuSpec::planar_arm("Arm", long.clone()).to_toml();
    let task = spec(
        "Task",
        ModelSpec::TaskSpaceController(TaskSpaceControllerSpec {
            model: long.arm.clone(),
            gains: TaskSpaceGains::default(),
            centre: [0.4, 0.1],
            scale: 1.0,
            q_start: vec![0.1; 65],
        }),
    );
    let nets = "identifier = \"C\"\n[model]\nkind = \"NnCompensator\"\njoints = 1000000000\nfriction = []\ngravity = \"g.json\"\n\
                enable_friction = false\nenable_gravity = true\n";
    for (what, text) in [("arm", arm), ("task-space controller", task), ("compensator", nets.to_owned())] {
        let (made, log) = instantiate_spec(&text, &[]);
        assert!(!made && log.contains("joints: an arm may have at most 64"), "{what}: {log}");
    }
    // The limit itself is allowed.
    let fmu = Fmu::new(&FmuSpec {
        identifier: "J64".into(),
        model: ModelSpec::JointController(JointControllerSpec { joints: 64, kp: 1.0, kd: 0.0, use_sequence: true }),
    });
    fmu.instance().initialize();
}

#[test]
fn a_spec_too_large_to_be_one_and_a_file_outside_resources_are_refused() {
    let padding = format!("# {}\n", "x".repeat(5 << 20));
    let (made, log) = instantiate_spec(&format!("{padding}{}", joint_controller("2")), &[]);
    assert!(!made && log.contains("larger than 4 MiB"), "{log}");
    for name in ["../gravity.json", "/etc/hostname", "sub/g.json"] {
        let text = format!(
            "identifier = \"C\"\n[model]\nkind = \"NnCompensator\"\njoints = 2\nfriction = []\ngravity = \"{name}\"\n\
             enable_friction = false\nenable_gravity = true\n"
        );
        let (made, log) = instantiate_spec(&text, &[]);
        assert!(!made && log.contains(&format!("resource file '{name}' is not a plain file name")), "{name}: {log}");
    }
}

#[test]
fn a_start_value_that_is_not_finite_is_refused_at_instantiation() {
    for k in ["nan", "inf", "-inf"] {
        let (made, log) = instantiate_spec(&format!("identifier = \"G\"\n[model]\nkind = \"Gain\"\nk = {k}\n"), &[]);
        assert!(!made && log.contains("the start value of 'k' is"), "{k}: {log}");
    }
}

fn arm_fmu() -> Fmu {
    Fmu::new(&FmuSpec::planar_arm("PlanarArm", ArmConfig::default()))
}

fn setup(i: &Instance, tolerance: Option<f64>, start: f64, stop: Option<f64>) -> std::ffi::c_int {
    i.setup_experiment(tolerance, start, stop)
}

fn last_time(i: &Instance) -> f64 {
    let mut t = f64::NAN;
    assert_eq!(i.get_real_status(2, &mut t), OK);
    t
}

#[test]
fn a_step_past_the_stop_time_is_refused_and_changes_nothing() {
    // h = 1e4 took over 10 s and h = 1e300 never returned, though the stop time was 10 s.
    let fmu = arm_fmu();
    let i = fmu.instance();
    assert_eq!(setup(&i, None, 0.0, Some(10.0)), OK);
    assert_eq!(i.enter(), OK);
    assert_eq!(i.exit(), OK);
    for h in [1e4, 1e300, 10.5] {
        assert_eq!(i.step(0.0, h), ERROR, "h = {h}");
        assert!(i.log.contains("past the stop time 10 s"), "{}", i.log.dump());
    }
    assert_eq!(last_time(&i), 0.0);
    assert_eq!(i.step(0.0, 5.0), OK, "{}", i.log.dump());
    assert_eq!(i.step(5.0, 4.999), OK, "{}", i.log.dump());
    // Rounding of the communication points is tolerated at the stop time itself (a few ulps,
    // instance::TIME_ULPS), and nothing more: 1e-12 s is 560 ulps of 10 s.
    assert_eq!(i.step(9.999, 0.001 + 1e-12), ERROR);
    assert_eq!(i.step(9.999, 0.001 + 2.0 * f64::EPSILON * 10.0), OK, "{}", i.log.dump());
    assert_eq!(i.step(last_time(&i), 1e-3), ERROR);
}

#[test]
fn a_step_beyond_the_work_bound_is_refused_at_once() {
    let fmu = arm_fmu();
    let i = fmu.instance();
    i.initialize();
    for h in [1e4, 1e300] {
        let started = std::time::Instant::now();
        assert_eq!(i.step(0.0, h), ERROR, "h = {h}");
        assert!(i.log.contains("RK4 sub-steps") && i.log.contains("MAX_STEP_WORK"), "{}", i.log.dump());
        // Bounded, not timed: refused before a single sub-step (a hang would never get here).
        assert!(started.elapsed().as_secs() < 60);
        assert_eq!(i.reset(), OK);
        i.initialize();
    }
    // 25 000 sub-steps of 0.25 ms is the 4-joint arm's limit: 6.25 s is taken, 6.251 s is not.
    assert_eq!(i.step(0.0, 6.251), ERROR);
    assert_eq!(i.reset(), OK);
    i.initialize();
    assert_eq!(i.step(0.0, 6.25), OK, "{}", i.log.dump());
}

#[test]
fn times_and_tolerances_that_cannot_be_used_are_refused() {
    let fmu = arm_fmu();
    for tolerance in [f64::NAN, f64::INFINITY, 0.0, -1e-6] {
        let i = fmu.instance();
        assert_eq!(setup(&i, Some(tolerance), 0.0, None), ERROR, "{tolerance}");
        assert!(i.log.contains("must be finite and > 0"), "{}", i.log.dump());
        assert_eq!(setup(&i, Some(1e-6), 0.0, None), OK);
    }
    let i = fmu.instance();
    assert_eq!(setup(&i, None, 0.0, Some(f64::INFINITY)), ERROR);
    // At t = 1e20 s a step of 1 ms does not move the time a double can hold: refused when set.
    assert_eq!(setup(&i, None, 1e20, None), ERROR);
    assert!(i.log.contains("no longer resolves this FMU's step of 0.001 s"), "{}", i.log.dump());
    assert_eq!(setup(&i, None, 1e9, None), OK);
    assert_eq!(i.enter(), OK);
    assert_eq!(i.exit(), OK);
    assert_eq!(i.step(1e9, 1e-20), ERROR);
    assert!(i.log.contains("not at a later time a double can hold"), "{}", i.log.dump());
    assert_eq!(i.step(1e9, 1e6), ERROR, "the arm's work bound");
}

#[test]
fn a_start_time_that_would_overflow_the_reference_is_refused_when_set() {
    let arm = ArmParams::default_four_link().frictionless();
    let fmu = Fmu::new(&FmuSpec {
        identifier: "Task".into(),
        model: ModelSpec::TaskSpaceController(TaskSpaceControllerSpec {
            model: arm,
            gains: TaskSpaceGains::default(),
            centre: [0.45, 0.1],
            scale: 1.0,
            q_start: vec![-0.4, 0.9, 0.7, 0.5],
        }),
    });
    let i = fmu.instance();
    // The layer's time horizon refuses it before the model sees it (the model's own check, "the
    // reference at t = … s is not finite", is tested in crates/models).
    assert_eq!(setup(&i, None, 1.7e308, None), ERROR);
    assert!(i.log.contains("start time 1.7e308 s is beyond"), "{}", i.log.dump());
    assert_eq!(setup(&i, None, 0.0, None), OK);
    assert_eq!(i.enter(), OK);
    assert_eq!(i.exit(), OK, "{}", i.log.dump());
}

#[test]
fn a_result_that_is_not_finite_fails_the_call_by_the_variable_name() {
    let fmu = Fmu::new(&FmuSpec {
        identifier: "Joint".into(),
        model: ModelSpec::JointController(JointControllerSpec { joints: 2, kp: 50.0, kd: 0.0, use_sequence: false }),
    });
    let i = fmu.instance();
    i.initialize();
    let (kp, q, tau) = (fmu.vr("kp_1"), fmu.vr("q_1"), fmu.vr("tau_1"));
    assert_eq!(i.set_real(&[kp, q], &[1e300, -1e300]), OK);
    // Outputs read after setting inputs: τ = kp·(0 − q) overflows.
    assert_eq!(i.get_real(&[tau]), Err(ERROR));
    assert!(i.log.contains("the model computed inf for 'tau_1'"), "{}", i.log.dump());
    i.log.take();
    assert_eq!(i.step(0.0, 1e-3), ERROR);
    assert!(i.log.contains("fmi2DoStep at t = 0 s: the model computed inf for 'tau_1'"), "{}", i.log.dump());
    assert_eq!(i.get_real(&[tau]), Err(ERROR), "the value left by the failed step is not read back");
    assert_eq!(i.reset(), OK, "the instance recovers");
    i.initialize();
}

/// Serialized state of `i`.
fn serialize(i: &Instance) -> Vec<u8> {
    let mut s = std::ptr::null_mut();
    assert_eq!(i.get_fmu_state(&mut s), OK);
    let mut size = 0;
    assert_eq!(i.serialized_fmu_state_size(s, &mut size), OK);
    let mut bytes = vec![0; size];
    assert_eq!(i.serialize_fmu_state(s, &mut bytes), OK);
    assert_eq!(i.free_fmu_state(&mut s), OK);
    bytes
}

/// Offsets of the 8 bytes of `value` in `bytes`.
fn places(bytes: &[u8], value: f64) -> Vec<usize> {
    let pattern = value.to_le_bytes();
    (0..bytes.len().saturating_sub(7)).filter(|&k| bytes[k..k + 8] == pattern).collect()
}

/// `bytes` with `value` written at `at` and the checksum recomputed, as an attacker would.
fn altered(bytes: &[u8], at: usize, value: f64) -> Vec<u8> {
    let mut b = bytes.to_vec();
    b[at..at + 8].copy_from_slice(&value.to_le_bytes());
    let n = b.len() - 4;
    let crc = crc32fast::hash(&b[..n]);
    b[n..].copy_from_slice(&crc.to_le_bytes());
    b
}

/// Deserializes `bytes` and, if that succeeds, restores the state: the layer checks its part
/// when reading the bytes, the model its own when it is given the state.
fn restore(i: &Instance, bytes: &[u8]) -> std::ffi::c_int {
    let mut s = std::ptr::null_mut();
    let mut status = i.deserialize_fmu_state(bytes, &mut s);
    if status == OK {
        status = i.set_fmu_state(s);
        i.free_fmu_state(&mut s);
    }
    status
}

#[test]
fn a_serialized_state_with_numbers_that_are_not_finite_is_refused_despite_its_checksum() {
    let fmu = arm_fmu();
    let i = fmu.instance();
    // Distinct numbers to find in the bytes: the angle in the parameter q0_1, the output q_1
    // and the arm's own state; the start time in the time and the start time.
    let angle = 0.123456789;
    assert_eq!(i.set_real(&[fmu.vr("q0_1")], &[angle]), OK);
    assert_eq!(setup(&i, None, 0.375, None), OK);
    assert_eq!(i.enter(), OK);
    assert_eq!(i.exit(), OK);
    let bytes = serialize(&i);
    assert_eq!(restore(&i, &bytes), OK, "{}", i.log.dump());
    let at_angle = places(&bytes, angle);
    let at_time = places(&bytes, 0.375);
    assert_eq!(at_time.len(), 3, "time, start time and the variable `time`");
    let mut named = Vec::new();
    for &at in at_angle.iter().chain(&at_time) {
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            i.log.take();
            assert_eq!(restore(&i, &altered(&bytes, at, bad)), ERROR, "{bad} at {at}");
            named.push(i.log.dump());
        }
    }
    let named = named.join("\n");
    for why in [
        "for 'q0_1', not a finite number",
        "for 'q_1', not a finite number",
        "for 'q_meas_1', not a finite number",
        "q[0] = NaN is not a finite number",
        "the state's time is inf",
        "the state's start time is -inf",
        "for 'time', not a finite number",
    ] {
        assert!(named.contains(why), "{why} not in {named}");
    }
    assert_eq!(at_angle.len(), 4, "q_1, q_meas_1, q0_1 and the arm's own state");
    // A time before the start time is no state this FMU saves.
    i.log.take();
    assert_eq!(restore(&i, &altered(&bytes, at_time[0], 0.25)), ERROR);
    assert!(i.log.contains("before its start time"), "{}", i.log.dump());
    // The instance is unchanged and still steps.
    assert_eq!(i.step(0.375, 1e-3), OK, "{}", i.log.dump());
}
