//! The run's figures: friction pairs, nets and true laws (the paper's Figs. 6/7), tracking
//! (Figs. 9/10), the gravity net's error over random poses, the joint-space runs
//! (Figs. 11/13/14), the gravity study and online adaptation, one function per figure. Each
//! case keeps its colour in every panel (see `plot`).

use std::path::Path;

use anyhow::Context as _;

use super::plot::{write_png, Panel, Series, Style};
use crate::experiments::gravity_study::GravityStudy;
use crate::experiments::paper::PaperRun;
use crate::experiments::{GravityDesign, LoopRun, ARM_UNIT, COMPENSATOR_UNIT, CONTROLLER_UNIT};
use neurarm_models::names::{self, joint_path, path};
use neurarm_nn::InputEncoding;

/// Most points of a scatter series: more only slows the PNG down.
const MAX_SCATTER: usize = 2000;

/// Writes `friction.png`, `tracking.png`, `gravity.png`, `gravity_compensation.png`,
/// `adaptation.png` and, if the run made the study, `gravity_study.png`.
pub fn write_figures(out: &Path, run: &PaperRun) -> anyhow::Result<()> {
    write_friction_figure(out, run)?;
    write_tracking_figure(out, run)?;
    write_gravity_figure(out, run)?;
    if let Some(study) = &run.results.gravity.study {
        write_study_figure(out, study)?;
    }
    write_gravity_compensation_figure(out, run)?;
    write_adaptation_figure(out, run)
}

/// Panels side by side in a figure with one panel per joint.
fn joint_columns(run: &PaperRun) -> usize {
    run.arms.joints().min(4)
}

/// Column `b` of `r` against its column `a` (empty where either is missing).
fn xy(r: &LoopRun, a: &str, b: &str) -> Vec<(f64, f64)> {
    r.column(a).unwrap_or_default().into_iter().zip(r.column(b).unwrap_or_default()).collect()
}

/// The recorded columns of the reference and the true end-effector position: x_d, y_d, x, y.
fn reference_and_position() -> [String; 4] {
    [
        path(CONTROLLER_UNIT, names::REFERENCE_X),
        path(CONTROLLER_UNIT, names::REFERENCE_Y),
        path(ARM_UNIT, names::END_EFFECTOR_X),
        path(ARM_UNIT, names::END_EFFECTOR_Y),
    ]
}

/// The distance of the true end-effector position from the reference [mm] against time [s].
fn error_mm(r: &LoopRun) -> Vec<(f64, f64)> {
    let c = |name: &str| r.column(name).unwrap_or_default();
    let [xr, yr, x, y] = reference_and_position().map(|name| c(&name));
    let t = c("time");
    (0..t.len().min(x.len())).map(|k| (t[k], 1e3 * (xr[k] - x[k]).hypot(yr[k] - y[k]))).collect()
}

/// `friction.png`: per arm and joint the identified pairs, the true law and the trained net
/// (the paper's Figs. 6/7).
fn write_friction_figure(out: &Path, run: &PaperRun) -> anyhow::Result<()> {
    let n = run.arms.joints();
    let top = run.results.settings.max_velocity;

    let mut panels = Vec::new();
    for (k, tag) in ["simulated", real_label(run)].iter().enumerate() {
        let arm = if k == 0 { &run.arms.nominal.arm } else { &run.arms.real.arm };
        for j in 0..n {
            let net = run.friction_nets[k * n + j].network().with_context(|| format!("the friction net of joint {} ({tag})", j + 1))?;
            let speeds: Vec<f64> = (-1000..=1000).map(|i| i as f64 * top / 1000.0).collect();
            let law = arm.friction[j];
            panels.push(Panel {
                title: format!("joint {} ({tag})", j + 1),
                x_label: "qd [rad/s]".into(),
                y_label: "τ [N·m]".into(),
                series: vec![
                    Series {
                        name: "identified pairs".into(),
                        points: run.friction_pairs[k][j].iter().map(|&(v, t, _)| (v, t)).collect(),
                        style: Style::Points,
                    },
                    // The law jumps at 0: break the line there rather than draw a vertical.
                    Series {
                        name: "true law".into(),
                        points: speeds.iter().map(|&v| (v, if v == 0.0 { f64::NAN } else { law.torque(v) })).collect(),
                        style: Style::Dashed,
                    },
                    Series { name: "net".into(), points: speeds.iter().map(|&v| (v, net.evaluate(&[v])[0])).collect(), style: Style::Line },
                ],
            });
        }
    }
    write_png(&out.join("friction.png"), "Friction: identified pairs, true law and trained net per joint", &panels, joint_columns(run))?;
    Ok(())
}

