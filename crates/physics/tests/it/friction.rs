//! Friction and stick–slip: constant-torque experiments reach the velocity the friction law
//! predicts (solved independently by bisection), and torques below breakaway move nothing.

use neurarm_physics::arm::*;

/// One link of the default arm, in the horizontal plane, with `friction`.
fn single_joint(friction: JointFriction) -> ArmParams {
    ArmParams { links: vec![LinkParams::uniform_rod(0.25, 2.0)], friction: vec![friction], gravity_m_s2: 9.81, base_angle_rad: 0.0 }
}

/// Velocity on the rising branch where the friction magnitude equals `torque` > breakaway.
fn predicted_speed(branch: &FrictionBranch, torque: f64) -> f64 {
    let (mut lo, mut hi) = (0.0, 1000.0);
    assert!(branch.magnitude(lo) < torque && branch.magnitude(hi) > torque);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if branch.magnitude(mid) < torque {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

fn run(arm: &ArmParams, tau: &[f64], seconds: f64) -> ArmState {
    let mut sim = ArmSimulator::new(arm.clone(), IntegratorSettings::default()).unwrap();
    let mut s = ArmState::at_rest(vec![0.0; arm.dof()]);
    for _ in 0..(seconds * 1000.0).round() as usize {
        sim.step(&mut s, tau, 1e-3).unwrap();
    }
    s
}

/// The real-robot shapes of the paper: Stribeck, sign asymmetry, falling viscous friction.
fn shaped() -> JointFriction {
    JointFriction {
        positive: FrictionBranch {
            coulomb_nm: 1.0,
            static_nm: 1.4,
            stribeck_velocity_rad_s: 0.15,
            viscous_nms_rad: 0.6,
            viscous_falloff_rad_s: Some(2.0),
        },
        negative: FrictionBranch {
            coulomb_nm: 0.8,
            static_nm: 1.1,
            stribeck_velocity_rad_s: 0.1,
            viscous_nms_rad: 0.9,
            viscous_falloff_rad_s: None,
        },
    }
}

#[test]
fn constant_torque_above_breakaway_reaches_predicted_velocity() {
    let shapes = [JointFriction::default_for_joint(0), shaped()];
    for friction in shapes {
        let arm = single_joint(friction);
        for &tau in &[1.6f64, 2.0, 2.4, -1.6, -2.0, -2.4] {
            let branch = if tau > 0.0 { &friction.positive } else { &friction.negative };
            assert!(tau.abs() > branch.static_nm);
            let want = tau.signum() * predicted_speed(branch, tau.abs());
            let s = run(&arm, &[tau], 20.0);
            assert!((s.qd[0] - want).abs() < 1e-6, "tau {tau}: steady velocity {} vs predicted {want}", s.qd[0]);
        }
    }
}

#[test]
fn torque_below_breakaway_does_not_move_the_joint() {
    for friction in [JointFriction::default_for_joint(0), shaped()] {
        let arm = single_joint(friction);
        for tau in [0.99 * friction.positive.static_nm, -0.99 * friction.negative.static_nm, 0.3] {
            let s = run(&arm, &[tau], 3.0);
            assert_eq!(s.q[0], 0.0, "tau {tau} moved the joint");
            assert_eq!(s.qd[0], 0.0);
        }
    }
}

#[test]
fn stribeck_joint_breaks_away_just_above_static_level() {
    // Between the Coulomb and the static level a Stribeck joint at rest stays at rest; just
    // above the static level it breaks away and jumps past the dip to the rising branch.
    let f = shaped();
    let arm = single_joint(f);
    let below = run(&arm, &[1.39], 2.0);
    assert_eq!(below.qd[0], 0.0);
    let above = run(&arm, &[1.41], 10.0);
    let want = predicted_speed(&f.positive, 1.41);
    assert!(want > 0.3, "the dip is crossed: v* = {want}");
    assert!((above.qd[0] - want).abs() < 1e-6);
}

#[test]
fn whole_arm_below_breakaway_stays_put_and_above_moves() {
    let arm = ArmParams::default_four_link();
    let below: Vec<f64> = arm
        .friction
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let sign = if i % 2 == 0 { 1.0 } else { -1.0 };
            0.95 * sign * f.positive.static_nm
        })
        .collect();
    let s = run(&arm, &below, 2.0);
    assert!(s.q.iter().chain(&s.qd).all(|&x| x == 0.0), "moved: {s:?}");
    let mut above = below.clone();
    above[3] = 1.05 * arm.friction[3].positive.static_nm;
    let s = run(&arm, &above, 0.5);
    assert!(s.q[3] != 0.0, "joint 4 above breakaway did not move");
}

