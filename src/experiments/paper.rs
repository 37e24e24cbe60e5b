//! `neurarm paper`: every experiment of the paper, end to end, into one output folder.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use rand::{Rng, SeedableRng};

use super::*;
use crate::table::{write_atomic, write_text_atomic};
use neurarm_physics::arm::gravity_torques;

/// The paper's Table 1 [m²]: sim perfect, sim NN, sim none, real NN, real none.
pub const PAPER_TABLE_1: [f64; 5] = [0.0014, 0.0016, 0.0248, 0.0071, 0.0291];

/// What the run measured; also written to `report.md`.
#[derive(Clone, Debug, Default)]
pub struct PaperResults {
    /// Tracking MSE [m²]: sim perfect, sim NN, sim none, real NN, real none.
    pub table_1: [f64; 5],
    /// Gravity net: RMS error per joint on random configurations [N·m].
    pub gravity_rms: Vec<f64>,
    /// Largest |gravity torque| over those configurations [N·m].
    pub gravity_max: f64,
    /// Joint-space loop: RMS of q_target − q per joint [rad], for ideal / NN / none.
    pub joint_rms: [Vec<f64>; 3],
    /// Joint-space loop: settled error per joint [rad] (see [`joint_settled_errors`]).
    pub joint_settled: [Vec<f64>; 3],
    /// Largest |averaged torque − true gravity at the averaged angles| over the gravity pairs [N·m].
    pub gravity_pair_error: f64,
    /// Friction data: (levels, bins) per joint, simulated then emulated real.
    pub friction_counts: Vec<(usize, usize)>,
    /// Gravity pairs measured.
    pub gravity_pairs: usize,
    /// Seconds per stage.
    pub timings: Vec<(String, f64)>,
}

/// The gravity net against the true gravity of the arm (base turned 90°) on
/// `settings.gravity_test_points` random configurations within the grid's span (not grid
/// points): RMS error per joint [N·m] and the largest |gravity torque| met [N·m].
pub fn gravity_net_errors(gravity_net: &WeightsFile, settings: &Settings) -> Result<(Vec<f64>, f64), String> {
    let vertical = ArmConfig::default().arm.with_base_angle(PI / 2.0);
    let net = gravity_net.network()?;
    let span = 2.0 * PI * (settings.grid as f64 - 1.0) / settings.grid as f64;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(settings.seed + 99);
    let mut sq = [0.0; 4];
    let mut worst: f64 = 0.0;
    for _ in 0..settings.gravity_test_points {
        let q: Vec<f64> = (0..4).map(|_| rng.gen::<f64>() * span).collect();
        let truth = gravity_torques(&vertical, &q);
        let guess = net.evaluate(&q);
        for i in 0..4 {
            sq[i] += (guess[i] - truth[i]).powi(2);
            worst = worst.max(truth[i].abs());
        }
    }
    Ok((sq.iter().map(|s| (s / settings.gravity_test_points as f64).sqrt()).collect(), worst))
}

fn bar(len: u64, what: &str) -> ProgressBar {
    let b = if std::io::IsTerminal::is_terminal(&std::io::stderr()) { ProgressBar::new(len) } else { ProgressBar::hidden() };
    b.set_style(ProgressStyle::with_template("{prefix:>28} {bar:30} {pos}/{len} {elapsed}").expect("valid template"));
    b.set_prefix(what.to_owned());
    b
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> String + '_ {
    move |e| format!("writing {}: {e}", path.display())
}

fn write_rows(path: &Path, names: &[&str], rows: impl Iterator<Item = Vec<f64>>) -> Result<(), String> {
    let names: Vec<String> = names.iter().map(|s| s.to_string()).collect();
    write_atomic(path, &names, rows).map_err(io(path))
}

fn write_run(path: &Path, run: &LoopRun, every: usize) -> Result<(), String> {
    let names: Vec<String> = run.columns.iter().map(|c| c.replace('.', "_")).collect();
    write_atomic(path, &names, run.rows.iter().step_by(every.max(1)).cloned()).map_err(io(path))
}

