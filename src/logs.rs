//! From a robot's logs to a compensator FMU: the files of `neurarm identify` (pairs as CSV, the
//! verdicts as JSON, a summary in words) and the whole path of `neurarm compensator`.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use serde::Serialize;

use crate::experiments::{train_friction_net, train_gravity_net, Settings};
use crate::export::export_fmu_for;
use crate::identify::{
    identify_friction_log, identify_gravity_log, FrictionCurve, FrictionIdentification, FrictionOptions, FrictionPair, GravityCorrection,
    GravityIdentification, GravityOptions, LogColumns, RobotLog, Verdict,
};
use crate::table::{header_cell, write_atomic, write_text_atomic, NumericTable};
use neurarm_models::{FmuSpec, ModelSpec, NnCompensatorSpec};
use neurarm_nn::{EpochInfo, InputEncoding};
use neurarm_physics::arm::ArmParams;

/// Writes joint `joint`'s (1-based) friction pairs: `qd_J [rad/s]`, `tau_friction_J [N.m]`,
/// `samples`, and, when `path` is a file, the identification's verdicts as JSON beside them
/// (`.json`); returns the JSON's path, or `None` when the pairs went to standard output, a
/// device or a FIFO (see [`crate::output`]), which have no "beside".
pub fn write_friction_pairs(path: &Path, joint: usize, found: &FrictionIdentification) -> Result<Option<PathBuf>> {
    let names = vec![header_cell(&format!("qd_{joint}"), "rad/s"), header_cell(&format!("tau_friction_{joint}"), "N.m"), "samples".into()];
    let json = serde_json::to_string_pretty(&FrictionFile { joint, identification: found })?;
    let report = write_report_beside(path, &json)?;
    write_atomic(path, &names, found.pairs.iter().map(|p| vec![p.0, p.1, p.2 as f64]))
        .with_context(|| format!("writing {}", crate::output::describe(path)))?;
    Ok(report)
}

/// Writes `json` to the report beside the pairs `path` when `path` is a file; returns its path.
fn write_report_beside(path: &Path, json: &str) -> Result<Option<PathBuf>> {
    let destination = crate::output::Destination::of(path).with_context(|| path.display().to_string())?;
    if !destination.is_file() {
        return Ok(None);
    }
    let report = report_path(path)?;
    write_text_atomic(&report, json).with_context(|| format!("writing {}", report.display()))?;
    Ok(Some(report))
}

#[derive(Serialize)]
struct FrictionFile<'a> {
    joint: usize,
    identification: &'a FrictionIdentification,
}

/// The JSON report beside a pairs file: same name, `.json`.
pub fn report_path(pairs: &Path) -> Result<PathBuf> {
    let report = pairs.with_extension("json");
    if report == pairs {
        bail!("{}: give the pairs a .csv name (the report goes to a .json beside it)", pairs.display());
    }
    Ok(report)
}

/// Reads friction pairs written by [`write_friction_pairs`] (any file with `qd_J` and
/// `tau_friction_J` or `tau_J` columns): (joint, pairs by speed).
pub fn read_friction_pairs(path: &Path) -> Result<(usize, Vec<FrictionPair>)> {
    let table = NumericTable::read(path, &[])?;
    let speed = table
        .names
        .iter()
        .find_map(|n| n.strip_prefix("qd_").and_then(|j| j.parse::<usize>().ok()))
        .with_context(|| format!("{}: no speed column qd_J (the header has: {})", path.display(), table.names.join(", ")))?;
    let torque = [format!("tau_friction_{speed}"), format!("tau_{speed}")]
        .into_iter()
        .find(|n| table.column(n).is_some())
        .with_context(|| format!("{}: no torque column tau_friction_{speed} for qd_{speed}", path.display()))?;
    let (v, t) = (table.column(&format!("qd_{speed}")).expect("found"), table.column(&torque).expect("found"));
    let mut pairs: Vec<FrictionPair> = v.iter().zip(t).map(|(&v, &t)| (v, t, 1)).collect();
    pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok((speed, pairs))
}

