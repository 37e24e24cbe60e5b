//! Online adaptation, the paper's further work: the robot drifts away from the model its nets
//! were trained on, and an adaptive compensator keeps learning while a static one stays where
//! it was. Three runs through the master on the real arm, each with four compensators —
//! perfect (the true, changing model), static NN, adaptive NN and none:
//! - **friction drift**: the paper's tracking task while every joint's viscous friction ramps
//!   to [`AdaptationSettings::viscous_scale`] and its Coulomb friction to
//!   [`AdaptationSettings::coulomb_scale`] (warm lubricant, worn seals), then holds;
//! - **payload**: the joint-space gravity loop, cycling through its targets, when a payload of
//!   [`AdaptationSettings::payload_share`] of the last link's mass is gripped at the tip;
//! - **steady**: the tracking task with no change, noise on, for a long time: does adapting
//!   cost anything when there is nothing to learn, and how far do the weights wander.
//!
//! The changes are `[[event]]`s of the loops' system files on the arm's tunable drift
//! parameters (and on the ideal compensator's, which follows the same change).

use std::collections::BTreeMap;
use std::path::Path;

use neurarm_cosim::{ConnectionSpec, EventSpec, SystemSpec, Value};
use neurarm_models::names::{self, all_joints, joint_path, joint_paths, path};
use neurarm_models::AdaptationLaw;
use serde::Serialize;

use super::{LoopRun, Settings, ARM_UNIT, COMPENSATOR_UNIT, CONTROLLER_UNIT};

/// Sizes and strengths of the adaptation runs.
#[derive(Clone, Debug, Serialize)]
pub struct AdaptationSettings {
    /// Length of the friction-drift run [s].
    pub drift_duration_s: f64,
    /// The drift ramps from 0 to this time [s], then holds.
    pub drift_ramp_s: f64,
    /// Viscous friction scale every joint ramps to.
    pub viscous_scale: f64,
    /// Coulomb (and static) friction scale every joint ramps to.
    pub coulomb_scale: f64,
    /// The drift run is judged over its last this many seconds [s].
    pub drift_window_s: f64,
    /// When the payload is gripped [s].
    pub payload_time_s: f64,
    /// Payload as a share of the last link's mass.
    pub payload_share: f64,
    /// Length of the payload run [s] (the target sequence repeats).
    pub payload_duration_s: f64,
    /// The payload run is judged on the settled windows from this long after the change [s].
    pub payload_settle_s: f64,
    /// Length of the steady run [s].
    pub steady_duration_s: f64,
    /// Width of the windows of the MSE-over-time figure [s].
    pub mse_window_s: f64,
    /// The law of the adaptive friction compensator.
    pub friction_law: AdaptationLaw,
    /// The law of the adaptive gravity compensator.
    pub gravity_law: AdaptationLaw,
}

impl AdaptationSettings {
    /// The full runs: 60 s of drift then 20 s judged; 10 minutes steady.
    pub fn full() -> Self {
        Self {
            drift_duration_s: 80.0,
            drift_ramp_s: 60.0,
            viscous_scale: 0.4,
            coulomb_scale: 1.5,
            drift_window_s: 20.0,
            payload_time_s: 10.0,
            payload_share: 0.3,
            payload_duration_s: 30.0,
            payload_settle_s: 5.0,
            steady_duration_s: 600.0,
            mse_window_s: 1.0,
            friction_law: AdaptationLaw::default(),
            gravity_law: AdaptationLaw::default(),
        }
    }

    /// The reduced runs of the test suite: the drift in 20 s, 10 s judged; one minute steady.
    pub fn quick() -> Self {
        Self { drift_duration_s: 30.0, drift_ramp_s: 20.0, drift_window_s: 10.0, steady_duration_s: 60.0, ..Self::full() }
    }
}

/// The four compensators of each run, in this order.
pub const CASES: [&str; 4] = ["perfect", "static NN", "adaptive NN", "none"];