/// `tracking.png`: the end-effector paths and tracking errors of the five task-space loops
/// (Figs. 9/10).
fn write_tracking_figure(out: &Path, run: &PaperRun) -> anyhow::Result<()> {
    let loops = &run.loops;
    let real = real_label(run);
    let labels = ["sim, perfect".to_owned(), "sim, NN".into(), "sim, none".into(), format!("{real}, NN"), format!("{real}, none")];
    let [xr, yr, x, y] = reference_and_position();
    let panels = vec![
        Panel {
            title: "end-effector path (true positions)".into(),
            x_label: "x [m]".into(),
            y_label: "y [m]".into(),
            series: std::iter::once(Series { name: "reference".into(), points: xy(&loops[0], &xr, &yr), style: Style::Dashed })
                .chain((0..5).map(|k| Series { name: labels[k].clone(), points: xy(&loops[k], &x, &y), style: Style::Line }))
                .collect(),
        },
        Panel {
            title: "tracking error |x_d − x| (true position)".into(),
            x_label: "t [s]".into(),
            y_label: "error [mm]".into(),
            series: (0..5).map(|k| Series { name: labels[k].clone(), points: error_mm(&loops[k]), style: Style::Line }).collect(),
        },
    ];
    write_png(&out.join("tracking.png"), "Task-space tracking with friction compensation (Table 1)", &panels, 1)?;
    Ok(())
}

/// `gravity.png`: the gravity net's error against the true torque per joint, on random poses.
fn write_gravity_figure(out: &Path, run: &PaperRun) -> anyhow::Result<()> {
    let n = run.arms.joints();
    let samples = &run.results.gravity.net.samples;
    let panels: Vec<Panel> = (0..n)
        .map(|j| {
            let every = samples[j].len().div_ceil(MAX_SCATTER).max(1);
            Panel {
                title: format!("joint {}", j + 1),
                x_label: "true gravity torque [N·m]".into(),
                y_label: "net − true [N·m]".into(),
                series: vec![Series {
                    name: "random poses".into(),
                    points: samples[j].iter().step_by(every).copied().collect(),
                    style: Style::Points,
                }],
            }
        })
        .collect();
    let poses = run.results.gravity.net.poses;
    write_png(
        &out.join("gravity.png"),
        &format!("Gravity net error on {poses} random poses (base turned 90°)"),
        &panels,
        joint_columns(run),
    )?;
    Ok(())
}

/// `gravity_compensation.png`: each joint's angle against its target in the joint-space loop,
/// per compensator (Figs. 11/13/14).
fn write_gravity_compensation_figure(out: &Path, run: &PaperRun) -> anyhow::Result<()> {
    let n = run.arms.joints();
    let loops = &run.loops;
    let mut panels = Vec::new();
    for j in 1..=n {
        let t = loops[5].column("time").unwrap_or_default();
        let mut series = vec![Series {
            name: "target".into(),
            points: t
                .iter()
                .copied()
                .zip(loops[5].column(&joint_path(CONTROLLER_UNIT, names::TARGET_ANGLE, j)).unwrap_or_default())
                .collect(),
            style: Style::Dashed,
        }];
        for (k, name) in ["ideal", "NN", "none"].iter().enumerate() {
            let r = &loops[5 + k];
            series.push(Series {
                name: format!("{name} compensation"),
                points: xy(r, "time", &joint_path(ARM_UNIT, names::ANGLE, j)),
                style: Style::Line,
            });
        }
        panels.push(Panel { title: format!("joint {j}"), x_label: "t [s]".into(), y_label: "q [rad]".into(), series });
    }
    write_png(&out.join("gravity_compensation.png"), "Joint-space P control with gravity compensation", &panels, 2)?;
    Ok(())
}

