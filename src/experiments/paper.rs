//! `neurarm paper`: every experiment of the paper for one arm, end to end. [`run_paper`]
//! computes and returns a [`PaperRun`]; `crate::report` writes it.

use std::path::{Path, PathBuf};
use std::time::Instant;

use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;

use super::friction::FrictionCurve;
use super::friction::{friction_net_error, hold_gains, pair_error, FrictionNetError};
use super::gravity::{gravity_pair_error, GravityNetErrors};
use super::gravity_study::{gravity_study, GravityStudy};
use super::*;
use crate::table::{write_text_atomic, writing};
use neurarm_nn::{InputEncoding, WeightsFile};

/// The paper's Table 1 [m²]: sim perfect, sim NN, sim none, real NN, real none.
pub const PAPER_TABLE_1: [f64; 5] = [0.0014, 0.0016, 0.0248, 0.0071, 0.0291];

/// The closed loops of a run, in order: the five of Table 1, then the three joint-space ones.
pub const LOOPS: [&str; 8] = [
    "tracking_sim_perfect",
    "tracking_sim_nn",
    "tracking_sim_none",
    "tracking_real_nn",
    "tracking_real_none",
    "joint_ideal",
    "joint_nn",
    "joint_none",
];

/// The online-adaptation loops of a run, in order: friction drift, payload (each per case of
/// [`adaptation::CASES`]), then the steady run of the static and the adaptive net.
pub const ADAPTATION_LOOPS: [&str; 10] = [
    "drift_perfect",
    "drift_static",
    "drift_adaptive",
    "drift_none",
    "payload_perfect",
    "payload_static",
    "payload_adaptive",
    "payload_none",
    "steady_static",
    "steady_adaptive",
];

/// Loops beside Table 1 that say what bounds its ratios, each a Table 1 system with one change:
/// the simulated arm's true friction law scaled by 1 ∓ [`LAW_ERROR`], then by 1 ∓
/// [`FINE_LAW_ERROR`], as compensator (see [`LawSensitivity`]); the real arm's true law as
/// compensator, then the real arm's true law, NN and no compensation with the sensors' noise
/// off (see [`SensorLimit`]; the quiet ones only when the real arm has noise).
pub const DIAGNOSTIC_LOOPS: [&str; 8] = [
    "tracking_sim_perfect_low",
    "tracking_sim_perfect_high",
    "tracking_sim_perfect_fine_low",
    "tracking_sim_perfect_fine_high",
    "tracking_real_perfect",
    "tracking_real_perfect_quiet",
    "tracking_real_nn_quiet",
    "tracking_real_none_quiet",
];

/// The relative error of the true friction law in the [`LawSensitivity`] loops: 1 %.
pub const LAW_ERROR: f64 = 0.01;

/// The smaller relative error of [`Table1::sim_law_sensitivity_fine`]: 0.1 %, below what
/// nets identified from binned pairs reach at low speed. Where even this moves NN/perfect by
/// more than the target's margin, the ratio cannot rank compensators on that arm: on the
/// 6-joint example (stick–slip on a redundant arm) the law 0.1 % low gave 1.64 × the exact
/// law's MSE, 0.1 % high 0.99.
pub const FINE_LAW_ERROR: f64 = 0.001;

/// How much sim NN/perfect can tell: the simulated arm tracked with its own true friction law
/// off by ∓[`LAW_ERROR`] (every joint's Coulomb and viscous parts scaled by 1 ∓ it), MSE over
/// the perfect run's (Table 1's measured MSEs).
///
/// Where even the true law 1 % off tracks several times worse than the exact one (a perfect
/// run with µm errors), NN/perfect ≤ 1.10 asks more of the nets than 1 % accuracy; where the
/// two scaled runs scatter around 1 (stick–slip), a ratio near 1 is within that scatter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct LawSensitivity {
    /// The relative error applied [1].
    pub law_error: f64,
    /// The law scaled by 1 − `law_error`: MSE over perfect's (`None` if the loop failed, see
    /// [`Table1::diagnostic_failures`]).
    pub low_over_perfect: Option<f64>,
    /// The law scaled by 1 + `law_error`: MSE over perfect's (`None` if the loop failed).
    pub high_over_perfect: Option<f64>,
}

impl LawSensitivity {
    /// How far the scaled laws moved the ratio from 1, either way: the larger of |low − 1| and
    /// |high − 1| [1] (`None` unless both loops ran). Above the target's margin (0.10 for
    /// NN/perfect ≤ 1.10), a compensator as close to the law as `law_error` may miss the target
    /// by the law's own scatter.
    pub fn largest_move(&self) -> Option<f64> {
        Some((self.low_over_perfect? - 1.0).abs().max((self.high_over_perfect? - 1.0).abs()))
    }
}

/// What the real arm's sensors cost its friction compensation, from the [`DIAGNOSTIC_LOOPS`]; all
/// MSEs from the true positions [m²], ratios over the uncompensated run of the same sensors.
///
/// A compensator reads the measured speed. Where that carries noise of the order of the speeds
/// at which a joint reverses, a friction law with a step at zero speed switches on the noise,
/// so even the arm's true law can track worse than no compensation: then real NN/none is
/// bounded by the sensors, not by the nets. Quiet runs keep the encoders' quantisation and
/// switch off only the noise (`q_noise_std`, `qd_noise_std` set to 0).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SensorLimit {
    /// The real arm's true friction law fed the same measured speed as the NN [m²] (`None` if
    /// the loop failed, see [`Table1::diagnostic_failures`]).
    pub perfect_mse_m2: Option<f64>,
    /// `perfect_mse_m2` over the uncompensated run's (Table 1's real none, true positions).
    pub perfect_over_none: Option<f64>,
    /// With the noise off, if the real arm has any and all three loops ran: true law, NN,
    /// none [m²].
    pub quiet_mse_m2: Option<[f64; 3]>,
    /// With the noise off: NN / none.
    pub quiet_nn_over_none: Option<f64>,
    /// With the noise off: true law / none.
    pub quiet_perfect_over_none: Option<f64>,
}

