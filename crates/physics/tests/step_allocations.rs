//! A step allocates nothing: a counting global allocator watches the stepping thread.

#[path = "support/counting.rs"]
mod counting;

use counting::allocations_during;
use neurarm_physics::arm::*;

#[test]
fn stepping_allocates_nothing() {
    // Friction with stick–slip (joints starting at rest), gravity, torque limits, sub-steps.
    let params = ArmParams::default_four_link().with_base_angle(1.0);
    let mut sim = ArmSimulator::new(params, IntegratorSettings::default()).unwrap();
    sim.set_torque_limits(Some(vec![5.0; 4])).unwrap();
    let mut state = ArmState::at_rest(vec![0.3, -0.5, 0.7, -0.2]);
    let mut sensors = Sensors::new(
        HardwareEffects {
            encoder_counts_per_rev: Some(vec![4096.0; 4]),
            q_noise_std_rad: 1e-3,
            qd_noise_std_rad_s: 1e-2,
            ..Default::default()
        },
        4,
    )
    .unwrap();
    let (mut q, mut qd) = ([0.0; 4], [0.0; 4]);
    // Warm up: the counter itself is lazily set up on first use.
    assert!(
        allocations_during(|| {
            let _ = Box::new(1);
        }) >= 1,
        "the counter must see allocations"
    );
    let count = allocations_during(|| {
        for k in 0..2000 {
            let tau = [3.0 * (k as f64 * 1e-3).sin(), 1.0, -0.5, 0.35];
            sim.step(&mut state, &tau, 1e-3).unwrap();
            sensors.measure(&state, &mut q, &mut qd);
        }
    });
    assert_eq!(count, 0);
    assert!(state.q[0] != 0.3);
}

#[test]
fn training_epochs_allocate_only_the_gemm_buffers() {
    use nalgebra::DMatrix;
    use neurarm_physics::nn::lm::{gemm_calls, train_with_threads};
    use neurarm_physics::nn::TrainSettings;
    let x = DMatrix::from_fn(2, 300, |r, c| ((c * (r + 3)) % 17) as f64 / 8.0 - 1.0);
    let t = DMatrix::from_fn(3, 300, |r, c| (x[(0, c)] * (r + 1) as f64).sin() + x[(1, c)] * x[(1, c)]);
    let settings = TrainSettings { hidden: 8, epochs: 40, max_fail: usize::MAX, ..Default::default() };
    // Count from the end of epoch 1's callback to epoch 40's: that span is epochs 2…40 whole
    // (linearise, solves, trial evaluations, validation). One thread, so that every GEMM call
    // is made on this one.
    let (per_linearisation, per_trial) = gemm_calls(2, 8, 3);
    let mut epochs_seen = 0;
    let mut counted = None;
    let mut gemms = 0;
    train_with_threads(&x, &t, &settings, 1, &mut |e| {
        if e.epoch == 1 {
            counting::start();
        } else {
            gemms += per_linearisation + per_trial * e.trials;
            if e.epoch == settings.epochs {
                counted = Some(counting::stop());
            }
        }
        epochs_seen += 1;
    })
    .unwrap();
    counting::stop();
    assert_eq!(epochs_seen, 40, "training ran all epochs");
    // Our own code allocates nothing; matrixmultiply allocates its packing buffer once per
    // call: the Gram matrix of [z; ã] by row panels, and each Cholesky factorisation's block
    // rows.
    assert!(gemms >= 39, "{gemms} GEMM calls");
    assert_eq!(counted, Some(gemms), "allocations during 39 epochs");
}
