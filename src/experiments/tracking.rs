//! Task-space tracking (Table 1): the paper's curve, placed for the arm, tracked by computed
//! torque with perfect, NN or no friction compensation.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{anyhow, Result};

use neurarm_cosim::{SystemSpec, Value};
use neurarm_models::names::{self, all_joints, joint_paths, path};
use neurarm_physics::arm::{jacobian, ArmParams, ArmState};
use neurarm_physics::control::{inverse_kinematics, pseudo_inverse, scaled_reference, ReferencePlacement};

use super::{closed_loop, LoopRun, Settings, ARM_UNIT, COMPENSATOR_UNIT, CONTROLLER_UNIT};

/// Pose the inverse kinematics for the tracking start is seeded from [rad]: an elbow-up
/// pose whose links are far from aligned; joint i of an n-joint arm takes entry i mod 4.
pub const TRACKING_SEED_POSE: [f64; 4] = [-0.4, 0.9, 0.7, 0.5];

/// The state the tracking runs start from: on the reference placed by `placement` at t = 0,
/// with its velocity, so no start-up transient enters the error. The pose comes from inverse
/// kinematics seeded with [`TRACKING_SEED_POSE`]. Fails, saying why, when the arm cannot hold
/// the curve or the inverse kinematics finds no pose.
pub fn tracking_start(arm: &ArmParams, placement: &ReferencePlacement) -> Result<ArmState> {
    placement.check(arm)?;
    let (x0, xd0, _) = scaled_reference(0.0, placement.centre, placement.scale);
    let seed: Vec<f64> = (0..arm.dof()).map(|i| TRACKING_SEED_POSE[i % 4]).collect();
    let q0 = inverse_kinematics(arm, x0, &seed)
        .ok_or_else(|| anyhow!("no joint angles put the end effector at the reference's start ({:.3}, {:.3}) m", x0.x, x0.y))?;
    let pinv = pseudo_inverse(&jacobian(arm, &q0)).ok_or_else(|| anyhow!("singular start pose"))?;
    let qd0: Vec<f64> = (&pinv * nalgebra::DVector::from_column_slice(xd0.as_slice())).iter().copied().collect();
    Ok(ArmState { q: q0, qd: qd0 })
}

/// The task-space tracking loop of Table 1 as a system: the arm in `arm` started at `start`
/// ([`tracking_start`]), the task-space controller, and the compensator FMU if any, for
/// `settings.tracking_duration` at `settings.step`. With `settings.intent_horizon` the
/// compensator's speed inputs come from the controller's `qd_intended_i` (see
/// [`Settings::intent_horizon`]) instead of the arm's measured speeds. FMU paths are taken as given (relative to
/// where the system file will be, or absolute).
pub fn tracking_system(arm: &Path, controller: &Path, compensator: Option<&Path>, start: &ArmState, settings: &Settings) -> SystemSpec {
    let n = start.q.len();
    let mut arm_parameters = BTreeMap::new();
    for i in 0..n {
        arm_parameters.insert(names::joint(names::START_ANGLE, i + 1), Value::Real(start.q[i]));
        arm_parameters.insert(names::joint(names::START_VELOCITY, i + 1), Value::Real(start.qd[i]));
    }
    let mut controller_parameters = BTreeMap::new();
    let mut spec = match (settings.intent_horizon, compensator) {
        (Some(horizon), Some(_)) => {
            controller_parameters.insert(names::INTENT_HORIZON.to_owned(), Value::Real(horizon));
            let mut spec = closed_loop(arm, controller, compensator, arm_parameters, controller_parameters);
            let speeds = path(COMPENSATOR_UNIT, &all_joints(names::VELOCITY));
            for c in spec.connection.iter_mut().filter(|c| c.to == speeds) {
                c.from = path(CONTROLLER_UNIT, &all_joints(names::INTENDED_VELOCITY));
            }
            spec
        }
        _ => closed_loop(arm, controller, compensator, arm_parameters, controller_parameters),
    };
    let mut record: Vec<String> = [
        (CONTROLLER_UNIT, names::ERROR_X),
        (CONTROLLER_UNIT, names::ERROR_Y),
        (CONTROLLER_UNIT, names::REFERENCE_X),
        (CONTROLLER_UNIT, names::REFERENCE_Y),
        (ARM_UNIT, names::END_EFFECTOR_X),
        (ARM_UNIT, names::END_EFFECTOR_Y),
    ]
    .iter()
    .map(|(unit, variable)| path(unit, variable))
    .collect();
    record.extend(joint_paths(ARM_UNIT, names::ANGLE, n));
    record.extend(joint_paths(ARM_UNIT, names::VELOCITY, n));
    record.extend(joint_paths(CONTROLLER_UNIT, names::TORQUE, n));
    spec.simulation.stop = settings.tracking_duration;
    spec.simulation.step = settings.step;
    spec.simulation.record = record;
    spec
}