/// One figure per case of Table 1 [unit as named by the field holding it].
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Cases {
    /// Simulated arm, perfect (true-model) friction compensation.
    pub sim_perfect: f64,
    /// Simulated arm, NN friction compensation.
    pub sim_nn: f64,
    /// Simulated arm, no friction compensation.
    pub sim_none: f64,
    /// Real arm, NN friction compensation (net trained on the real arm's data).
    pub real_nn: f64,
    /// Real arm, no friction compensation.
    pub real_none: f64,
}

impl Cases {
    /// From the five values in Table 1's order.
    pub fn from_array(v: [f64; 5]) -> Self {
        Self { sim_perfect: v[0], sim_nn: v[1], sim_none: v[2], real_nn: v[3], real_none: v[4] }
    }

    /// The five values in Table 1's order.
    pub fn to_array(&self) -> [f64; 5] {
        [self.sim_perfect, self.sim_nn, self.sim_none, self.real_nn, self.real_none]
    }
}

/// Table 1 and what it takes to read it.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Table1 {
    /// MSE from the measured position (the controller's error), as the paper [m²].
    pub mse_m2: Cases,
    /// MSE from the arm's true position [m²].
    pub true_mse_m2: Cases,
    /// RMS distance to the true position [mm].
    pub rms_mm: Cases,
    /// Sum of the squared distances over the samples, measured [m²].
    pub sum_m2: Cases,
    /// Samples per run.
    pub samples: usize,
    /// Share of the samples with some joint at rest (see
    /// [`super::tracking::TrackingErrors::resting_share`]).
    pub resting_share: Cases,
    /// Ratios of the measured MSEs.
    pub ratios: Ratios,
    /// How sim NN/perfect reacts to a true law 1 % off.
    pub sim_law_sensitivity: LawSensitivity,
    /// How it reacts to a true law 0.1 % off ([`FINE_LAW_ERROR`]).
    pub sim_law_sensitivity_fine: LawSensitivity,
    /// What the real arm's sensors cost its compensation.
    pub real_sensors: SensorLimit,
    /// The [`DIAGNOSTIC_LOOPS`] that failed, each "name: why" (a loop that goes unstable, e.g.
    /// the real arm's true law on a quiet but quantised speed): their figures are missing, the
    /// rest of the run stands.
    pub diagnostic_failures: Vec<String>,
    /// The paper's values [m²].
    pub paper_m2: Cases,
    /// Geometric mean over the five cases of paper / ours (measured MSE).
    pub paper_over_ours: f64,
}

/// The ratios of Table 1 the paper's claims rest on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Ratios {
    /// sim NN / sim perfect (the paper: 1.14).
    pub sim_nn_over_perfect: f64,
    /// sim none / sim perfect (the paper: 17.7).
    pub sim_none_over_perfect: f64,
    /// sim none / sim NN (the paper: 15.5).
    pub sim_none_over_nn: f64,
    /// real NN / real none (the paper: 0.24).
    pub real_nn_over_none: f64,
}

impl Ratios {
    /// The ratios of `m`.
    pub fn of(m: &Cases) -> Self {
        Self {
            sim_nn_over_perfect: m.sim_nn / m.sim_perfect,
            sim_none_over_perfect: m.sim_none / m.sim_perfect,
            sim_none_over_nn: m.sim_none / m.sim_nn,
            real_nn_over_none: m.real_nn / m.real_none,
        }
    }
}

/// The friction identification of one joint of one arm.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrictionJoint {
    /// "sim" or "real".
    pub arm: String,
    /// Joint, from 1.
    pub joint: usize,
    /// Torque levels that moved the joint, both directions.
    pub levels: usize,
    /// Training pairs (bins plus the pair at rest).
    pub pairs: usize,
    /// Largest |pair − true law| over the moving pairs [N·m], and where [rad/s].
    pub pair_error_nm: f64,
    /// Velocity of that largest pair error [rad/s].
    pub pair_error_at_rad_s: f64,
    /// The trained net against the true law over 0.2 ≤ |q̇| ≤ the top speed.
    pub net_error: FrictionNetError,
    /// `net_error.rms_nm` as a share of the joint's largest friction torque.
    pub net_error_share: f64,
    /// The trained net against the true law at low speed, [`LOW_SPEED_RANGE_RAD_S`], where
    /// it crosses the Coulomb step.
    pub low_speed_error: FrictionNetError,
    /// The measured speed's noise the identification found (a standard deviation) [rad/s].
    pub speed_noise_rad_s: f64,
    /// How the net sees the speed: "log_speed" when it was trained on the Coulomb step,
    /// "raw" (the paper's) when the noise left no room below the lowest pairs (see
    /// [`crate::experiments::train_friction_net`]).
    pub encoding: String,
}

/// The low speeds a friction net is also judged over [rad/s]: from 5 mrad/s (a few step
/// widths of a noiseless arm's net) to where the pairs' judging range starts.
pub const LOW_SPEED_RANGE_RAD_S: (f64, f64) = (0.005, 0.2);

/// The gravity identification.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct GravityResults {
    /// The design of the poses.
    pub design: GravityDesign,
    /// Whether the design is the default for the joint count (not given by the user).
    pub default_design: bool,
    /// Poses measured.
    pub pairs: usize,
    /// Pass pairs measured again because a joint was not steady in a measuring window.
    pub repeated_passes: usize,
    /// Poses left out because their passes stayed unsteady (angles in [0, 2π) [rad]).
    pub dropped_poses: Vec<Vec<f64>>,
    /// Whether each pass had the identified friction taken out before averaging.
    pub friction_correction: bool,
    /// Largest |averaged torque − true gravity at the averaged angles| of the pairs trained
    /// on [N·m].
    pub pair_error_nm: f64,
    /// The same for the plain average of the passes (the paper's procedure) [N·m].
    pub pair_error_uncorrected_nm: f64,
    /// Hidden neurons of the net.
    pub hidden: usize,
    /// How the compensator's gravity net sees the angles.
    pub encoding: InputEncoding,
    /// The compensator's net against the true gravity on random poses.
    pub net: GravityNetErrors,
    /// Error against the number of measured poses (with `--gravity-study`).
    pub study: Option<GravityStudy>,
    /// The paper's raw-angle net trained on the same pairs, for comparison (when the
    /// compensator's net is a periodic one).
    pub raw_net: Option<GravityNetErrors>,
    /// RMS error per joint as a share of the largest gravity torque of any joint (the paper's
    /// reading), over the trained span for a raw net and the whole turn for a periodic one;
    /// see `net` for each joint's own share.
    pub net_error_share: Vec<f64>,
}

