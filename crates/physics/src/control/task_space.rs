//! Task-space computed torque for the redundant arm: the joint accelerations of the task-space
//! law (J# of the task acceleration plus the null-space term), and the torques of those
//! accelerations by the controller's model.

use nalgebra::{DMatrix, DVector, Vector2};

use super::gains::TaskSpaceGains;
use super::inverse::{damped_inverse_into, SINGULAR_MARGIN_SHARE};
use super::reference::TaskReference;
use crate::arm::{inverse_dynamics_rnea_into, jacobian_dot_qd, jacobian_into, ArmData, ArmParams};

/// Scratch space of the task-space law for one arm, made once: the Jacobian J, its
/// pseudo-inverse J⁺, the null-space projector I − J⁺J, the joint accelerations u and the
/// rigid-body data of the computed torque.
#[derive(Clone, Debug)]
pub struct TaskSpaceData {
    jacobian: DMatrix<f64>,
    jacobian_t: DMatrix<f64>,
    jjt_inverse: DMatrix<f64>,
    pseudo_inverse: DMatrix<f64>,
    pinv_j: DMatrix<f64>,
    null_projector: DMatrix<f64>,
    qd: DVector<f64>,
    task_acceleration: DVector<f64>,
    task: DVector<f64>,
    null_motion: DVector<f64>,
    /// The null-space term before projection: k_s (q_rest − q) − k q̇ [rad/s²].
    null_target: DVector<f64>,
    rest_pose: DVector<f64>,
    has_rest_pose: bool,
    u: DVector<f64>,
    /// ε of [`damped_inverse_into`]: [`SINGULAR_MARGIN_SHARE`] of the reach [m/rad].
    singular_margin: f64,
    arm: ArmData,
}

impl TaskSpaceData {
    /// Scratch space for the arm of `model`.
    pub fn new(model: &ArmParams) -> Self {
        let n = model.dof();
        Self {
            jacobian: DMatrix::zeros(2, n),
            jacobian_t: DMatrix::zeros(n, 2),
            jjt_inverse: DMatrix::zeros(2, 2),
            pseudo_inverse: DMatrix::zeros(n, 2),
            pinv_j: DMatrix::zeros(n, n),
            null_projector: DMatrix::zeros(n, n),
            qd: DVector::zeros(n),
            task_acceleration: DVector::zeros(2),
            task: DVector::zeros(n),
            null_motion: DVector::zeros(n),
            null_target: DVector::zeros(n),
            rest_pose: DVector::zeros(n),
            has_rest_pose: false,
            u: DVector::zeros(n),
            singular_margin: SINGULAR_MARGIN_SHARE * model.links.iter().map(|l| l.length_m).sum::<f64>(),
            arm: ArmData::new(model),
        }
    }

    /// ε of the task-space law's inverse [m/rad] (see [`damped_inverse_into`]).
    pub fn singular_margin(&self) -> f64 {
        self.singular_margin
    }

    /// Gives the self-motion a rest pose `q_rest` [rad], one angle per joint (see
    /// [`TaskSpaceGains::null_stiffness`]); `None` leaves it damped only. Each joint's
    /// distance to its rest angle is taken within (−π, π], so a joint that has turned a whole
    /// revolution is home. Allocates nothing; panics when `q_rest` has not one angle per joint.
    pub fn set_rest_pose(&mut self, q_rest: Option<&[f64]>) {
        self.has_rest_pose = q_rest.is_some();
        if let Some(q) = q_rest {
            self.rest_pose.copy_from_slice(q);
        }
    }

    /// The rest pose of the self-motion [rad], if any.
    pub fn rest_pose(&self) -> Option<&[f64]> {
        self.has_rest_pose.then_some(self.rest_pose.as_slice())
    }

    /// The joint accelerations u [rad/s²] of the last [`task_space_acceleration_into`].
    pub fn acceleration(&self) -> &[f64] {
        self.u.as_slice()
    }

    /// The Jacobian J [m/rad] of the last call.
    pub fn jacobian(&self) -> &DMatrix<f64> {
        &self.jacobian
    }

    /// The inverse J# [rad/m] of the last call: J⁺, damped near a singular pose ([`damped_inverse_into`]).
    pub fn pseudo_inverse(&self) -> &DMatrix<f64> {
        &self.pseudo_inverse
    }

    /// I − J#J of the last call: the null-space projector I − J⁺J away from singular poses.
    pub fn null_projector(&self) -> &DMatrix<f64> {
        &self.null_projector
    }
}

