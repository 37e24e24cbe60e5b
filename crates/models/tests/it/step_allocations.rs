//! Every model's `fmi2DoStep` allocates nothing: each model runs through the FMI layer's
//! instance (the code the C ABI calls), initialised and driven with changing inputs, while a
//! counting global allocator watches the stepping thread.

use neurarm_test_support::allocations as counting;

use neurarm_test_support::nets;

use counting::allocations_during;
use nets::net_file;
use neurarm_fmi_export::instance::{Instance, Status};
use neurarm_fmi_export::Model;
use neurarm_models::*;
use neurarm_nn::WeightsFile;
use neurarm_physics::arm::ArmParams;
use neurarm_physics::config::ArmConfig;
use neurarm_physics::control::TaskSpaceGains;

/// Initialises `model`, then counts the allocations of 500 steps of 1 ms, setting every real
/// input to a new value before each step.
fn step_allocations(model: Box<dyn Model>) -> usize {
    let description = model.description().clone();
    let inputs: Vec<u32> = description
        .variables
        .iter()
        .filter(|v| v.causality == neurarm_fmi_export::Causality::Input && v.base_type() == neurarm_fmi_export::description::BaseType::Real)
        .map(|v| v.value_reference)
        .collect();
    let outputs: Vec<u32> =
        description.variables.iter().filter(|v| v.causality == neurarm_fmi_export::Causality::Output).map(|v| v.value_reference).collect();
    let name = description.model_identifier.clone();
    let mut instance = Instance::new("probe", &description.guid(), model, Box::new(|_, _, m| eprintln!("{m}")), false).unwrap();
    assert_eq!(instance.setup_experiment(None, 0.0, None), Status::Ok);
    assert_eq!(instance.enter_initialization_mode(), Status::Ok);
    assert_eq!(instance.exit_initialization_mode(), Status::Ok, "{name}");
    let mut values = vec![0.0; inputs.len()];
    let mut out = vec![0.0; outputs.len()];
    // Warm up: the counter itself is lazily set up on first use.
    assert!(allocations_during(|| drop(std::hint::black_box(Box::new(1)))) >= 1, "the counter must see allocations");
    let count = allocations_during(|| {
        for k in 0..500 {
            let t = k as f64 * 1e-3;
            for (i, v) in values.iter_mut().enumerate() {
                *v = 0.4 + 0.3 * (3.0 * t + i as f64).sin();
            }
            assert_eq!(instance.set_real(&inputs, &values), Status::Ok);
            assert_eq!(instance.do_step(t, 1e-3), Status::Ok);
            assert_eq!(instance.get_real(&outputs, &mut out), Status::Ok);
        }
    });
    assert!(out.iter().all(|v| v.is_finite()) && out.iter().any(|v| *v != 0.0), "{name} computed something: {out:?}");
    count
}

#[test]
fn every_models_step_allocates_nothing() {
    let dir = tempfile::tempdir().unwrap();
    // One net per joint (the compensator refuses the same net twice), each a little different.
    let mut files: Vec<(String, WeightsFile)> = (1..=4)
        .map(|j| {
            let mut net = net_file(1, 5, 1);
            net.b2[0] += 0.1 * j as f64;
            (format!("friction_{j}.json"), net)
        })
        .collect();
    files.push(("gravity.json".into(), net_file(4, 6, 4)));
    for (name, file) in &files {
        std::fs::write(dir.path().join(name), file.to_json()).unwrap();
    }
    let mut config = ArmConfig::default();
    config.arm.base_angle_rad = 1.0;
    config.hardware.q_noise_std_rad = 1e-3;
    config.hardware.encoder_counts_per_rev = Some(vec![4096.0; 4]);
    let arm = ArmParams::default_four_link();
    let specs = [
        ModelSpec::PlanarArm(PlanarArmSpec { config, q0: vec![0.3, -0.5, 0.7, -0.2], qd0: vec![0.0; 4] }),
        ModelSpec::NnCompensator(NnCompensatorSpec {
            joints: 4,
            friction: (1..=4).map(|j| format!("friction_{j}.json")).collect(),
            gravity: Some("gravity.json".into()),
            enable_friction: true,
            enable_gravity: true,
        }),
        ModelSpec::AdaptiveCompensator(AdaptiveCompensatorSpec {
            joints: 4,
            friction: (1..=4).map(|j| format!("friction_{j}.json")).collect(),
            gravity: Some("gravity.json".into()),
            enable_friction: true,
            enable_gravity: true,
            law: AdaptationLaw::default(),
        }),
        ModelSpec::IdealCompensator(IdealCompensatorSpec {
            arm: arm.clone().with_base_angle(1.0),
            enable_friction: true,
            enable_gravity: true,
        }),
        ModelSpec::TaskSpaceController(TaskSpaceControllerSpec {
            model: arm.clone().frictionless(),
            gains: TaskSpaceGains::default(),
            centre: [0.45, 0.1],
            scale: 1.0,
            q_start: vec![-0.4, 0.9, 0.7, 0.5],
        }),
        ModelSpec::JointController(JointControllerSpec { joints: 4, kp: 50.0, kd: 2.0, use_sequence: true }),
        ModelSpec::Integrator(IntegratorSpec { y0: 1.0 }),
        ModelSpec::Gain(GainSpec { k: 2.0 }),
    ];
    for (i, model) in specs.into_iter().enumerate() {
        let spec = FmuSpec { identifier: format!("Model{i}"), model };
        let built = spec.build_from(Some(dir.path())).unwrap();
        assert_eq!(step_allocations(built), 0, "{:?}", spec.model);
    }
}
