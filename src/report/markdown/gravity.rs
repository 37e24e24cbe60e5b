//! Gravity identification: how the pairs are measured and checked against the true model, what
//! the gravity net sees, and its error over random poses, per joint.

use std::fmt::Write as _;

use super::{header, row};
use crate::experiments::gravity::{RegionErrors, STEADY_RETRIES, STEADY_SHARE};
use crate::experiments::paper::PaperRun;
use crate::experiments::{GravityDesign, GRAVITY_SWEEP_SPEED_RAD_S};
use neurarm_nn::InputEncoding;

/// Appends the section "Gravity identification".
pub(super) fn write(s: &mut String, run: &PaperRun) {
    let _ = writeln!(s, "\n## Gravity identification\n");
    sweep(s, run);
    steadiness_and_procedure(s, run);
    net_inputs(s, run);
    error_table(s, run);
}

/// The poses measured and how each pair's torque is made from the two passes.
fn sweep(s: &mut String, run: &PaperRun) {
    let r = &run.results;
    let settings = &r.settings;
    let n = r.setup.joints;
    let g = &r.gravity;
    let grid_note = if g.default_design && n > 4 {
        format!(
            " For more than 4 joints the default is sampled poses, as many as the {0}⁴ grid of 4 joints: a full {0}ⁿ grid is {1} \
             poses for {n} joints (`--gravity-grid` gives one).",
            settings.grid,
            settings.grid.saturating_pow(n as u32)
        )
    } else {
        String::new()
    };
    let poses = match g.design {
        GravityDesign::Grid { per_joint } => format!("a {per_joint}ⁿ grid = {} configurations", g.pairs),
        GravityDesign::Sampled { poses } => format!(
            "{poses} configurations drawn uniformly over the whole turn [0, 2π)ⁿ (seeded), visited in a nearest-neighbour order \
             (see `sampled_poses`)"
        ),
    };
    let correction = if g.friction_correction {
        "each pass's torque had the identified friction (the simulated arm's friction pairs, interpolated at the measured \
         speeds) and the Coriolis and centrifugal torques of the nominal model taken out, and the two passes were averaged"
    } else {
        "the torques of the two passes were averaged as measured (the paper's procedure)"
    };
    let _ = writeln!(
        s,
        "Base turned 90°; {poses}, each passed slowly up and down by all joints ({} rad/s); {correction}. The joints are held on \
         the moves by an inertia-scaled PD from the gravity-free rigid-body model (see `gravity_sweep`).{grid_note}\n",
        GRAVITY_SWEEP_SPEED_RAD_S
    );
}

/// Which passes were steady or repeated, and the pairs' error against the true model.
fn steadiness_and_procedure(s: &mut String, run: &PaperRun) {
    let g = &run.results.gravity;
    let procedure = if g.friction_correction {
        format!(
            "{:.2e} N·m with the friction and velocity terms taken out and {:.2e} N·m for the plain average of the passes, which \
             keeps the Coriolis and centrifugal torques and half the difference of the two directions' friction",
            g.pair_error_nm, g.pair_error_uncorrected_nm
        )
    } else {
        format!("{:.2e} N·m", g.pair_error_nm)
    };
    let _ = writeln!(
        s,
        "A pass is steady when every joint's speed stays within {:.0} % of the pass speed in the measuring window; {} of {} pass \
         pairs were measured again with passes twice as long, and {} poses were left out after {} repeats.\n",
        100.0 * STEADY_SHARE,
        g.repeated_passes,
        g.pairs + g.dropped_poses.len() + g.repeated_passes,
        g.dropped_poses.len(),
        STEADY_RETRIES
    );
    let _ = writeln!(
        s,
        "The procedure itself, checked against the true model: the largest difference between a pair's torque and the true \
         gravity torque at its angles is {procedure}.\n"
    );
}

