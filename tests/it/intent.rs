//! The task-space loops with the compensator fed the controller's intended speed
//! (`Settings::intent_horizon`): on an arm of the random family whose joints stick under the
//! measured-speed compensation (seed 9, 3 joints: Stribeck friction, a joint reversing on every
//! lap), perfect compensation fed the intended speed keeps every joint moving and tracks far
//! better. The error is computed here from the recorded angles and the reference's formula.
//! Needs the FMU binary: `cargo build --release -p neurarm-fmu` (scripts/test builds it).

use neurarm::experiments::{build_fmus, run_loop, tracking_start, tracking_system, Arms, LoopRun, Settings};
use neurarm_physics::arm::end_effector_position;
use neurarm_physics::control::scaled_reference;
use neurarm_physics::family::random_arm;

/// Mean squared distance to the reference [m²] and the share of samples with some joint at
/// rest (|q̇| < 1 mrad/s).
fn figures(run: &LoopRun, arms: &Arms) -> (f64, f64) {
    let n = arms.joints();
    let time = run.column("time").unwrap();
    let q: Vec<Vec<f64>> = (1..=n).map(|i| run.column(&format!("arm.q_{i}")).unwrap()).collect();
    let qd: Vec<Vec<f64>> = (1..=n).map(|i| run.column(&format!("arm.qd_{i}")).unwrap()).collect();
    let p = &arms.placement;
    let (mut squares, mut resting) = (0.0, 0);
    for k in 0..time.len() {
        let angles: Vec<f64> = q.iter().map(|c| c[k]).collect();
        squares += (scaled_reference(time[k], p.centre, p.scale).0 - end_effector_position(&arms.nominal.arm, &angles)).norm_squared();
        resting += usize::from(qd.iter().any(|c| c[k].abs() < 1e-3));
    }
    (squares / (2.0 * time.len() as f64), resting as f64 / time.len() as f64)
}

#[test]
fn perfect_compensation_fed_the_intended_speed_keeps_sticking_joints_moving() {
    let arms = Arms::new(random_arm(9, 3), None, None).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let settings = Settings::quick();
    let fmus = build_fmus(dir.path(), &arms, &settings).unwrap();
    let start = tracking_start(&arms.nominal.arm, &arms.placement).unwrap();
    let run = |horizon: Option<f64>| {
        let settings = Settings { intent_horizon: horizon, ..settings.clone() };
        let spec = tracking_system(&fmus.arm, &fmus.task_controller, Some(&fmus.ideal_friction), &start, &settings);
        let fed = spec.connection.iter().find(|c| c.to == "comp.qd_*").unwrap().from.clone();
        assert_eq!(fed, if horizon.is_some() { "ctl.qd_intended_*" } else { "arm.qd_meas_*" });
        figures(&run_loop(&spec, dir.path()).unwrap(), &arms)
    };
    let (measured, measured_resting) = run(None);
    let (intended, intended_resting) = run(Some(0.005));
    eprintln!(
        "perfect compensation, MSE: measured speed {measured:.3e} m² ({:.1} % of samples with a joint at rest), intended speed \
         {intended:.3e} m² ({:.1} %)",
        100.0 * measured_resting,
        100.0 * intended_resting
    );
    assert!(intended < 0.1 * measured, "intended {intended:e} vs measured {measured:e}");
    assert!(intended_resting < 0.5 * measured_resting, "at rest: {intended_resting} vs {measured_resting}");
}

/// Seed 12 (6 joints, H = 10 ms): the lead `H u` points against a joint that still moves the
/// other way near its reversals; fed to the exact friction law it flips the compensation to the
/// opposite static level while the joint moves on, a kick of tens of N·m. Before the lead was
/// kept from reversing a moving joint, this perfect compensator tracked ten times worse than
/// none at all.
#[test]
fn the_intended_speed_never_reverses_a_moving_joint_so_perfect_compensation_beats_none() {
    let arms = Arms::new(random_arm(12, 6), None, None).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let settings = Settings { intent_horizon: Some(0.01), ..Settings::quick() };
    let fmus = build_fmus(dir.path(), &arms, &settings).unwrap();
    let start = tracking_start(&arms.nominal.arm, &arms.placement).unwrap();
    let run = |compensator| {
        let spec = tracking_system(&fmus.arm, &fmus.task_controller, compensator, &start, &settings);
        figures(&run_loop(&spec, dir.path()).unwrap(), &arms).0
    };
    let (perfect, none) = (run(Some(&fmus.ideal_friction)), run(None));
    eprintln!("seed 12, intended speed: MSE perfect {perfect:.3e} m², none {none:.3e} m²");
    assert!(none >= 5.0 * perfect, "none/perfect {} (target ≥ 5)", none / perfect);
}