/// The joint-space loop with gravity compensation.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct JointLoopResults {
    /// Position gain per joint [N·m/rad].
    pub kp: Vec<f64>,
    /// Velocity gain per joint [N·m·s/rad].
    pub kd: Vec<f64>,
    /// RMS of q_target − q per joint [rad]: ideal, NN, none.
    pub rms_rad: [Vec<f64>; 3],
    /// Settled error per joint [rad] (see [`joint_settled_errors`]): ideal, NN, none.
    pub settled_rad: [Vec<f64>; 3],
}

/// The arm, the reference and the gains of a run.
#[derive(Clone, Debug, Serialize)]
pub struct RunSetup {
    /// Joints.
    pub joints: usize,
    /// Reach: the sum of the link lengths [m].
    pub reach_m: f64,
    /// The nominal arm.
    pub nominal: ArmConfig,
    /// The real arm.
    pub real: ArmConfig,
    /// Where the real arm comes from.
    pub real_origin: RealOrigin,
    /// Centre of the reference [m].
    pub reference_centre_m: [f64; 2],
    /// Scale of the reference (1 = the paper's 0.4 m × 0.3 m).
    pub reference_scale: f64,
    /// Nearest and farthest distance of the reference from the first joint [m].
    pub reference_distance_m: [f64; 2],
    /// [`gravity_scale`] of the arm.
    pub gravity_scale: f64,
    /// (K_p [N·m/rad], K_d [N·m·s/rad]) per joint of the hold in the friction runs.
    pub hold_gains: Vec<[f64; 2]>,
}

/// Every figure of a run: what `results.json` holds and `report.md` shows.
#[derive(Clone, Debug, Serialize)]
pub struct PaperResults {
    /// neurarm's version.
    pub neurarm_version: String,
    /// The settings of the run.
    pub settings: Settings,
    /// The arm and the gains.
    pub setup: RunSetup,
    /// Table 1.
    pub table_1: Table1,
    /// Friction identification, sim joints then real joints.
    pub friction: Vec<FrictionJoint>,
    /// Gravity identification.
    pub gravity: GravityResults,
    /// The joint-space loop.
    pub joint_loop: JointLoopResults,
    /// Online adaptation: friction drift, payload, steady operation.
    pub adaptation: adaptation::AdaptationResults,
    /// Seconds per stage.
    pub timings_s: Vec<(String, f64)>,
    /// Seconds in all.
    pub total_s: f64,
}

/// What a run computed: the figures and the data the report plots and writes.
#[derive(Clone, Debug)]
pub struct PaperRun {
    /// Every figure.
    pub results: PaperResults,
    /// Binned friction pairs per joint: simulated arm, then real arm.
    pub friction_pairs: [Vec<Vec<FrictionPair>>; 2],
    /// Friction nets: the simulated arm's joints, then the real arm's.
    pub friction_nets: Vec<WeightsFile>,
    /// The gravity pairs.
    pub gravity_pairs: Vec<GravityPair>,
    /// The closed-loop runs, in the order of [`LOOPS`].
    pub loops: Vec<LoopRun>,
    /// The adaptation runs, in the order of [`ADAPTATION_LOOPS`].
    pub adaptation_loops: Vec<LoopRun>,
    /// The arms.
    pub arms: Arms,
}

fn bar(len: u64, what: &str) -> ProgressBar {
    let b = if std::io::IsTerminal::is_terminal(&std::io::stderr()) { ProgressBar::new(len) } else { ProgressBar::hidden() };
    b.set_style(ProgressStyle::with_template("{prefix:>28} {bar:30} {pos}/{len} {elapsed}").expect("valid template"));
    b.set_prefix(what.to_owned());
    b
}

/// Runs every experiment on `arms` with `settings`, then has `crate::report` write the run;
/// `log` gets one line per stage. Everything is written into a staging folder beside `out`
/// that replaces `out` only when the whole run has succeeded, so a failed run leaves no
/// folder that looks finished (and an earlier run in `out` untouched). `out` must be absent,
/// empty, or an earlier run's folder (it has a `results.json`).
pub fn run_paper(out: &Path, arms: &Arms, settings: &Settings, log: &mut dyn FnMut(&str)) -> Result<PaperRun, String> {
    settings.design_for(arms.joints()).check(arms.joints())?;
    if crate::output::is_stdout(out) {
        return Err("the run is a folder (report, data, nets, FMUs, plots): give the folder's name, not '-'".into());
    }
    // Through a symbolic link, the folder it points to is the one replaced: the link stays.
    let out = &crate::output::follow_links(out).map_err(|e| format!("{}: {e}", out.display()))?;
    if out.exists() && !out.is_dir() {
        return Err(format!("{} is not a folder: give a folder for the run", out.display()));
    }
    if out.exists() {
        let empty = std::fs::read_dir(out).map_err(|e| format!("{}: {e}", out.display()))?.next().is_none();
        if !empty && !out.join("results.json").is_file() {
            return Err(format!(
                "{} exists and is not the folder of an earlier run (no results.json): choose another output folder",
                out.display()
            ));
        }
    }
    let name = out.file_name().ok_or_else(|| format!("{}: not a folder name", out.display()))?.to_string_lossy().into_owned();
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&parent).map_err(|e| format!("{}: {e}", parent.display()))?;
    let staging = tempfile::Builder::new()
        .prefix(&format!(".{name}.partial-"))
        .tempdir_in(&parent)
        .map_err(|e| format!("cannot create a staging folder in {}: {e}", parent.display()))?;
    let run = compute(staging.path(), arms, settings, log)?;
    crate::report::write_report(staging.path(), &run)?;
    let staged = staging.keep();
    let finish = || -> Result<(), String> {
        if out.exists() {
            std::fs::remove_dir_all(out).map_err(|e| format!("removing the earlier run in {}: {e}", out.display()))?;
        }
        std::fs::rename(&staged, out).map_err(|e| format!("moving the finished run to {}: {e}", out.display()))
    };
    finish().inspect_err(|_| {
        let _ = std::fs::remove_dir_all(&staged);
    })?;
    Ok(run)
}