/// The compensator's net: its size and what it sees of the angles.
fn net_inputs(s: &mut String, run: &PaperRun) {
    let g = &run.results.gravity;
    let n = run.results.setup.joints;
    let features = g.net.encoding.features(n);
    let seen = match g.encoding {
        InputEncoding::LinkAngles => {
            "each link angle φⱼ = q₁ + … + qⱼ as (cos φⱼ, sin φⱼ), which the kinematics give: the net is \
             periodic in every angle and has to learn the masses, centres of mass and the base's tilt (a rigid planar arm's \
             gravity torques are a linear map of these inputs)"
        }
        InputEncoding::JointAngles => "each joint angle as (cos qᵢ, sin qᵢ): the net is periodic in every angle",
        InputEncoding::Raw => "the raw angles, as in the paper: the net is not periodic",
        // A gravity net's file with a speed encoding is refused when read.
        InputEncoding::LogSpeed => "speeds on a log scale (not angles)",
    };
    let _ = writeln!(
        s,
        "The compensator's net (`nets/gravity.json`, {features}-{}-{n}) sees {seen}.{}\n",
        g.hidden,
        if g.raw_net.is_some() {
            format!(" Beside it, the paper's raw-angle {n}-{}-{n} net trained on the same pairs (`nets/gravity_raw.json`).", g.hidden)
        } else {
            String::new()
        }
    );
}

/// The net's errors over random poses per joint: whole turn, trained span, paper's reading.
fn error_table(s: &mut String, run: &PaperRun) {
    let g = &run.results.gravity;
    let n = run.results.setup.joints;
    let largest_any = g.net.whole_turn.largest_torque_nm.iter().copied().fold(0.0, f64::max);
    let _ = writeln!(
        s,
        "Error on {} random poses (not training poses) over the whole turn [0, 2π)ⁿ, each angle wrapped into a raw net's trained \
         turn as the `NnCompensator` FMU does, which is what a user of the compensator gets; for a raw net also within the \
         trained span (for the grid [0, 2π(k−1)/k)ⁿ, the paper's reading: the grid never covers the last 1/k of the turn). \
         Shares are of each joint's own largest gravity torque; the paper's reading divides every joint by the largest of all \
         ({largest_any:.2} N·m). `gravity.png` shows each whole-turn pose's error against its true torque:\n",
        g.net.poses
    );
    let _ = writeln!(s, "{}", header("", n));
    let line = |label: &str, values: &[f64], f: &dyn Fn(f64) -> String| {
        row(&std::iter::once(label.to_owned()).chain(values.iter().map(|&v| f(v))).collect::<Vec<_>>())
    };
    let nm = |v: f64| format!("{v:.4}");
    // Three places: a periodic net's errors are hundredths of a percent.
    let pct = |v: f64| format!("{:.3} %", 100.0 * v);
    let mut regions: Vec<(String, &RegionErrors)> = Vec::new();
    for (name, net) in std::iter::once(("net", &g.net)).chain(g.raw_net.as_ref().map(|r| ("paper's raw net", r))) {
        let name = if g.raw_net.is_some() { format!("{name}, ") } else { String::new() };
        regions.push((format!("{name}whole turn"), &net.whole_turn));
        if let Some(span) = &net.span {
            regions.push((format!("{name}span"), span));
        }
    }
    for (region, e) in regions {
        let _ = writeln!(s, "{}", line(&format!("{region}: RMS [N·m]"), &e.rms_nm, &nm));
        let _ = writeln!(s, "{}", line(&format!("{region}: RMS, share of the joint's largest torque"), &e.rms_share, &pct));
        let _ = writeln!(s, "{}", line(&format!("{region}: largest error [N·m]"), &e.max_nm, &nm));
        let _ = writeln!(s, "{}", line(&format!("{region}: largest error, share"), &e.max_share, &pct));
    }
    let paper_region = if g.net.span.is_some() { "span" } else { "whole turn" };
    let _ = writeln!(
        s,
        "{}",
        line(&format!("net, {paper_region}: RMS, share of the largest torque of all (the paper's reading)"), &g.net_error_share, &pct)
    );
}