/// What was kept and rejected, level by level, in words.
pub fn friction_summary(joint: usize, found: &FrictionIdentification) -> String {
    let mut text = String::new();
    for (k, l) in found.levels.iter().enumerate() {
        let mark = if l.verdict == Verdict::Kept { "kept" } else { "----" };
        text += &format!(
            "joint {joint} level {:>3} (t {:>8.2}–{:>8.2} s, line {:>7}): tau {:>+8.4} N·m, speed {:>+8.4} rad/s, drift {:.4} (limit {:.4}), spread {:.4} rad/s: {mark} {}\n",
            k + 1,
            l.start_s,
            l.end_s,
            l.line,
            l.torque_nm,
            l.speed_rad_s,
            l.drift_rad_s,
            l.drift_limit_rad_s,
            l.spread_rad_s,
            l.verdict.reason()
        );
    }
    let rejected = found.levels.iter().filter(|l| !matches!(l.verdict, Verdict::Kept | Verdict::AtRest | Verdict::NoTorque)).count();
    text += &format!(
        "joint {joint}: {} levels kept, {} at rest, {rejected} rejected ({} rows of varying torque, the joint under control, ignored); {} pairs",
        found.kept(),
        found.levels.iter().filter(|l| l.verdict == Verdict::AtRest).count(),
        found.ignored_rows,
        found.pairs.len()
    );
    match &found.rest {
        Some(r) => {
            text += &format!(
                ", the pair at rest {:+.4} N·m (midpoint of {:+.4} and {:+.4} N·m, the largest torques that left the joint at rest)\n",
                r.torque_nm, r.positive_nm, r.negative_nm
            )
        }
        None => text += "; no pair at rest: the log has no breakaway probe that left the joint at rest in both directions\n",
    }
    text
}

/// Writes gravity pairs: `q_i [rad]`, `tau_gravity_i [N.m]` (corrected), `tau_plain_i [N.m]` (the
/// plain average), and, when `path` is a file, the poses' verdicts as JSON beside them; returns
/// the JSON's path as [`write_friction_pairs`] does.
pub fn write_gravity_pairs(path: &Path, found: &GravityIdentification) -> Result<Option<PathBuf>> {
    let n = found.pairs.first().map_or(0, |p| p.q.len());
    let mut names: Vec<String> = (1..=n).map(|i| header_cell(&format!("q_{i}"), "rad")).collect();
    names.extend((1..=n).map(|i| header_cell(&format!("tau_gravity_{i}"), "N.m")));
    names.extend((1..=n).map(|i| header_cell(&format!("tau_plain_{i}"), "N.m")));
    let json = serde_json::to_string_pretty(found)?;
    let report = write_report_beside(path, &json)?;
    write_atomic(path, &names, found.pairs.iter().map(|p| [p.q.clone(), p.torque.clone(), p.torque_uncorrected.clone()].concat()))
        .with_context(|| format!("writing {}", crate::output::describe(path)))?;
    Ok(report)
}

/// What became of the poses, in words.
pub fn gravity_summary(found: &GravityIdentification) -> String {
    let mut text = String::new();
    for p in found.poses.iter().filter(|p| p.refused.is_some()) {
        let q: Vec<String> = p.q.iter().map(|v| format!("{v:.3}")).collect();
        text += &format!("pose at ({}) rad, line {}: refused, {}\n", q.join(", "), p.line, p.refused.as_deref().unwrap_or(""));
    }
    text += &format!(
        "{} passes, {} poses found, {} pairs kept, {} refused\n",
        found.passes,
        found.poses.len(),
        found.pairs.len(),
        found.poses.len() - found.pairs.len()
    );
    text
}

/// Hidden neurons of a link-angle gravity net for `pairs` pairs of `joints` joints: the paper's 25
/// at most, and no more weights than half the training part's target values (70 % of the pairs
/// × joints), at least 3. A few dozen poses cannot fit 25 neurons' 250 weights: they are learnt
/// exactly and validate badly (52 pairs: validation MSE 0.26 N²m² with 25, 1e-3 with 5).
pub fn gravity_hidden(pairs: usize, joints: usize) -> usize {
    let per_neuron = 2 * joints + joints + 1;
    ((0.7 * pairs as f64 * joints as f64 / (2.0 * per_neuron as f64)).floor() as usize).clamp(3, 25)
}

