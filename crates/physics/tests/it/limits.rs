//! Values that parse but describe no arm and no step are refused by name (issue 14's fuzzing
//! findings): configuration values beyond their physical limits, more joints than
//! [`MAX_JOINTS`], a step beyond [`MAX_STEP_WORK`]. (Weights beyond their limits: the tests of
//! `neurarm-nn`.)

use neurarm_physics::arm::{max_substeps, ArmSimulator, ArmState, IntegratorSettings, StepError, MAX_JOINTS, MAX_STEP_WORK};
use neurarm_physics::config::ArmConfig;

fn refused(text: &str) -> String {
    match ArmConfig::from_toml_str(text) {
        Ok(_) => panic!("accepted:\n{text}"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn configuration_values_beyond_their_limits_are_refused_by_name() {
    let default = ArmConfig::default().to_toml_string();
    // (the line as the default writes it, the value put there, what the message names)
    let cases = [
        ("qd_noise_std_rad_s = 0.0", "1.7e308", "qd_noise_std_rad_s = 1.7e308 is invalid: must be at most 1e5 rad/s"),
        ("q_noise_std_rad = 0.0", "4.0", "q_noise_std_rad = 4 is invalid: must be at most π rad"),
        ("mass_kg = 2.0", "1e300", "links[0].mass_kg = 1e300 is invalid: must be at most 1e5 kg"),
        ("length_m = 0.25", "1000.0", "links[0].length_m = 1000 is invalid: must be at most 100 m"),
        ("com_m = 0.125", "-1e6", "links[0].com_m = -1000000 is invalid: must be at most 100 m"),
        ("gravity_m_s2 = 9.81", "1e9", "gravity_m_s2 = 1000000000 is invalid: must be at most 100 m/s²"),
        ("base_angle_rad = 0.0", "1e20", "base_angle_rad = 1e20 is invalid: must be within one turn"),
        ("coulomb_nm = 1.5", "1e7", "friction[0].positive.coulomb_nm = 10000000 is invalid: must be at most 1e6 N·m"),
        ("viscous_nms_rad = 0.8", "1e7", "friction[0].positive.viscous_nms_rad = 10000000 is invalid: must be at most 1e6"),
        ("stribeck_velocity_rad_s = 1.0", "1e6", "stribeck_velocity_rad_s = 1000000 is invalid: must be at most 1e5 rad/s"),
        ("internal_step_s = 0.00025", "1e-12", "internal_step_s = 1e-12 is invalid: must be between 1e-9 s and 1 s"),
        ("internal_step_s = 0.00025", "2.0", "internal_step_s = 2 is invalid: must be between 1e-9 s and 1 s"),
    ];
    for (line, value, why) in cases {
        assert!(default.contains(line), "{line} not in the default configuration");
        let key = line.split(" = ").next().unwrap();
        let e = refused(&default.replacen(line, &format!("{key} = {value}"), 1));
        assert!(e.contains(why), "{why:?} not in {e:?}");
    }
    // Hardware lists: a count below one per turn, too many counts, a torque limit too large.
    let with = |extra: &str| default.replacen("[hardware]\n", &format!("[hardware]\n{extra}\n"), 1);
    assert!(default.contains("[hardware]\n"));
    let e = refused(&with("encoder_counts_per_rev = [0.5, 0.0, 0.0, 0.0]"));
    assert!(e.contains("encoder_counts_per_rev[0] = 0.5 is invalid: must be 0 (off) or at least 1 count"), "{e}");
    let e = refused(&with("encoder_counts_per_rev = [1e300, 0.0, 0.0, 0.0]"));
    assert!(e.contains("encoder_counts_per_rev[0] = 1e300 is invalid: must be at most 1e12"), "{e}");
    let e = refused(&with("torque_limit_nm = [0.0, 1e9, 0.0, 0.0]"));
    assert!(e.contains("torque_limit_nm[1] = 1000000000 is invalid: must be at most 1e6 N·m"), "{e}");
    // The limits themselves are values an arm may have.
    let edge = with("encoder_counts_per_rev = [1.0, 1e12, 0.0, 0.0]\ntorque_limit_nm = [1e6, 0.0, 0.0, 0.0]")
        .replacen("qd_noise_std_rad_s = 0.0", "qd_noise_std_rad_s = 1e5", 1)
        .replacen("mass_kg = 2.0", "mass_kg = 1e5", 1)
        .replacen("internal_step_s = 0.00025", "internal_step_s = 1.0", 1);
    ArmConfig::from_toml_str(&edge).unwrap();
}

#[test]
fn an_arm_of_more_joints_than_the_limit_is_refused() {
    let mut config = ArmConfig::default();
    config.arm.links = vec![config.arm.links[0].clone(); MAX_JOINTS];
    config.arm.friction = vec![config.arm.friction[0]; MAX_JOINTS];
    config.validate().unwrap();
    config.arm.links.push(config.arm.links[0].clone());
    config.arm.friction.push(config.arm.friction[0]);
    let e = config.validate().unwrap_err().to_string();
    assert_eq!(e, "65 joints: an arm may have at most 64");
}

#[test]
fn a_step_beyond_the_work_bound_is_refused_before_any_sub_step() {
    assert_eq!(max_substeps(4), MAX_STEP_WORK / 16);
    assert_eq!(max_substeps(4), 25_000);
    // The 1- and 2-joint arms are the slowest at their limit (fuzzing timed out at an earlier,
    // four times larger bound under the sanitizer).
    assert_eq!((max_substeps(1), max_substeps(2)), (400_000, 100_000));
    assert_eq!(max_substeps(64), 97);
    let config = ArmConfig::default();
    let (mut sim, _) = config.build().unwrap();
    let start = ArmState { q: vec![0.1, 0.2, 0.3, 0.4], qd: vec![0.5, 0.0, 0.0, -0.5] };
    let tau = [1.0, 0.0, 0.0, 0.0];
    for dt in [1e300, 1e4, 6.251] {
        let mut state = start.clone();
        match sim.step(&mut state, &tau, dt) {
            Err(StepError::TooMuchWork { joints: 4, max: 25_000, .. }) => {}
            other => panic!("dt = {dt}: {other:?}"),
        }
        assert_eq!(state, start, "the state is untouched");
    }
    assert_eq!(sim.check_step(6.25), Ok(25_000));
    // A tiny internal step reaches the bound with an ordinary communication step.
    let (mut fine, _) = ArmConfig { integrator: IntegratorSettings { internal_step_s: 1e-9 }, ..config }.build().unwrap();
    assert!(matches!(fine.check_step(1e-3), Err(StepError::TooMuchWork { .. })));
    let e = fine.step(&mut start.clone(), &tau, 1e-3).unwrap_err().to_string();
    assert!(e.contains("a step of 0.001 s needs 1.000e6 RK4 sub-steps"), "{e}");
    let mut single = ArmSimulator::new(ArmConfig::default().arm, IntegratorSettings::default()).unwrap();
    let mut state = start.clone();
    single.step(&mut state, &tau, 1e-3).unwrap();
    assert_ne!(state, start);
}