/// The experiments themselves, writing the FMUs, nets and loop files under `out`.
fn compute(out: &Path, arms: &Arms, settings: &Settings, log: &mut dyn FnMut(&str)) -> Result<PaperRun, String> {
    let started = Instant::now();
    let n = arms.joints();
    let mut timings: Vec<(String, f64)> = Vec::new();
    let mut stage = Instant::now();
    let mut lap = |name: &str, log: &mut dyn FnMut(&str)| {
        let s = stage.elapsed().as_secs_f64();
        log(&format!("{name}: {s:.1} s"));
        timings.push((name.to_owned(), s));
        stage = Instant::now();
    };
    let (fmu_dir, net_dir) = (out.join("fmu"), out.join("nets"));
    for d in [&fmu_dir, &net_dir] {
        std::fs::create_dir_all(d).map_err(|e| format!("{}: {e}", d.display()))?;
    }
    let fmus = build_fmus(&fmu_dir, arms, settings)?;
    let model = &arms.nominal.arm;
    lap("building FMUs", log);

    // Friction identification on both arms, every joint and direction in parallel; the hold
    // is tuned on the nominal model (all the user knows) for both.
    let tasks: Vec<(bool, usize, f64)> =
        [false, true].iter().flat_map(|&real| (0..n).flat_map(move |j| [(real, j, 1.0), (real, j, -1.0)])).collect();
    let b = bar(tasks.len() as u64, "friction identification");
    let runs = parallel(
        tasks.clone(),
        settings.threads,
        |(real, joint, dir)| {
            friction_run(if real { &fmus.arm_real } else { &fmus.arm }, &fmus.joint_controller, model, joint, dir, settings).map_err(|e| {
                let arm = if real { "real" } else { "simulated" };
                format!("friction identification, {arm} arm, joint {} driven {}: {e}", joint + 1, if dir > 0.0 { "+" } else { "−" })
            })
        },
        || b.inc(1),
    )?;
    b.finish_and_clear();
    let mut friction_pairs: [Vec<Vec<FrictionPair>>; 2] = [Vec::new(), Vec::new()];
    let mut levels_of = Vec::new();
    let mut speed_noise: [Vec<f64>; 2] = [Vec::new(), Vec::new()];
    for (k, real) in [false, true].into_iter().enumerate() {
        for joint in 0..n {
            let mine: Vec<&FrictionRun> = runs.iter().zip(&tasks).filter(|(_, t)| t.0 == real && t.1 == joint).map(|(r, _)| r).collect();
            let rigid = settings.friction_hold == FrictionHold::Rigid;
            let inertia = rigid.then(|| held_inertia(model, joint));
            let identified = pairs_of_runs(&mine, &run_options(settings, inertia));
            levels_of.push(identified.kept());
            speed_noise[k].push(identified.speed_noise_rad_s());
            let binned = identified.pairs;
            if binned.len() < 4 {
                return Err(format!(
                    "friction identification, {} arm, joint {}: only {} training pairs",
                    if real { "real" } else { "simulated" },
                    joint + 1,
                    binned.len()
                ));
            }
            friction_pairs[k].push(binned);
        }
    }
    lap("friction identification", log);
    let b = bar(2 * n as u64, "friction nets");
    let friction_nets = parallel(
        (0..2 * n).collect(),
        settings.threads,
        |i: usize| train_friction_net(i % n, &friction_pairs[i / n][i % n], speed_noise[i / n][i % n], settings.seed),
        || b.inc(1),
    )?;
    b.finish_and_clear();
    let mut friction_files: [Vec<(String, PathBuf)>; 2] = [Vec::new(), Vec::new()];
    let mut friction = Vec::new();
    for (i, net) in friction_nets.iter().enumerate() {
        let (k, joint) = (i / n, i % n);
        let tag = if k == 0 { "sim" } else { "real" };
        let name = format!("friction_{tag}_joint{}.json", joint + 1);
        let path = net_dir.join(&name);
        write_text_atomic(&path, &net.to_json()).map_err(writing(&path))?;
        friction_files[k].push((format!("friction_{}.json", joint + 1), path));
        let law = if k == 0 { &arms.nominal.arm.friction[joint] } else { &arms.real.arm.friction[joint] };
        let (pair_error_nm, pair_error_at_rad_s) = pair_error(&friction_pairs[k][joint], law);
        let net_error = friction_net_error(net, law, 0.2, settings.max_velocity)?;
        let low_speed_error = friction_net_error(net, law, LOW_SPEED_RANGE_RAD_S.0, LOW_SPEED_RANGE_RAD_S.1)?;
        friction.push(FrictionJoint {
            arm: tag.into(),
            joint: joint + 1,
            levels: levels_of[i],
            pairs: friction_pairs[k][joint].len(),
            pair_error_nm,
            pair_error_at_rad_s,
            net_error,
            net_error_share: net_error.share(),
            low_speed_error,
            speed_noise_rad_s: speed_noise[k][joint],
            encoding: net.encoding.name().into(),
        });
    }
    lap("training friction nets", log);

    // Gravity identification: the grid split between the workers.
    let design = settings.design_for(n);
    let (poses, span) = design_poses(design, n, settings.seed + 17);
    let b = bar(settings.threads.min(poses.len()) as u64, "gravity identification");
    let curves: Vec<FrictionCurve> = friction_pairs[0].iter().map(|p| FrictionCurve::new(p)).collect();
    let correction = settings.gravity_friction_correction.then_some(curves.as_slice());
    let wrap = matches!(design, GravityDesign::Sampled { .. });
    let sweep = measure_gravity(&fmus.arm, &fmus.joint_controller, model, &poses, wrap, correction, settings, &|| b.inc(1))?;
    b.finish_and_clear();
    let (gravity_pairs, uncorrected) = (sweep.pairs, sweep.pairs_uncorrected);
    let (repeated_passes, dropped_poses) = (sweep.repeated, sweep.dropped);
    lap("gravity identification", log);
    // The compensator's net and, beside a periodic one, the paper's raw-angle net on the same
    // pairs, trained in parallel.
    let mut encodings = vec![settings.gravity_encoding];
    if settings.gravity_encoding != InputEncoding::Raw {
        encodings.push(InputEncoding::Raw);
    }
    let b =
        bar((settings.gravity_epochs * encodings.len()) as u64, &format!("gravity nets ({n} angles, {} hidden)", settings.gravity_hidden));
    let mut nets =
        parallel(encodings, settings.threads, |encoding| train_gravity_net(&gravity_pairs, encoding, settings, &mut |_| b.inc(1)), || {})?;
    b.finish_and_clear();
    let raw_net = (nets.len() > 1).then(|| nets.remove(1));
    let gravity_net = nets.remove(0);
    let gravity_path = net_dir.join("gravity.json");
    write_text_atomic(&gravity_path, &gravity_net.to_json()).map_err(writing(&gravity_path))?;
    let net_errors = gravity_net_errors(&gravity_net, model, span, settings)?;
    let raw_errors = match &raw_net {
        Some(raw) => {
            let path = net_dir.join("gravity_raw.json");
            write_text_atomic(&path, &raw.to_json()).map_err(writing(&path))?;
            Some(gravity_net_errors(raw, model, span, settings)?)
        }
        None => None,
    };
    let mut gravity = GravityResults {
        design,
        default_design: settings.gravity_design.is_none(),
        pairs: gravity_pairs.len(),
        repeated_passes,
        dropped_poses,
        friction_correction: settings.gravity_friction_correction,
        pair_error_nm: gravity_pair_error(&gravity_pairs, model),
        pair_error_uncorrected_nm: gravity_pair_error(&uncorrected, model),
        hidden: settings.gravity_hidden,
        encoding: settings.gravity_encoding,
        net_error_share: {
            let region = net_errors.span.as_ref().unwrap_or(&net_errors.whole_turn);
            let largest = region.largest_torque_nm.iter().copied().fold(0.0, f64::max);
            region.rms_nm.iter().map(|e| e / largest).collect()
        },
        net: net_errors,
        raw_net: raw_errors,
        study: None,
    };
    lap("training gravity net", log);
    if let Some(largest) = settings.gravity_study {
        let b = bar(1, &format!("gravity study (up to {largest} poses)"));
        gravity.study = Some(gravity_study(&fmus.arm, &fmus.joint_controller, model, correction, largest, settings)?);
        b.finish_and_clear();
        lap("gravity study", log);
    }

    // The NN compensator FMUs: the full one (both nets) is the deliverable; the loops use
    // ones exported with only the part they compensate.
    let nn = |identifier: &str, friction: &[(String, PathBuf)], gravity: bool| {
        export_nn_compensator(
            &fmu_dir.join(format!("{identifier}.fmu")),
            identifier,
            n,
            friction,
            gravity.then_some(gravity_path.as_path()),
            settings.platforms.as_deref(),
        )
    };
    nn("NnCompensator", &friction_files[0], true)?;
    let nn_friction = nn("NnFrictionCompensator", &friction_files[0], false)?;
    let nn_real = nn("NnFrictionCompensatorReal", &friction_files[1], false)?;
    let nn_gravity = nn("NnGravityCompensator", &[], true)?;

    // Table 1 and the gravity-compensation runs as system files (paths relative to
    // out/systems) and SSP archives, run in parallel.
    let systems_dir = out.join("systems");
    std::fs::create_dir_all(&systems_dir).map_err(|e| format!("{}: {e}", systems_dir.display()))?;
    let rel = |p: &Path| Path::new("..").join(p.strip_prefix(out).unwrap_or(p));
    let (arm, arm_real) = (rel(&fmus.arm), rel(&fmus.arm_real));
    let (task, joint) = (rel(&fmus.task_controller), rel(&fmus.joint_controller));
    let start = tracking_start(model, &arms.placement)?;
    let tracking = |arm: &Path, comp: Option<PathBuf>| tracking_system(arm, &task, comp.as_deref(), &start, settings);
    let joint_gains = joint_loop_gains(model, settings);
    let joint_space = |comp: Option<PathBuf>| gravity_compensation_system(&arm, &joint, comp.as_deref(), &joint_gains, settings);
    let specs: Vec<SystemSpec> = vec![
        tracking(&arm, Some(rel(&fmus.ideal_friction))),
        tracking(&arm, Some(rel(&nn_friction))),
        tracking(&arm, None),
        tracking(&arm_real, Some(rel(&nn_real))),
        tracking(&arm_real, None),
        joint_space(Some(rel(&fmus.ideal_gravity))),
        joint_space(Some(rel(&nn_gravity))),
        joint_space(None),
    ];
    for (name, spec) in LOOPS.iter().zip(&specs) {
        write_loop_files(name, "", spec, &systems_dir, out)?;
    }
    let b = bar(specs.len() as u64, "closed loops");
    let tasks: Vec<(&str, SystemSpec)> = LOOPS.iter().copied().zip(specs).collect();
    let loops = parallel(
        tasks,
        settings.threads,
        |(name, spec)| {
            run_loop(&spec, &systems_dir).map_err(|e| {
                let hint = if name.starts_with("tracking") { "--tracking-gains" } else { "--joint-gains" };
                format!("loop {name}: {e} ({hint})")
            })
        },
        || b.inc(1),
    )?;
    b.finish_and_clear();
    let errors: Vec<TrackingErrors> = loops[..5].iter().map(tracking_errors).collect();
    let pick = |f: &dyn Fn(&TrackingErrors) -> f64| Cases::from_array([0, 1, 2, 3, 4].map(|k| f(&errors[k])));
    let mse = pick(&|e| e.measured_mse_m2);
    let paper = Cases::from_array(PAPER_TABLE_1);
    let log_ratio: f64 = (0..5).map(|k| (paper.to_array()[k] / mse.to_array()[k]).ln()).sum::<f64>() / 5.0;
    let table_1 = Table1 {
        mse_m2: mse,
        true_mse_m2: pick(&|e| e.true_mse_m2),
        rms_mm: pick(&|e| e.true_rms_mm),
        sum_m2: pick(&|e| e.measured_sum_m2),
        samples: errors[0].samples,
        resting_share: pick(&|e| e.resting_share),
        ratios: Ratios::of(&mse),
        sim_law_sensitivity: LawSensitivity::default(),
        sim_law_sensitivity_fine: LawSensitivity::default(),
        real_sensors: SensorLimit::default(),
        diagnostic_failures: Vec::new(),
        paper_m2: paper,
        paper_over_ours: log_ratio.exp(),
    };
    let joint_loop = JointLoopResults {
        kp: joint_gains.iter().map(|g| g.0).collect(),
        kd: joint_gains.iter().map(|g| g.1).collect(),
        rms_rad: [0, 1, 2].map(|k| joint_rms_errors(&loops[5 + k], n)),
        settled_rad: [0, 1, 2].map(|k| joint_settled_errors(&loops[5 + k], n)),
    };
    lap("closed loops", log);
    let noisy = arms.real.hardware.q_noise_std_rad > 0.0 || arms.real.hardware.qd_noise_std_rad_s > 0.0;
    let ([sim_law_sensitivity, sim_law_sensitivity_fine], real_sensors, diagnostic_failures) = diagnostics(
        &DiagnosticBases {
            sim_perfect: tracking(&arm, Some(rel(&fmus.ideal_friction))),
            real_nn: tracking(&arm_real, Some(rel(&nn_real))),
            real_perfect: tracking(&arm_real, Some(rel(&fmus.ideal_friction_real))),
            real_none: tracking(&arm_real, None),
        },
        n,
        noisy,
        &table_1,
        out,
        &systems_dir,
        settings.threads,
    )?;
    for failure in &diagnostic_failures {
        log(&format!("diagnostic loop {failure} (its figures are left out)"));
    }
    let table_1 = Table1 { sim_law_sensitivity, sim_law_sensitivity_fine, real_sensors, diagnostic_failures, ..table_1 };
    lap("diagnostic loops", log);

    let (adaptation, adaptation_loops) =
        adaptation_runs(out, &fmu_dir, &systems_dir, arms, settings, &fmus.ideal_friction_real, &friction_files[1], &gravity_path)?;
    lap("online adaptation", log);

    if settings.fmi3 {
        write_fmi3_twins(&fmu_dir)?;
        lap("FMI 3.0 twins", log);
    }

    let (near, far) = arms.placement.distance_range();
    let setup = RunSetup {
        joints: n,
        reach_m: model.links.iter().map(|l| l.length_m).sum(),
        nominal: arms.nominal.clone(),
        real: arms.real.clone(),
        real_origin: arms.real_origin.clone(),
        reference_centre_m: [arms.placement.centre.x, arms.placement.centre.y],
        reference_scale: arms.placement.scale,
        reference_distance_m: [near, far],
        gravity_scale: gravity_scale(model),
        hold_gains: hold_gains(model).into_iter().map(|(p, d)| [p, d]).collect(),
    };
    let results = PaperResults {
        neurarm_version: env!("CARGO_PKG_VERSION").to_owned(),
        settings: settings.clone(),
        setup,
        table_1,
        friction,
        gravity,
        joint_loop,
        adaptation,
        timings_s: timings,
        total_s: started.elapsed().as_secs_f64(),
    };
    Ok(PaperRun { results, friction_pairs, friction_nets, gravity_pairs, loops, adaptation_loops, arms: arms.clone() })
}