/// Mean squared tracking error of a run [m²] as the controller sees it (from the measured
/// angles): the mean over samples and both coordinates of (x_d − x)².
pub fn tracking_mse(run: &LoopRun) -> f64 {
    tracking_errors(run).measured_mse_m2
}

/// The tracking errors of one run.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct TrackingErrors {
    /// Mean over samples and both coordinates of (x_d − x)², x from the measured angles
    /// (the controller's `error_x`, `error_y`) [m²]: Table 1's figure.
    pub measured_mse_m2: f64,
    /// The same with x the arm's true end-effector position [m²]; equal to the measured one
    /// on an arm without sensor effects.
    pub true_mse_m2: f64,
    /// RMS of the distance |x_d − x| to the true position [mm]: √(2 · true MSE).
    pub true_rms_mm: f64,
    /// Sum over the samples of the squared distance |x_d − x|², measured [m²]: what Table 1
    /// would show were it a sum instead of a mean.
    pub measured_sum_m2: f64,
    /// Samples.
    pub samples: usize,
    /// Share of the samples in which some joint is at rest, |q̇ᵢ| < [`RESTING_SPEED_RAD_S`]
    /// (the arm's true speeds): joints that stick under friction, where a compensator fed the
    /// measured speed gives nothing.
    pub resting_share: f64,
}

/// A joint slower than this is at rest for [`TrackingErrors::resting_share`] [rad/s].
pub const RESTING_SPEED_RAD_S: f64 = 1e-3;

/// The errors of a tracking run: against the measured and the true position.
pub fn tracking_errors(run: &LoopRun) -> TrackingErrors {
    let col = |unit: &str, variable: &str| run.column(&path(unit, variable)).unwrap_or_default();
    let (ex, ey) = (col(CONTROLLER_UNIT, names::ERROR_X), col(CONTROLLER_UNIT, names::ERROR_Y));
    let (xr, yr) = (col(CONTROLLER_UNIT, names::REFERENCE_X), col(CONTROLLER_UNIT, names::REFERENCE_Y));
    let (x, y) = (col(ARM_UNIT, names::END_EFFECTOR_X), col(ARM_UNIT, names::END_EFFECTOR_Y));
    let samples = ex.len();
    let measured_sum: f64 = ex.iter().zip(&ey).map(|(a, b)| a * a + b * b).sum();
    let true_sum: f64 = (0..xr.len().min(x.len())).map(|k| (xr[k] - x[k]).powi(2) + (yr[k] - y[k]).powi(2)).sum();
    let denominator = 2.0 * samples.max(1) as f64;
    let speed = path(ARM_UNIT, &names::joint_prefix(names::VELOCITY));
    let speeds: Vec<Vec<f64>> = run.columns.iter().filter(|c| c.starts_with(&speed)).filter_map(|c| run.column(c)).collect();
    let resting = (0..samples).filter(|&k| speeds.iter().any(|c| c.get(k).is_some_and(|v| v.abs() < RESTING_SPEED_RAD_S))).count();
    let true_mse = true_sum / denominator;
    TrackingErrors {
        measured_mse_m2: measured_sum / denominator,
        true_mse_m2: true_mse,
        true_rms_mm: 1e3 * (2.0 * true_mse).sqrt(),
        measured_sum_m2: measured_sum,
        samples,
        resting_share: resting as f64 / samples.max(1) as f64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_resting_share_counts_samples_with_any_joint_below_a_milliradian_per_second() {
        let mut columns = vec!["time".to_owned(), path(CONTROLLER_UNIT, names::ERROR_X), path(CONTROLLER_UNIT, names::ERROR_Y)];
        columns.extend(joint_paths(ARM_UNIT, names::VELOCITY, 2));
        // Samples 1 and 3 have a joint at rest (one each), sample 2 a joint just above it.
        let speeds = [[0.5, -0.2], [0.0, 1.0], [0.5, -1.5e-3], [0.3, 5e-4]];
        let rows = speeds.iter().enumerate().map(|(k, s)| vec![k as f64, 1e-3, -2e-3, s[0], s[1]]).collect();
        let e = tracking_errors(&LoopRun { columns, rows });
        assert_eq!(e.samples, 4);
        assert_eq!(e.resting_share, 0.5);
        assert!((e.measured_mse_m2 - 2.5e-6).abs() < 1e-18, "{}", e.measured_mse_m2);
    }
}