/// The inputs of [`compensator_from_logs`].
#[derive(Clone, Debug)]
pub struct CompensatorJob {
    /// Log of the friction plan (every joint's runs).
    pub friction_log: PathBuf,
    /// Log of the gravity plan, if gravity is to be compensated.
    pub gravity_log: Option<PathBuf>,
    /// Column names of both logs.
    pub columns: LogColumns,
    /// How friction levels are judged.
    pub friction: FrictionOptions,
    /// How gravity passes are found.
    pub gravity: GravityOptions,
    /// A rigid-body model of the arm, to take the velocity terms out of the gravity passes.
    pub model: Option<ArmParams>,
    /// Folder for every intermediate file (pairs, reports, nets).
    pub work: PathBuf,
    /// The FMU to write.
    pub output: PathBuf,
    /// Its model identifier.
    pub identifier: String,
    /// Seed of the trainings.
    pub seed: u64,
    /// Platforms the FMU carries: `None` for every one built (see [`crate::export::fmu_binaries`]).
    pub platforms: Option<Vec<String>>,
}

/// What [`compensator_from_logs`] made.
#[derive(Clone, Debug, Serialize)]
pub struct CompensatorSummary {
    /// Joints.
    pub joints: usize,
    /// Friction pairs per joint.
    pub friction_pairs: Vec<usize>,
    /// Gravity pairs.
    pub gravity_pairs: Option<usize>,
    /// Every file written, the FMU last.
    pub files: Vec<PathBuf>,
}

