//! The control laws against independent computations: the reference against finite
//! differences, and the closed loop through forward dynamics against the error dynamics
//! ë + K_d ė + K_p e = 0 that computed torque promises with a perfect model.

use nalgebra::{DVector, Vector2};
use neurarm_physics::arm::*;
use neurarm_physics::control::*;

#[test]
fn reference_derivatives_match_finite_differences_and_it_passes_its_centre() {
    let c = Vector2::new(0.4, 0.3);
    let eps = 1e-6;
    for t in [0.0, 0.7, 2.0, 5.5] {
        let (_, v, a) = paper_reference(t, c);
        let (xp, vp, _) = paper_reference(t + eps, c);
        let (xm, vm, _) = paper_reference(t - eps, c);
        assert!(((xp - xm) / (2.0 * eps) - v).norm() < 1e-8);
        assert!(((vp - vm) / (2.0 * eps) - a).norm() < 1e-8);
    }
    let t = 7.0 * std::f64::consts::PI / 6.0; // sin t = −1/2
    assert!((paper_reference(t, c).0 - c).norm() < 1e-12);
}

/// J⁺ checked against its definition, the four Penrose conditions, at a regular pose and
/// at two singular ones (stretched out; folded back on itself).
#[test]
fn pseudo_inverse_meets_the_penrose_conditions_at_regular_and_singular_poses() {
    let arm = ArmParams::default_four_link();
    for q in [[0.3, 1.1, -0.7, 0.5], [0.3, 0.0, 0.0, 0.0], [0.0, 0.0, std::f64::consts::PI, 0.0]] {
        let jac = jacobian(&arm, &q);
        let pinv = pseudo_inverse(&jac).unwrap();
        let (jp, pj) = (&jac * &pinv, &pinv * &jac);
        assert!((&jp * &jac - &jac).amax() < 1e-12, "J J⁺ J = J at {q:?}");
        assert!((&pj * &pinv - &pinv).amax() < 1e-9, "J⁺ J J⁺ = J⁺ at {q:?}");
        assert!((&jp - jp.transpose()).amax() < 1e-12 && (&pj - pj.transpose()).amax() < 1e-12, "symmetric at {q:?}");
        assert!(pinv.amax() < 1e3, "bounded at {q:?}");
    }
    let regular = pseudo_inverse(&jacobian(&arm, &[0.3, 1.1, -0.7, 0.5])).unwrap();
    assert!((&jacobian(&arm, &[0.3, 1.1, -0.7, 0.5]) * regular - nalgebra::DMatrix::<f64>::identity(2, 2)).amax() < 1e-12);
    // Stretched out, J has rank 1: J J⁺ projects onto the one direction left.
    let jac = jacobian(&arm, &[0.3, 0.0, 0.0, 0.0]);
    let jp = &jac * pseudo_inverse(&jac).unwrap();
    assert!((jp.trace() - 1.0).abs() < 1e-9);
    assert!(pseudo_inverse(&nalgebra::DMatrix::from_element(2, 4, f64::NAN)).is_none());
}

/// With the controller's model equal to the arm (no friction), the end-effector acceleration
/// produced by forward dynamics equals ẍ_d + K_d ė + K_p e exactly, and the null-space part
/// of q̈ is the commanded damping.
#[test]
fn computed_torque_gives_the_commanded_task_acceleration() {
    let arm = ArmParams::default_four_link().frictionless().with_base_angle(1.0);
    let mut sim = ArmSimulator::new(arm.clone(), IntegratorSettings::default()).unwrap();
    let gains = TaskSpaceGains::default();
    let centre = Vector2::new(0.45, 0.2);
    for (k, q) in [[0.3, 1.1, -0.7, 0.5], [-0.4, 0.9, 1.2, -0.8], [1.0, -1.3, 0.6, 1.4]].iter().enumerate() {
        let qd = [0.5, -0.3, 0.8 * k as f64, 0.2];
        let (x, v, a) = paper_reference(0.3 * k as f64, centre);
        let reference = TaskReference { position: x, velocity: v, acceleration: a };
        let u = task_space_acceleration(&arm, q, &qd, &reference, &gains).unwrap();
        let tau = computed_torque(&arm, q, &qd, &u, &[0.0; 4]);
        let qdd = sim.forward_dynamics(&ArmState { q: q.to_vec(), qd: qd.to_vec() }, tau.as_slice());
        let jac = jacobian(&arm, q);
        let xdd = &jac * DVector::from_column_slice(&qdd) + DVector::from_column_slice(jacobian_dot_qd(&arm, q, &qd).as_slice());
        let xnow = end_effector_position(&arm, q);
        let vnow = end_effector_velocity(&arm, q, &qd);
        let want = a + gains.kd * (v - vnow) + gains.kp * (x - xnow);
        assert!((xdd[0] - want[0]).abs() < 1e-9 && (xdd[1] - want[1]).abs() < 1e-9, "pose {k}");
        // Null-space component of q̈ is −k (I − J⁺J) q̇.
        let pinv = pseudo_inverse(&jac).unwrap();
        let null = nalgebra::DMatrix::<f64>::identity(4, 4) - &pinv * &jac;
        let got = &null * DVector::from_column_slice(&qdd);
        let expected = -gains.null_damping * (&null * DVector::from_column_slice(&qd));
        assert!((got - expected).amax() < 1e-9);
    }
}

