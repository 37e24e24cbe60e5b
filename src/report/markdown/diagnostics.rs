//! What the diagnostic loops tell about Table 1: how far NN/perfect can be read, what the
//! sensors cost on the real arm, which loops failed, and whether the arm has little friction.

use std::fmt::Write as _;

use crate::experiments::paper::{LawSensitivity, PaperRun, Table1};
use crate::report::figures::real_label;

/// Below this none/perfect ratio the report says the arm has little friction.
const LITTLE_FRICTION_RATIO: f64 = 5.0;
/// The NN/perfect ratio the paper's 1.14 suggests, the project's target.
const SIM_NN_OVER_PERFECT_TARGET: f64 = 1.10;

/// Appends the notes of the diagnostic loops to the Table 1 section.
pub(super) fn write(s: &mut String, run: &PaperRun) {
    law_sensitivity(s, run);
    sensor_cost(s, run);
    failed_loops(s, run);
    friction_size(s, run);
}

/// How far the law 0.1 % off moved the ratio, where that is past the target's margin: the
/// ratio is chaotic on this arm (read by the law-sensitivity and the none/perfect notes).
fn chaotic_move(t: &Table1) -> Option<f64> {
    t.sim_law_sensitivity_fine.largest_move().filter(|m| *m > SIM_NN_OVER_PERFECT_TARGET - 1.0)
}

/// The simulated arm's worst friction net at low speed, where the nets cross the Coulomb step:
/// what NN/perfect is most sensitive to (over the whole speed range the nets can be far closer).
/// RMS error as a share of the joint's largest friction torque.
fn worst_sim_net(run: &PaperRun) -> f64 {
    run.results
        .friction
        .iter()
        .filter(|f| f.arm == "sim")
        .map(|f| f.low_speed_error.rms_nm / f.low_speed_error.largest_friction_nm)
        .fold(0.0, f64::max)
}

/// "What NN/perfect can tell": the simulated arm tracked with its true law scaled by 1 ± a few
/// per cent and by 1 ± 0.1 %.
fn law_sensitivity(s: &mut String, run: &PaperRun) {
    let t = &run.results.table_1;
    let law = &t.sim_law_sensitivity;
    let worst_sim_net = worst_sim_net(run);
    if let (Some(low), Some(high)) = (law.low_over_perfect, law.high_over_perfect) {
        let reading = coarse_reading(law, low, high, worst_sim_net);
        let fine_reading = fine_reading(t, worst_sim_net);
        let _ = writeln!(
            s,
            "**What NN/perfect can tell.** The simulated arm tracked with its own true friction law scaled by {:.2} and {:.2} gives \
             {low:.3} and {high:.3} × the exact law's MSE (`systems/tracking_sim_perfect_low.toml`, `_high.toml`).{reading}\
             {fine_reading}\n",
            1.0 - law.law_error,
            1.0 + law.law_error
        );
    }
}

/// What the law scaled by 1 ± a few per cent says of NN/perfect (`low`, `high`: its MSE over
/// the exact law's).
fn coarse_reading(law: &LawSensitivity, low: f64, high: f64, worst_sim_net: f64) -> String {
    if low.min(high) > SIM_NN_OVER_PERFECT_TARGET {
        format!(
            " Even a law {pct:.0} % off tracks worse than NN/perfect ≤ {SIM_NN_OVER_PERFECT_TARGET} allows: the exact law leaves so \
             little error that the ratio measures the compensator's accuracy below 1 % (the nets here, at low speed: RMS error up to \
             {:.1} % of a joint's largest friction torque).",
            100.0 * worst_sim_net,
            pct = 100.0 * law.law_error
        )
    } else if law.largest_move().is_some_and(|m| m > SIM_NN_OVER_PERFECT_TARGET - 1.0) {
        format!(
            " A {pct:.0} % change of the law itself moves the ratio by more than the target's margin (stick–slip makes the \
             error sensitive to small changes), so NN/perfect differences within that scatter say little.",
            pct = 100.0 * law.law_error
        )
    } else {
        String::new()
    }
}

