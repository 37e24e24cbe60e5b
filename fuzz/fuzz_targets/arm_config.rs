//! (c) The arm configuration (TOML). A configuration that is accepted must be usable: it
//! builds a simulator and sensors, writes back to TOML that reads as the same configuration,
//! and its steps either succeed with finite states and finite measurements (while the state
//! stays in a physical range) or are refused, in bounded time.

#![no_main]

use libfuzzer_sys::fuzz_target;
use neurarm_physics::arm::{end_effector_position, ArmState};
use neurarm_physics::config::ArmConfig;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(config) = ArmConfig::from_toml_str(text) else { return };
    let again = ArmConfig::from_toml_str(&config.to_toml_string()).expect("a valid configuration reads back");
    assert_eq!(again, config, "TOML round trip");
    let (mut sim, mut sensors) = config.build().expect("a valid configuration builds");
    let n = config.arm.dof();
    let mut state = ArmState { q: (0..n).map(|i| 0.3 * i as f64).collect(), qd: vec![0.0; n] };
    let tau: Vec<f64> = (0..n).map(|i| if i % 2 == 0 { 1.5 } else { -0.7 }).collect();
    let (mut q, mut qd) = (vec![0.0; n], vec![0.0; n]);
    for _ in 0..5 {
        if sim.step(&mut state, &tau, 1e-3).is_err() {
            break;
        }
        if state.q.iter().chain(&state.qd).any(|v| !v.is_finite()) {
            break; // diverged: the FMU and `simulate` report it as such
        }
        assert!(end_effector_position(&config.arm, &state.q).iter().all(|v| v.is_finite()));
        if state.q.iter().chain(&state.qd).all(|v| v.abs() <= 1e6) {
            sensors.measure(&state, &mut q, &mut qd);
            assert!(q.iter().chain(&qd).all(|v| v.is_finite()), "measured {q:?} {qd:?} of {state:?}");
        }
    }
});
