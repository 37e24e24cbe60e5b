//! The arm's physics against independent computations: Pinocchio's values, a second
//! formulation (Newton–Euler), finite differences and energy.

use nalgebra::{DMatrix, DVector};
use neurarm_physics::arm::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn reference() -> serde_json::Value {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/dynamics-reference.json");
    let text = std::fs::read_to_string(path).expect("tests/data/dynamics-reference.json");
    serde_json::from_str(&text).unwrap()
}

fn vec_of(v: &serde_json::Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

/// Asserts |got − want| <= tol entrywise; returns the largest difference.
fn assert_close(what: &str, got: &[f64], want: &[f64], tol: f64) -> f64 {
    assert_eq!(got.len(), want.len(), "{what}: length");
    let mut worst: f64 = 0.0;
    for (i, (g, w)) in got.iter().zip(want).enumerate() {
        assert!((g - w).abs() <= tol, "{what}[{i}]: got {g}, want {w} (diff {:e})", (g - w).abs());
        worst = worst.max((g - w).abs());
    }
    worst
}

/// The reference arm: default geometry and masses, base turned 90°, no friction.
fn reference_arm(params: &serde_json::Value) -> ArmParams {
    let arm = ArmParams::default_four_link().frictionless().with_base_angle(std::f64::consts::FRAC_PI_2);
    // Guard against the defaults drifting from the reference's parameters.
    let lengths = vec_of(&params["link_lengths_m"]);
    let masses = vec_of(&params["link_masses_kg"]);
    let coms = vec_of(&params["com_distance_from_joint_m"]);
    let inertias = vec_of(&params["link_inertia_about_com_kgm2"]);
    for (i, l) in arm.links.iter().enumerate() {
        assert_eq!(l.length_m, lengths[i]);
        assert_eq!(l.mass_kg, masses[i]);
        assert_eq!(l.com_m, coms[i]);
        assert!((l.inertia_kgm2 - inertias[i]).abs() < 1e-18);
    }
    assert_eq!(arm.gravity_m_s2, params["gravity_m_s2"].as_f64().unwrap());
    arm
}

#[test]
fn matches_pinocchio_reference_values() {
    let r = reference();
    let arm = reference_arm(&r["params"]);
    let cases = r["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 8);
    let mut worst: f64 = 0.0;
    for (c, case) in cases.iter().enumerate() {
        let (q, qd, qdd) = (vec_of(&case["q"]), vec_of(&case["qd"]), vec_of(&case["qdd"]));
        let h = mass_matrix(&arm, &q);
        let h_ref: Vec<f64> = case["mass_matrix"].as_array().unwrap().iter().flat_map(vec_of).collect();
        let h_rows: Vec<f64> = (0..4).flat_map(|i| (0..4).map(move |j| (i, j))).map(|(i, j)| h[(i, j)]).collect();
        worst = worst.max(assert_close(&format!("case {c} H"), &h_rows, &h_ref, 1e-9));
        let tol = 1e-9;
        worst = worst.max(assert_close(
            &format!("case {c} C·qd"),
            coriolis_centrifugal(&arm, &q, &qd).as_slice(),
            &vec_of(&case["coriolis_centrifugal"]),
            tol,
        ));
        worst = worst.max(assert_close(&format!("case {c} g"), gravity_torques(&arm, &q).as_slice(), &vec_of(&case["gravity"]), tol));
        let id_ref = vec_of(&case["inverse_dynamics"]);
        worst = worst.max(assert_close(&format!("case {c} ID"), inverse_dynamics(&arm, &q, &qd, &qdd).as_slice(), &id_ref, tol));
        worst = worst.max(assert_close(&format!("case {c} RNEA"), inverse_dynamics_rnea(&arm, &q, &qd, &qdd).as_slice(), &id_ref, tol));
        worst = worst.max(assert_close(
            &format!("case {c} x"),
            end_effector_position(&arm, &q).as_slice(),
            &vec_of(&case["end_effector"]),
            tol,
        ));
        let jac = jacobian(&arm, &q);
        let jac_ref: Vec<f64> = case["jacobian"].as_array().unwrap().iter().flat_map(vec_of).collect();
        let jac_rows: Vec<f64> = (0..2).flat_map(|i| (0..4).map(move |j| (i, j))).map(|(i, j)| jac[(i, j)]).collect();
        worst = worst.max(assert_close(&format!("case {c} J"), &jac_rows, &jac_ref, tol));
    }
    eprintln!("largest difference from Pinocchio over all quantities and cases: {worst:e}");
}

fn random_arm(rng: &mut ChaCha8Rng, n: usize) -> ArmParams {
    ArmParams {
        links: (0..n)
            .map(|_| LinkParams {
                length_m: rng.gen_range(0.1..0.6),
                mass_kg: rng.gen_range(0.2..3.0),
                com_m: rng.gen_range(-0.1..0.5),
                inertia_kgm2: rng.gen_range(1e-4..0.05),
            })
            .collect(),
        friction: vec![JointFriction::none(); n],
        gravity_m_s2: 9.81,
        base_angle_rad: rng.gen_range(-3.0..3.0),
    }
}

fn random_vec(rng: &mut ChaCha8Rng, n: usize, range: f64) -> Vec<f64> {
    (0..n).map(|_| rng.gen_range(-range..range)).collect()
}

#[test]
fn newton_euler_agrees_with_closed_form_for_one_to_six_joints() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for n in 1..=6 {
        for _ in 0..50 {
            let arm = random_arm(&mut rng, n);
            let (q, qd, qdd) = (random_vec(&mut rng, n, 4.0), random_vec(&mut rng, n, 5.0), random_vec(&mut rng, n, 20.0));
            let closed = inverse_dynamics(&arm, &q, &qd, &qdd);
            let rnea = inverse_dynamics_rnea(&arm, &q, &qd, &qdd);
            let scale = 1.0 + closed.amax();
            assert!((closed - &rnea).amax() <= 1e-10 * scale, "n = {n}: closed form vs RNEA differ");
        }
    }
}

#[test]
fn mass_matrix_columns_equal_newton_euler_unit_accelerations() {
    // H e_k is RNEA at q̈ = e_k with no velocity and no gravity: a third route to H.
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    for n in 1..=6 {
        let mut arm = random_arm(&mut rng, n);
        arm.gravity_m_s2 = 0.0;
        let q = random_vec(&mut rng, n, 4.0);
        let h = mass_matrix(&arm, &q);
        for k in 0..n {
            let mut e = vec![0.0; n];
            e[k] = 1.0;
            let col = inverse_dynamics_rnea(&arm, &q, &vec![0.0; n], &e);
            assert!((h.column(k) - col).amax() < 1e-12);
        }
    }
}

#[test]
fn mass_matrix_is_symmetric_positive_definite() {
    let mut rng = ChaCha8Rng::seed_from_u64(13);
    for n in 1..=6 {
        for _ in 0..20 {
            let arm = random_arm(&mut rng, n);
            let h = mass_matrix(&arm, &random_vec(&mut rng, n, 4.0));
            assert!((&h - h.transpose()).amax() <= 1e-14 * h.amax(), "n = {n}: H not symmetric");
            let eig = h.symmetric_eigenvalues();
            assert!(eig.min() > 0.0, "n = {n}: eigenvalues {eig}");
        }
    }
}

#[test]
fn hdot_minus_two_c_is_skew_symmetric() {
    let mut rng = ChaCha8Rng::seed_from_u64(14);
    for n in 1..=6 {
        let arm = random_arm(&mut rng, n);
        let (q, qd) = (random_vec(&mut rng, n, 4.0), random_vec(&mut rng, n, 5.0));
        // Ḣ = d/dt H(q + q̇ t) by central differences.
        let eps = 1e-6;
        let at = |s: f64| -> DMatrix<f64> {
            let qs: Vec<f64> = q.iter().zip(&qd).map(|(a, b)| a + s * b).collect();
            mass_matrix(&arm, &qs)
        };
        let hdot = (at(eps) - at(-eps)) / (2.0 * eps);
        let c = coriolis_matrix(&arm, &q, &qd);
        let n_mat = &hdot - 2.0 * &c;
        assert!((&n_mat + n_mat.transpose()).amax() < 1e-7, "n = {n}: Ḣ − 2C not skew");
        // and C q̇ is the Coriolis vector
        let cqd = &c * DVector::from_column_slice(&qd);
        assert!((cqd - coriolis_centrifugal(&arm, &q, &qd)).amax() < 1e-12);
    }
}

#[test]
fn gravity_is_gradient_of_potential_energy() {
    let mut rng = ChaCha8Rng::seed_from_u64(15);
    for n in 1..=6 {
        let arm = random_arm(&mut rng, n);
        let q = random_vec(&mut rng, n, 4.0);
        let g = gravity_torques(&arm, &q);
        let eps = 1e-6;
        for j in 0..n {
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[j] += eps;
            qm[j] -= eps;
            let d = (potential_energy(&arm, &qp) - potential_energy(&arm, &qm)) / (2.0 * eps);
            assert!((d - g[j]).abs() < 1e-7, "n = {n}, joint {j}: dV/dq {d} vs g {}", g[j]);
        }
    }
}

#[test]
fn forward_dynamics_inverts_inverse_dynamics() {
    let mut rng = ChaCha8Rng::seed_from_u64(16);
    for n in 1..=6 {
        let arm = random_arm(&mut rng, n);
        let mut sim = ArmSimulator::new(arm.clone(), IntegratorSettings::default()).unwrap();
        let state = ArmState { q: random_vec(&mut rng, n, 4.0), qd: random_vec(&mut rng, n, 5.0) };
        let qdd = random_vec(&mut rng, n, 20.0);
        let tau = inverse_dynamics_rnea(&arm, &state.q, &state.qd, &qdd);
        let back = sim.forward_dynamics(&state, tau.as_slice());
        for j in 0..n {
            assert!((back[j] - qdd[j]).abs() < 1e-9 * (1.0 + qdd[j].abs()), "n = {n}");
        }
    }
}

fn total_energy(arm: &ArmParams, s: &ArmState) -> f64 {
    kinetic_energy(arm, &s.q, &s.qd) + potential_energy(arm, &s.q)
}

/// Largest |E(t) − E(0)| over 10 s of free motion with no friction and zero torque, stepping
/// with one RK4 step of `step_s` per call.
fn energy_drift(arm: &ArmParams, start: &ArmState, step_s: f64) -> f64 {
    let mut sim = ArmSimulator::new(arm.clone(), IntegratorSettings { internal_step_s: step_s }).unwrap();
    let mut s = start.clone();
    let e0 = total_energy(arm, &s);
    let zero = vec![0.0; arm.dof()];
    let mut worst: f64 = 0.0;
    for _ in 0..(10.0 / step_s).round() as usize {
        sim.step(&mut s, &zero, step_s).unwrap();
        worst = worst.max((total_energy(arm, &s) - e0).abs());
    }
    worst
}

/// Documented bound: with the default internal step (0.25 ms) the default arm, started from a
/// random state with joint speeds up to 5 rad/s and no friction, gravity or torque, keeps its
/// total energy within 1e-10 of its start, relative, over 10 s. With coarse steps, where the
/// truncation error dominates round-off, halving the step divides the drift by about 2⁴.
#[test]
fn energy_is_conserved_and_error_shrinks_with_rk4_order() {
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let arm = ArmParams::default_four_link().frictionless();
    let start = ArmState { q: random_vec(&mut rng, 4, 3.0), qd: random_vec(&mut rng, 4, 5.0) };
    let e0 = total_energy(&arm, &start);
    let default = energy_drift(&arm, &start, IntegratorSettings::default().internal_step_s);
    let drifts: Vec<f64> = [4e-3, 2e-3, 1e-3].iter().map(|&h| energy_drift(&arm, &start, h)).collect();
    eprintln!("E0 = {e0:.6} J; drift over 10 s: h = 4, 2, 1 ms: {drifts:?} J; 0.25 ms: {default:e} J");
    assert!(default < 1e-10 * e0, "drift {default:e} J over the documented bound");
    for w in drifts.windows(2) {
        let ratio = w[0] / w[1];
        assert!(ratio > 10.0 && ratio < 40.0, "halving the step changed the drift {ratio}×, not ~16×");
    }
}

/// With gravity (base turned 90°) the total energy including the potential is conserved too.
#[test]
fn energy_is_conserved_under_gravity() {
    let mut rng = ChaCha8Rng::seed_from_u64(18);
    let arm = ArmParams::default_four_link().frictionless().with_base_angle(std::f64::consts::FRAC_PI_2);
    let start = ArmState { q: random_vec(&mut rng, 4, 3.0), qd: random_vec(&mut rng, 4, 1.0) };
    let drift = energy_drift(&arm, &start, 2.5e-4);
    assert!(drift < 1e-6, "drift {drift:e} J");
}

/// The gravity load of a joint is the gravity torque of the arm stretched out level (q = 0)
/// with the base turned 90°, where the plane carries the full g.
#[test]
fn gravity_load_is_the_level_stretched_arms_gravity_torque() {
    let mut rng = ChaCha8Rng::seed_from_u64(19);
    for n in 1..=8 {
        let mut arm = random_arm(&mut rng, n);
        for link in &mut arm.links {
            link.com_m = link.com_m.abs();
        }
        let level = gravity_torques(&arm.clone().with_base_angle(std::f64::consts::FRAC_PI_2), &vec![0.0; n]);
        for j in 0..n {
            let load = arm.gravity_load_nm(j);
            assert!((load - level[j]).abs() <= 1e-12 * load, "{n} joints, joint {j}: {load} vs {}", level[j]);
        }
    }
}

/// The Coriolis torques of one moving joint, from the few ∂H/∂q entries they need, are the
/// full Christoffel sum's with that speed vector, and agree with Newton–Euler (q̈ = 0, no
/// gravity).
#[test]
fn coriolis_of_one_moving_joint_is_the_full_sum() {
    let mut rng = ChaCha8Rng::seed_from_u64(20);
    for n in 1..=8 {
        let arm = random_arm(&mut rng, n).with_base_angle(0.0);
        let mut data = ArmData::new(&arm);
        let q = random_vec(&mut rng, n, 3.0);
        for joint in 0..n {
            let speed = rng.gen_range(-5.0..5.0);
            let mut speeds = vec![0.0; n];
            speeds[joint] = speed;
            let (mut one, mut full, mut rnea) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
            coriolis_of_one_joint_into(&arm, &mut data, &q, joint, speed, &mut one);
            coriolis_centrifugal_into(&arm, &mut data, &q, &speeds, &mut full);
            inverse_dynamics_rnea_into(&arm, &mut data, &q, &speeds, &vec![0.0; n], &mut rnea);
            assert_eq!(one, full, "{n} joints, joint {joint}");
            for i in 0..n {
                assert!((one[i] - rnea[i]).abs() <= 1e-9 * (1.0 + rnea[i].abs()), "{n} joints, joint {joint}: {one:?} vs {rnea:?}");
            }
        }
    }
}

/// One joint: viscous friction b on the link's inertia about its joint, I + m c², decays the
/// speed at b / (I + m c²).
#[test]
fn the_viscous_rate_of_one_joint_is_its_slope_over_its_inertia() {
    let mut arm = ArmParams::default_four_link();
    arm.links.truncate(1);
    arm.friction.truncate(1);
    arm.friction[0].positive.viscous_nms_rad = 0.3;
    arm.friction[0].negative.viscous_nms_rad = 0.7;
    let link = &arm.links[0];
    let want = 0.7 / (link.inertia_kgm2 + link.mass_kg * link.com_m * link.com_m);
    let got = largest_viscous_rate(&arm, &[0.4]).unwrap();
    assert!((got - want).abs() <= 1e-12 * want, "{got} vs {want}");
}
