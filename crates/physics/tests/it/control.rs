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

/// The task-space law's inverse J# against an independent formulation: away from singular
/// poses it is J⁺ itself; within the margin ε of one, u = J# a is the minimiser of
/// ‖J u − a‖² + λ² ‖u‖² (its gradient Jᵀ(J u − a) + λ² u vanishes) with λ² = ε² − σ₂², σ₂ from
/// an SVD of J; it stays within 1/ε through the singular pose and has no jump at σ₂ = ε.
#[test]
fn the_damped_inverse_is_the_pseudo_inverse_away_from_singular_poses_and_bounded_through_them() {
    let arm = ArmParams::default_four_link();
    let margin = SINGULAR_MARGIN_SHARE * arm.links.iter().map(|l| l.length_m).sum::<f64>();
    let damped = |jac: &nalgebra::DMatrix<f64>| {
        let (mut jt, mut inv, mut out) = (nalgebra::DMatrix::zeros(4, 2), nalgebra::DMatrix::zeros(2, 2), nalgebra::DMatrix::zeros(4, 2));
        assert!(damped_inverse_into(jac, margin, &mut jt, &mut inv, &mut out));
        out
    };
    let smallest_singular = |jac: &nalgebra::DMatrix<f64>| jac.clone().svd(false, false).singular_values.min();
    // Regular: the same numbers as J⁺.
    let jac = jacobian(&arm, &[0.3, 1.1, -0.7, 0.5]);
    assert!(smallest_singular(&jac) > margin);
    assert_eq!(damped(&jac), pseudo_inverse(&jac).unwrap());
    // Sweep joint 2 through the stretched pose (σ₂ = 0 at q₂ = q₃ = q₄ = 0).
    let a = DVector::from_vec(vec![0.7, -1.3]);
    let mut damped_poses = 0;
    let mut previous: Option<(f64, nalgebra::DMatrix<f64>)> = None;
    for k in -400..=400 {
        let bend = k as f64 * 1e-3;
        let jac = jacobian(&arm, &[0.3, bend, 0.5 * bend, 0.0]);
        let sigma = smallest_singular(&jac);
        let inverse = damped(&jac);
        assert!(inverse.norm() <= 2f64.sqrt() / margin * (1.0 + 1e-9), "‖J#‖ {} at bend {bend}", inverse.norm());
        if sigma < margin {
            damped_poses += 1;
            let lambda2 = margin * margin - sigma * sigma;
            let u = &inverse * &a;
            let gradient = jac.transpose() * (&jac * &u - &a) + lambda2 * &u;
            assert!(gradient.amax() < 1e-9 * (1.0 + a.amax()), "gradient {} at bend {bend}", gradient.amax());
        } else {
            assert_eq!(inverse, pseudo_inverse(&jac).unwrap(), "undamped at bend {bend}");
        }
        // Continuous: neighbouring poses 1 mrad apart give neighbouring inverses, the switch
        // between the two forms included.
        if let Some((last_bend, last)) = &previous {
            let step = (&inverse - last).amax();
            assert!(step < 0.05 / margin * (bend - last_bend) / 1e-3, "jump {step} at bend {bend}");
        }
        previous = Some((bend, inverse));
    }
    assert!(damped_poses > 10 && damped_poses < 801, "{damped_poses} damped poses: the sweep must cross the margin");
    let nan = nalgebra::DMatrix::from_element(2, 4, f64::NAN);
    let (mut jt, mut inv, mut out) = (nalgebra::DMatrix::zeros(4, 2), nalgebra::DMatrix::zeros(2, 2), nalgebra::DMatrix::zeros(4, 2));
    assert!(!damped_inverse_into(&nan, margin, &mut jt, &mut inv, &mut out));
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

/// With a rest pose, the null-space part of q̈ (forward dynamics of the computed torque) is
/// (I − J⁺J)(k_s wrap(q_rest − q) − k q̇), the task part unchanged; a joint one turn away from
/// its rest angle is home.
#[test]
fn the_rest_pose_pulls_the_self_motion_back_through_the_null_space() {
    let arm = ArmParams::default_four_link().frictionless().with_base_angle(0.7);
    let mut sim = ArmSimulator::new(arm.clone(), IntegratorSettings::default()).unwrap();
    let gains = TaskSpaceGains { null_stiffness: 25.0, ..TaskSpaceGains::default() };
    let mut data = TaskSpaceData::new(&arm);
    let rest = [0.1, 0.8, -0.4, 0.9 + std::f64::consts::TAU];
    data.set_rest_pose(Some(&rest));
    assert_eq!(data.rest_pose(), Some(&rest[..]));
    let (x, v, a) = paper_reference(0.5, Vector2::new(0.45, 0.2));
    let reference = TaskReference { position: x, velocity: v, acceleration: a };
    for q in [[0.3, 1.1, -0.7, 0.5], [-0.4, 0.9, 1.2, -0.8]] {
        let qd = [0.4, -0.2, 0.6, 0.1];
        let mut tau = [0.0; 4];
        assert!(task_space_torque_into(&arm, &mut data, &q, &qd, &reference, &gains, &[0.0; 4], &mut tau));
        let qdd = DVector::from_column_slice(&sim.forward_dynamics(&ArmState { q: q.to_vec(), qd: qd.to_vec() }, &tau));
        let jac = jacobian(&arm, &q);
        let null = nalgebra::DMatrix::<f64>::identity(4, 4) - &pseudo_inverse(&jac).unwrap() * &jac;
        let wrapped: Vec<f64> = (0..4).map(|i| rest[i] - q[i] - if i == 3 { std::f64::consts::TAU } else { 0.0 }).collect();
        let target = DVector::from_iterator(4, (0..4).map(|i| gains.null_stiffness * wrapped[i] - gains.null_damping * qd[i]));
        assert!((&null * &qdd - &null * target).amax() < 1e-9, "pose {q:?}");
        let xdd = &jac * &qdd + DVector::from_column_slice(jacobian_dot_qd(&arm, &q, &qd).as_slice());
        let want = a + gains.kd * (v - end_effector_velocity(&arm, &q, &qd)) + gains.kp * (x - end_effector_position(&arm, &q));
        assert!((xdd[0] - want[0]).abs() < 1e-9 && (xdd[1] - want[1]).abs() < 1e-9);
    }
    assert!(
        (wrapped_angle(3.5) - (3.5 - std::f64::consts::TAU)).abs() < 1e-15 && wrapped_angle(std::f64::consts::PI) == std::f64::consts::PI
    );
}

/// Damping alone lets the self-motion drift: a small constant torque error on a redundant
/// arm holding a fixed point moves its pose through the task's null space until the error has
/// no share there, while with the rest pose it settles near home, where the first-order
/// balance k_s Δq = (I − J⁺J) H⁻¹ τ_offset puts it.
#[test]
fn with_a_rest_pose_a_small_torque_error_no_longer_makes_the_pose_drift() {
    let arm = ArmParams::default_four_link().frictionless();
    let q0 = vec![0.3, 1.1, -0.7, 0.5];
    let target = end_effector_position(&arm, &q0);
    let reference = TaskReference { position: target, velocity: Vector2::zeros(), acceleration: Vector2::zeros() };
    let offset = [0.0, 0.0, 0.0, 0.05];
    let gains = TaskSpaceGains { null_stiffness: 25.0, ..TaskSpaceGains::default() };
    let run = |rest: bool| {
        let mut sim = ArmSimulator::new(arm.clone(), IntegratorSettings { internal_step_s: 1e-3 }).unwrap();
        let mut data = TaskSpaceData::new(&arm);
        data.set_rest_pose(rest.then_some(&q0[..]));
        let mut state = ArmState::at_rest(q0.clone());
        let mut tau = [0.0; 4];
        let mut drift = [0.0; 2];
        for step in 0..20_000 {
            assert!(task_space_torque_into(&arm, &mut data, &state.q, &state.qd, &reference, &gains, &offset, &mut tau));
            sim.step(&mut state, &tau, 1e-3).unwrap();
            if step == 9_999 || step == 19_999 {
                drift[step / 10_000] = state.q.iter().zip(&q0).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
            }
        }
        // The offset leaves a steady task error of J H⁻¹ offset / K_p, about 1 mm here, either way.
        assert!((end_effector_position(&arm, &state.q) - target).norm() < 5e-3);
        drift
    };
    let damped = run(false);
    let held = run(true);
    // To first order the held pose sits where k_s (I − J⁺J) Δq balances the offset's
    // null-space acceleration (I − J⁺J) H⁻¹ τ_offset.
    let jac = jacobian(&arm, &q0);
    let null = nalgebra::DMatrix::<f64>::identity(4, 4) - &pseudo_inverse(&jac).unwrap() * &jac;
    let push = &null * mass_matrix(&arm, &q0).try_inverse().unwrap() * DVector::from_column_slice(&offset);
    let predicted = push.norm() / gains.null_stiffness;
    assert!((held[1] - held[0]).abs() < 0.01 * held[0], "held pose settled: {held:?} rad");
    assert!((held[1] / predicted - 1.0).abs() < 0.3, "held {held:?} rad, first-order prediction {predicted} rad");
    // Damped only, the pose wanders until the offset has no null-space share left.
    assert!(damped[0] > 4.0 * held[0], "damped only the pose drifts far: {damped:?} rad (held {held:?})");
}

#[test]
fn joint_p_torque_adds_gravity_compensation() {
    let tau = joint_p_torque(&[0.1, 0.2], &[0.3, 0.0], 2.0, &[1.0, -1.0]);
    assert!((tau[0] - 1.4).abs() < 1e-15 && (tau[1] + 1.4).abs() < 1e-15);
}

/// The placement rule scales the paper's curve with the reach: for the default 1 m arm it is
/// the paper's size around (0.45, 0.10) m, between 0.23 m and 0.84 m from the base (from the
/// curve's formula, sampled here); an arm too short is refused, and for one with a hole in its
/// workspace the curve is fitted into the ring the arm reaches.
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
    let by_reach = ReferencePlacement { centre: Vector2::new(0.45 * 0.3, 0.10 * 0.3), scale: 0.3 };
    let hole = by_reach.check(&lopsided).unwrap_err();
    assert!(matches!(hole, PlacementError::TooNear { hole, .. } if (hole - 0.2).abs() < 1e-12), "{hole}");
    assert!((workspace_hole(&lopsided) - 0.2).abs() < 1e-12 && workspace_hole(&arm) == 0.0);
    // for_arm fits the curve into the ring 0.2–0.3 m the lopsided arm reaches instead: the
    // distances sampled from the curve itself lie 23 % / 16 % of the ring inside its edges.
    let fitted = ReferencePlacement::for_arm(&lopsided);
    assert!(fitted.fitted(&lopsided) && !p.fitted(&arm));
    assert!(fitted.check(&lopsided).is_ok(), "{:?}", fitted.check(&lopsided));
    let distances: Vec<f64> = (0..6284).map(|k| scaled_reference(k as f64 * 1e-3, fitted.centre, fitted.scale).0.norm()).collect();
    let (near, far) = (distances.iter().cloned().fold(f64::INFINITY, f64::min), distances.iter().cloned().fold(0.0, f64::max));
    assert!(near >= 0.2 + 0.23 * 0.1 - 1e-6 && far <= 0.3 - 0.16 * 0.1 + 1e-6, "{near} {far}");
    // As large as fits: one margin is met within 0.1 mm.
    assert!((near - 0.223).abs() < 1e-4 || (far - 0.284).abs() < 1e-4, "{near} {far}");
    assert!(matches!(ReferencePlacement { scale: -1.0, ..p }.check(&arm), Err(PlacementError::Invalid { .. })));
}
