//! The `JointController` FMU: joint-space P(D) control with a compensation input,
//! `τ_i = τ_comp,i + K_p,i (q_d,i − q_i) + K_d,i (q̇_d,i − q̇_i)`. The paper's law is K_d = 0
//! with gravity compensation as `tau_comp`. The target q_d is the built-in
//! [`JOINT_SEQUENCE`] (with q̇_d = 0) or, with `use_sequence` false, the inputs `q_ref_i`,
//! `qd_ref_i`. Static in its inputs (direct feedthrough); the sequence depends on time.
//! Outputs `s_i = (q̇_d,i − q̇_i) + λ (q_d,i − q_i)`, the learning signal an adaptive
//! compensator takes.

use std::path::Path;

use neurarm_fmi_export::{BooleanVar, Model, ModelDescription, ModelError, RealVar, StaticModel, TableBuilder, Values};
use serde::{Deserialize, Serialize};

use crate::names;
use crate::ports::ControllerInputs;
use crate::units::{NEWTON_METRE, NEWTON_METRE_PER_RADIAN, NEWTON_METRE_SECOND_PER_RADIAN, PER_SECOND, RADIAN, RADIAN_PER_SECOND};
use crate::{describe, per_joint, BuildError, ModelKind};

/// Default λ of the learning signal [1/s].
pub const DEFAULT_JOINT_LAMBDA: f64 = 5.0;

/// Spec of a joint controller.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointControllerSpec {
    /// Number of joints.
    pub joints: usize,
    /// Default position gain of every joint [N·m/rad].
    pub kp: f64,
    /// Default velocity gain of every joint [N·m·s/rad].
    pub kd: f64,
    /// Default of `use_sequence`.
    pub use_sequence: bool,
}

impl ModelKind for JointControllerSpec {
    fn build(&self, identifier: &str, _resources: Option<&Path>) -> Result<Box<dyn Model>, BuildError> {
        Ok(Box::new(JointControllerModel::new(identifier, self.joints, self.kp, self.kd, self.use_sequence)?))
    }

    fn equations_html(&self) -> &'static str {
        "<p><code>τ_i = tau_comp_i + kp_i (q_d,i − q_i) + kd_i (q̇_d,i − q̇_i)</code>; \
the paper's law has kd = 0 and gravity compensation as tau_comp. With use_sequence the targets follow a \
built-in sequence of 5 segments of 3 s (q̇_d = 0); otherwise the inputs q_ref_i, qd_ref_i.</p>"
    }
}

/// The built-in joint targets of the `JointController` [rad]: segment k holds for
/// [`SEQUENCE_SEGMENT_S`] seconds from t = k·T; joint i of an n-joint arm uses column i mod 4.
/// With the base turned 90° (gravity along −y), the first target is the hanging pose
/// (q_1 = −π/2, the others 0); the next segments move every joint away from it.
pub const JOINT_SEQUENCE: [[f64; 4]; 5] = [
    [-std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0],
    [-std::f64::consts::FRAC_PI_4, 0.5, -0.5, 0.5],
    [0.0, -0.7, 0.7, -0.7],
    [-1.0, 1.0, 0.5, -1.0],
    [-0.5, -0.5, -1.0, 1.0],
];

/// Duration of one segment of [`JOINT_SEQUENCE`] [s].
pub const SEQUENCE_SEGMENT_S: f64 = 3.0;

/// The built-in target of joint `i` at time `t` [s]; after the last segment, that segment
/// holds, or with `repeat` the sequence starts again (period 5 × [`SEQUENCE_SEGMENT_S`]).
pub fn sequence_target(i: usize, t: f64, repeat: bool) -> f64 {
    let segments = JOINT_SEQUENCE.len();
    let k = (t / SEQUENCE_SEGMENT_S).floor().max(0.0);
    let k = if repeat { (k % segments as f64) as usize } else { (k as usize).min(segments - 1) };
    JOINT_SEQUENCE[k][i % 4]
}

/// The joint controller behind the FMU.
pub struct JointControllerModel {
    description: ModelDescription,
    q: Vec<RealVar>,
    qd: Vec<RealVar>,
    tau_comp: Vec<RealVar>,
    q_ref: Vec<RealVar>,
    qd_ref: Vec<RealVar>,
    tau: Vec<RealVar>,
    target: Vec<RealVar>,
    signal: Vec<RealVar>,
    lambda: RealVar,
    kp: Vec<RealVar>,
    kd: Vec<RealVar>,
    use_sequence: BooleanVar,
    repeat_sequence: BooleanVar,
}