/// Joint accelerations the task-space law asks for,
/// u = J# (ẍ_d + K_d (ẋ_d − ẋ) + K_p (x_d − x) − J̇q̇) + (I − J#J)(k_s (q_rest − q) − k q̇)
/// [rad/s²], into `data` ([`TaskSpaceData::acceleration`]), J# the pseudo-inverse J⁺, damped
/// within [`TaskSpaceData::singular_margin`] of a singular pose ([`damped_inverse_into`]);
/// without a rest pose in `data` the k_s term is left out. False when the inputs are not
/// finite.
pub fn task_space_acceleration_into(
    model: &ArmParams,
    data: &mut TaskSpaceData,
    q: &[f64],
    qd: &[f64],
    reference: &TaskReference,
    gains: &TaskSpaceGains,
) -> bool {
    let d = data;
    jacobian_into(model, q, d.jacobian.as_mut_slice());
    if !damped_inverse_into(&d.jacobian, d.singular_margin, &mut d.jacobian_t, &mut d.jjt_inverse, &mut d.pseudo_inverse) {
        return false;
    }
    d.qd.copy_from_slice(qd);
    let x = crate::arm::end_effector_position(model, q);
    let xd = Vector2::new((d.jacobian.row(0) * &d.qd)[0], (d.jacobian.row(1) * &d.qd)[0]);
    let a =
        reference.acceleration + gains.kd * (reference.velocity - xd) + gains.kp * (reference.position - x) - jacobian_dot_qd(model, q, qd);
    d.task_acceleration.copy_from_slice(a.as_slice());
    d.pseudo_inverse.mul_to(&d.task_acceleration, &mut d.task);
    d.pseudo_inverse.mul_to(&d.jacobian, &mut d.pinv_j);
    d.null_projector.fill_with_identity();
    d.null_projector -= &d.pinv_j;
    if d.has_rest_pose && gains.null_stiffness != 0.0 {
        for i in 0..q.len() {
            d.null_target[i] = gains.null_stiffness * wrapped_angle(d.rest_pose[i] - q[i]) - gains.null_damping * qd[i];
        }
        d.null_projector.mul_to(&d.null_target, &mut d.null_motion);
        for ((u, t), m) in d.u.iter_mut().zip(d.task.iter()).zip(d.null_motion.iter()) {
            *u = t + m;
        }
    } else {
        // Damping only, computed as −k (N q̇) rather than N (−k q̇): the same in exact
        // arithmetic, and the rounding the long closed loops were measured with
        // (docs/decisions/0001-null-space-damping.md).
        d.null_projector.mul_to(&d.qd, &mut d.null_motion);
        for ((u, t), m) in d.u.iter_mut().zip(d.task.iter()).zip(d.null_motion.iter()) {
            *u = t - gains.null_damping * m;
        }
    }
    d.u.iter().all(|u| u.is_finite())
}

/// `angle` [rad] moved by whole turns into (−π, π].
pub fn wrapped_angle(angle: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    let a = angle - tau * (angle / tau).round();
    if a <= -std::f64::consts::PI {
        a + tau
    } else {
        a
    }
}

/// Joint accelerations the task-space law asks for: [`task_space_acceleration_into`] into a
/// new vector, without a rest pose; `None` when the inputs are not finite.
pub fn task_space_acceleration(
    model: &ArmParams,
    q: &[f64],
    qd: &[f64],
    reference: &TaskReference,
    gains: &TaskSpaceGains,
) -> Option<DVector<f64>> {
    let mut data = TaskSpaceData::new(model);
    task_space_acceleration_into(model, &mut data, q, qd, reference, gains).then_some(data.u)
}

/// Computed torque τ = Ĥ(q) u + Ĉ(q,q̇) q̇ + ĝ(q) + τ_comp [N·m] into `out`, with `model` the
/// controller's model of the arm (friction excluded: that is what `tau_comp` is for).
pub fn computed_torque_into(model: &ArmParams, data: &mut ArmData, q: &[f64], qd: &[f64], u: &[f64], tau_comp: &[f64], out: &mut [f64]) {
    inverse_dynamics_rnea_into(model, data, q, qd, u, out);
    for (t, c) in out.iter_mut().zip(tau_comp) {
        *t += c;
    }
}

/// Computed torque: [`computed_torque_into`] into a new vector.
pub fn computed_torque(model: &ArmParams, q: &[f64], qd: &[f64], u: &DVector<f64>, tau_comp: &[f64]) -> DVector<f64> {
    let mut tau = DVector::zeros(model.dof());
    computed_torque_into(model, &mut ArmData::new(model), q, qd, u.as_slice(), tau_comp, tau.as_mut_slice());
    tau
}

/// The whole task-space law: the accelerations of [`task_space_acceleration_into`] turned
/// into joint torques by [`computed_torque_into`], plus `tau_comp` [N·m], into `out`. False
/// when the inputs are not finite.
#[allow(clippy::too_many_arguments)] // the law's inputs, each a different quantity
pub fn task_space_torque_into(
    model: &ArmParams,
    data: &mut TaskSpaceData,
    q: &[f64],
    qd: &[f64],
    reference: &TaskReference,
    gains: &TaskSpaceGains,
    tau_comp: &[f64],
    out: &mut [f64],
) -> bool {
    if !task_space_acceleration_into(model, data, q, qd, reference, gains) {
        return false;
    }
    computed_torque_into(model, &mut data.arm, q, qd, data.u.as_slice(), tau_comp, out);
    true
}