/// Writes the FMI 3.0 twin of every FMU in `fmu_dir` into `fmu_dir/fmi3/`, same file names.
fn write_fmi3_twins(fmu_dir: &Path) -> Result<(), String> {
    let twins = fmu_dir.join("fmi3");
    std::fs::create_dir_all(&twins).map_err(|e| format!("{}: {e}", twins.display()))?;
    let mut fmus: Vec<PathBuf> = std::fs::read_dir(fmu_dir)
        .map_err(|e| format!("{}: {e}", fmu_dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "fmu"))
        .collect();
    fmus.sort();
    for fmu in fmus {
        let name = fmu.file_name().expect("a file from read_dir has a name");
        crate::export::export_fmi3_twin(&fmu, &twins.join(name))?;
    }
    Ok(())
}

/// The Table 1 systems the [`DIAGNOSTIC_LOOPS`] are built from.
struct DiagnosticBases {
    sim_perfect: SystemSpec,
    real_nn: SystemSpec,
    real_perfect: SystemSpec,
    real_none: SystemSpec,
}

/// Runs the [`DIAGNOSTIC_LOOPS`] of an arm of `n` joints (their files written into
/// `systems_dir` beside the others; the quiet ones only if the real arm is `noisy`) and returns
/// their figures against `table_1`'s.
fn diagnostics(
    bases: &DiagnosticBases,
    n: usize,
    noisy: bool,
    table_1: &Table1,
    out: &Path,
    systems_dir: &Path,
    threads: usize,
) -> Result<([LawSensitivity; 2], SensorLimit, Vec<String>), String> {
    let set = |mut spec: SystemSpec, unit: &str, values: &[(String, f64)]| {
        if let Some(entry) = spec.fmu.iter_mut().find(|f| f.name == unit) {
            for (name, value) in values {
                entry.parameters.insert(name.clone(), neurarm_cosim::Value::Real(*value));
            }
        }
        spec
    };
    let law_scaled = |scale: f64| {
        let values: Vec<(String, f64)> =
            (1..=n).flat_map(|i| [(format!("coulomb_scale_{i}"), scale), (format!("viscous_scale_{i}"), scale)]).collect();
        set(bases.sim_perfect.clone(), "comp", &values)
    };
    let quiet = |spec: &SystemSpec| set(spec.clone(), "arm", &[("q_noise_std".into(), 0.0), ("qd_noise_std".into(), 0.0)]);
    let mut specs = vec![
        law_scaled(1.0 - LAW_ERROR),
        law_scaled(1.0 + LAW_ERROR),
        law_scaled(1.0 - FINE_LAW_ERROR),
        law_scaled(1.0 + FINE_LAW_ERROR),
        bases.real_perfect.clone(),
    ];
    if noisy {
        specs.extend([quiet(&bases.real_perfect), quiet(&bases.real_nn), quiet(&bases.real_none)]);
    }
    for (name, spec) in DIAGNOSTIC_LOOPS.iter().zip(&specs) {
        write_loop_files(name, " (what bounds Table 1's ratios)", spec, systems_dir, out)?;
    }
    let b = bar(specs.len() as u64, "diagnostic loops");
    let tasks: Vec<(&str, SystemSpec)> = DIAGNOSTIC_LOOPS.iter().copied().zip(specs).collect();
    // A diagnostic loop that fails (goes unstable) takes only its own figures with it.
    let runs = parallel(tasks, threads, |(name, spec)| Ok(run_loop(&spec, systems_dir).map_err(|e| format!("{name}: {e}"))), || b.inc(1))?;
    b.finish_and_clear();
    let failures: Vec<String> = runs.iter().filter_map(|r| r.as_ref().err().cloned()).collect();
    let errors: Vec<Option<TrackingErrors>> = runs.iter().map(|r| r.as_ref().ok().map(tracking_errors)).collect();
    let measured = |k: usize| errors[k].as_ref().map(|e| e.measured_mse_m2);
    let true_mse = |k: usize| errors.get(k).and_then(|e| e.as_ref()).map(|e| e.true_mse_m2);
    let sensitivity = |error: f64, low: usize| LawSensitivity {
        law_error: error,
        low_over_perfect: measured(low).map(|m| m / table_1.mse_m2.sim_perfect),
        high_over_perfect: measured(low + 1).map(|m| m / table_1.mse_m2.sim_perfect),
    };
    let quiet_mse = match (noisy, true_mse(5), true_mse(6), true_mse(7)) {
        (true, Some(p), Some(nn), Some(none)) => Some([p, nn, none]),
        _ => None,
    };
    let sensors = SensorLimit {
        perfect_mse_m2: true_mse(4),
        perfect_over_none: true_mse(4).map(|m| m / table_1.true_mse_m2.real_none),
        quiet_mse_m2: quiet_mse,
        quiet_nn_over_none: quiet_mse.map(|m| m[1] / m[2]),
        quiet_perfect_over_none: quiet_mse.map(|m| m[0] / m[2]),
    };
    Ok(([sensitivity(LAW_ERROR, 0), sensitivity(FINE_LAW_ERROR, 2)], sensors, failures))
}

