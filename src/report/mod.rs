//! Writes what a run computed: `report.md` for people, `results.json` with every figure for
//! scripts, the data as CSV and the figures as PNG. Nothing here computes an experiment.

pub mod figures;
pub mod markdown;
pub mod plot;

use std::path::Path;

use crate::experiments::paper::{PaperRun, LOOPS};
use crate::experiments::LoopRun;
use crate::table::{write_atomic, write_text_atomic, writing};

fn write_rows(path: &Path, names: &[String], rows: impl Iterator<Item = Vec<f64>>) -> Result<(), String> {
    write_atomic(path, names, rows).map_err(writing(path))
}

fn write_run(path: &Path, run: &LoopRun, every: usize) -> Result<(), String> {
    let names: Vec<String> = run.columns.iter().map(|c| c.replace('.', "_")).collect();
    write_atomic(path, &names, run.rows.iter().step_by(every.max(1)).cloned()).map_err(writing(path))
}

/// Writes the run into `out`: `data/` (friction pairs per arm and joint, gravity pairs, every
/// closed loop at every 10th step), the figures, `results.json` and `report.md`.
pub fn write_report(out: &Path, run: &PaperRun) -> Result<(), String> {
    let data = out.join("data");
    std::fs::create_dir_all(&data).map_err(|e| format!("{}: {e}", data.display()))?;
    let n = run.arms.joints();
    for (k, tag) in ["sim", "real"].iter().enumerate() {
        for (j, pairs) in run.friction_pairs[k].iter().enumerate() {
            let csv = data.join(format!("friction_{tag}_joint{}.csv", j + 1));
            let names = ["qd", "tau", "samples"].map(String::from);
            write_rows(&csv, &names, pairs.iter().map(|&(v, t, c)| vec![v, t, c as f64]))?;
        }
    }
    let names: Vec<String> = (1..=n).map(|i| format!("q_{i}")).chain((1..=n).map(|i| format!("tau_{i}"))).collect();
    write_rows(&data.join("gravity_pairs.csv"), &names, run.gravity_pairs.iter().map(|(q, t)| [q.clone(), t.clone()].concat()))?;
    for (name, r) in LOOPS.iter().zip(&run.loops) {
        write_run(&data.join(format!("{name}.csv")), r, 10)?;
    }
    figures::write_figures(out, run)?;
    let json = out.join("results.json");
    let text = serde_json::to_string_pretty(&run.results).map_err(|e| format!("results.json: {e}"))?;
    write_text_atomic(&json, &text).map_err(writing(&json))?;
    let md = out.join("report.md");
    write_text_atomic(&md, &markdown::report_markdown(run)).map_err(writing(&md))
}
