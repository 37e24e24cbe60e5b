//! The drift parameters of the arm and the ideal compensator: tunable while running, taken up
//! from the next step, refused by their FMU names, allocation-free when ramped.

use neurarm_test_support::allocations as counting;

use neurarm_fmi_export::instance::{Instance, Status};
use neurarm_models::*;
use neurarm_physics::arm::{ArmParams, ArmSimulator, ArmState, IntegratorSettings, OperatingChange};
use neurarm_physics::config::ArmConfig;

fn vr(instance: &Instance, name: &str) -> u32 {
    instance.description().variables.iter().find(|v| v.name == name).unwrap_or_else(|| panic!("no {name}")).value_reference
}

fn running(spec: ModelSpec) -> Instance {
    let model = FmuSpec { identifier: "M".into(), model: spec }.build().unwrap();
    let guid = model.description().guid();
    let mut instance = Instance::new("probe", &guid, model, Box::new(|_, _, m| eprintln!("{m}")), false).unwrap();
    assert_eq!(instance.setup_experiment(None, 0.0, None), Status::Ok);
    assert_eq!(instance.enter_initialization_mode(), Status::Ok);
    assert_eq!(instance.exit_initialization_mode(), Status::Ok);
    instance
}

fn vertical_arm() -> ArmConfig {
    let mut config = ArmConfig::default();
    config.arm.base_angle_rad = std::f64::consts::FRAC_PI_2;
    config
}

fn get(instance: &mut Instance, names: &[String]) -> Vec<f64> {
    let vrs: Vec<u32> = names.iter().map(|n| vr(instance, n)).collect();
    let mut out = vec![0.0; vrs.len()];
    assert_eq!(instance.get_real(&vrs, &mut out), Status::Ok);
    out
}

#[test]
fn a_payload_and_friction_set_while_running_act_from_the_next_step() {
    let config = vertical_arm();
    let q0 = vec![-1.2, 0.4, 0.3, -0.2];
    let mut fmu = running(ModelSpec::PlanarArm(PlanarArmSpec { config: config.clone(), q0: q0.clone(), qd0: vec![0.0; 4] }));
    let names: Vec<String> = (1..=4).flat_map(|i| [format!("q_{i}"), format!("qd_{i}")]).collect();
    let tau = [4.0, 1.5, 0.5, 0.2];
    let tau_vrs: Vec<u32> = (1..=4).map(|i| vr(&fmu, &format!("tau_{i}"))).collect();
    assert_eq!(fmu.set_real(&tau_vrs, &tau), Status::Ok);
    // The same motion by the simulator, the arm switched at the same step.
    let mut sim = ArmSimulator::new(config.arm.clone(), IntegratorSettings::default()).unwrap();
    let mut state = ArmState { q: q0, qd: vec![0.0; 4] };
    let change = OperatingChange {
        coulomb_scale: vec![1.3; 4],
        viscous_scale: vec![0.6, 0.6, 1.0, 1.0],
        payload_mass_kg: 0.24,
        payload_offset_m: 0.02,
    };
    let h = 1e-3;
    for k in 0..400 {
        if k == 200 {
            let set = |fmu: &mut Instance, name: String, v: f64| {
                let r = vr(fmu, &name);
                assert_eq!(fmu.set_real(&[r], &[v]), Status::Ok, "{name} is settable while running");
            };
            for i in 1..=4 {
                set(&mut fmu, format!("coulomb_scale_{i}"), change.coulomb_scale[i - 1]);
                set(&mut fmu, format!("viscous_scale_{i}"), change.viscous_scale[i - 1]);
            }
            set(&mut fmu, "payload_mass".into(), change.payload_mass_kg);
            set(&mut fmu, "payload_offset".into(), change.payload_offset_m);
            sim.set_params(&change.applied(&config.arm).unwrap()).unwrap();
        }
        assert_eq!(fmu.do_step(k as f64 * h, h), Status::Ok);
        sim.step(&mut state, &tau, h).unwrap();
    }
    let expected: Vec<f64> = (0..4).flat_map(|i| [state.q[i], state.qd[i]]).collect();
    assert_eq!(get(&mut fmu, &names), expected);
    // And it made a difference: the unchanged arm ends elsewhere.
    let mut unchanged = ArmSimulator::new(config.arm.clone(), IntegratorSettings::default()).unwrap();
    let mut other = ArmState { q: vec![-1.2, 0.4, 0.3, -0.2], qd: vec![0.0; 4] };
    for _ in 0..400 {
        unchanged.step(&mut other, &tau, h).unwrap();
    }
    assert!((other.q[0] - state.q[0]).abs() > 1e-3, "{} vs {}", other.q[0], state.q[0]);
}

