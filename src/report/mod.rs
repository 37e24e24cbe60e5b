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
    if let Some(study) = &run.results.gravity.study {
        // One row per net: design, poses, encoding, then per joint RMS and largest shares.
        let names: Vec<String> = ["grid_per_joint", "poses", "encoding"]
            .into_iter()
            .map(String::from)
            .chain((1..=n).map(|i| format!("rms_share_{i}")))
            .chain((1..=n).map(|i| format!("max_share_{i}")))
            .collect();
        let encoding_code = |e: neurarm_nn::InputEncoding| match e {
            neurarm_nn::InputEncoding::Raw => 0.0,
            neurarm_nn::InputEncoding::JointAngles => 1.0,
            neurarm_nn::InputEncoding::LinkAngles => 2.0,
            neurarm_nn::InputEncoding::LogSpeed => 3.0,
        };
        let rows = study.points.iter().map(|p| {
            let grid = match p.design {
                crate::experiments::GravityDesign::Grid { per_joint } => per_joint as f64,
                crate::experiments::GravityDesign::Sampled { .. } => 0.0,
            };
            [vec![grid, p.poses as f64, encoding_code(p.encoding)], p.rms_share.clone(), p.max_share.clone()].concat()
        });
        write_rows(&data.join("gravity_study.csv"), &names, rows)?;
    }
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