/// The FMUs (paths as the system files hold them) of one adaptation run: the perfect,
/// static, adaptive compensators (the last case has none).
pub struct Compensators<'a> {
    /// The ideal compensator of the real arm (the part the run compensates switched on).
    pub perfect: &'a Path,
    /// The NN compensator.
    pub static_nn: &'a Path,
    /// The adaptive compensator.
    pub adaptive: &'a Path,
}

impl Compensators<'_> {
    fn of(&self, case: usize) -> Option<&Path> {
        [Some(self.perfect), Some(self.static_nn), Some(self.adaptive), None][case]
    }
}

/// The drift every joint of an `joints`-joint arm goes through, as a ramp of `unit`'s drift
/// parameters.
fn drift_event(unit: &str, joints: usize, a: &AdaptationSettings) -> EventSpec {
    let mut set = BTreeMap::new();
    for i in 1..=joints {
        set.insert(joint_path(unit, names::VISCOUS_SCALE, i), Value::Real(a.viscous_scale));
        set.insert(joint_path(unit, names::COULOMB_SCALE, i), Value::Real(a.coulomb_scale));
    }
    EventSpec { time: 0.0, until: Some(a.drift_ramp_s), set }
}

/// Makes `spec` one case of an adaptation run: the drift `events` go to the arm and, for the
/// perfect case, to its compensator; the adaptive case learns from the controller's `s_i`.
fn as_case(mut spec: SystemSpec, case: usize, joints: usize, events: &dyn Fn(&str) -> EventSpec, stop: f64) -> SystemSpec {
    spec.simulation.stop = stop;
    spec.event.push(events(ARM_UNIT));
    if case == 0 {
        spec.event.push(events(COMPENSATOR_UNIT));
    }
    if case == 2 {
        spec.connection.push(learning_connection());
        spec.simulation.record.extend(joint_paths(COMPENSATOR_UNIT, names::ADAPTED_FRICTION, joints));
        spec.simulation.record.extend(joint_paths(COMPENSATOR_UNIT, names::ADAPTED_GRAVITY, joints));
    }
    spec
}

/// The controller's learning signal to the adaptive compensator, every joint.
fn learning_connection() -> ConnectionSpec {
    let every = |unit: &str| path(unit, &all_joints(names::LEARNING_SIGNAL));
    ConnectionSpec { from: every(CONTROLLER_UNIT), to: every(COMPENSATOR_UNIT) }
}

/// The friction-drift run of `case` (0 to 3, see [`CASES`]): the tracking loop on `arm` from
/// `start` with the task-space controller `task`.
pub fn drift_system(
    arm: &Path,
    task: &Path,
    comps: &Compensators,
    case: usize,
    start: &neurarm_physics::arm::ArmState,
    settings: &Settings,
) -> SystemSpec {
    let a = &settings.adaptation;
    let joints = start.q.len();
    let spec = super::tracking_system(arm, task, comps.of(case), start, settings);
    as_case(spec, case, joints, &|unit| drift_event(unit, joints, a), a.drift_duration_s)
}

/// The steady run of `case` (static or adaptive only make sense; any is accepted): tracking on
/// `arm`, no change.
pub fn steady_system(
    arm: &Path,
    task: &Path,
    comps: &Compensators,
    case: usize,
    start: &neurarm_physics::arm::ArmState,
    settings: &Settings,
) -> SystemSpec {
    let joints = start.q.len();
    let mut spec = super::tracking_system(arm, task, comps.of(case), start, settings);
    spec.simulation.stop = settings.adaptation.steady_duration_s;
    if case == 2 {
        spec.connection.push(learning_connection());
        spec.simulation.record.extend(joint_paths(COMPENSATOR_UNIT, names::ADAPTED_FRICTION, joints));
    }
    spec
}

/// The payload run of `case`: the joint-space gravity loop on `arm` with the joint controller
/// `joint` cycling through its targets, a payload of `payload_kg` gripped at the tip.
pub fn payload_system(
    arm: &Path,
    joint: &Path,
    comps: &Compensators,
    case: usize,
    gains: &[(f64, f64)],
    payload_kg: f64,
    settings: &Settings,
) -> SystemSpec {
    let a = &settings.adaptation;
    let joints = gains.len();
    let mut spec = super::gravity_compensation_system(arm, joint, comps.of(case), gains, settings);
    let ctl = spec.fmu.iter_mut().find(|f| f.name == CONTROLLER_UNIT).expect("the loop has a controller");
    ctl.parameters.insert(names::REPEAT_SEQUENCE.into(), Value::Boolean(true));
    let event = |unit: &str| EventSpec {
        time: a.payload_time_s,
        until: None,
        set: BTreeMap::from([(path(unit, names::PAYLOAD_MASS), Value::Real(payload_kg))]),
    };
    as_case(spec, case, joints, &event, a.payload_duration_s)
}