#[test]
fn coasting_joint_stops_and_stays_stopped() {
    // Set spinning with no torque, Coulomb friction brings the joint to rest in finite time
    // (v0 · I / F_c at most), after which it stays exactly at rest without chattering.
    let arm = single_joint(JointFriction::default_for_joint(0));
    let mut sim = ArmSimulator::new(arm, IntegratorSettings::default()).unwrap();
    let mut s = ArmState { q: vec![0.0], qd: vec![3.0] };
    for _ in 0..1000 {
        sim.step(&mut s, &[0.0], 1e-3).unwrap();
    }
    assert_eq!(s.qd[0], 0.0);
    let q_stop = s.q[0];
    assert!(q_stop > 0.0);
    for _ in 0..1000 {
        sim.step(&mut s, &[0.0], 1e-3).unwrap();
        assert_eq!((s.q[0], s.qd[0]), (q_stop, 0.0));
    }
}

#[test]
fn static_friction_holds_a_link_against_gravity_below_breakaway() {
    // Base turned 90°, link horizontal: gravity torque m g c = 2 · 9.81 · 0.125 = 2.45 N·m.
    let hold = JointFriction::symmetric(FrictionBranch::coulomb_viscous(3.0, 0.5));
    let slip = JointFriction::symmetric(FrictionBranch::coulomb_viscous(2.0, 0.5));
    for (friction, should_hold) in [(hold, true), (slip, false)] {
        let arm = single_joint(friction).with_base_angle(std::f64::consts::FRAC_PI_2);
        let s = run(&arm, &[0.0], 0.5);
        assert_eq!(s.q[0] == 0.0, should_hold, "friction {friction:?}: q = {}", s.q[0]);
    }
}

#[test]
fn bad_step_arguments_leave_the_state_untouched() {
    let arm = ArmParams::default_four_link();
    let mut sim = ArmSimulator::new(arm, IntegratorSettings::default()).unwrap();
    let mut s = ArmState { q: vec![0.1; 4], qd: vec![0.2; 4] };
    let before = s.clone();
    assert!(matches!(sim.step(&mut s, &[1.0; 4], 0.0), Err(StepError::BadStep(_))));
    assert!(matches!(sim.step(&mut s, &[1.0; 4], f64::NAN), Err(StepError::BadStep(_))));
    assert!(matches!(sim.step(&mut s, &[1.0; 3], 1e-3), Err(StepError::WrongLength { .. })));
    assert!(matches!(sim.step(&mut s, &[1.0, f64::NAN, 0.0, 0.0], 1e-3), Err(StepError::NotFinite { what: "tau", index: 1, .. })));
    assert_eq!(s, before);
}

#[test]
fn torque_limits_clip_the_applied_torque() {
    // A clipped command behaves exactly like the limit itself.
    let arm = single_joint(JointFriction::default_for_joint(0));
    let mut clipped = ArmSimulator::new(arm.clone(), IntegratorSettings::default()).unwrap();
    clipped.set_torque_limits(Some(vec![2.0])).unwrap();
    let mut exact = ArmSimulator::new(arm, IntegratorSettings::default()).unwrap();
    let (mut a, mut b) = (ArmState::at_rest(vec![0.0]), ArmState::at_rest(vec![0.0]));
    for _ in 0..500 {
        clipped.step(&mut a, &[10.0], 1e-3).unwrap();
        exact.step(&mut b, &[2.0], 1e-3).unwrap();
    }
    assert_eq!(a, b);
    assert!(clipped.set_torque_limits(Some(vec![-1.0])).is_err());
}