/// What the law scaled by 1 ± 0.1 % says of NN/perfect: whether the ratio is chaotic.
fn fine_reading(t: &Table1, worst_sim_net: f64) -> String {
    let chaotic_move = chaotic_move(t);
    let fine = &t.sim_law_sensitivity_fine;
    match (fine.low_over_perfect, fine.high_over_perfect) {
        (Some(fine_low), Some(fine_high)) => {
            let chaotic = chaotic_move.is_some();
            format!(
                " Scaled by {:.3} and {:.3} it gives {fine_low:.3} and {fine_high:.3} (`_fine_low.toml`, `_fine_high.toml`){}",
                1.0 - fine.law_error,
                1.0 + fine.law_error,
                if chaotic {
                    format!(
                        ": **the ratio is chaotic on this arm.** A law {:.1} % off (the nets here are up to {:.1} % off at low \
                         speed) already moves it past the target's margin, so NN/perfect ≤ {SIM_NN_OVER_PERFECT_TARGET} cannot be \
                         asked of a compensator identified from data here, and the ratio does not rank compensators; none/perfect \
                         and the nets' errors (below) do. Which joints stick also depends on the null-space damping \
                         (`--tracking-gains kp,kd,k`; `benches/python/null_damping_scan.py` reruns these loops at several k).",
                        100.0 * fine.law_error,
                        100.0 * worst_sim_net
                    )
                } else {
                    ".".to_owned()
                }
            )
        }
        _ => String::new(),
    }
}

/// "What the sensors cost": the real arm's true law, fed the measured speed as the net is.
fn sensor_cost(s: &mut String, run: &PaperRun) {
    let t = &run.results.table_1;
    let real = real_label(run);
    let true_real_ratio = t.true_mse_m2.real_nn / t.true_mse_m2.real_none;
    let sensors = &t.real_sensors;
    let quiet = match (sensors.quiet_nn_over_none, sensors.quiet_perfect_over_none) {
        (Some(nn), Some(perfect)) => {
            format!(" With the sensors' noise off (quantisation kept) NN/none is {nn:.3} and the true law's {perfect:.3}.")
        }
        _ => String::new(),
    };
    if let Some(perfect_over_none) = sensors.perfect_over_none {
        let verdict = if perfect_over_none >= true_real_ratio {
            " Even the true law, fed the measured speed, does no better than the net here: a friction step at zero speed \
             switches on the speed's noise, so the sensors, not the nets, bound real NN/none (a filtered speed or a dead \
             band at rest would be the remedy, not better nets)."
        } else {
            ""
        };
        let _ = writeln!(
            s,
            "**What the sensors cost.** Fed the same measured speed as the net, the {real} arm's true friction law tracks with \
             {perfect_over_none:.3} × the uncompensated MSE (true positions; `systems/tracking_real_perfect.toml`).{quiet}{verdict}\n",
        );
    }
}

/// The diagnostic loops that failed, if any.
fn failed_loops(s: &mut String, run: &PaperRun) {
    let t = &run.results.table_1;
    if !t.diagnostic_failures.is_empty() {
        let _ = writeln!(
            s,
            "**Diagnostic loops that failed** (their figures are left out; Table 1 itself is not affected): {}.\n",
            t.diagnostic_failures.iter().map(|f| format!("`{f}`")).collect::<Vec<_>>().join("; ")
        );
    }
}

/// Where none/perfect is small: little friction, or a chaotic arm.
fn friction_size(s: &mut String, run: &PaperRun) {
    let t = &run.results.table_1;
    let q = &t.ratios;
    let chaotic_move = chaotic_move(t);
    if let (true, Some(moved)) = (q.sim_none_over_perfect < LITTLE_FRICTION_RATIO, chaotic_move) {
        let _ = writeln!(
            s,
            "**none/perfect under {LITTLE_FRICTION_RATIO} on a chaotic arm.** Without compensation the simulated arm tracks only \
             {:.1} × worse than with the true friction model, but the perfect run's own error moves {:.0} % under a law 0.1 % \
             off (above): which joints stick decides it, so the ratio need not mean little friction.\n",
            q.sim_none_over_perfect,
            100.0 * moved
        );
    } else if q.sim_none_over_perfect < LITTLE_FRICTION_RATIO {
        let _ = writeln!(
            s,
            "**Little friction.** Without compensation the simulated arm tracks only {:.1} × worse than with the true friction model \
             (under {LITTLE_FRICTION_RATIO}): its friction is small against its inertia and the loop's gains, so what the \
             compensators change is small, and the NN ratios mostly measure other effects.\n",
            q.sim_none_over_perfect
        );
    }
}