/// Runs everything with `settings` and writes `out/`: the FMUs, the identified data as CSV,
/// the nets, the closed-loop runs, and `report.md`. `log` gets one line per stage.
pub fn run_paper(out: &Path, settings: &Settings, log: &mut dyn FnMut(&str)) -> Result<PaperResults, String> {
    let started = Instant::now();
    let mut results = PaperResults::default();
    let mut stage = Instant::now();
    let mut lap = |results: &mut PaperResults, name: &str, log: &mut dyn FnMut(&str)| {
        let s = stage.elapsed().as_secs_f64();
        log(&format!("{name}: {s:.1} s"));
        results.timings.push((name.to_owned(), s));
        stage = Instant::now();
    };
    let (fmu_dir, data_dir, net_dir) = (out.join("fmu"), out.join("data"), out.join("nets"));
    for d in [&fmu_dir, &data_dir, &net_dir] {
        std::fs::create_dir_all(d).map_err(|e| format!("{}: {e}", d.display()))?;
    }
    let fmus = build_fmus(&fmu_dir)?;
    lap(&mut results, "building FMUs", log);

    // Friction identification on both arms, every joint and direction in parallel.
    let tasks: Vec<(bool, usize, f64)> =
        [false, true].iter().flat_map(|&real| (0..4).flat_map(move |j| [(real, j, 1.0), (real, j, -1.0)])).collect();
    let b = bar(tasks.len() as u64, "friction identification");
    let runs = parallel(
        tasks.clone(),
        settings.threads,
        |(real, joint, dir)| friction_run(if real { &fmus.arm_real } else { &fmus.arm }, &fmus.joint_controller, joint, dir, settings),
        || b.inc(1),
    )?;
    b.finish_and_clear();
    let mut friction_files: [Vec<(String, PathBuf)>; 2] = [Vec::new(), Vec::new()];
    let mut binned_all: [Vec<Vec<FrictionPair>>; 2] = [Vec::new(), Vec::new()];
    for (k, real) in [false, true].into_iter().enumerate() {
        let tag = if real { "real" } else { "sim" };
        for joint in 0..4 {
            let mine: Vec<&FrictionRun> = runs.iter().zip(&tasks).filter(|(_, t)| t.0 == real && t.1 == joint).map(|(r, _)| r).collect();
            let samples: Vec<(f64, f64)> = mine.iter().flat_map(|r| r.samples.iter().copied()).collect();
            let levels: usize = mine.iter().map(|r| r.levels.len()).sum();
            let mut binned = bin_friction(&samples, settings.bin_width, settings.max_velocity);
            if let Some(rest) = rest_pair(&mine) {
                binned.retain(|b| b.0 != 0.0);
                let at = binned.partition_point(|b| b.0 < 0.0);
                binned.insert(at, rest);
            }
            results.friction_counts.push((levels, binned.len()));
            let csv = data_dir.join(format!("friction_{tag}_joint{}.csv", joint + 1));
            write_rows(&csv, &["qd", "tau", "samples"], binned.iter().map(|&(v, t, n)| vec![v, t, n as f64]))?;
            binned_all[k].push(binned);
        }
    }
    lap(&mut results, "friction identification", log);
    let b = bar(8, "friction nets");
    let nets = parallel(
        (0..8).collect(),
        settings.threads,
        |i: usize| train_friction_net(i % 4, &binned_all[i / 4][i % 4], settings.seed),
        || b.inc(1),
    )?;
    b.finish_and_clear();
    for (i, net) in nets.iter().enumerate() {
        let tag = if i < 4 { "sim" } else { "real" };
        let name = format!("friction_{tag}_joint{}.json", i % 4 + 1);
        let path = net_dir.join(&name);
        write_text_atomic(&path, &net.to_json()).map_err(io(&path))?;
        friction_files[i / 4].push((name, path));
    }
    lap(&mut results, "training friction nets", log);

    // Gravity identification: the grid split between the workers.
    let grid = gravity_grid(settings.grid, 4);
    let chunk = grid.len().div_ceil(settings.threads.max(1));
    let chunks: Vec<Vec<Vec<f64>>> = grid.chunks(chunk).map(|c| c.to_vec()).collect();
    let b = bar(chunks.len() as u64, "gravity identification");
    let swept =
        parallel(chunks, settings.threads, |points| gravity_sweep(&fmus.arm, &fmus.joint_controller, &points, settings), || b.inc(1))?;
    b.finish_and_clear();
    let pairs: Vec<GravityPair> = swept.into_iter().flat_map(|(p, _)| p).collect();
    results.gravity_pairs = pairs.len();
    let vertical = ArmConfig::default().arm.with_base_angle(PI / 2.0);
    results.gravity_pair_error = pairs
        .iter()
        .map(|(q, t)| gravity_torques(&vertical, q).iter().zip(t).map(|(g, t)| (g - t).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max);
    let csv = data_dir.join("gravity_pairs.csv");
    write_rows(
        &csv,
        &["q_1", "q_2", "q_3", "q_4", "tau_1", "tau_2", "tau_3", "tau_4"],
        pairs.iter().map(|(q, t)| [q.clone(), t.clone()].concat()),
    )?;
    lap(&mut results, "gravity identification", log);
    let b = bar(settings.gravity_epochs as u64, "gravity net (4-25-4)");
    let gravity_net = train_gravity_net(&pairs, settings, &mut |e| b.set_position(e as u64))?;
    b.finish_and_clear();
    let gravity_path = net_dir.join("gravity.json");
    write_text_atomic(&gravity_path, &gravity_net.to_json()).map_err(io(&gravity_path))?;
    (results.gravity_rms, results.gravity_max) = gravity_net_errors(&gravity_net, settings)?;
    lap(&mut results, "training gravity net", log);

    // The NN compensator FMUs: the full one (both nets) is the deliverable; the loops use
    // ones exported with only the part they compensate.
    let nn_fmu = |identifier: &str, friction: &[(String, PathBuf)], gravity: bool| -> Result<PathBuf, String> {
        let path = fmu_dir.join(format!("{identifier}.fmu"));
        let mut sources = friction.to_vec();
        if gravity {
            sources.push(("gravity.json".into(), gravity_path.clone()));
        }
        let model = ModelSpec::NnCompensator(NnCompensatorSpec {
            joints: 4,
            friction: friction.iter().map(|(n, _)| n.clone()).collect(),
            gravity: gravity.then(|| "gravity.json".to_owned()),
            enable_friction: !friction.is_empty(),
            enable_gravity: gravity,
        });
        export_fmu(&FmuSpec { identifier: identifier.into(), model }, &sources, &path)?;
        Ok(path)
    };
    nn_fmu("NnCompensator", &friction_files[0], true)?;
    let nn_friction = nn_fmu("NnFrictionCompensator", &friction_files[0], false)?;
    let nn_real = nn_fmu("NnFrictionCompensatorReal", &friction_files[1], false)?;
    let nn_gravity = nn_fmu("NnGravityCompensator", &[], true)?;

    // Table 1 and the gravity-compensation runs as system files (paths relative to
    // out/systems) and SSP archives, run in parallel.
    let systems_dir = out.join("systems");
    std::fs::create_dir_all(&systems_dir).map_err(|e| format!("{}: {e}", systems_dir.display()))?;
    let rel = |p: &Path| Path::new("..").join(p.strip_prefix(out).unwrap_or(p));
    let (arm, arm_real) = (rel(&fmus.arm), rel(&fmus.arm_real));
    let (task, joint) = (rel(&fmus.task_controller), rel(&fmus.joint_controller));
    let tracking = |arm: &Path, comp: Option<PathBuf>| tracking_system(arm, &task, comp.as_deref(), settings);
    let joint_space = |comp: Option<PathBuf>| Ok::<_, String>(gravity_compensation_system(&arm, &joint, comp.as_deref(), settings));
    let loops: Vec<(&str, SystemSpec)> = vec![
        ("tracking_sim_perfect", tracking(&arm, Some(rel(&fmus.ideal_friction)))?),
        ("tracking_sim_nn", tracking(&arm, Some(rel(&nn_friction)))?),
        ("tracking_sim_none", tracking(&arm, None)?),
        ("tracking_real_nn", tracking(&arm_real, Some(rel(&nn_real)))?),
        ("tracking_real_none", tracking(&arm_real, None)?),
        ("joint_ideal", joint_space(Some(rel(&fmus.ideal_gravity)))?),
        ("joint_nn", joint_space(Some(rel(&nn_gravity)))?),
        ("joint_none", joint_space(None)?),
    ];
    for (name, spec) in &loops {
        let toml = systems_dir.join(format!("{name}.toml"));
        let text = format!(
            "# The {name} loop of `neurarm paper`; rerun it with\n# neurarm simulate {name}.toml -o {name}.csv\n\n{}",
            spec.to_toml()?
        );
        write_text_atomic(&toml, &text).map_err(io(&toml))?;
        fmi2_cosim::ssp::write_ssp(spec, &systems_dir, &out.join(format!("{name}.ssp"))).map_err(|e| e.to_string())?;
    }
    let b = bar(loops.len() as u64, "closed loops");
    let loop_runs = parallel(loops.clone(), settings.threads, |(_, spec)| run_loop(&spec, &systems_dir), || b.inc(1))?;
    b.finish_and_clear();
    for (k, run) in loop_runs.iter().enumerate() {
        let name = loops[k].0;
        write_run(&data_dir.join(format!("{name}.csv")), run, 10)?;
        if k < 5 {
            results.table_1[k] = tracking_mse(run);
        } else {
            results.joint_rms[k - 5] = joint_rms_errors(run, 4);
            results.joint_settled[k - 5] = joint_settled_errors(run, 4);
        }
    }
    lap(&mut results, "closed loops", log);
    write_plots(out, &binned_all, &nets, &loop_runs)?;
    lap(&mut results, "plots", log);
    let report = report_markdown(&results, settings, started.elapsed().as_secs_f64());
    let path = out.join("report.md");
    write_text_atomic(&path, &report).map_err(io(&path))?;
    Ok(results)
}

/// `report.md`.
pub fn report_markdown(r: &PaperResults, settings: &Settings, total_s: f64) -> String {
    let mut s = String::new();
    let t = &r.table_1;
    let p = PAPER_TABLE_1;
    let _ = writeln!(s, "# neurarm: the paper's experiments, reproduced\n");
    let _ = writeln!(
        s,
        "Seeded run (seed {}), communication step {} ms, {} worker threads, {:.1} s in all. \
         Every loop ran through the Rust master with the FMUs in `fmu/`.\n",
        settings.seed,
        settings.step * 1e3,
        settings.threads,
        total_s
    );
    let _ = writeln!(s, "## Table 1: tracking error of the task-space loop\n");
    let _ = writeln!(
        s,
        "Mean over time and both coordinates of (x_d − x)² [m²], over {:.2} s ({:.1} periods of the reference).\n",
        settings.tracking_duration,
        settings.tracking_duration / (2.0 * PI)
    );
    let _ = writeln!(s, "| average MSE | sim, perfect | sim, NN | sim, none | real, NN | real, none |");
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    let _ = writeln!(s, "| paper | {} | {} | {} | {} | {} |", p[0], p[1], p[2], p[3], p[4]);
    let _ = writeln!(s, "| neurarm | {:.3e} | {:.3e} | {:.3e} | {:.3e} | {:.3e} |\n", t[0], t[1], t[2], t[3], t[4]);
    let _ = writeln!(s, "| ratio | paper | neurarm |");
    let _ = writeln!(s, "|---|---|---|");
    let _ = writeln!(s, "| sim NN / perfect | {:.2} | {:.3} |", p[1] / p[0], t[1] / t[0]);
    let _ = writeln!(s, "| sim none / perfect | {:.1} | {:.1} |", p[2] / p[0], t[2] / t[0]);
    let _ = writeln!(s, "| sim none / NN | {:.1} | {:.1} |", p[2] / p[1], t[2] / t[1]);
    let _ = writeln!(s, "| real NN / none | {:.2} | {:.3} |", p[3] / p[4], t[3] / t[4]);
    let _ = writeln!(s, "| real none / NN | {:.1} | {:.1} |\n", p[4] / p[3], t[4] / t[3]);
    let _ = writeln!(
        s,
        "Absolute values differ from the paper's: its robot's parameters and run length are not published. \
        The simulated arm starts on the reference with its velocity, so no start-up transient is counted. \
        The \"real\" arm is emulated: asymmetric friction with Stribeck break-away and (joints 2, 3) viscous friction \
        falling with speed, measurement noise and 16-bit encoders; its NN was trained on data measured on it.\n"
    );
    let _ = writeln!(s, "## Friction identification\n");
    let _ = writeln!(s, "Constant torques on one joint, the others held by the joint controller; steady velocity per level; \
        samples binned by {} rad/s over ±{} rad/s; mean torque per bin = one training pair, plus one at rest (0 rad/s, the midpoint of the two breakaway torques; see `rest_pair`). Data: `data/friction_*_joint*.csv`; nets: `nets/friction_*.json`.\n", settings.bin_width, settings.max_velocity);
    let _ = writeln!(s, "| joint | sim levels | sim pairs | real levels | real pairs |");
    let _ = writeln!(s, "|---|---|---|---|---|");
    for j in 0..4 {
        let (a, b) = r.friction_counts.get(j).copied().unwrap_or_default();
        let (c, d) = r.friction_counts.get(4 + j).copied().unwrap_or_default();
        let _ = writeln!(s, "| {} | {a} | {b} | {c} | {d} |", j + 1);
    }
    let _ = writeln!(s, "\n## Gravity identification\n");
    let _ = writeln!(
        s,
        "Base turned 90°; {}⁴ grid = {} configurations, each passed slowly up and down by all joints ({} rad/s), \
        torques of the two passes averaged; the joints held on the moves by an inertia-scaled PD from the gravity-free rigid-body model \
        (see `gravity_sweep`). A 4-{}-4 net trained on them (`nets/gravity.json`).\n",
        settings.grid, r.gravity_pairs, GRAVITY_SWEEP_SPEED_RAD_S, settings.gravity_hidden
    );
    let _ = writeln!(s, "The procedure itself, checked against the true model: the largest difference between an averaged torque and the true gravity torque at the averaged angles is {:.2e} N·m (what remains of friction, Coriolis terms and lag).\n", r.gravity_pair_error);
    let _ = writeln!(
        s,
        "Error on {} random configurations (not grid points), as RMS per joint and as a share of the largest gravity torque ({:.2} N·m):\n",
        settings.gravity_test_points, r.gravity_max
    );
    let _ = writeln!(s, "| joint | RMS error [N·m] | share of max |");
    let _ = writeln!(s, "|---|---|---|");
    for (j, e) in r.gravity_rms.iter().enumerate() {
        let _ = writeln!(s, "| {} | {:.4} | {:.3} % |", j + 1, e, 100.0 * e / r.gravity_max);
    }
    let _ = writeln!(s, "\n## Gravity compensation in the joint-space loop\n");
    let _ = writeln!(
        s,
        "τ = τ_comp + K_p (q_d − q), K_p = {} N·m/rad, K_d = {}; the built-in target sequence (5 × 3 s). RMS of q_d − q [rad]:\n",
        settings.joint_kp, settings.joint_kd
    );
    let _ = writeln!(s, "| compensation | joint 1 | joint 2 | joint 3 | joint 4 |");
    let _ = writeln!(s, "|---|---|---|---|---|");
    for (name, e) in ["ideal", "NN", "none"].iter().zip(&r.joint_rms) {
        let cells: Vec<String> = e.iter().map(|x| format!("{x:.4}")).collect();
        let _ = writeln!(s, "| {name} | {} |", cells.join(" | "));
    }
    let _ = writeln!(s, "\nSettled error, mean |q_d − q| over the last 0.5 s of each segment [rad]:\n");
    let _ = writeln!(s, "| compensation | joint 1 | joint 2 | joint 3 | joint 4 |");
    let _ = writeln!(s, "|---|---|---|---|---|");
    for (name, e) in ["ideal", "NN", "none"].iter().zip(&r.joint_settled) {
        let cells: Vec<String> = e.iter().map(|x| format!("{x:.4}")).collect();
        let _ = writeln!(s, "| {name} | {} |", cells.join(" | "));
    }
    let _ = writeln!(s, "\nThe paper's K_p = 0.025 has no units; in N·m/rad it would move no joint against its Coulomb friction \
        (0.3–1.5 N·m needs an error of 12–60 rad), so this run uses {} N·m/rad, with a small K_d = {} N·m·s/rad: with P alone the loop rings for seconds after each target step (damped only by friction).\n", settings.joint_kp, settings.joint_kd);
    let _ = writeln!(
        s,
        "## Figures\n\n![friction](friction.png)\n\n![tracking](tracking.png)\n\n![gravity compensation](gravity_compensation.png)\n"
    );
    let _ = writeln!(s, "## Time per stage\n");
    for (name, secs) in &r.timings {
        let _ = writeln!(s, "- {name}: {secs:.1} s");
    }
    s
}

/// The figures: friction data with the nets (Figs. 6/7), tracking (Figs. 9/10), joint runs
/// (Figs. 11/13/14).
fn write_plots(out: &Path, binned: &[Vec<Vec<FrictionPair>>; 2], nets: &[WeightsFile], runs: &[LoopRun]) -> Result<(), String> {
    use crate::report::plot::{write_png, Panel, Series, Style};
    let mut panels = Vec::new();
    for (k, tag) in ["simulated", "emulated real"].iter().enumerate() {
        for j in 0..4 {
            let net = nets[4 * k + j].network()?;
            let curve: Vec<(f64, f64)> = (-500..=500).map(|i| i as f64 * 0.01).map(|v| (v, net.evaluate(&[v])[0])).collect();
            panels.push(Panel {
                title: format!("joint {} ({tag})", j + 1),
                x_label: "qd [rad/s]".into(),
                y_label: "τ [N·m]".into(),
                series: vec![
                    Series {
                        name: "binned data".into(),
                        points: binned[k][j].iter().map(|&(v, t, _)| (v, t)).collect(),
                        style: Style::Points,
                    },
                    Series { name: "net".into(), points: curve, style: Style::Line },
                ],
            });
        }
    }
    write_png(&out.join("friction.png"), "Friction: identified pairs and trained nets", &panels, 4)?;
    let xy = |r: &LoopRun, a: &str, b: &str| -> Vec<(f64, f64)> {
        r.column(a).unwrap_or_default().into_iter().zip(r.column(b).unwrap_or_default()).collect()
    };
    let err = |r: &LoopRun| -> Vec<(f64, f64)> {
        let (t, ex, ey) = (
            r.column("time").unwrap_or_default(),
            r.column("ctl.error_x").unwrap_or_default(),
            r.column("ctl.error_y").unwrap_or_default(),
        );
        t.iter().zip(ex.iter().zip(&ey)).map(|(t, (a, b))| (*t, 1e3 * (a * a + b * b).sqrt())).collect()
    };
    let names = ["perfect", "NN", "none", "real NN", "real none"];
    let styles = [Style::Dashed, Style::Line, Style::Line, Style::Line, Style::Line];
    let panels = vec![
        Panel {
            title: "end-effector path (simulated)".into(),
            x_label: "x [m]".into(),
            y_label: "y [m]".into(),
            series: std::iter::once(Series {
                name: "reference".into(),
                points: xy(&runs[0], "ctl.x_ref", "ctl.y_ref"),
                style: Style::Dashed,
            })
            .chain((0..3).map(|k| Series { name: names[k].into(), points: xy(&runs[k], "arm.x", "arm.y"), style: Style::Line }))
            .collect(),
        },
        Panel {
            title: "tracking error |x_d − x|".into(),
            x_label: "t [s]".into(),
            y_label: "error [mm]".into(),
            series: (0..5).map(|k| Series { name: names[k].into(), points: err(&runs[k]), style: styles[k] }).collect(),
        },
    ];
    write_png(&out.join("tracking.png"), "Task-space tracking with friction compensation (Table 1)", &panels, 1)?;
    let mut panels = Vec::new();
    for j in 1..=4 {
        let t = runs[5].column("time").unwrap_or_default();
        let mut series = vec![Series {
            name: "target".into(),
            points: t.iter().copied().zip(runs[5].column(&format!("ctl.q_target_{j}")).unwrap_or_default()).collect(),
            style: Style::Dashed,
        }];
        for (k, name) in ["ideal", "NN", "none"].iter().enumerate() {
            let r = &runs[5 + k];
            series.push(Series {
                name: (*name).into(),
                points: r.column("time").unwrap_or_default().into_iter().zip(r.column(&format!("arm.q_{j}")).unwrap_or_default()).collect(),
                style: Style::Line,
            });
        }
        panels.push(Panel { title: format!("joint {j}"), x_label: "t [s]".into(), y_label: "q [rad]".into(), series });
    }
    write_png(&out.join("gravity_compensation.png"), "Joint-space P control with gravity compensation", &panels, 2)
}
