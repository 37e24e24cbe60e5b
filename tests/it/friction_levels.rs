//! The constant-torque friction runs space their levels by speed on any joint, also one with
//! almost no viscous friction, where the first torque steps (made before any slope is known)
//! used to jump 1.7 → 3.6 rad/s and leave a gap the friction net bridged blindly (a family arm's
//! joint 4, Coulomb 0.06 N·m, viscous 0.01 N·m·s/rad: net error 11.7 % of its friction).
//! Needs the FMU binary: `cargo build --release -p neurarm-fmu` (scripts/test builds it).

use neurarm::experiments::{build_fmus, friction_run, held_inertia, pairs_of_runs, run_options, Arms, Settings};
use neurarm_physics::arm::FrictionBranch;
use neurarm_physics::config::ArmConfig;

#[test]
fn the_levels_leave_no_gap_on_a_joint_with_almost_no_viscous_friction() {
    let mut config = ArmConfig::default();
    config.arm.links.truncate(2);
    config.arm.friction.truncate(2);
    let slippery = FrictionBranch {
        coulomb_nm: 0.06,
        static_nm: 0.06,
        stribeck_velocity_rad_s: 1.0,
        viscous_nms_rad: 0.01,
        viscous_falloff_rad_s: None,
    };
    config.arm.friction[1].positive = slippery;
    config.arm.friction[1].negative = slippery;
    let arms = Arms::new(config.clone(), None, None).unwrap();
    let settings = Settings::quick();
    let dir = tempfile::tempdir().unwrap();
    let fmus = build_fmus(dir.path(), &arms, &settings).unwrap();
    let run = friction_run(&fmus.arm, &fmus.joint_controller, &config.arm, 1, 1.0, &settings).unwrap();
    let identified = pairs_of_runs(&[&run], &run_options(&settings, Some(held_inertia(&config.arm, 1))));
    let mut speeds: Vec<f64> = identified.pairs.iter().map(|p| p.0).filter(|&v| v > 0.0).collect();
    speeds.sort_by(f64::total_cmp);
    assert!(speeds.last().is_some_and(|&v| v >= settings.max_velocity - settings.bin_width), "up to the top speed: {speeds:?}");
    let widest = speeds.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
    assert!(widest <= 3.0 * settings.velocity_spacing, "a gap of {widest} rad/s between identified speeds: {speeds:?}");
    // And the pairs lie on the law there.
    for &(speed, torque, _) in &identified.pairs {
        if speed > 0.05 {
            let law = config.arm.friction[1].torque(speed);
            assert!((torque - law).abs() < 0.005, "{speed} rad/s: {torque} N·m, law {law}");
        }
    }
}
