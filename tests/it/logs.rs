//! From a robot's logs to pairs and nets: the plans of `neurarm plan` played by `simulate_plan`
//! on a 3-joint arm with Stribeck, asymmetric and falling-viscous friction, encoder quantisation
//! and noise (examples/robot/real3.toml), planned from a belief of it that differs
//! (examples/arms/arm3.toml), written as CSV logs, read back and identified. The pairs and nets
//! are checked against the real arm's own friction law and gravity, computed here.

use std::f64::consts::PI;
use std::path::Path;

use neurarm::experiments::friction::friction_net_error;
use neurarm::experiments::{train_friction_net, GravityDesign};
use neurarm::identify::{
    identify_friction_log, identify_gravity_log, FrictionCurve, FrictionOptions, GravityCorrection, GravityOptions, LogColumns, RobotLog,
};
use neurarm::plan::{friction_plan, gravity_plan, FrictionPlanSettings, GravityPlanSettings};
use neurarm::simulate::{simulate_plan, Plan};
use neurarm::table::write_atomic;
use neurarm_physics::arm::{gravity_torques, ArmState};
use neurarm_physics::config::ArmConfig;

fn config(path: &str) -> ArmConfig {
    ArmConfig::from_toml_file(&Path::new(env!("CARGO_MANIFEST_DIR")).join(path)).unwrap()
}

/// The measured columns, as a robot logs them.
fn measured() -> LogColumns {
    LogColumns { q: "q_meas_{i}".into(), qd: "qd_meas_{i}".into(), ..LogColumns::default() }
}

/// Writes `csv` as a plan, plays it on `robot` and returns the log read back.
fn play(dir: &Path, name: &str, csv: &str, robot: &ArmConfig, every: usize) -> RobotLog {
    let plan_path = dir.join(format!("{name}_plan.csv"));
    std::fs::write(&plan_path, csv).unwrap();
    let n = robot.arm.dof();
    let plan = Plan::read_csv(&plan_path, n).unwrap();
    let initial = ArmState { q: plan.start(&vec![0.0; n]), qd: vec![0.0; n] };
    let trajectory = simulate_plan(robot, &initial, &plan, 1e-3, every).unwrap();
    let log_path = dir.join(format!("{name}_log.csv"));
    write_atomic(&log_path, &trajectory.names, trajectory.rows.into_iter()).unwrap();
    RobotLog::read_all(&log_path, &measured(), Some(n)).unwrap()
}

