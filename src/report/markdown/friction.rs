//! Friction identification: how the pairs are measured and the nets trained, and per arm and
//! joint the levels, pairs and the pairs' and nets' errors against the true law.

use std::fmt::Write as _;

use crate::experiments::paper::PaperRun;
use crate::report::figures::real_label;

/// Appends the section "Friction identification".
pub(super) fn write(s: &mut String, run: &PaperRun) {
    let r = &run.results;
    let settings = &r.settings;
    let real = real_label(run);
    let _ = writeln!(s, "## Friction identification\n");
    let _ = writeln!(
        s,
        "Constant torques on one joint, the others held rigidly by computed torque from the nominal rigid-body model (see \
         `FrictionHold::Rigid`), raised level by level until the speed passes {1} rad/s, each level lasting until its last 0.5 s is steady by \
         the test `neurarm identify friction` applies to logs; each level's torque corrected by the fitted \
         acceleration (friction = τ − H_ff q̈); below the first moving level, where constant torques cannot hold a Stribeck joint, \
         speed-controlled levels down to {6} rad/s, and more of them wherever two moving levels lie over {7} rad/s apart (friction \
         falling with speed faster than the torque steps follow). The steady levels binned by {0} \
         rad/s at their mean speeds; mean friction per bin = one training pair, plus one at rest (0 rad/s, the midpoint of the two breakaway \
         torques; see `neurarm::identify::identify_levels`). The pairs and nets are checked against the true law of the arm they were measured on: pair error \
         is the largest |pair − law| over the moving pairs, net error the RMS of net − law over {2} ≤ |q̇| ≤ {3} rad/s, also as a share \
         of the joint's largest friction torque, and at low speed ({4} ≤ |q̇| ≤ {5} rad/s), where the net crosses the Coulomb step. \
         Where the lowest moving pairs lie above twice the step width w = max(1 mrad/s, 2σ), σ the measured speed's noise, \
         the net is trained on the step as well: pairs at ±w with the lowest pairs' friction, and the speed on a log scale \
         (input `log_speed`); otherwise on the pairs alone and the raw speed (`raw`, the paper's). Data: `data/friction_*_joint*.csv`; nets: `nets/friction_*.json`.\n",
        settings.bin_width,
        settings.max_velocity,
        0.2,
        settings.max_velocity,
        crate::experiments::LOW_SPEED_RANGE_RAD_S.0,
        crate::experiments::LOW_SPEED_RANGE_RAD_S.1,
        0.5 * settings.bin_width,
        2.0 * settings.velocity_spacing
    );
    let _ = writeln!(
        s,
        "| arm | joint | levels | pairs | largest pair error [N·m] (at q̇ [rad/s]) | net RMS error [N·m] | share of largest friction | \
         low-speed RMS error [N·m] | speed noise σ [rad/s] | net input |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|---|");
    for f in &r.friction {
        let arm = if f.arm == "sim" { "simulated" } else { real };
        let _ = writeln!(
            s,
            "| {arm} | {} | {} | {} | {:.4} ({:+.2}) | {:.4} | {:.2} % | {:.4} | {:.2e} | {} |",
            f.joint,
            f.levels,
            f.pairs,
            f.pair_error_nm,
            f.pair_error_at_rad_s,
            f.net_error.rms_nm,
            100.0 * f.net_error_share,
            f.low_speed_error.rms_nm,
            f.speed_noise_rad_s,
            f.encoding
        );
    }
}
