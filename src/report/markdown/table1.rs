//! Table 1: the task-space loop's tracking error per case beside the paper's values, the
//! ratios of the errors, and notes where joints stick or the sensors bound a ratio.

use std::f64::consts::PI;
use std::fmt::Write as _;

use super::cases;
use crate::experiments::paper::PaperRun;
use crate::report::figures::real_label;

/// Above this share of the perfect run's samples with a joint at rest, the report says the
/// joints stick.
const STICKING_SHARE: f64 = 0.05;
/// Above this share of the real NN run's measured MSE coming from the sensors, the report
/// says the noise bounds real NN/none.
const NOISE_BOUND_SHARE: f64 = 0.5;

/// Appends the heading of Table 1, the table, its ratios and the notes on them.
pub(super) fn write(s: &mut String, run: &PaperRun) {
    error_table(s, run);
    sticking_note(s, run);
    ratio_table(s, run);
    noise_note(s, run);
}

/// The heading and the MSE, RMS and resting shares per case, beside the paper's MSE.
fn error_table(s: &mut String, run: &PaperRun) {
    let settings = &run.results.settings;
    let t = &run.results.table_1;
    let real = real_label(run);
    let _ = writeln!(s, "## Table 1: tracking error of the task-space loop\n");
    let _ = writeln!(
        s,
        "Mean over time and both coordinates of (x_d − x)² [m²] with x from the measured angles, as the controller sees it and as \
         the paper reports it, over {:.2} s ({:.1} periods of the reference, {} samples).\n",
        settings.tracking_duration,
        settings.tracking_duration / (2.0 * PI),
        t.samples
    );
    let _ = writeln!(s, "| | sim, perfect | sim, NN | sim, none | {real}, NN | {real}, none |");
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    let p = t.paper_m2;
    let _ = writeln!(s, "| paper, MSE [m²] | {} |", cases(&p, |v| format!("{v}")));
    let _ = writeln!(s, "| neurarm, MSE measured [m²] | {} |", cases(&t.mse_m2, |v| format!("{v:.3e}")));
    let _ = writeln!(s, "| neurarm, MSE true position [m²] | {} |", cases(&t.true_mse_m2, |v| format!("{v:.3e}")));
    let _ = writeln!(s, "| neurarm, RMS distance, true position [mm] | {} |", cases(&t.rms_mm, |v| format!("{v:.3}")));
    let _ = writeln!(s, "| neurarm, samples with a joint at rest [%] | {} |\n", cases(&t.resting_share, |v| format!("{:.1}", 100.0 * v)));
}

/// Where joints are at rest in much of the perfect run: stick–slip decides the error.
fn sticking_note(s: &mut String, run: &PaperRun) {
    let settings = &run.results.settings;
    let t = &run.results.table_1;
    if t.resting_share.sim_perfect > STICKING_SHARE {
        let _ = writeln!(
            s,
            "**Joints stick.** In {:.0} % of the perfect-compensation run some joint is at rest (|q̇| < 1 mrad/s): friction holds it \
             until the law's torque breaks it away, and a compensator fed the measured speed gives nothing at rest. Which joints stick \
             then decides the error more than the compensator does, so the NN/perfect ratio below is a comparison of two stick–slip \
             motions, sensitive to small torque differences. {}\n",
            100.0 * t.resting_share.sim_perfect,
            match settings.intent_horizon {
                None =>
                    "To compensate joints at rest the way the law moves them, feed the compensators the commanded speed: \
                     `neurarm paper --intent-horizon 0.01` (see the README).",
                Some(_) => "The compensators are fed the commanded speed already (`--intent-horizon`).",
            }
        );
    }
}

/// Measured against true positions, then the ratios of the MSEs beside the paper's.
fn ratio_table(s: &mut String, run: &PaperRun) {
    let t = &run.results.table_1;
    let real = real_label(run);
    let p = t.paper_m2;
    let _ = writeln!(
        s,
        "On the simulated arm the measured and true positions are the same; on the {real} arm the measured one carries the sensor \
         noise, which inflates the small errors most (NN: {:.2} × its true MSE).\n",
        t.mse_m2.real_nn / t.true_mse_m2.real_nn
    );
    let q = &t.ratios;
    let _ = writeln!(s, "| ratio of MSEs | paper | neurarm |");
    let _ = writeln!(s, "|---|---|---|");
    let _ = writeln!(s, "| sim NN / perfect | {:.2} | {:.3} |", p.sim_nn / p.sim_perfect, q.sim_nn_over_perfect);
    let _ = writeln!(s, "| sim none / perfect | {:.1} | {:.1} |", p.sim_none / p.sim_perfect, q.sim_none_over_perfect);
    let _ = writeln!(s, "| sim none / NN | {:.1} | {:.1} |", p.sim_none / p.sim_nn, q.sim_none_over_nn);
    let _ = writeln!(s, "| real NN / none | {:.2} | {:.3} |", p.real_nn / p.real_none, q.real_nn_over_none);
    let true_real_ratio = t.true_mse_m2.real_nn / t.true_mse_m2.real_none;
    let _ = writeln!(s, "| real NN / none, true positions | | {true_real_ratio:.3} |\n");
}

/// Where the sensors make most of the real NN run's measured MSE, they bound real NN/none.
fn noise_note(s: &mut String, run: &PaperRun) {
    let t = &run.results.table_1;
    let real = real_label(run);
    let true_real_ratio = t.true_mse_m2.real_nn / t.true_mse_m2.real_none;
    let noise_share = 1.0 - t.true_mse_m2.real_nn / t.mse_m2.real_nn;
    if noise_share > NOISE_BOUND_SHARE {
        let _ = writeln!(
            s,
            "**The sensors bound real NN/none.** {:.0} % of the {real} NN run's measured MSE ({:.2e} m² of {:.2e} m²) is the angle \
             sensors' noise and quantisation seen in the measured position, not tracking error, and about as much is in the \
             uncompensated run ({:.2e} m²), so a compensator that left no tracking error at all would still measure NN/none ≈ \
             {:.3}. Against the true positions NN/none is {true_real_ratio:.3}.\n",
            100.0 * noise_share,
            t.mse_m2.real_nn - t.true_mse_m2.real_nn,
            t.mse_m2.real_nn,
            t.mse_m2.real_none - t.true_mse_m2.real_none,
            (t.mse_m2.real_none - t.true_mse_m2.real_none) / t.mse_m2.real_none,
        );
    }
}
