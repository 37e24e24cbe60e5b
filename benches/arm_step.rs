//! One RK4 step of the default arm at dt = 1 ms (internal step = 1 ms, so exactly one RK4 step
//! as MuJoCo's RK4 takes), with and without friction, and one 1 ms step with the default
//! 0.25 ms internal step. `scripts/bench-arm` runs this and MuJoCo and prints the ratio.
//! Also, for an 8-joint arm, the closed-form mass matrix and Coriolis torques, in full and of
//! one moving joint (what the friction identification's rigid hold computes every step),
//! beside Newton–Euler inverse dynamics, the O(n) peer: `cargo bench --bench arm_step -- rigid_body`.
//!
//! Every run (`--test` too) first writes the frictionless arm's trajectory over the bench's
//! first 1000 steps to `<target>/arm-bench/frictionless.csv`, where `benches/python/arm_ratio.py`
//! checks that MuJoCo computes the same before it compares their times.

#![allow(missing_docs)] // criterion_group! makes an undocumented public function

use std::fmt::Write as _;
use std::path::PathBuf;

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use neurarm_physics::arm::*;

const Q0: [f64; 4] = [0.3, -0.5, 0.7, -0.2];
const QD0: [f64; 4] = [1.0, -2.0, 1.5, 3.0];
const TAU: [f64; 4] = [2.0, -1.0, 0.5, 0.2];

/// Steps between restarts of the timed loops, and of the reference trajectory.
const RESTART: u32 = 1000;

fn bench_step(c: &mut Criterion, name: &str, params: ArmParams, internal_step_s: f64) {
    let mut sim = ArmSimulator::new(params, IntegratorSettings { internal_step_s }).unwrap();
    let start = ArmState { q: Q0.to_vec(), qd: QD0.to_vec() };
    let mut state = start.clone();
    let mut steps = 0u32;
    c.bench_function(name, |b| {
        b.iter(|| {
            // Restart now and then so the arm keeps sliding in a typical regime.
            steps += 1;
            if steps % RESTART == 0 {
                state.clone_from(&start);
            }
            sim.step(black_box(&mut state), black_box(&TAU), 1e-3).unwrap();
        })
    });
}

/// The frictionless arm's states (time [s], q [rad], q̇ [rad/s]) from the bench's start under its
/// torques, at the start and after each of the first [`RESTART`] steps of 1 ms (one RK4 step
/// each), written where `benches/python/arm_ratio.py` reads them.
fn write_reference_trajectory(arm: ArmParams) {
    let mut sim = ArmSimulator::new(arm, IntegratorSettings { internal_step_s: 1e-3 }).unwrap();
    let mut state = ArmState { q: Q0.to_vec(), qd: QD0.to_vec() };
    let mut csv = String::from("time,q1,q2,q3,q4,qd1,qd2,qd3,qd4\n");
    for k in 0..=RESTART {
        if k > 0 {
            sim.step(&mut state, &TAU, 1e-3).unwrap();
        }
        let row: Vec<String> = state.q.iter().chain(&state.qd).map(f64::to_string).collect();
        writeln!(csv, "{},{}", f64::from(k) * 1e-3, row.join(",")).unwrap();
    }
    let target =
        std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target"));
    let dir = target.join("arm-bench");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("frictionless.csv"), csv).unwrap();
}

fn arm_step(c: &mut Criterion) {
    let arm = ArmParams::default_four_link();
    write_reference_trajectory(arm.clone().frictionless());
    bench_step(c, "rk4_step_1ms/friction", arm.clone(), 1e-3);
    bench_step(c, "rk4_step_1ms/frictionless", arm.clone().frictionless(), 1e-3);
    bench_step(c, "step_1ms_default_substeps/friction", arm, IntegratorSettings::default().internal_step_s);
}

fn rigid_body_terms(c: &mut Criterion) {
    let n = 8;
    let arm = neurarm_physics::family::random_arm(2, n).arm;
    let mut data = ArmData::new(&arm);
    let q: Vec<f64> = (0..n).map(|i| 0.3 * i as f64 - 1.0).collect();
    let qd: Vec<f64> = (0..n).map(|i| 0.5 - 0.1 * i as f64).collect();
    let (mut h, mut out) = (nalgebra::DMatrix::zeros(n, n), vec![0.0; n]);
    c.bench_function("rigid_body_8_joints/mass_matrix_and_coriolis", |b| {
        b.iter(|| {
            mass_matrix_into(&arm, &mut data, black_box(&q), &mut h);
            coriolis_centrifugal_into(&arm, &mut data, black_box(&q), black_box(&qd), &mut out);
        })
    });
    c.bench_function("rigid_body_8_joints/mass_matrix_and_coriolis_of_one_joint", |b| {
        b.iter(|| {
            mass_matrix_into(&arm, &mut data, black_box(&q), &mut h);
            coriolis_of_one_joint_into(&arm, &mut data, black_box(&q), 2, black_box(qd[2]), &mut out);
        })
    });
    c.bench_function("rigid_body_8_joints/newton_euler_inverse_dynamics", |b| {
        b.iter(|| inverse_dynamics_rnea_into(&arm, &mut data, black_box(&q), black_box(&qd), black_box(&qd), &mut out))
    });
}

criterion_group!(benches, arm_step, rigid_body_terms);
criterion_main!(benches);
