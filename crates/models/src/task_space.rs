//! The `TaskSpaceController` FMU: task-space computed torque for the redundant planar arm,
//! tracking the paper's reference `x_d(t) = c + s (0.2 (cos t + sin 2t), 0.15 (sin t + cos 2t))`
//! [m] around the centre c, scaled by s:
//! `u = J⁺ (ẍ_d + K_d (ẋ_d − ẋ) + K_p (x_d − x) − J̇q̇) + (I − J⁺J)(k_rest (q_rest − q) − k_null q̇)`,
//! `τ = Ĥ(q) u + Ĉ(q, q̇) q̇ + ĝ(q) + τ_comp`, with Ĥ, Ĉ, ĝ from the controller's model of the
//! arm (friction is left to `tau_comp`). Static in its inputs (direct feedthrough); the
//! reference depends on time. Outputs `s_i`, the learning signal an adaptive compensator
//! takes: `s = Ĥ⁻¹ Jᵀ (ė + λ e)` with e = x_d − x ([`task_learning_signal_into`]); and
//! `qd_intended_i = q̇ᵢ + h uᵢ` (h = `intent_horizon`), the speed the law drives joint i
//! towards, for a friction compensator that should push a joint at rest the way the law
//! accelerates it (it depends on q and q̇ only, so feeding a compensator makes no loop); a
//! lead `h uᵢ` against a moving joint's motion is dropped ([`intended_speed`]).

use std::path::Path;

use nalgebra::Vector2;
use neurarm_fmi_export::{Model, ModelDescription, ModelError, RealVar, StaticModel, TableBuilder, Values};
use neurarm_physics::arm::{end_effector_position, ArmParams};
use neurarm_physics::control::{
    scaled_reference, task_learning_signal_into, task_space_torque_into, LearningSignalData, TaskReference, TaskSpaceData, TaskSpaceGains,
};
use serde::{Deserialize, Serialize};

use crate::names::{self, joint};
use crate::ports::ControllerInputs;
use crate::units::{METRE, NEWTON_METRE, PER_SECOND, PER_SECOND_SQUARED, RADIAN, RADIAN_PER_SECOND};
use crate::{describe, per_joint, BuildError, ModelKind};
use neurarm_fmi_export::Unit;

/// Default λ of the learning signal [1/s]: the position error's weight, between 0 and the
/// paper's K_d = 160 (the Lyapunov argument needs 0 < λ < K_d).
pub const DEFAULT_TASK_LAMBDA: f64 = 20.0;

/// Spec of a task-space controller.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskSpaceControllerSpec {
    /// The controller's model of the arm (its friction is not used).
    pub model: ArmParams,
    /// Default gains.
    pub gains: TaskSpaceGains,
    /// Default centre of the reference [m].
    pub centre: [f64; 2],
    /// Default scale of the reference (1: the paper's size).
    #[serde(default = "unit_scale")]
    pub scale: f64,
    /// Start values of the angle inputs [rad]: a pose where J has full rank.
    pub q_start: Vec<f64>,
}

fn unit_scale() -> f64 {
    1.0
}

impl ModelKind for TaskSpaceControllerSpec {
    fn build(&self, identifier: &str, _resources: Option<&Path>) -> Result<Box<dyn Model>, BuildError> {
        let reference = (self.centre, self.scale);
        Ok(Box::new(TaskSpaceControllerModel::new(identifier, self.model.clone(), self.gains, reference, &self.q_start)?))
    }

    fn equations_html(&self) -> &'static str {
        "<p>Reference (centre c = (centre_x, centre_y), scale s = reference_scale): \
<code>x_d(t) = c + s (0.2 (cos t + sin 2t), 0.15 (sin t + cos 2t))</code> [m].</p>\
<p><code>u = J# (ẍ_d + K_d (ẋ_d − ẋ) + K_p (x_d − x) − J̇q̇) + (I − J#J)(k_rest (q_rest − q) − k_null q̇)</code>, with J# the Moore–Penrose pseudo-inverse \
(Jᵀ(JJᵀ)⁻¹ away from singular poses; at a singular pose the direction J has lost gets no acceleration); the last term acts on the self-motion of the redundant joints, which the task does not fix: it damps it and, with k_rest &gt; 0 (default 0), brings it back to the rest pose q_rest (each joint's distance taken within ±π), so it cannot drift; on arms with strong joint friction a stiffness lets redundant joints come to rest and stick, hence the default.</p>\
<p><code>τ = Ĥ(q) u + Ĉ(q, q̇) q̇ + ĝ(q) + tau_comp</code>, Ĥ, Ĉ, ĝ from the controller's own arm model \
(in resources/neurarm.toml). Non-finite inputs fail the step with fmi2Error.</p>\
<p><code>qd_intended_i = qd_i + intent_horizon · u_i</code>: the speed the law drives joint i towards, for a friction \
compensator fed it instead of the measured speed (then a joint at rest is compensated the way the law accelerates it); \
where the lead <code>intent_horizon · u_i</code> points against the joint's motion (qd_i ≠ 0, a reversal ahead) it is dropped \
and <code>qd_intended_i = qd_i</code>, so the compensation keeps the direction in which the joint's friction still acts \
until the joint stops; it depends on q and qd only.</p>"
    }
}