#[test]
fn a_change_the_arm_cannot_take_fails_the_step_naming_the_fmu_variable() {
    let spec = FmuSpec {
        identifier: "M".into(),
        model: ModelSpec::PlanarArm(PlanarArmSpec { config: vertical_arm(), q0: vec![0.0; 4], qd0: vec![0.0; 4] }),
    };
    let built = spec.build().unwrap();
    let logged = std::sync::Arc::new(std::sync::Mutex::new(String::new()));
    let sink = logged.clone();
    let guid = built.description().guid();
    let mut fmu = Instance::new("probe", &guid, built, Box::new(move |_, _, m| sink.lock().unwrap().push_str(m)), false).unwrap();
    assert_eq!(fmu.setup_experiment(None, 0.0, None), Status::Ok);
    assert_eq!(fmu.enter_initialization_mode(), Status::Ok);
    assert_eq!(fmu.exit_initialization_mode(), Status::Ok);
    let r = vr(&fmu, "viscous_scale_2");
    assert_eq!(fmu.set_real(&[r], &[-0.5]), Status::Ok, "a finite value is taken when set");
    assert_eq!(fmu.do_step(0.0, 1e-3), Status::Error, "and refused by the step");
    let text = logged.lock().unwrap().clone();
    assert!(text.contains("viscous_scale_2 = -0.5 is invalid: must be >= 0"), "{text}");
}

#[test]
fn the_ideal_compensator_follows_the_same_change() {
    let arm = ArmParams::default_four_link().with_base_angle(std::f64::consts::FRAC_PI_2);
    let mut comp =
        running(ModelSpec::IdealCompensator(IdealCompensatorSpec { arm: arm.clone(), enable_friction: true, enable_gravity: true }));
    let change = OperatingChange {
        coulomb_scale: vec![1.3, 1.0, 0.7, 1.0],
        viscous_scale: vec![0.6, 1.2, 1.0, 0.9],
        payload_mass_kg: 0.3,
        payload_offset_m: 0.0,
    };
    for i in 1..=4 {
        let (c, v) = (vr(&comp, &format!("coulomb_scale_{i}")), vr(&comp, &format!("viscous_scale_{i}")));
        assert_eq!(comp.set_real(&[c, v], &[change.coulomb_scale[i - 1], change.viscous_scale[i - 1]]), Status::Ok);
    }
    let m = vr(&comp, "payload_mass");
    assert_eq!(comp.set_real(&[m], &[0.3]), Status::Ok);
    let q = [0.3, -0.7, 0.9, 0.2];
    let qd = [0.8, -1.1, 2.0, -0.3];
    let inputs: Vec<u32> = (1..=4).flat_map(|i| [format!("q_{i}"), format!("qd_{i}")]).map(|n| vr(&comp, &n)).collect();
    let values: Vec<f64> = (0..4).flat_map(|i| [q[i], qd[i]]).collect();
    assert_eq!(comp.set_real(&inputs, &values), Status::Ok);
    let changed = change.applied(&arm).unwrap();
    let gravity = neurarm_physics::arm::gravity_torques(&changed, &q);
    let names: Vec<String> = (1..=4).flat_map(|i| [format!("tau_friction_{i}"), format!("tau_gravity_{i}")]).collect();
    let out = get(&mut comp, &names);
    for i in 0..4 {
        assert_eq!(out[2 * i], changed.friction[i].torque(qd[i]), "friction {i}");
        assert!((out[2 * i + 1] - gravity[i]).abs() < 1e-12, "gravity {i}");
    }
    assert_ne!(out[0], arm.friction[0].torque(qd[0]));
}

#[test]
fn ramping_the_drift_every_step_allocates_nothing() {
    let mut fmu = running(ModelSpec::PlanarArm(PlanarArmSpec { config: vertical_arm(), q0: vec![0.0; 4], qd0: vec![0.0; 4] }));
    let ramp: Vec<u32> = ["viscous_scale_1", "coulomb_scale_3", "payload_mass"].iter().map(|n| vr(&fmu, n)).collect();
    assert!(counting::allocations_during(|| drop(std::hint::black_box(Box::new(1)))) >= 1);
    let count = counting::allocations_during(|| {
        for k in 0..300 {
            let s = k as f64 / 300.0;
            assert_eq!(fmu.set_real(&ramp, &[1.0 - 0.4 * s, 1.0 + 0.3 * s, 0.2 * s]), Status::Ok);
            assert_eq!(fmu.do_step(k as f64 * 1e-3, 1e-3), Status::Ok);
        }
    });
    assert_eq!(count, 0);
}
