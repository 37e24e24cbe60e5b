//! Online adaptation (the paper's further work): failed runs, the adaptation law, and the
//! friction-drift, payload and no-change runs' errors against static and perfect compensation.

use std::fmt::Write as _;

use super::{header, row};
use crate::experiments::adaptation::CASES;
use crate::experiments::paper::PaperRun;
use crate::report::figures::real_label;

/// Appends the section "Online adaptation": the law, the drift, payload and steady tables.
pub(super) fn write(s: &mut String, run: &PaperRun) {
    let _ = writeln!(s, "## Online adaptation (the paper's further work)\n");
    failures(s, run);
    law(s, run);
    drift(s, run);
    payload(s, run);
    steady(s, run);
}

/// The runs that failed and why; on a redundant arm, what holds its self-motion.
fn failures(s: &mut String, run: &PaperRun) {
    let r = &run.results.adaptation;
    let n = run.arms.joints();
    for (name, why) in &r.failures {
        // The task-space runs of a redundant arm: a compensator's friction error acts on the
        // self-motion, which only the null-space damping holds (see DEFAULT_NULL_DAMPING).
        let self_motion = if n > 2 && !name.starts_with("payload") {
            format!(
                " On this redundant arm the task leaves a self-motion that only the null-space damping ({} 1/s, \
                 `--tracking-gains {},{},K`) holds against the compensator's friction errors; over a long run it can also \
                 drift into a singular pose.",
                run.results.settings.tracking_gains.null_damping,
                run.results.settings.tracking_gains.kp,
                run.results.settings.tracking_gains.kd
            )
        } else {
            String::new()
        };
        let _ = writeln!(s, "**Run {name} failed**: {why}. Its figures below read NaN.{self_motion}\n");
    }
}

/// The adaptation law and its settings; where the changes come from.
fn law(s: &mut String, run: &PaperRun) {
    let a = &run.results.settings.adaptation;
    let (f, g) = (&a.friction_law, &a.gravity_law);
    let _ = writeln!(
        s,
        "The `AdaptiveCompensator` FMU starts from the offline nets and adapts their output layers while the robot works: per \
         torque, `ẇ = γ φ s − σ (w − w⁰)` with φ the net's hidden layer and a bias, s the controller's learning signal \
         (H⁻¹Jᵀ(ė + λe) of the task-space controller, ė + λe of the joint controller) and σ the leakage back to the offline \
         weights, then a projection that keeps every torque within the bound of the offline net's (see the crate \
         documentation of `neurarm_models::adaptive` for why it stays bounded). Friction: γ = {}, σ = {} 1/s, bound {} N·m; \
         gravity: γ = {}, σ = {} 1/s, bound {} N·m. All runs are on the {} arm, through the master, with the changes as \
         `[[event]]`s of their system files (`systems/drift_*.toml`, `payload_*.toml`, `steady_*.toml`); perfect compensation \
         is the ideal compensator of the real arm following the same change.\n",
        f.gain_friction,
        f.leakage,
        f.bound_friction,
        g.gain_gravity,
        g.leakage,
        g.bound_gravity,
        real_label(run)
    );
}

/// The friction-drift run: tracking MSE before and after the drift, per compensator.
fn drift(s: &mut String, run: &PaperRun) {
    let r = &run.results.adaptation;
    let a = &run.results.settings.adaptation;
    let _ = writeln!(
        s,
        "**Friction drift.** The tracking task of Table 1 while every joint's viscous friction ramps to {} × and its Coulomb \
         friction to {} × over {} s (warm gear oil is several times thinner than cold, and wear raises the Coulomb level), then \
         holds; tracking MSE [m²] before (first 2π s) and over the last {} s of {} s:\n",
        a.viscous_scale, a.coulomb_scale, a.drift_ramp_s, a.drift_window_s, a.drift_duration_s
    );
    let _ = writeln!(s, "| | {} |\n| --- | --- | --- | --- | --- |", CASES.join(" | "));
    let cells = |v: &[f64; 4], f: &dyn Fn(f64) -> String| v.iter().map(|x| f(*x)).collect::<Vec<_>>().join(" | ");
    let _ = writeln!(s, "| before the drift | {} |", cells(&r.drift_before_mse_m2, &|x| format!("{x:.3e}")));
    let _ = writeln!(s, "| after the drift | {} |", cells(&r.drift_mse_m2, &|x| format!("{x:.3e}")));
    let _ = writeln!(s, "| after, / perfect | {} |", cells(&r.drift_over_perfect, &|x| format!("{x:.2}")));
    let _ = writeln!(s, "\nThe adapted friction weights allowed a torque to differ from the offline net's by up to {:.3} N·m (the worst case over all inputs).\n", r.drift_largest_adaptation_nm);
}

/// The payload run: settled joint errors after the change, per compensator and over perfect.
fn payload(s: &mut String, run: &PaperRun) {
    let r = &run.results.adaptation;
    let a = &run.results.settings.adaptation;
    let n = run.arms.joints();
    let _ = writeln!(
        s,
        "**Payload.** The joint-space gravity loop, its targets repeating, gripping {:.3} kg ({} × the last link's mass) at the \
         tip at t = {} s. Settled error, mean |q_d − q| over the last 0.5 s of each segment starting {} s or more after the \
         change [rad], and over the ideal compensator's:\n",
        r.payload_kg, a.payload_share, a.payload_time_s, a.payload_settle_s
    );
    let _ = writeln!(s, "{}", header("compensation", n));
    for (k, name) in CASES.iter().enumerate() {
        let _ = writeln!(
            s,
            "{}",
            row(&std::iter::once(name.to_string()).chain(r.payload_settled_rad[k].iter().map(|x| format!("{x:.4}"))).collect::<Vec<_>>())
        );
    }
    for (k, name) in CASES.iter().enumerate().skip(1) {
        let label = format!("{name} / perfect");
        let _ = writeln!(
            s,
            "{}",
            row(&std::iter::once(label).chain(r.payload_over_perfect[k].iter().map(|x| format!("{x:.2}"))).collect::<Vec<_>>())
        );
    }
    let _ = writeln!(s, "\nThe adapted gravity weights allowed a torque to differ from the offline net's by up to {:.3} N·m (the worst case over all inputs).\n", r.payload_largest_adaptation_nm);
}

/// The no-change run with noise on: adaptive against static, and how far the weights moved.
fn steady(s: &mut String, run: &PaperRun) {
    let r = &run.results.adaptation;
    let a = &run.results.settings.adaptation;
    let _ = writeln!(
        s,
        "**No change, noise on.** The tracking task for {} s: MSE static {:.3e} m², adaptive {:.3e} m² (adaptive / static = {:.3}); \
         the adapted weights allowed a friction torque to differ from the offline net's by up to {:.3} N·m, within the {} N·m bound.\n",
        a.steady_duration_s,
        r.steady_mse_m2[0],
        r.steady_mse_m2[1],
        r.steady_adaptive_over_static,
        r.steady_largest_adaptation_nm,
        r.friction_bound_nm
    );
}
