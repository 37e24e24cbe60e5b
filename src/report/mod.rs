//! Writes what a run computed: `report.md` for people, `results.json` with every figure for
//! scripts, the data as CSV and the figures as PNG. Nothing here computes an experiment.

pub mod figures;
pub mod markdown;
pub mod plot;

use std::path::Path;

use anyhow::Context as _;

use crate::experiments::gravity_study::GravityStudy;
use crate::experiments::paper::{PaperRun, LOOPS};
use crate::experiments::{GravityDesign, LoopRun};
use crate::table::{write_atomic, write_text_atomic};
use neurarm_nn::InputEncoding;

/// Writes a CSV table with a header of `names` to `path`.
fn write_rows(path: &Path, names: &[String], rows: impl Iterator<Item = Vec<f64>>) -> anyhow::Result<()> {
    write_atomic(path, names, rows).with_context(|| format!("writing {}", path.display()))
}

/// Writes every `every`th row of a closed loop to `path`, `.` in column names as `_`.
fn write_run(path: &Path, run: &LoopRun, every: usize) -> anyhow::Result<()> {
    let names: Vec<String> = run.columns.iter().map(|c| c.replace('.', "_")).collect();
    write_rows(path, &names, run.rows.iter().step_by(every.max(1)).cloned())
}

/// Writes `text` to `path`.
fn write_text(path: &Path, text: &str) -> anyhow::Result<()> {
    write_text_atomic(path, text).with_context(|| format!("writing {}", path.display()))
}

/// Writes the run into `out`: `data/` (friction pairs per arm and joint, gravity pairs, every
/// closed loop at every 10th step), the figures, `results.json` and `report.md`.
pub fn write_report(out: &Path, run: &PaperRun) -> anyhow::Result<()> {
    let data = out.join("data");
    std::fs::create_dir_all(&data).with_context(|| format!("creating {}", data.display()))?;
    write_friction_pairs(&data, run)?;
    write_gravity_pairs(&data, run)?;
    if let Some(study) = &run.results.gravity.study {
        write_gravity_study(&data, study, run.arms.joints())?;
    }
    for (name, r) in LOOPS.iter().zip(&run.loops) {
        write_run(&data.join(format!("{name}.csv")), r, 10)?;
    }
    figures::write_figures(out, run)?;
    let text = serde_json::to_string_pretty(&run.results).context("serializing results.json")?;
    write_text(&out.join("results.json"), &text)?;
    write_text(&out.join("report.md"), &markdown::report_markdown(run))
}

/// `friction_{sim,real}_joint{i}.csv`: speed, friction torque and samples of each pair.
fn write_friction_pairs(data: &Path, run: &PaperRun) -> anyhow::Result<()> {
    for (k, tag) in ["sim", "real"].iter().enumerate() {
        for (j, pairs) in run.friction_pairs[k].iter().enumerate() {
            let csv = data.join(format!("friction_{tag}_joint{}.csv", j + 1));
            let names = ["qd", "tau", "samples"].map(String::from);
            write_rows(&csv, &names, pairs.iter().map(|&(v, t, c)| vec![v, t, c as f64]))?;
        }
    }
    Ok(())
}

/// `gravity_pairs.csv`: the angles and gravity torques of each pair.
fn write_gravity_pairs(data: &Path, run: &PaperRun) -> anyhow::Result<()> {
    let n = run.arms.joints();
    let names: Vec<String> = (1..=n).map(|i| format!("q_{i}")).chain((1..=n).map(|i| format!("tau_{i}"))).collect();
    write_rows(&data.join("gravity_pairs.csv"), &names, run.gravity_pairs.iter().map(|(q, t)| [q.clone(), t.clone()].concat()))
}

/// `gravity_study.csv`: one row per net of the study: design, poses, encoding, then per joint
/// the RMS and largest error as shares of the joint's largest gravity torque.
fn write_gravity_study(data: &Path, study: &GravityStudy, n: usize) -> anyhow::Result<()> {
    let names: Vec<String> = ["grid_per_joint", "poses", "encoding"]
        .into_iter()
        .map(String::from)
        .chain((1..=n).map(|i| format!("rms_share_{i}")))
        .chain((1..=n).map(|i| format!("max_share_{i}")))
        .collect();
    let encoding_code = |e: InputEncoding| match e {
        InputEncoding::Raw => 0.0,
        InputEncoding::JointAngles => 1.0,
        InputEncoding::LinkAngles => 2.0,
        InputEncoding::LogSpeed => 3.0,
    };
    let rows = study.points.iter().map(|p| {
        let grid = match p.design {
            GravityDesign::Grid { per_joint } => per_joint as f64,
            GravityDesign::Sampled { .. } => 0.0,
        };
        [vec![grid, p.poses as f64, encoding_code(p.encoding)], p.rms_share.clone(), p.max_share.clone()].concat()
    });
    write_rows(&data.join("gravity_study.csv"), &names, rows)
}
