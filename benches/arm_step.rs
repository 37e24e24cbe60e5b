//! One RK4 step of the default arm at dt = 1 ms (internal step = 1 ms, so exactly one RK4 step
//! as MuJoCo's RK4 takes), with and without friction, and one 1 ms step with the default
//! 0.25 ms internal step. `scripts/bench-arm` runs this and MuJoCo and prints the ratio.

#![allow(missing_docs)] // criterion_group! makes an undocumented public function

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use neurarm_physics::arm::*;

fn bench_step(c: &mut Criterion, name: &str, params: ArmParams, internal_step_s: f64) {
    let mut sim = ArmSimulator::new(params, IntegratorSettings { internal_step_s }).unwrap();
    let start = ArmState { q: vec![0.3, -0.5, 0.7, -0.2], qd: vec![1.0, -2.0, 1.5, 3.0] };
    let tau = [2.0, -1.0, 0.5, 0.2];
    let mut state = start.clone();
    let mut steps = 0u32;
    c.bench_function(name, |b| {
        b.iter(|| {
            // Restart now and then so the arm keeps sliding in a typical regime.
            steps += 1;
            if steps % 1000 == 0 {
                state.clone_from(&start);
            }
            sim.step(black_box(&mut state), black_box(&tau), 1e-3).unwrap();
        })
    });
}

fn arm_step(c: &mut Criterion) {
    let arm = ArmParams::default_four_link();
    bench_step(c, "rk4_step_1ms/friction", arm.clone(), 1e-3);
    bench_step(c, "rk4_step_1ms/frictionless", arm.clone().frictionless(), 1e-3);
    bench_step(c, "step_1ms_default_substeps/friction", arm, IntegratorSettings::default().internal_step_s);
}

criterion_group!(benches, arm_step);
criterion_main!(benches);