/// The online-adaptation runs on the real arm ([`adaptation`]): exports their compensators
/// into `fmu_dir` (the real arm's ideal gravity compensator, the adaptive ones from the real
/// arm's friction nets `real_friction` and the gravity net; `perfect_friction` is the real
/// arm's ideal friction compensator, exported already), writes their system files into
/// `systems_dir` and runs them.
#[allow(clippy::too_many_arguments)]
fn adaptation_runs(
    out: &Path,
    fmu_dir: &Path,
    systems_dir: &Path,
    arms: &Arms,
    settings: &Settings,
    perfect_friction: &Path,
    real_friction: &[(String, PathBuf)],
    gravity_path: &Path,
) -> Result<(adaptation::AdaptationResults, Vec<LoopRun>), String> {
    let n = arms.joints();
    let a = &settings.adaptation;
    let real = &arms.real.arm;
    let export = |id: &str, model: ModelSpec, sources: &[(String, PathBuf)]| -> Result<PathBuf, String> {
        let path = fmu_dir.join(format!("{id}.fmu"));
        export_fmu_for(&FmuSpec { identifier: id.into(), model }, sources, &path, settings.platforms.as_deref())?;
        Ok(path)
    };
    let ideal = |id: &str, arm: ArmParams, friction: bool| {
        export(id, ModelSpec::IdealCompensator(IdealCompensatorSpec { arm, enable_friction: friction, enable_gravity: !friction }), &[])
    };
    let perfect_gravity = ideal("IdealGravityCompensatorReal", real.clone().with_base_angle(std::f64::consts::FRAC_PI_2), false)?;
    let adaptive = |id: &str, friction: &[(String, PathBuf)], gravity: Option<&Path>, law: neurarm_models::AdaptationLaw| {
        let mut sources = friction.to_vec();
        if let Some(g) = gravity {
            sources.push(("gravity.json".into(), g.to_path_buf()));
        }
        let nets = neurarm_models::NnCompensatorSpec::of_nets(
            n,
            friction.iter().map(|(name, _)| name.clone()).collect(),
            gravity.map(|_| "gravity.json".to_owned()),
        );
        let model = ModelSpec::AdaptiveCompensator(nets.adaptive(law));
        export(id, model, &sources)
    };
    let adaptive_friction = adaptive("AdaptiveFrictionCompensatorReal", real_friction, None, a.friction_law)?;
    let adaptive_gravity = adaptive("AdaptiveGravityCompensator", &[], Some(gravity_path), a.gravity_law)?;
    let rel = |p: &Path| Path::new("..").join(p.strip_prefix(out).unwrap_or(p));
    let fmu = |id: &str| rel(&fmu_dir.join(format!("{id}.fmu")));
    let (arm_real, task, joint) = (fmu("PlanarArmReal"), fmu("TaskSpaceController"), fmu("JointController"));
    let (pf, pg, af, ag) = (rel(perfect_friction), rel(&perfect_gravity), rel(&adaptive_friction), rel(&adaptive_gravity));
    let (sf, sg) = (fmu("NnFrictionCompensatorReal"), fmu("NnGravityCompensator"));
    let friction_comps = adaptation::Compensators { perfect: &pf, static_nn: &sf, adaptive: &af };
    let gravity_comps = adaptation::Compensators { perfect: &pg, static_nn: &sg, adaptive: &ag };
    let start = tracking_start(&arms.nominal.arm, &arms.placement)?;
    let gains = joint_loop_gains(&arms.nominal.arm, settings);
    let payload_kg = a.payload_share * real.links[n - 1].mass_kg;
    let mut specs: Vec<SystemSpec> =
        (0..4).map(|c| adaptation::drift_system(&arm_real, &task, &friction_comps, c, &start, settings)).collect();
    specs.extend((0..4).map(|c| adaptation::payload_system(&arm_real, &joint, &gravity_comps, c, &gains, payload_kg, settings)));
    specs.extend([1, 2].map(|c| adaptation::steady_system(&arm_real, &task, &friction_comps, c, &start, settings)));
    for (name, spec) in ADAPTATION_LOOPS.iter().zip(&specs) {
        write_loop_files(name, " (online adaptation)", spec, systems_dir, out)?;
    }
    let b = bar(specs.len() as u64, "online adaptation");
    let tasks: Vec<(&str, SystemSpec)> = ADAPTATION_LOOPS.iter().copied().zip(specs).collect();
    // A run that fails (a long tracking run of some arm drifting into a singular pose) is
    // reported, not fatal: the rest of the paper stands, and its figures read NaN.
    let outcomes = parallel(tasks, settings.threads, |(_, spec)| Ok(run_loop(&spec, systems_dir)), || b.inc(1))?;
    b.finish_and_clear();
    let mut failures = Vec::new();
    let loops: Vec<LoopRun> = ADAPTATION_LOOPS
        .iter()
        .zip(outcomes)
        .map(|(name, outcome)| {
            outcome.unwrap_or_else(|e| {
                failures.push((name.to_string(), e));
                LoopRun { columns: Vec::new(), rows: Vec::new() }
            })
        })
        .collect();
    let end = a.drift_duration_s;
    let drift_mse: [f64; 4] = std::array::from_fn(|c| adaptation::tracking_mse_between(&loops[c], end - a.drift_window_s, end));
    let before: [f64; 4] = std::array::from_fn(|c| adaptation::tracking_mse_between(&loops[c], 0.0, 2.0 * std::f64::consts::PI));
    let after = a.payload_time_s + a.payload_settle_s;
    let settled: [Vec<f64>; 4] = std::array::from_fn(|c| adaptation::settled_errors_after(&loops[4 + c], n, after));
    let settled_before: [Vec<f64>; 4] = std::array::from_fn(|c| {
        let run = &loops[4 + c];
        let kept: Vec<Vec<f64>> = run.rows.iter().filter(|r| r[0] < a.payload_time_s).cloned().collect();
        adaptation::settled_errors_after(&LoopRun { columns: run.columns.clone(), rows: kept }, n, 0.0)
    });
    let steady = [0, 1].map(|k| adaptation::tracking_mse_between(&loops[8 + k], 0.0, a.steady_duration_s));
    let results = adaptation::AdaptationResults {
        drift_mse_m2: drift_mse,
        drift_over_perfect: drift_mse.map(|m| m / drift_mse[0]),
        drift_before_mse_m2: before,
        drift_largest_adaptation_nm: adaptation::largest_adaptation(&loops[2], "friction"),
        payload_kg,
        payload_over_perfect: std::array::from_fn(|c| settled[c].iter().zip(&settled[0]).map(|(e, p)| e / p).collect()),
        payload_settled_rad: settled,
        payload_before_rad: settled_before,
        payload_largest_adaptation_nm: adaptation::largest_adaptation(&loops[6], "gravity"),
        steady_mse_m2: steady,
        steady_adaptive_over_static: steady[1] / steady[0],
        steady_largest_adaptation_nm: adaptation::largest_adaptation(&loops[9], "friction"),
        friction_bound_nm: a.friction_law.bound_friction,
        failures,
    };
    Ok((results, loops))
}