/// `adaptation.png`: windowed tracking MSE over time of the friction-drift, payload and steady
/// runs per compensator, and how far the adaptive nets moved.
fn write_adaptation_figure(out: &Path, run: &PaperRun) -> anyhow::Result<()> {
    use crate::experiments::adaptation::{settled_error_per_segment, windowed_joint_mse, windowed_tracking_mse, CASES};
    let loops = &run.adaptation_loops;
    let a = &run.results.settings.adaptation;
    let n = run.arms.joints();
    let scaled = |points: Vec<(f64, f64)>, factor: f64| points.into_iter().map(|(t, m)| (t, m * factor)).collect::<Vec<_>>();
    let series = |range: std::ops::Range<usize>, names: &[&str], points: &dyn Fn(&LoopRun) -> Vec<(f64, f64)>| -> Vec<Series> {
        range.zip(names).map(|(k, name)| Series { name: name.to_string(), points: points(&loops[k]), style: Style::Line }).collect()
    };
    let tracking = |r: &LoopRun| scaled(windowed_tracking_mse(r, a.mse_window_s), 1e6);
    let largest = |family: &'static str| {
        move |r: &LoopRun| -> Vec<(f64, f64)> {
            let prefix = path(COMPENSATOR_UNIT, &names::joint_prefix(family));
            let columns: Vec<usize> = r.columns.iter().enumerate().filter(|(_, c)| c.starts_with(&prefix)).map(|(k, _)| k).collect();
            r.rows.iter().step_by(10).map(|row| (row[0], columns.iter().map(|&k| row[k]).fold(0.0, f64::max))).collect()
        }
    };
    let panels = vec![
        Panel {
            title: format!("friction drift: viscous × {}, Coulomb × {} over {} s", a.viscous_scale, a.coulomb_scale, a.drift_ramp_s),
            x_label: "t [s]".into(),
            y_label: format!("tracking MSE over {} s [mm²]", a.mse_window_s),
            series: series(0..4, &CASES, &tracking),
        },
        Panel {
            title: format!("payload {:.3} kg at the tip from t = {} s", run.results.adaptation.payload_kg, a.payload_time_s),
            x_label: "t [s]".into(),
            y_label: "settled error per segment [mrad]".into(),
            series: series(4..8, &CASES, &|r| scaled(settled_error_per_segment(r, n), 1e3)),
        },
        Panel {
            title: "payload: joint MSE, target steps included".into(),
            x_label: "t [s]".into(),
            y_label: format!("joint MSE over {} s [mrad²]", a.mse_window_s),
            series: series(4..8, &CASES, &|r| scaled(windowed_joint_mse(r, n, a.mse_window_s), 1e6)),
        },
        Panel {
            title: "no change, noise on".into(),
            x_label: "t [s]".into(),
            y_label: format!("tracking MSE over {} s [mm²]", a.mse_window_s),
            series: series(8..10, &CASES[1..3], &tracking),
        },
        Panel {
            title: "largest change of a torque the adapted weights allow".into(),
            x_label: "t [s]".into(),
            y_label: "[N·m]".into(),
            series: vec![
                Series { name: "drift (friction)".into(), points: largest(names::ADAPTED_FRICTION)(&loops[2]), style: Style::Line },
                Series { name: "payload (gravity)".into(), points: largest(names::ADAPTED_GRAVITY)(&loops[6]), style: Style::Line },
                Series { name: "no change (friction)".into(), points: largest(names::ADAPTED_FRICTION)(&loops[9]), style: Style::Dashed },
            ],
        },
    ];
    write_png(&out.join("adaptation.png"), "Online adaptation (real arm)", &panels, 2)?;
    Ok(())
}

/// `gravity_study.png`: the worst joint's whole-turn RMS error and largest error against the
/// poses measured, per design and encoding, both axes in decades.
fn write_study_figure(out: &Path, study: &GravityStudy) -> anyhow::Result<()> {
    let series_of = |largest: bool| -> Vec<Series> {
        let mut series = Vec::new();
        for encoding in [InputEncoding::LinkAngles, InputEncoding::JointAngles, InputEncoding::Raw] {
            for (design, grid) in [("grid", true), ("sampled", false)] {
                let points = study
                    .points
                    .iter()
                    .filter(|p| p.encoding == encoding && matches!(p.design, GravityDesign::Grid { .. }) == grid)
                    .map(|p| {
                        let share = if largest { p.worst_max_share() } else { p.worst_rms_share() };
                        ((p.poses as f64).log10(), (100.0 * share).log10())
                    })
                    .collect();
                let style = if grid { Style::Dashed } else { Style::Line };
                series.push(Series { name: format!("{design}, {}", encoding.name().replace('_', " ")), points, style });
            }
        }
        series
    };
    let panels = [("RMS error, worst joint", false), ("largest error, worst joint", true)].map(|(title, largest)| Panel {
        title: title.into(),
        x_label: "log10 poses measured".into(),
        y_label: "log10 error [% of the joint's largest torque]".into(),
        series: series_of(largest),
    });
    write_png(
        &out.join("gravity_study.png"),
        &format!("Gravity net error over the whole turn against the poses measured ({} joints)", study.joints),
        &panels,
        2,
    )?;
    Ok(())
}

/// How the report names the real arm: "emulated real" or "real (given)".
pub fn real_label(run: &PaperRun) -> &'static str {
    match run.arms.real_origin {
        crate::experiments::RealOrigin::Emulated => "emulated real",
        crate::experiments::RealOrigin::Given { .. } => "real (given)",
    }
}