/// The speed a joint moving at `speed` [rad/s] is commanded towards, given the law's lead
/// `h u` [rad/s]: `speed + lead`, except that a lead against the joint's motion is dropped
/// (the joint's own speed is returned). Near a reversal the lead points the new way while the
/// joint still moves the old way; a friction law fed the sum would give the new direction's
/// friction while the arm's friction still acts the old way, a kick of twice the Coulomb level.
/// A joint at rest (speed 0) takes the lead, which is what breaks it away.
pub fn intended_speed(speed: f64, lead: f64) -> f64 {
    if lead * speed >= 0.0 {
        speed + lead
    } else {
        speed
    }
}

/// The task-space controller behind the FMU.
pub struct TaskSpaceControllerModel {
    description: ModelDescription,
    model: ArmParams,
    q: Vec<RealVar>,
    qd: Vec<RealVar>,
    tau_comp: Vec<RealVar>,
    tau: Vec<RealVar>,
    reference: [RealVar; 2],
    error: [RealVar; 2],
    kp: RealVar,
    kd: RealVar,
    null_damping: RealVar,
    null_stiffness: RealVar,
    rest_pose: Vec<RealVar>,
    centre: [RealVar; 2],
    scale: RealVar,
    signal: Vec<RealVar>,
    lambda: RealVar,
    intended_speed: Vec<RealVar>,
    intent_horizon: RealVar,
    data: TaskSpaceData,
    learning: LearningSignalData,
    /// Inputs as read: angles, velocities, compensation; and the torques.
    buf: [Vec<f64>; 4],
}

impl TaskSpaceControllerModel {
    /// A controller named `identifier` using `model` (the controller's idea of the arm),
    /// default gains `gains`, the reference's default centre [m] and scale in `reference`, and
    /// start values `q_start` of the angle inputs [rad] (a pose away from singularities, so
    /// initial outputs exist).
    pub fn new(
        identifier: &str,
        model: ArmParams,
        gains: TaskSpaceGains,
        reference: ([f64; 2], f64),
        q_start: &[f64],
    ) -> Result<Self, BuildError> {
        let (centre, scale) = reference;
        if !(scale > 0.0 && scale.is_finite()) {
            return Err(BuildError::Spec(format!("the reference's scale {scale} must be finite and > 0")));
        }
        model.validate()?;
        let n = model.dof();
        if n < 2 {
            return Err(BuildError::Spec("task-space control of a planar position needs at least 2 joints".into()));
        }
        if q_start.len() != n {
            return Err(BuildError::Spec(format!("{} start angles for {n} joints", q_start.len())));
        }
        let mut b = TableBuilder::new();
        let ControllerInputs { q, qd, tau_comp } = ControllerInputs::declare(&mut b, n, q_start);
        let all: Vec<RealVar> = q.iter().chain(&qd).chain(&tau_comp).copied().collect();
        let tau = per_joint(&mut b, n, |b, i| {
            b.output(joint(names::TORQUE, i + 1), NEWTON_METRE, format!("Torque command of joint {}", i + 1), &all)
        });
        let q_and_qd: Vec<RealVar> = q.iter().chain(&qd).copied().collect();
        let signal = per_joint(&mut b, n, |b, i| {
            b.output(
                joint(names::LEARNING_SIGNAL, i + 1),
                None,
                format!("Learning signal of joint {} for an adaptive compensator: (H⁻¹ Jᵀ (ė + λ e))_{} [1/(kg·s)]", i + 1, i + 1),
                &q_and_qd,
            )
        });
        let intended_speed = per_joint(&mut b, n, |b, i| {
            b.output(
                joint(names::INTENDED_VELOCITY, i + 1),
                RADIAN_PER_SECOND,
                format!(
                    "Speed joint {} is commanded towards: qd_{} + intent_horizon · u_{} (u the law's joint acceleration; the second term dropped where it points against the joint's motion)",
                    i + 1,
                    i + 1,
                    i + 1
                ),
                &q_and_qd,
            )
        });
        let reference =
            [b.output(names::REFERENCE_X, METRE, "Reference x_d(t)", &[]), b.output(names::REFERENCE_Y, METRE, "Reference y_d(t)", &[])];
        let error =
            [b.output(names::ERROR_X, METRE, "Tracking error x_d − x", &q), b.output(names::ERROR_Y, METRE, "Tracking error y_d − y", &q)];
        let kp = b.tunable(names::KP, PER_SECOND_SQUARED, gains.kp, "Position gain K_p");
        let kd = b.tunable(names::KD, PER_SECOND, gains.kd, "Velocity gain K_d");
        let null_damping = b.tunable(
            names::NULL_DAMPING,
            PER_SECOND,
            gains.null_damping,
            "Null-space damping k_null: self-motion decays as -k_null (I - J#J) qd",
        );
        let null_stiffness = b.tunable(
            names::NULL_STIFFNESS,
            PER_SECOND_SQUARED,
            gains.null_stiffness,
            "Null-space stiffness k_rest: the self-motion returns to the rest pose as (I - J#J)(k_rest (q_rest - q) - k_null qd); 0 (default) damps it only",
        );
        let rest_pose = per_joint(&mut b, n, |b, i| {
            b.tunable(
                joint(names::REST_ANGLE, i + 1),
                RADIAN,
                q_start[i],
                format!("Rest angle of joint {} the self-motion returns to (default: the start pose)", i + 1),
            )
        });
        let lambda = b.tunable(
            names::LAMBDA,
            PER_SECOND,
            DEFAULT_TASK_LAMBDA,
            "Weight of the position error in the learning signal, lambda (between 0 and kd)",
        );
        let intent_horizon = b.tunable(
            names::INTENT_HORIZON,
            Unit::SECOND,
            0.0,
            "Look-ahead of qd_intended [s]: a friction compensator fed qd_intended instead of the measured speed pushes a joint at rest the way the law accelerates it (0: qd_intended = qd)",
        );
        let centre = [
            b.parameter(names::CENTRE_X, METRE, centre[0], "x of the reference's centre"),
            b.parameter(names::CENTRE_Y, METRE, centre[1], "y of the reference's centre"),
        ];
        let scale = b.parameter(names::REFERENCE_SCALE, None, scale, "Scale of the reference (1: the paper's size, 0.4 m × 0.3 m across)");
        let text = format!("Task-space computed-torque controller for a {n}-joint planar arm, the paper's reference (neurarm)");
        let description = describe(identifier, text, b.finish())?;
        let data = TaskSpaceData::new(&model);
        let learning = LearningSignalData::new(&model);
        Ok(Self {
            description,
            model,
            q,
            qd,
            tau_comp,
            tau,
            reference,
            error,
            kp,
            kd,
            null_damping,
            null_stiffness,
            rest_pose,
            centre,
            scale,
            signal,
            lambda,
            intended_speed,
            intent_horizon,
            data,
            learning,
            buf: std::array::from_fn(|_| vec![0.0; n]),
        })
    }
}

