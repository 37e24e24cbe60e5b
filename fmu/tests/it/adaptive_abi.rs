//! The AdaptiveCompensator FMU through its C ABI, as the PlanarArm in `fmu_abi.rs`: the state
//! machine refuses a step before initialization, a bad law parameter fails the step with its
//! name logged, adapted weights restore bit for bit through FMU states and serialisation into
//! another instance, and eight instances in eight threads learn as one alone.

use crate::common;

use common::*;
use neurarm_models::{AdaptationLaw, AdaptiveCompensatorSpec, ModelSpec};

fn adaptive_fmu() -> Fmu {
    fmu_with_nets(
        "Adaptive",
        ModelSpec::AdaptiveCompensator(AdaptiveCompensatorSpec {
            joints: 4,
            friction: (1..=4).map(|j| format!("friction_{j}.json")).collect(),
            gravity: Some("gravity.json".into()),
            enable_friction: true,
            enable_gravity: true,
            law: AdaptationLaw { gain_friction: 20.0, ..AdaptationLaw::default() },
        }),
    )
}

/// Steps from step `from` for `steps` steps of 1 ms with moving inputs and learning signals;
/// returns every compensating torque and how far each may now differ from the offline net's.
fn run(fmu: &Fmu, i: &Instance, from: usize, steps: usize) -> Vec<u64> {
    let names = |p: &str| -> Vec<u32> { (1..=4).map(|j| fmu.vr(&format!("{p}_{j}"))).collect() };
    let (q, qd, s) = (names("q"), names("qd"), names("s"));
    for k in from..from + steps {
        let t = k as f64 * 1e-3;
        let wave = |a: f64, j: usize| a * (3.0 * t + j as f64).sin();
        assert_eq!(i.set_real(&q, &(0..4).map(|j| wave(2.0, j)).collect::<Vec<_>>()), OK);
        assert_eq!(i.set_real(&qd, &(0..4).map(|j| wave(1.5, j + 1)).collect::<Vec<_>>()), OK);
        assert_eq!(i.set_real(&s, &(0..4).map(|j| wave(0.8, j + 2) + 0.2).collect::<Vec<_>>()), OK);
        assert_eq!(i.step(t, 1e-3), OK, "{}", i.log.dump());
    }
    let outputs: Vec<u32> = [names("tau_comp"), names("adapted_friction"), names("adapted_gravity")].concat();
    i.get_real(&outputs).unwrap().iter().map(|v| v.to_bits()).collect()
}

fn started(fmu: &Fmu) -> Instance {
    let i = fmu.instance();
    i.initialize();
    i
}

#[test]
fn a_step_before_initialization_and_a_bad_gain_are_refused_with_a_logged_reason() {
    let fmu = adaptive_fmu();
    let i = fmu.instance();
    assert_eq!(i.step(0.0, 1e-3), ERROR);
    assert!(i.log.contains("fmi2DoStep"), "{}", i.log.dump());
    let i = started(&fmu);
    assert_eq!(i.set_real(&[fmu.vr("gain_friction")], &[-1.0]), OK);
    assert_eq!(i.step(0.0, 1e-3), ERROR);
    assert!(i.log.contains("gain_friction = -1 must be a finite number >= 0"), "{}", i.log.dump());
}

#[test]
fn adapted_weights_restore_bit_identically_also_through_serialization() {
    let fmu = adaptive_fmu();
    let i = started(&fmu);
    run(&fmu, &i, 0, 300);
    let mut saved = std::ptr::null_mut();
    assert_eq!(i.get_fmu_state(&mut saved), OK);
    let reference = run(&fmu, &i, 300, 500);
    assert!(reference[4..].iter().all(|&b| f64::from_bits(b) > 0.0), "every net adapted");
    assert_eq!(i.set_fmu_state(saved), OK);
    assert_eq!(run(&fmu, &i, 300, 500), reference);
    let mut size = 0;
    assert_eq!(i.serialized_fmu_state_size(saved, &mut size), OK);
    let mut bytes = vec![0u8; size];
    assert_eq!(i.serialize_fmu_state(saved, &mut bytes), OK);
    let other = fmu.instance();
    let mut restored = std::ptr::null_mut();
    assert_eq!(other.deserialize_fmu_state(&bytes, &mut restored), OK);
    assert_eq!(other.set_fmu_state(restored), OK);
    assert_eq!(run(&fmu, &other, 300, 500), reference);
    assert_eq!(i.free_fmu_state(&mut saved), OK);
    assert_eq!(other.free_fmu_state(&mut restored), OK);
    // And a reset forgets what was learned: the run equals a fresh instance's.
    assert_eq!(i.reset(), OK);
    i.initialize();
    assert_eq!(run(&fmu, &i, 0, 200), run(&fmu, &started(&fmu), 0, 200));
}

#[test]
fn eight_instances_in_eight_threads_learn_as_one_alone() {
    let fmu = adaptive_fmu();
    let alone = run(&fmu, &started(&fmu), 0, 1500);
    let fmu = std::sync::Arc::new(fmu);
    let handles: Vec<_> = (0..8)
        .map(|_| {
            let fmu = fmu.clone();
            std::thread::spawn(move || run(&fmu, &started(&fmu), 0, 1500))
        })
        .collect();
    for h in handles {
        assert_eq!(h.join().unwrap(), alone);
    }
}