/// Writes loop `name`'s system file (`systems_dir/<name>.toml`, headed by how to rerun it;
/// `purpose` follows the loop's name in that header) and its SSP file (`out/<name>.ssp`).
fn write_loop_files(name: &str, purpose: &str, spec: &SystemSpec, systems_dir: &Path, out: &Path) -> Result<(), String> {
    let toml = systems_dir.join(format!("{name}.toml"));
    let text = format!(
        "# The {name} loop of `neurarm paper`{purpose}; rerun it with\n# neurarm simulate {name}.toml -o {name}.csv\n\n{}",
        spec.to_toml()?
    );
    write_text_atomic(&toml, &text).map_err(writing(&toml))?;
    neurarm_cosim::ssp::write_ssp(spec, systems_dir, &out.join(format!("{name}.ssp"))).map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::LawSensitivity;

    #[test]
    fn the_largest_move_is_the_scaled_law_furthest_from_one_either_way() {
        let sensitivity = |low, high| LawSensitivity { law_error: 0.001, low_over_perfect: low, high_over_perfect: high };
        // The 6-joint example's stick–slip: 0.1 % low slows the loop, 0.1 % high leaves it.
        let moved = sensitivity(Some(1.639), Some(0.994)).largest_move().unwrap();
        assert!((moved - 0.639).abs() < 1e-12, "{moved}");
        // A downward move counts as much as an upward one (seed 5 of the family: 0.37 × perfect).
        let moved = sensitivity(Some(0.37), Some(1.05)).largest_move().unwrap();
        assert!((moved - 0.63).abs() < 1e-12, "{moved}");
        // A loop that failed leaves no figure.
        assert_eq!(sensitivity(None, Some(1.2)).largest_move(), None);
        assert_eq!(sensitivity(Some(1.2), None).largest_move(), None);
    }
}
