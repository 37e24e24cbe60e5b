//! Figures: links to the run's PNG figures, the gravity study's if the run made it.

use std::fmt::Write as _;

use crate::experiments::paper::PaperRun;

/// Appends the section "Figures".
pub(super) fn write(s: &mut String, run: &PaperRun) {
    let g = &run.results.gravity;
    let _ = writeln!(
        s,
        "## Figures\n\n![friction](friction.png)\n\n![tracking](tracking.png)\n\n![gravity net](gravity.png)\n\n![gravity compensation](gravity_compensation.png)\n\n![online adaptation](adaptation.png)\n{}",
        if g.study.is_some() { "\n![gravity study](gravity_study.png)\n" } else { "" }
    );
}
