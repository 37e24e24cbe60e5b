//! The whole pipeline of `neurarm paper` on its reduced configuration (3⁴ gravity grid, one
//! period of tracking): it runs, writes its outputs, and its quality figures hold.
//! Needs the FMU binary: `cargo build --release -p neurarm-fmu` (scripts/test builds it).

use fmi2_cosim::SystemSpec;
use neurarm::experiments::{paper::run_paper, Arms, Settings};
use neurarm_physics::arm::JointFriction;

#[test]
fn the_quick_paper_run_reproduces_the_papers_findings() {
    let out = tempfile::tempdir().unwrap();
    let settings = Settings::quick();
    let run = run_paper(out.path(), &Arms::builtin(), &settings, &mut |line| eprintln!("{line}")).unwrap();
    let r = &run.results;
    let t = r.table_1.mse_m2.to_array();
    eprintln!("Table 1: {t:?}; NN/perfect {:.3}, none/perfect {:.1}, real NN/none {:.3}", t[1] / t[0], t[2] / t[0], t[3] / t[4]);
    assert!(t[1] / t[0] <= 1.05, "sim NN/perfect {} (the paper: 1.14)", t[1] / t[0]);
    assert!(t[2] / t[0] >= 5.0, "sim none/perfect {}", t[2] / t[0]);
    assert!(t[3] / t[4] <= 0.3, "real NN/none {} (the paper: 0.24)", t[3] / t[4]);
    assert_eq!(r.gravity.pairs, 81);
    // The sweep's own accuracy: averaged torques against the true gravity at the averaged
    // angles (measured 0.39 N·m; a diagonal PD hold gave 2.7 N·m here).
    assert!(r.gravity.pair_error_nm < 0.5, "gravity pairs off by up to {} N·m", r.gravity.pair_error_nm);

    for f in [
        "report.md",
        "fmu/PlanarArm.fmu",
        "fmu/NnCompensator.fmu",
        "fmu/TaskSpaceController.fmu",
        "nets/gravity.json",
        "data/gravity_pairs.csv",
        "data/tracking_sim_nn.csv",
    ] {
        assert!(out.path().join(f).is_file(), "{f} written");
    }
    // Every closed loop as a system file and an SSP archive; the system file reruns the
    // recorded run exactly (tests/python/test_closed_loops.py reruns it without our master).
    for name in [
        "tracking_sim_perfect",
        "tracking_sim_nn",
        "tracking_sim_none",
        "tracking_real_nn",
        "tracking_real_none",
        "joint_ideal",
        "joint_nn",
        "joint_none",
    ] {
        assert!(out.path().join(format!("{name}.ssp")).is_file(), "{name}.ssp written");
        let path = out.path().join(format!("systems/{name}.toml"));
        let spec = SystemSpec::from_toml(&std::fs::read_to_string(&path).unwrap(), name).unwrap();
        assert_eq!(SystemSpec::from_toml(&spec.to_toml().unwrap(), name).unwrap(), spec);
    }
    let spec = SystemSpec::from_toml(&std::fs::read_to_string(out.path().join("systems/joint_nn.toml")).unwrap(), "joint_nn").unwrap();
    let rerun = fmi2_cosim::run(&spec, &out.path().join("systems")).unwrap();
    assert!(rerun.error.is_none());
    let recorded = std::fs::read_to_string(out.path().join("data/joint_nn.csv")).unwrap();
    let first_after_start: Vec<f64> = recorded.lines().nth(2).unwrap().split(',').map(|x| x.parse().unwrap()).collect();
    assert_eq!(rerun.rows[10], first_after_start, "row at t = 10 steps");
    assert_eq!(rerun.rows.last().unwrap()[0], spec.simulation.stop);

    let report = std::fs::read_to_string(out.path().join("report.md")).unwrap();
    assert!(report.contains("| paper | 0.0014 | 0.0016 | 0.0248 | 0.0071 | 0.0291 |"));

    // The identified friction pairs against the simulated arm's own friction law: an
    // independent check of the constant-torque procedure. Up to 2 rad/s it is exact to the
    // settling tolerance; faster, joints 2 and 3 deviate by up to ~0.5 N·m because the PD
    // "hold" of the other joints is not rigid (measured, reported, not yet fixed), so the
    // bound is asserted where the procedure is meant to be exact.
    for joint in 0..4 {
        let text = std::fs::read_to_string(out.path().join(format!("data/friction_sim_joint{}.csv", joint + 1))).unwrap();
        let law = JointFriction::default_for_joint(joint);
        let (mut worst, mut fast): (f64, f64) = (0.0, 0.0);
        let mut rows = 0;
        for line in text.lines().skip(1) {
            let v: Vec<f64> = line.split(',').map(|x| x.parse().unwrap()).collect();
            if v[0].abs() <= 2.0 {
                worst = worst.max((v[1] - law.torque(v[0])).abs());
            } else {
                fast = fast.max((v[1] - law.torque(v[0])).abs());
            }
            rows += 1;
        }
        eprintln!("joint {}: {rows} pairs, largest |tau - f(qd)| up to 2 rad/s = {worst:.2e} N.m, above {fast:.2e}", joint + 1);
        assert!(rows >= 60, "pairs over ±5 rad/s");
        assert!(worst < 0.01, "joint {}: identified friction off the law by {worst} N·m", joint + 1);
    }
}

/// The gravity identification at the paper's size (7⁴ grid, 4-25-4 net): the net's RMS error
/// on 10 000 random configurations stays under 1 % of the largest gravity torque per joint.
#[test]
fn the_full_gravity_identification_is_within_one_percent() {
    use neurarm::experiments::{build_fmus, gravity_grid, gravity_net_errors, gravity_sweep, parallel, train_gravity_net};
    let dir = tempfile::tempdir().unwrap();
    let settings = Settings { threads: 2, ..Settings::paper() };
    let arms = Arms::builtin();
    let model = &arms.nominal.arm;
    let fmus = build_fmus(dir.path(), &arms, &settings).unwrap();
    let grid = gravity_grid(settings.grid, 4);
    let chunks: Vec<Vec<Vec<f64>>> = grid.chunks(grid.len().div_ceil(2)).map(|c| c.to_vec()).collect();
    let swept = parallel(chunks, 2, |points| gravity_sweep(&fmus.arm, &fmus.joint_controller, model, &points, &settings), || {}).unwrap();
    let pairs: Vec<_> = swept.into_iter().flat_map(|(p, _)| p).collect();
    assert_eq!(pairs.len(), 2401);
    let net = train_gravity_net(&pairs, &settings, &mut |_| {}).unwrap();
    let errors = gravity_net_errors(&net, model, settings.grid, &settings).unwrap();
    let (rms, largest) = (errors.rms_nm, errors.largest_torque_nm);
    let shares: Vec<f64> = rms.iter().map(|e| 100.0 * e / largest).collect();
    eprintln!("gravity net RMS {rms:?} N·m = {shares:.3?} % of {largest:.2} N·m");
    assert!(shares.iter().all(|&s| s < 1.0), "gravity net error {shares:?} % of the largest torque");
}