/// Mean over samples and both coordinates of (x_d − x)² of the rows with `from ≤ t ≤ to`,
/// from the controller's (measured) error, as Table 1 [m²].
pub fn tracking_mse_between(run: &LoopRun, from: f64, to: f64) -> f64 {
    let (ex, ey) = (column(run, &path(CONTROLLER_UNIT, names::ERROR_X)), column(run, &path(CONTROLLER_UNIT, names::ERROR_Y)));
    let t = column(run, "time");
    let (sum, count) = (0..t.len())
        .filter(|&k| t[k] >= from - 1e-9 && t[k] <= to + 1e-9)
        .fold((0.0, 0usize), |(s, c), k| (s + ex[k] * ex[k] + ey[k] * ey[k], c + 1));
    // No rows (a run that failed): NaN, not a perfect score.
    if count == 0 {
        return f64::NAN;
    }
    sum / (2.0 * count as f64)
}

fn column(run: &LoopRun, name: &str) -> Vec<f64> {
    run.column(name).unwrap_or_default()
}

/// Each joint's recorded target and angle in a joint-space run: (q_target, q) [rad].
fn targets_and_angles(run: &LoopRun, joints: usize) -> Vec<(Vec<f64>, Vec<f64>)> {
    let of = |unit: &str, family: &str, j: usize| column(run, &joint_path(unit, family, j));
    (1..=joints).map(|j| (of(CONTROLLER_UNIT, names::TARGET_ANGLE, j), of(ARM_UNIT, names::ANGLE, j))).collect()
}

/// The tracking MSE in consecutive windows of `width` [s]: (window centre [s], MSE [m²]).
pub fn windowed_tracking_mse(run: &LoopRun, width: f64) -> Vec<(f64, f64)> {
    let end = run.rows.last().map_or(0.0, |r| r[0]);
    let windows = (end / width).floor() as usize;
    (0..windows).map(|k| ((k as f64 + 0.5) * width, tracking_mse_between(run, k as f64 * width, (k + 1) as f64 * width))).collect()
}

/// The joint error's mean square over joints in consecutive windows of `width` [s]:
/// (window centre [s], mean of (q_target − q)² [rad²]).
pub fn windowed_joint_mse(run: &LoopRun, joints: usize, width: f64) -> Vec<(f64, f64)> {
    let t = column(run, "time");
    let errors: Vec<Vec<f64>> = targets_and_angles(run, joints)
        .into_iter()
        .map(|(target, q)| target.iter().zip(&q).map(|(a, b)| (a - b).powi(2)).collect())
        .collect();
    let end = t.last().copied().unwrap_or(0.0);
    let windows = (end / width).floor() as usize;
    (0..windows)
        .map(|k| {
            let (from, to) = (k as f64 * width, (k + 1) as f64 * width);
            let rows: Vec<usize> = (0..t.len()).filter(|&r| t[r] >= from - 1e-9 && t[r] < to - 1e-9).collect();
            let sum: f64 = rows.iter().map(|&r| errors.iter().map(|e| e[r]).sum::<f64>()).sum();
            ((k as f64 + 0.5) * width, sum / (joints * rows.len().max(1)) as f64)
        })
        .collect()
}

