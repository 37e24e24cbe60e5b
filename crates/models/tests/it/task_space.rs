//! The task-space controller's `qd_intended_i`: the measured speed plus `intent_horizon` times
//! the joint acceleration its torques give the arm of its own model, found here by forward
//! dynamics from those torques (H⁻¹ (τ − τ_comp − C q̇ − g)), not from the law's own numbers;
//! where that lead points against a moving joint's motion, the measured speed alone.

use neurarm_fmi_export::instance::{Instance, Status};
use neurarm_models::*;
use neurarm_physics::arm::{coriolis_centrifugal, gravity_torques, mass_matrix, ArmParams};
use neurarm_physics::control::TaskSpaceGains;

fn controller(model: &ArmParams) -> Instance {
    let n = model.dof();
    let spec = ModelSpec::TaskSpaceController(TaskSpaceControllerSpec {
        model: model.clone(),
        gains: TaskSpaceGains::default(),
        centre: [0.5, 0.1],
        scale: 1.0,
        q_start: (0..n).map(|i| 0.3 + 0.2 * i as f64).collect(),
    });
    let built = FmuSpec { identifier: "Ctl".into(), model: spec }.build_from(None).unwrap();
    let guid = built.description().guid();
    let mut i = Instance::new("probe", &guid, built, Box::new(|_, _, m| eprintln!("{m}")), false).unwrap();
    assert_eq!(i.setup_experiment(None, 0.0, None), Status::Ok);
    assert_eq!(i.enter_initialization_mode(), Status::Ok);
    assert_eq!(i.exit_initialization_mode(), Status::Ok);
    i
}

fn vr(i: &Instance, name: &str) -> u32 {
    i.description().variables.iter().find(|v| v.name == name).unwrap_or_else(|| panic!("no {name}")).value_reference
}

fn set(i: &mut Instance, names: &[String], values: &[f64]) {
    let vrs: Vec<u32> = names.iter().map(|n| vr(i, n)).collect();
    assert_eq!(i.set_real(&vrs, values), Status::Ok);
}

fn get(i: &mut Instance, names: &[String]) -> Vec<f64> {
    let vrs: Vec<u32> = names.iter().map(|n| vr(i, n)).collect();
    let mut out = vec![0.0; vrs.len()];
    assert_eq!(i.get_real(&vrs, &mut out), Status::Ok);
    out
}

fn names(prefix: &str, n: usize) -> Vec<String> {
    (1..=n).map(|i| format!("{prefix}_{i}")).collect()
}

#[test]
fn the_intended_speed_is_the_measured_one_plus_the_horizon_times_the_commanded_acceleration_unless_that_reverses_the_joint() {
    let model = ArmParams::default_four_link().with_base_angle(0.7);
    let n = model.dof();
    let mut ctl = controller(&model);
    let (q, qd, comp) = (vec![-0.4, 0.9, 0.7, 0.5], vec![0.3, -1.2, 0.0, 2.0], vec![0.5, -0.25, 0.1, 0.0]);
    set(&mut ctl, &names("q", n), &q);
    set(&mut ctl, &names("qd", n), &qd);
    set(&mut ctl, &names("tau_comp", n), &comp);
    // Without a horizon the output is the measured speed, bit for bit.
    assert_eq!(get(&mut ctl, &names("qd_intended", n)), qd);
    let horizon = 0.02;
    set(&mut ctl, &["intent_horizon".to_owned()], &[horizon]);
    let tau = get(&mut ctl, &names("tau", n));
    let intended = get(&mut ctl, &names("qd_intended", n));
    let bias = coriolis_centrifugal(&model, &q, &qd) + gravity_torques(&model, &q);
    let rhs = nalgebra::DVector::from_iterator(n, (0..n).map(|i| tau[i] - comp[i] - bias[i]));
    let acceleration = mass_matrix(&model, &q).lu().solve(&rhs).unwrap();
    let (mut led, mut held) = (0, 0);
    for i in 0..n {
        // A lead against the joint's motion is dropped: the joint keeps its measured speed.
        let against = qd[i] * acceleration[i] < 0.0;
        let want = if against { qd[i] } else { qd[i] + horizon * acceleration[i] };
        assert!((intended[i] - want).abs() <= 1e-9 * (1.0 + want.abs()), "joint {}: {} vs {want}", i + 1, intended[i]);
        if against {
            held += 1;
        } else {
            assert!((intended[i] - qd[i]).abs() > 1e-4, "joint {}: the horizon moves the speed", i + 1);
            led += 1;
        }
    }
    // The state is chosen so that both cases occur, the joint at rest among the led ones.
    assert!(led >= 2 && held >= 1, "{led} joints led, {held} held: {acceleration:?}");
    assert!((intended[2] - horizon * acceleration[2]).abs() <= 1e-9, "the joint at rest takes the lead");
    // The output does not depend on the compensation input (no algebraic loop through a
    // compensator fed by it).
    set(&mut ctl, &names("tau_comp", n), &[0.0; 4]);
    assert_eq!(get(&mut ctl, &names("qd_intended", n)), intended);
}

#[test]
fn a_time_at_which_the_reference_overflows_fails_initialization_by_name() {
    // The FMU layer refuses such a start time before the model sees it; the model still
    // refuses it on its own, for a host of the model that is not that layer.
    let model = ArmParams::default_four_link().frictionless();
    let spec = ModelSpec::TaskSpaceController(TaskSpaceControllerSpec {
        model,
        gains: TaskSpaceGains::default(),
        centre: [0.45, 0.1],
        scale: 1.0,
        q_start: vec![-0.4, 0.9, 0.7, 0.5],
    });
    let mut built = FmuSpec { identifier: "Ctl".into(), model: spec }.build_from(None).unwrap();
    let mut values = neurarm_fmi_export::Values::start(built.description());
    let e = built.initialize(&mut values, 1.7e308).expect_err("refused").to_string();
    assert!(e.contains("the reference at t = 1.7e308 s is not finite"), "{e}");
    assert!(built.initialize(&mut values, 0.0).is_ok());
}