/// Identifies, trains and exports: friction pairs and a net per joint from the friction log,
/// gravity pairs (the friction pairs' curves and the model's velocity terms taken out) and the
/// periodic link-angle net from the gravity log, then the `NnCompensator` FMU. Every file but the
/// FMU goes to `work`. Nothing is written to `output` unless everything succeeded. `say` gets
/// each step's summary line, `on_epoch` every epoch of the gravity net's fit (the long one).
pub fn compensator_from_logs(
    job: &CompensatorJob,
    say: &mut dyn FnMut(&str),
    on_epoch: &mut dyn FnMut(&EpochInfo<'_>),
) -> Result<CompensatorSummary> {
    job.columns.check()?;
    std::fs::create_dir_all(&job.work).with_context(|| job.work.display().to_string())?;
    let probe = RobotLog::read_all(&job.friction_log, &job.columns, None)?;
    let n = probe.joints.len();
    if let Some(model) = &job.model {
        if model.dof() != n {
            bail!("{}: the log has {n} joints, the arm has {}", job.friction_log.display(), model.dof());
        }
    }
    let mut written = Written::default();
    let mut curves = Vec::new();
    let mut friction_pairs = Vec::new();
    for joint in 1..=n {
        let pairs = friction_net_from_log(job, &probe, joint, &mut written, say)?;
        friction_pairs.push(pairs.len());
        curves.push(FrictionCurve::new(&pairs));
    }
    let gravity_pairs = match &job.gravity_log {
        Some(log) => Some(gravity_net_from_log(job, log, n, &curves, &mut written, say, on_epoch)?),
        None => None,
    };
    let spec = FmuSpec {
        identifier: job.identifier.clone(),
        model: ModelSpec::NnCompensator(NnCompensatorSpec::of_nets(
            n,
            (1..=n).map(|i| format!("friction_{i}.json")).collect(),
            gravity_pairs.map(|_| "gravity.json".to_owned()),
        )),
    };
    export_fmu_for(&spec, &written.sources, &job.output, job.platforms.as_deref())?;
    written.files.push(job.output.clone());
    Ok(CompensatorSummary { joints: n, friction_pairs, gravity_pairs, files: written.files })
}

/// What the steps of [`compensator_from_logs`] wrote: every file in order, and the nets the
/// FMU carries as `(resource name, file)`.
#[derive(Default)]
struct Written {
    files: Vec<PathBuf>,
    sources: Vec<(String, PathBuf)>,
}

impl Written {
    /// Writes the net `net` to `name` in `work`, as a source of the FMU.
    fn net(&mut self, work: &Path, name: &str, net: &neurarm_nn::WeightsFile) -> Result<()> {
        let path = work.join(name);
        write_text_atomic(&path, &net.to_json()).with_context(|| format!("writing {}", path.display()))?;
        self.files.push(path.clone());
        self.sources.push((name.to_owned(), path));
        Ok(())
    }
}

/// Joint `joint`'s friction pairs from the friction log `probe`, written with their report and
/// net (`friction_J.csv`, `.json`); returns the pairs.
fn friction_net_from_log(
    job: &CompensatorJob,
    probe: &RobotLog,
    joint: usize,
    written: &mut Written,
    say: &mut dyn FnMut(&str),
) -> Result<Vec<FrictionPair>> {
    let found = identify_friction_log(probe, joint, &job.friction).context("friction")?;
    say(friction_summary(joint, &found).lines().last().unwrap_or(""));
    if found.pairs.len() < 4 {
        bail!("friction of joint {joint}: only {} pairs from {}", found.pairs.len(), job.friction_log.display());
    }
    let pairs_path = job.work.join(format!("friction_{joint}.csv"));
    let report = write_friction_pairs(&pairs_path, joint, &found)?;
    written.files.push(pairs_path);
    written.files.extend(report);
    say(&format!("training the friction net of joint {joint} on {} pairs", found.pairs.len()));
    // `train_friction_net` (the experiments') says what failed in words.
    let net = train_friction_net(joint - 1, &found.pairs, found.speed_noise_rad_s(), job.seed)?;
    written.net(&job.work, &format!("friction_{joint}.json"), &net)?;
    Ok(found.pairs)
}

/// The gravity pairs of the gravity log `log` of `n` joints, `curves` (each joint's friction)
/// and the model's velocity terms taken out, written with their report and the link-angle net
/// (`gravity.csv`, `.json`); returns the number of pairs.
fn gravity_net_from_log(
    job: &CompensatorJob,
    log: &Path,
    n: usize,
    curves: &[FrictionCurve],
    written: &mut Written,
    say: &mut dyn FnMut(&str),
    on_epoch: &mut dyn FnMut(&EpochInfo<'_>),
) -> Result<usize> {
    let log = RobotLog::read_all(log, &job.columns, Some(n))?;
    let rigid = job.model.as_ref().map(|m| m.clone().with_base_angle(0.0).frictionless());
    let correction = GravityCorrection { friction: curves, model: rigid.as_ref() };
    let found = identify_gravity_log(&log, &job.gravity, &correction).context("gravity")?;
    say(gravity_summary(&found).lines().last().unwrap_or(""));
    let pairs_path = job.work.join("gravity.csv");
    let report = write_gravity_pairs(&pairs_path, &found)?;
    written.files.push(pairs_path);
    written.files.extend(report);
    let pairs: Vec<(Vec<f64>, Vec<f64>)> = found.pairs.iter().map(|p| (p.q.clone(), p.torque.clone())).collect();
    if pairs.len() < 10 {
        bail!("gravity: only {} pairs from {}; the net needs at least 10 poses", pairs.len(), log.path.display());
    }
    let hidden = gravity_hidden(pairs.len(), n);
    say(&format!("training the gravity net ({hidden} hidden neurons) on {} pairs", pairs.len()));
    let settings = Settings { seed: job.seed, gravity_hidden: hidden, ..Settings::paper() };
    // `train_gravity_net` (the experiments') says what failed in words.
    let net = train_gravity_net(&pairs, InputEncoding::LinkAngles, &settings, on_epoch)?;
    written.net(&job.work, "gravity.json", &net)?;
    Ok(pairs.len())
}