impl StaticModel for TaskSpaceControllerModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }

    fn compute(&mut self, values: &mut Values, time: f64) -> Result<(), ModelError> {
        let [q, qd, comp, tau] = &mut self.buf;
        values.read_reals(&self.q, q);
        values.read_reals(&self.qd, qd);
        values.read_reals(&self.tau_comp, comp);
        let centre = Vector2::new(values[self.centre[0]], values[self.centre[1]]);
        let gains = TaskSpaceGains {
            kp: values[self.kp],
            kd: values[self.kd],
            null_damping: values[self.null_damping],
            null_stiffness: values[self.null_stiffness],
        };
        // The rest pose goes through the torque buffer, which the law overwrites.
        values.read_reals(&self.rest_pose, tau);
        self.data.set_rest_pose(Some(tau));
        let (position, velocity, acceleration) = scaled_reference(time, centre, values[self.scale]);
        if ![position, velocity, acceleration].iter().all(|v| v.x.is_finite() && v.y.is_finite()) {
            return Err(ModelError::msg(format!(
                "the reference at t = {} s is not finite: the time or the reference's centre or scale is too large",
                neurarm_physics::arm::show_number(time)
            )));
        }
        let x = end_effector_position(&self.model, q);
        values[self.reference[0]] = position.x;
        values[self.reference[1]] = position.y;
        values[self.error[0]] = position.x - x.x;
        values[self.error[1]] = position.y - x.y;
        let reference = TaskReference { position, velocity, acceleration };
        if !task_space_torque_into(&self.model, &mut self.data, q, qd, &reference, &gains, comp, tau) {
            return Err(ModelError::msg(format!("no control law at t = {time} s: the inputs q = {q:?}, qd = {qd:?} are not finite")));
        }
        values.write_reals(&self.tau, tau);
        let horizon = values[self.intent_horizon];
        for ((v, &w), u) in tau.iter_mut().zip(qd.iter()).zip(self.data.acceleration()) {
            *v = intended_speed(w, horizon * u);
        }
        values.write_reals(&self.intended_speed, tau);
        // The torque buffer is written: reuse the compensation buffer for the signal.
        if !task_learning_signal_into(&self.model, &mut self.learning, q, qd, &reference, values[self.lambda], comp) {
            return Err(ModelError::msg(format!(
                "no learning signal at t = {time} s: the controller's mass matrix is not positive definite"
            )));
        }
        values.write_reals(&self.signal, comp);
        Ok(())
    }
}