#[test]
fn friction_and_gravity_from_logs_of_a_noisy_three_joint_arm() {
    let dir = tempfile::tempdir().unwrap();
    let belief = config("examples/arms/arm3.toml");
    let robot = config("examples/robot/real3.toml");
    let n = robot.arm.dof();

    // A shortened friction plan: up to 2 rad/s (the default: 5).
    let settings = FrictionPlanSettings { max_speed_rad_s: 2.0, spacing_rad_s: 0.1, ..FrictionPlanSettings::for_joints(n) };
    let plan = friction_plan(&belief.arm, &settings).unwrap();
    let log = play(dir.path(), "friction", &plan.to_csv(), &robot, 5);
    let mut curves = Vec::new();
    for joint in 1..=n {
        let found = identify_friction_log(&log, joint, &FrictionOptions::default()).unwrap();
        let law = robot.arm.friction[joint - 1];
        let moving: Vec<_> = found.pairs.iter().filter(|p| p.0 != 0.0).collect();
        let worst = moving.iter().map(|p| (p.1 - law.torque(p.0)).abs()).fold(0.0, f64::max);
        let rest = found.rest.expect("the plan's breakaway probes give the pair at rest");
        // Both directions' levels from 0.2 to 2 rad/s, most of them kept.
        assert!(moving.iter().filter(|p| p.0 > 0.0).count() >= 8 && moving.iter().filter(|p| p.0 < 0.0).count() >= 8, "{:?}", found.pairs);
        // The pair at rest lies between the true breakaway torques.
        assert!(rest.torque_nm < law.breakaway(1.0) && rest.torque_nm > -law.breakaway(-1.0), "{rest:?}");
        let net = train_friction_net(joint - 1, &found.pairs, found.speed_noise_rad_s(), 1).unwrap();
        let error = friction_net_error(&net, &law, 0.2, 2.0).unwrap();
        if std::env::var_os("NEURARM_DEBUG").is_some() {
            let mlp = net.network().unwrap();
            for v in [-2.0, -1.0, -0.5, -0.3, -0.25, -0.2, -0.1, 0.0, 0.1, 0.2, 0.25, 0.3, 0.5, 1.0, 2.0] {
                eprintln!("  v {v:+.2}: net {:+.4} law {:+.4}", mlp.evaluate(&[v])[0], law.torque(v));
            }
            eprintln!("  pairs {:?}", found.pairs);
        }
        eprintln!(
            "joint {joint}: {} pairs, {} levels kept; largest pair error {worst:.4} N·m; net RMS {:.4} N·m = {:.2} % of {:.3} N·m; rest {:+.3} N·m",
            found.pairs.len(),
            found.kept(),
            error.rms_nm,
            100.0 * error.share(),
            error.largest_friction_nm,
            rest.torque_nm
        );
        assert!(worst < 0.05, "joint {joint}: a friction pair is {worst} N·m off the true law");
        assert!(error.share() < 0.03, "joint {joint}: the net is {:.2} % off (RMS, |q̇| ≥ 0.2 rad/s)", 100.0 * error.share());
        curves.push(FrictionCurve::new(&found.pairs));
    }

    // A shortened gravity plan: 40 sampled poses, gravity in the plane of motion.
    let vertical = ArmConfig { arm: robot.arm.clone().with_base_angle(PI / 2.0), ..robot.clone() };
    let gravity_settings = GravityPlanSettings { design: GravityDesign::Sampled { poses: 40 }, ..GravityPlanSettings::default() };
    let plan = gravity_plan(n, &gravity_settings).unwrap();
    let log = play(dir.path(), "gravity", &plan.to_csv(), &vertical, 1);
    let model = belief.arm.clone().with_base_angle(0.0).frictionless();
    let correction = GravityCorrection { friction: &curves, model: Some(&model) };
    let found = identify_gravity_log(&log, &GravityOptions::default(), &correction).unwrap();
    // The largest gravity torque of each joint: the arm stretched horizontally.
    let largest: Vec<f64> = gravity_torques(&vertical.arm, &vec![0.0; n]).iter().map(|g| g.abs()).collect();
    let (mut worst, mut worst_plain) = (vec![0.0f64; n], vec![0.0f64; n]);
    for pair in &found.pairs {
        let truth = gravity_torques(&vertical.arm, &pair.q);
        for i in 0..n {
            worst[i] = worst[i].max((pair.torque[i] - truth[i]).abs() / largest[i]);
            worst_plain[i] = worst_plain[i].max((pair.torque_uncorrected[i] - truth[i]).abs() / largest[i]);
        }
    }
    let share = |v: &[f64]| v.iter().map(|w| format!("{:.3} %", 100.0 * w)).collect::<Vec<_>>().join(", ");
    eprintln!(
        "gravity: {} pairs of {} poses; largest error per joint {} of its largest torque (plain average: {})",
        found.pairs.len(),
        found.poses.len(),
        share(&worst),
        share(&worst_plain)
    );
    for p in found.poses.iter().filter(|p| p.refused.is_some()) {
        eprintln!("  refused at {:?}: {}", p.q, p.refused.as_deref().unwrap_or(""));
    }
    assert!(found.pairs.len() >= 30, "only {} of 40 poses paired", found.pairs.len());
    assert!(worst.iter().all(|&w| w < 0.01), "gravity pairs off by up to {} of the largest torque", share(&worst));
}
