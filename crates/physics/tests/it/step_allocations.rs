//! A step allocates nothing: a counting global allocator watches the stepping thread.

use neurarm_test_support::allocations as counting;

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
            let _ = std::hint::black_box(Box::new(1));
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
