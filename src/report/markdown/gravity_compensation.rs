//! Gravity compensation in the joint-space loop: RMS and settled joint errors per compensator,
//! and notes on the gains against the arm's friction and the paper's gain.

use std::fmt::Write as _;

use super::{header, list, row};
use crate::experiments::paper::PaperRun;

/// Above this settled error of the ideal compensator [rad] the report says the gains are low
/// for the friction.
const STUCK_SETTLED_RAD: f64 = 0.05;

/// Appends the section "Gravity compensation in the joint-space loop".
pub(super) fn write(s: &mut String, run: &PaperRun) {
    error_tables(s, run);
    low_gains_note(s, run);
    let _ = writeln!(
        s,
        "\nThe paper's K_p = 0.025 has no units; in N·m/rad it would move no joint against its Coulomb friction (0.3–1.5 N·m on the \
         built-in arm needs an error of 12–60 rad), so this run uses the gains above, with a small K_d: with P alone the loop rings \
         for seconds after each target step (damped only by friction).\n"
    );
}

/// The law and gains, then the RMS and settled errors per compensator and joint.
fn error_tables(s: &mut String, run: &PaperRun) {
    let r = &run.results;
    let n = r.setup.joints;
    let j = &r.joint_loop;
    let _ = writeln!(s, "\n## Gravity compensation in the joint-space loop\n");
    let _ = writeln!(
        s,
        "τ = τ_comp + K_p (q_d − q) + K_d (q̇_d − q̇), K_p = {} N·m/rad, K_d = {} N·m·s/rad per joint; the built-in target sequence \
         (5 × 3 s; joint i follows column i mod 4). RMS of q_d − q [rad]:\n",
        list(&j.kp),
        list(&j.kd)
    );
    let _ = writeln!(s, "{}", header("compensation", n));
    for (name, e) in ["ideal", "NN", "none"].iter().zip(&j.rms_rad) {
        let _ = writeln!(s, "{}", row(&std::iter::once(name.to_string()).chain(e.iter().map(|x| format!("{x:.4}"))).collect::<Vec<_>>()));
    }
    let _ = writeln!(s, "\nSettled error, mean |q_d − q| over the last 0.5 s of each segment [rad]:\n");
    let _ = writeln!(s, "{}", header("compensation", n));
    for (name, e) in ["ideal", "NN", "none"].iter().zip(&j.settled_rad) {
        let _ = writeln!(s, "{}", row(&std::iter::once(name.to_string()).chain(e.iter().map(|x| format!("{x:.4}"))).collect::<Vec<_>>()));
    }
}

/// Where even the ideal compensator settles far from the targets: the gains are low against
/// the joints' breakaway torques.
fn low_gains_note(s: &mut String, run: &PaperRun) {
    let r = &run.results;
    let n = r.setup.joints;
    let j = &r.joint_loop;
    let (worst_joint, worst_ideal) =
        j.settled_rad[0].iter().copied().enumerate().fold((0, 0.0), |a, (i, e)| if e > a.1 { (i, e) } else { a });
    if worst_ideal > STUCK_SETTLED_RAD {
        let friction = &r.setup.nominal.arm.friction;
        let (band_joint, band) = (0..n)
            .map(|i| (i, friction[i].breakaway(1.0).max(friction[i].breakaway(-1.0)) / j.kp[i]))
            .fold((0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        let _ = writeln!(
            s,
            "\n**The joint loop's gains are low for this arm's friction.** Even the ideal compensator settles {worst_ideal:.3} rad from \
             the targets (joint {}): a joint comes to rest wherever K_p (q_d − q) falls below its breakaway torque, up to \
             breakaway / K_p = {band:.3} rad away (joint {}). NN/ideal then compares where the joints stuck more than the gravity \
             compensation; raise the gains with `--joint-gains`.",
            worst_joint + 1,
            band_joint + 1
        );
    }
}
