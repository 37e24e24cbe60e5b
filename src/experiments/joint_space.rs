//! The joint-space loop with gravity compensation: P control (plus a small D) along the
//! joint controller's built-in target sequence, with ideal, NN or no gravity compensation.

use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::Path;

use neurarm_cosim::{SystemSpec, Value};
use neurarm_models::names::{self, joint_path, joint_paths};

use super::{closed_loop, LoopRun, Settings, ARM_UNIT, CONTROLLER_UNIT};

/// The joint-space loop as a system: the `joints`-joint arm with its base turned 90° starting
/// at the hanging pose, the joint controller on its built-in sequence (joint i follows column
/// i mod 4 of `JOINT_SEQUENCE`) with gains (K_p [N·m/rad], K_d [N·m·s/rad]) per joint in
/// `gains`, and the compensator FMU if any.
pub fn gravity_compensation_system(
    arm: &Path,
    controller: &Path,
    compensator: Option<&Path>,
    gains: &[(f64, f64)],
    settings: &Settings,
) -> SystemSpec {
    let n = gains.len();
    let arm_parameters = BTreeMap::from([
        (names::BASE_ANGLE.to_owned(), Value::Real(PI / 2.0)),
        (names::joint(names::START_ANGLE, 1), Value::Real(-PI / 2.0)),
    ]);
    let mut parameters = BTreeMap::new();
    for (i, (kp, kd)) in gains.iter().enumerate() {
        parameters.insert(names::joint(names::KP, i + 1), Value::Real(*kp));
        parameters.insert(names::joint(names::KD, i + 1), Value::Real(*kd));
    }
    let mut spec = closed_loop(arm, controller, compensator, arm_parameters, parameters);
    let mut record = joint_paths(CONTROLLER_UNIT, names::TARGET_ANGLE, n);
    record.extend(joint_paths(ARM_UNIT, names::ANGLE, n));
    record.extend(joint_paths(CONTROLLER_UNIT, names::TORQUE, n));
    record.extend(joint_paths(ARM_UNIT, names::VELOCITY, n));
    spec.simulation.stop = neurarm_models::joint::SEQUENCE_SEGMENT_S * neurarm_models::joint::JOINT_SEQUENCE.len() as f64;
    spec.simulation.step = settings.step;
    spec.simulation.record = record;
    spec
}

/// RMS of q_target − q per joint over a joint-space run [rad].
pub fn joint_rms_errors(run: &LoopRun, joints: usize) -> Vec<f64> {
    (1..=joints)
        .map(|i| {
            let t = run.column(&joint_path(CONTROLLER_UNIT, names::TARGET_ANGLE, i)).unwrap_or_default();
            let q = run.column(&joint_path(ARM_UNIT, names::ANGLE, i)).unwrap_or_default();
            (t.iter().zip(&q).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / t.len().max(1) as f64).sqrt()
        })
        .collect()
}

/// Mean |q_target − q| per joint over the last 0.5 s of each target segment [rad]: the
/// error the loop settles to, which gravity left uncompensated dominates.
pub fn joint_settled_errors(run: &LoopRun, joints: usize) -> Vec<f64> {
    let time = run.column("time").unwrap_or_default();
    let segment = neurarm_models::joint::SEQUENCE_SEGMENT_S;
    let settled: Vec<bool> =
        time.iter().map(|t| t.rem_euclid(segment) >= segment - 0.5 || (*t > 0.0 && t.rem_euclid(segment) == 0.0)).collect();
    (1..=joints)
        .map(|i| {
            let t = run.column(&joint_path(CONTROLLER_UNIT, names::TARGET_ANGLE, i)).unwrap_or_default();
            let q = run.column(&joint_path(ARM_UNIT, names::ANGLE, i)).unwrap_or_default();
            let (sum, count) =
                t.iter().zip(&q).zip(&settled).filter(|(_, &s)| s).fold((0.0, 0usize), |(s, c), ((a, b), _)| (s + (a - b).abs(), c + 1));
            sum / count.max(1) as f64
        })
        .collect()
}