impl JointControllerModel {
    /// A controller for `joints` joints with gains `kp` [N·m/rad] and `kd` [N·m·s/rad] on
    /// every joint, following the built-in sequence if `use_sequence`.
    pub fn new(identifier: &str, joints: usize, kp: f64, kd: f64, use_sequence: bool) -> Result<Self, BuildError> {
        neurarm_physics::arm::check_joint_count(joints)?;
        let mut b = TableBuilder::new();
        let ControllerInputs { q, qd, tau_comp } = ControllerInputs::declare(&mut b, joints, &vec![0.0; joints]);
        let q_ref = per_joint(&mut b, joints, |b, i| {
            b.input(
                names::joint(names::REFERENCE_ANGLE, i + 1),
                RADIAN,
                0.0,
                format!("Target angle of joint {} when use_sequence is false", i + 1),
            )
        });
        let qd_ref = per_joint(&mut b, joints, |b, i| {
            b.input(
                names::joint(names::REFERENCE_VELOCITY, i + 1),
                RADIAN_PER_SECOND,
                0.0,
                format!("Target velocity of joint {} when use_sequence is false", i + 1),
            )
        });
        let tau = per_joint(&mut b, joints, |b, i| {
            let deps = [q[i], qd[i], tau_comp[i], q_ref[i], qd_ref[i]];
            b.output(names::joint(names::TORQUE, i + 1), NEWTON_METRE, format!("Torque command of joint {}", i + 1), &deps)
        });
        let target = per_joint(&mut b, joints, |b, i| {
            b.output(names::joint(names::TARGET_ANGLE, i + 1), RADIAN, format!("Active target angle of joint {}", i + 1), &[q_ref[i]])
        });
        let signal = per_joint(&mut b, joints, |b, i| {
            let deps = [q[i], qd[i], q_ref[i], qd_ref[i]];
            b.output(
                names::joint(names::LEARNING_SIGNAL, i + 1),
                RADIAN_PER_SECOND,
                format!("Learning signal of joint {} for an adaptive compensator: (qd_d − qd) + lambda (q_d − q)", i + 1),
                &deps,
            )
        });
        let lambda =
            b.tunable(names::LAMBDA, PER_SECOND, DEFAULT_JOINT_LAMBDA, "Weight of the position error in the learning signal, lambda");
        let kp = per_joint(&mut b, joints, |b, i| {
            b.tunable(names::joint(names::KP, i + 1), NEWTON_METRE_PER_RADIAN, kp, format!("Position gain of joint {}", i + 1))
        });
        let kd = per_joint(&mut b, joints, |b, i| {
            b.tunable(
                names::joint(names::KD, i + 1),
                NEWTON_METRE_SECOND_PER_RADIAN,
                kd,
                format!("Velocity gain of joint {} (0 in the paper)", i + 1),
            )
        });
        let use_sequence = b.tunable_flag(
            names::USE_SEQUENCE,
            use_sequence,
            "Follow the built-in target sequence (true) or the q_ref/qd_ref inputs (false)",
        );
        let repeat_sequence = b.tunable_flag(
            names::REPEAT_SEQUENCE,
            false,
            "Start the built-in sequence again after its last segment (false: the last target holds)",
        );
        let text = format!("Joint-space P(D) controller with a compensation input for {joints} joints (neurarm)");
        let description = describe(identifier, text, b.finish())?;
        Ok(Self { description, q, qd, tau_comp, q_ref, qd_ref, tau, target, signal, lambda, kp, kd, use_sequence, repeat_sequence })
    }
}

impl StaticModel for JointControllerModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }

    fn compute(&mut self, values: &mut Values, time: f64) -> Result<(), ModelError> {
        let sequence = values[self.use_sequence];
        let repeat = values[self.repeat_sequence];
        for i in 0..self.q.len() {
            let (target, target_velocity) =
                if sequence { (sequence_target(i, time, repeat), 0.0) } else { (values[self.q_ref[i]], values[self.qd_ref[i]]) };
            let tau = values[self.tau_comp[i]]
                + values[self.kp[i]] * (target - values[self.q[i]])
                + values[self.kd[i]] * (target_velocity - values[self.qd[i]]);
            values[self.tau[i]] = tau;
            values[self.target[i]] = target;
            values[self.signal[i]] = (target_velocity - values[self.qd[i]]) + values[self.lambda] * (target - values[self.q[i]]);
        }
        Ok(())
    }
}