/// Mean |q_target − q| per joint over the last 0.5 s of each target segment that starts at or
/// after `from` [s] [rad]: the error the loop settles to.
pub fn settled_errors_after(run: &LoopRun, joints: usize, from: f64) -> Vec<f64> {
    let t = column(run, "time");
    let segment = neurarm_models::joint::SEQUENCE_SEGMENT_S;
    let keep: Vec<bool> = t
        .iter()
        .map(|&time| {
            let phase = time.rem_euclid(segment);
            let segment_start = time - phase;
            let settled = phase >= segment - 0.5 - 1e-9;
            settled && segment_start >= from - 1e-9
        })
        .collect();
    targets_and_angles(run, joints)
        .into_iter()
        .map(|(target, q)| {
            let (sum, count) = (0..t.len()).filter(|&k| keep[k]).fold((0.0, 0usize), |(s, c), k| (s + (target[k] - q[k]).abs(), c + 1));
            if count == 0 {
                f64::NAN
            } else {
                sum / count as f64
            }
        })
        .collect()
}

/// The settled error of each target segment: (segment end [s], mean over the joints of
/// |q_target − q| over its last 0.5 s [rad]).
pub fn settled_error_per_segment(run: &LoopRun, joints: usize) -> Vec<(f64, f64)> {
    let t = column(run, "time");
    let segment = neurarm_models::joint::SEQUENCE_SEGMENT_S;
    let errors = targets_and_angles(run, joints);
    let end = t.last().copied().unwrap_or(0.0);
    let segments = (end / segment + 1e-9).floor() as usize;
    (0..segments)
        .map(|k| {
            let (from, to) = ((k + 1) as f64 * segment - 0.5, (k + 1) as f64 * segment);
            let rows: Vec<usize> = (0..t.len()).filter(|&r| t[r] >= from - 1e-9 && t[r] < to - 1e-9).collect();
            let sum: f64 = rows.iter().map(|&r| errors.iter().map(|(target, q)| (target[r] - q[r]).abs()).sum::<f64>()).sum();
            (to, sum / (joints * rows.len().max(1)) as f64)
        })
        .collect()
}

/// The largest of the recorded `comp.<family>_i` over a run [N·m], `family` being
/// [`names::ADAPTED_FRICTION`] or [`names::ADAPTED_GRAVITY`]; NaN for a run without rows.
pub fn largest_adaptation(run: &LoopRun, family: &str) -> f64 {
    if run.rows.is_empty() {
        return f64::NAN;
    }
    let prefix = path(COMPENSATOR_UNIT, &names::joint_prefix(family));
    run.columns
        .iter()
        .enumerate()
        .filter(|(_, c)| c.starts_with(&prefix))
        .flat_map(|(k, _)| run.rows.iter().map(move |r| r[k]))
        .fold(0.0, f64::max)
}

/// The figures of the adaptation runs.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct AdaptationResults {
    /// The friction-drift run: tracking MSE over the last window [m²] per case (see [`CASES`]).
    pub drift_mse_m2: [f64; 4],
    /// Each case's drift MSE over the perfect one's.
    pub drift_over_perfect: [f64; 4],
    /// The same cases before the drift: tracking MSE over the first 2π s [m²].
    pub drift_before_mse_m2: [f64; 4],
    /// Largest change of a friction torque the adaptive net made during the drift [N·m].
    pub drift_largest_adaptation_nm: f64,
    /// The payload [kg].
    pub payload_kg: f64,
    /// The payload run: settled error per joint after the change [rad], per case.
    pub payload_settled_rad: [Vec<f64>; 4],
    /// Each joint's settled error over the perfect (ideal) case's.
    pub payload_over_perfect: [Vec<f64>; 4],
    /// The payload run before the change: settled error per joint [rad], per case.
    pub payload_before_rad: [Vec<f64>; 4],
    /// Largest change of a gravity torque the adaptive net made [N·m].
    pub payload_largest_adaptation_nm: f64,
    /// The steady run: tracking MSE [m²], static then adaptive.
    pub steady_mse_m2: [f64; 2],
    /// Adaptive over static.
    pub steady_adaptive_over_static: f64,
    /// Largest change of a friction torque the adaptive net made in the steady run [N·m], and
    /// the bound it may not pass.
    pub steady_largest_adaptation_nm: f64,
    /// The friction law's bound [N·m].
    pub friction_bound_nm: f64,
    /// Runs that failed (loop name, why); their figures are NaN.
    pub failures: Vec<(String, String)>,
}