/// In closed loop (controller evaluated every 0.1 ms, torque held in between), an initial
/// task error decays as the solution of ë + K_d ė + K_p e = 0, within 2 % of e(0).
#[test]
fn closed_loop_error_follows_the_second_order_error_dynamics() {
    let arm = ArmParams::default_four_link().frictionless();
    let mut sim = ArmSimulator::new(arm.clone(), IntegratorSettings { internal_step_s: 1e-4 }).unwrap();
    let gains = TaskSpaceGains::default();
    let centre = Vector2::new(0.45, 0.2);
    let mut state = ArmState::at_rest(vec![0.2, 1.0, 0.8, -0.6]);
    let e0 = paper_reference(0.0, centre).0 - end_effector_position(&arm, &state.q);
    let ed0 = paper_reference(0.0, centre).1; // arm at rest
    assert!(e0.norm() > 0.01, "start away from the reference");
    let (kp, kd) = (gains.kp, gains.kd);
    let disc = (kd * kd - 4.0 * kp).sqrt();
    let (r1, r2) = ((-kd + disc) / 2.0, (-kd - disc) / 2.0);
    let analytic = |t: f64, e: f64, ed: f64| {
        let b = (ed - r1 * e) / (r2 - r1);
        (e - b) * (r1 * t).exp() + b * (r2 * t).exp()
    };
    let h = 1e-4;
    for step in 0..5000 {
        let t = step as f64 * h;
        let (x, v, a) = paper_reference(t, centre);
        let u = task_space_acceleration(&arm, &state.q, &state.qd, &TaskReference { position: x, velocity: v, acceleration: a }, &gains)
            .unwrap();
        let tau = computed_torque(&arm, &state.q, &state.qd, &u, &[0.0; 4]);
        sim.step(&mut state, tau.as_slice(), h).unwrap();
        if (step + 1) % 500 == 0 {
            let t1 = t + h;
            let e = paper_reference(t1, centre).0 - end_effector_position(&arm, &state.q);
            for axis in 0..2 {
                let want = analytic(t1, e0[axis], ed0[axis]);
                assert!((e[axis] - want).abs() < 0.02 * e0.norm(), "t {t1}: axis {axis} error {} vs {want}", e[axis]);
            }
        }
    }
}

#[test]
fn joint_p_torque_adds_gravity_compensation() {
    let tau = joint_p_torque(&[0.1, 0.2], &[0.3, 0.0], 2.0, &[1.0, -1.0]);
    assert!((tau[0] - 1.4).abs() < 1e-15 && (tau[1] + 1.4).abs() < 1e-15);
}

/// The placement rule scales the paper's curve with the reach: for the default 1 m arm it is
/// the paper's size around (0.45, 0.10) m, between 0.23 m and 0.84 m from the base (from the
/// curve's formula, sampled here); an arm too short, or with a hole in its workspace, is refused.
#[test]
fn the_reference_is_placed_by_the_reach_and_checked_against_the_workspace() {
    let arm = ArmParams::default_four_link();
    let p = ReferencePlacement::for_arm(&arm);
    assert_eq!((p.centre, p.scale), (Vector2::new(0.45, 0.10), 1.0));
    let (near, far) = p.distance_range();
    let sampled: Vec<f64> = (0..6284).map(|k| scaled_reference(k as f64 * 1e-3, p.centre, 1.0).0.norm()).collect();
    assert!((near - sampled.iter().cloned().fold(f64::INFINITY, f64::min)).abs() < 1e-12);
    assert!((0.22..0.23).contains(&near) && (0.83..0.84).contains(&far), "{near} {far}");
    assert!(p.check(&arm).is_ok());
    // The same rule for an arm twice as long: twice the size, twice the distances.
    let mut long = arm.clone();
    for l in &mut long.links {
        l.length_m *= 2.0;
    }
    let q = ReferencePlacement::for_arm(&long);
    let (near2, far2) = q.distance_range();
    assert!((near2 - 2.0 * near).abs() < 1e-12 && (far2 - 2.0 * far).abs() < 1e-12);
    // Scaled by s about its centre: the paper's curve's velocity scales by s too.
    let (_, v1, a1) = scaled_reference(0.4, p.centre, 1.0);
    let (_, v3, a3) = scaled_reference(0.4, p.centre, 3.0);
    assert!((v3 - 3.0 * v1).norm() < 1e-15 && (a3 - 3.0 * a1).norm() < 1e-15);
    assert_eq!(scaled_reference(0.4, p.centre, 1.0), paper_reference(0.4, p.centre));
    // Too far for the arm, and too near for one whose first link outreaches the others.
    let far_away = ReferencePlacement { centre: Vector2::new(0.9, 0.5), scale: 1.0 };
    assert!(matches!(far_away.check(&arm), Err(PlacementError::TooFar { reach, .. }) if reach == 1.0));
    let mut lopsided = arm.clone();
    lopsided.links.truncate(2);
    lopsided.friction.truncate(2);
    lopsided.links[1].length_m = 0.05;
    let hole = ReferencePlacement::for_arm(&lopsided).check(&lopsided).unwrap_err();
    assert!(matches!(hole, PlacementError::TooNear { hole, .. } if (hole - 0.2).abs() < 1e-12), "{hole}");
    assert!(matches!(ReferencePlacement { scale: -1.0, ..p }.check(&arm), Err(PlacementError::Invalid { .. })));
}
