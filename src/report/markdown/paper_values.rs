//! Reading the paper's values: its MSEs over ours per case, and this run's errors in cm² and
//! summed over the samples, the two readings that fit, beside the paper's.

use std::fmt::Write as _;

use super::cases;
use crate::experiments::paper::{Cases, PaperRun};
use crate::report::figures::real_label;

/// Appends the note on the paper's absolute values and its table.
pub(super) fn write(s: &mut String, run: &PaperRun) {
    let t = &run.results.table_1;
    let real = real_label(run);
    let p = t.paper_m2;
    let per_case: Vec<String> = (0..5).map(|k| format!("{:.0}", p.to_array()[k] / t.mse_m2.to_array()[k])).collect();
    let in_cm2 = Cases::from_array(t.mse_m2.to_array().map(|v| v * 1e4));
    let summed = Cases::from_array(t.sum_m2.to_array().map(|v| v / 2.0));
    let _ = writeln!(
        s,
        "**Reading the paper's values.** Its absolute values are {} × ours case by case (geometric mean {:.0}), while the ratios \
         are close. Two readings fit a factor of about 10⁴: the values are in cm², not m² (× 10⁴), or they are a sum over the samples \
         instead of a mean (× {} samples here). Both computed from this run's recorded errors:\n",
        per_case.join(", "),
        t.paper_over_ours,
        t.samples
    );
    let _ = writeln!(s, "| | sim, perfect | sim, NN | sim, none | {real}, NN | {real}, none |");
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    let _ = writeln!(s, "| paper | {} |", cases(&p, |v| format!("{v}")));
    let _ = writeln!(s, "| neurarm, mean in cm² | {} |", cases(&in_cm2, |v| format!("{v:.4}")));
    let _ = writeln!(s, "| neurarm, sum over samples [m²] | {} |\n", cases(&summed, |v| format!("{v:.4}")));
    let _ = writeln!(
        s,
        "The paper's robot parameters and run length are not published, so neither reading can be confirmed; the ratios are what \
         this reproduction compares.\n"
    );
}
