//! The title and the summary: what the run shows in one paragraph, then the seed, step,
//! threads and computing time of the run.

use std::fmt::Write as _;

use crate::experiments::paper::PaperRun;
use crate::experiments::GravityDesign;
use crate::report::figures::real_label;

/// Appends the title, the summary paragraph and the line on how the run was made.
pub(super) fn write(s: &mut String, run: &PaperRun) {
    let r = &run.results;
    let settings = &r.settings;
    let setup = &r.setup;
    let n = setup.joints;
    let t = &r.table_1;
    let real = real_label(run);
    let _ = writeln!(s, "# neurarm: the paper's experiments on a {n}-joint arm\n");

    // The summary: what the run shows, in one paragraph.
    let sim_friction = r.friction.iter().filter(|f| f.arm == "sim");
    let worst_friction = sim_friction.map(|f| (f.net_error_share, f.joint)).fold((0.0, 0), |a, b| if b.0 > a.0 { b } else { a });
    let worst_gravity = r.gravity.net.whole_turn.rms_share.iter().copied().fold(0.0, f64::max);
    let settled = |k: usize| r.joint_loop.settled_rad[k].iter().copied().fold(0.0, f64::max);
    let _ = writeln!(
        s,
        "**Summary.** On this {n}-joint arm (reach {:.3} m) the task-space loop tracks the paper's curve with an RMS error of \
         {:.3} mm with NN friction compensation, against {:.3} mm with the true friction model and {:.3} mm without compensation \
         (MSE ratios NN/perfect {:.3}, none/perfect {:.1}). On the {real} arm, the net trained on its own data cuts the error from \
         {:.3} mm to {:.3} mm (MSE ratio NN/none {:.3}; true positions). The friction nets of the simulated arm are within {:.1} % \
         of each joint's largest friction torque (worst: joint {}); the gravity net's RMS error over the whole turn is up to {:.2} % \
         of a joint's own largest gravity torque{}. \
         In the joint-space loop, NN gravity compensation settles to at most {:.4} rad from the targets, against {:.4} rad with the \
         ideal compensator and {:.4} rad without.{}\n",
        setup.reach_m,
        t.rms_mm.sim_nn,
        t.rms_mm.sim_perfect,
        t.rms_mm.sim_none,
        t.ratios.sim_nn_over_perfect,
        t.ratios.sim_none_over_perfect,
        t.rms_mm.real_none,
        t.rms_mm.real_nn,
        t.true_mse_m2.real_nn / t.true_mse_m2.real_none,
        100.0 * worst_friction.0,
        worst_friction.1,
        100.0 * worst_gravity,
        match r.gravity.design {
            GravityDesign::Sampled { poses } => format!(" (from {poses} sampled poses)"),
            GravityDesign::Grid { per_joint } => format!(" (from a {per_joint}ⁿ grid)"),
        },
        settled(1),
        settled(0),
        settled(2),
        if settings.quick { " This is a reduced run (`--quick`): its figures are for testing, not for quoting." } else { "" }
    );
    let _ = writeln!(
        s,
        "Seeded run (seed {}), communication step {} ms, {} worker threads, {:.1} s of computation. Every loop ran through the \
         Rust master with the FMUs in `fmu/`; every figure here is also in `results.json`.\n",
        settings.seed,
        settings.step * 1e3,
        settings.threads,
        r.total_s
    );
}
