//! `report.md`: the run for people. Every number here is also in `results.json`. One module
//! per part of the report, in the report's order; each appends its text to the report.

mod adaptation;
mod arm;
mod diagnostics;
mod figure_links;
mod friction;
mod gravity;
mod gravity_compensation;
mod gravity_study;
mod paper_values;
mod summary;
mod table1;
mod timings;

use crate::experiments::paper::{Cases, PaperRun};

fn row(cells: &[String]) -> String {
    format!("| {} |", cells.join(" | "))
}

fn header(first: &str, n: usize) -> String {
    let mut s = row(&std::iter::once(first.to_owned()).chain((1..=n).map(|j| format!("joint {j}"))).collect::<Vec<_>>());
    s.push('\n');
    s.push_str(&row(&vec!["---".to_owned(); n + 1]));
    s
}

fn list(values: &[f64]) -> String {
    values.iter().map(|v| format!("{v:.4}")).collect::<Vec<_>>().join(", ")
}

fn cases(c: &Cases, f: impl Fn(f64) -> String) -> String {
    c.to_array().iter().map(|&v| f(v)).collect::<Vec<_>>().join(" | ")
}

/// The text of `report.md`.
pub fn report_markdown(run: &PaperRun) -> String {
    let mut s = String::new();
    summary::write(&mut s, run);
    arm::write(&mut s, run);
    table1::write(&mut s, run);
    diagnostics::write(&mut s, run);
    paper_values::write(&mut s, run);
    friction::write(&mut s, run);
    gravity::write(&mut s, run);
    gravity_study::write(&mut s, run);
    gravity_compensation::write(&mut s, run);
    adaptation::write(&mut s, run);
    figure_links::write(&mut s, run);
    timings::write(&mut s, run);
    s
}
