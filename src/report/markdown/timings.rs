//! Time per stage: the wall-clock seconds of each stage of the run and the largest one.

use std::fmt::Write as _;

use crate::experiments::paper::PaperRun;

/// Appends the section "Time per stage".
pub(super) fn write(s: &mut String, run: &PaperRun) {
    let r = &run.results;
    let _ = writeln!(s, "## Time per stage\n");
    let dominant = r.timings_s.iter().fold(("", 0.0), |a, (name, secs)| if *secs > a.1 { (name.as_str(), *secs) } else { a });
    for (name, secs) in &r.timings_s {
        let _ = writeln!(s, "- {name}: {secs:.1} s");
    }
    let _ = writeln!(s, "\nThe largest stage is {} ({:.0} % of {:.1} s).", dominant.0, 100.0 * dominant.1 / r.total_s.max(1e-9), r.total_s);
}
