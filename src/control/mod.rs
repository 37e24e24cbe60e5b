//! Control laws of the paper as plain functions of the arm model: task-space computed torque
//! for the redundant arm (pseudo-inverse with null-space damping) and joint-space P control
//! with gravity compensation. Nothing here knows about FMI; the controller FMUs wrap these.

use nalgebra::{DMatrix, DVector, Matrix2, Vector2};

use crate::arm::{inverse_dynamics_rnea, jacobian, jacobian_dot_qd, ArmParams};

/// The paper's task-space reference around `centre` [m] at time `t` [s]:
/// x_d = centre + (0.2 (cos t + sin 2t), 0.15 (sin t + cos 2t)). The curve (period 2π s) starts
/// at centre + (0.2, 0.15) and passes through `centre` itself where sin t = −1/2.
/// Returns position [m], velocity [m/s] and acceleration [m/s²].
pub fn paper_reference(t: f64, centre: Vector2<f64>) -> (Vector2<f64>, Vector2<f64>, Vector2<f64>) {
    let (s1, c1, s2, c2) = (t.sin(), t.cos(), (2.0 * t).sin(), (2.0 * t).cos());
    let x = centre + Vector2::new(0.2 * (c1 + s2), 0.15 * (s1 + c2));
    let xd = Vector2::new(0.2 * (-s1 + 2.0 * c2), 0.15 * (c1 - 2.0 * s2));
    let xdd = Vector2::new(0.2 * (-c1 - 4.0 * s2), 0.15 * (-s1 - 4.0 * c2));
    (x, xd, xdd)
}

/// Moore–Penrose pseudo-inverse J⁺ (n×2) of a 2×n Jacobian. Away from singular poses this
/// is Jᵀ (J Jᵀ)⁻¹; where J loses rank (σ_min < 1e-6 σ_max) it comes from the SVD with the
/// lost direction dropped, so J⁺ exists at every pose: any master that starts its
/// connections at zero (q = 0 is the stretched, singular pose) gets a bounded answer.
/// `None` only when J is not finite.
pub fn pseudo_inverse(jac: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    if !jac.iter().all(|v| v.is_finite()) {
        return None;
    }
    let jjt = jac * jac.transpose();
    let m = Matrix2::new(jjt[(0, 0)], jjt[(0, 1)], jjt[(1, 0)], jjt[(1, 1)]);
    // det(JJᵀ)/‖JJᵀ‖² ≈ (σ₂/σ₁)²: the fast form while σ₂/σ₁ > 1e-6.
    if m.determinant().abs() > 1e-12 * m.norm_squared() {
        if let Some(inv) = m.try_inverse() {
            return Some(jac.transpose() * DMatrix::from_fn(2, 2, |r, c| inv[(r, c)]));
        }
    }
    let svd = jac.clone().try_svd(true, true, f64::EPSILON, 0)?;
    let largest = svd.singular_values.max();
    svd.pseudo_inverse(1e-6 * largest.max(f64::MIN_POSITIVE)).ok()
}

/// Gains and null-space damping of the task-space controller.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TaskSpaceGains {
    /// Position gain K_p [1/s²] (the paper: 1000).
    pub kp: f64,
    /// Velocity gain K_d [1/s] (the paper: 160).
    pub kd: f64,
    /// Damping of the self-motion in the null space of J [1/s]: the redundant joints get
    /// q̈_null = −k (I − J⁺J) q̇, so motion the task does not need dies out.
    pub null_damping: f64,
}

impl Default for TaskSpaceGains {
    fn default() -> Self {
        Self { kp: 1000.0, kd: 160.0, null_damping: 10.0 }
    }
}

/// Desired end-effector motion: position [m], velocity [m/s], acceleration [m/s²].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaskReference {
    /// x_d.
    pub position: Vector2<f64>,
    /// ẋ_d.
    pub velocity: Vector2<f64>,
    /// ẍ_d.
    pub acceleration: Vector2<f64>,
}

/// Joint accelerations the task-space law asks for:
/// u = J⁺ (ẍ_d + K_d (ẋ_d − ẋ) + K_p (x_d − x) − J̇q̇) − k (I − J⁺J) q̇.
pub fn task_space_acceleration(model: &ArmParams, q: &[f64], qd: &[f64], reference: &TaskReference, gains: &TaskSpaceGains) -> Option<DVector<f64>> {
    let n = model.dof();
    let jac = jacobian(model, q);
    let pinv = pseudo_inverse(&jac)?;
    let qd_v = DVector::from_column_slice(qd);
    let x = crate::arm::end_effector_position(model, q);
    let xd = Vector2::new((jac.row(0) * &qd_v)[0], (jac.row(1) * &qd_v)[0]);
    let a = reference.acceleration + gains.kd * (reference.velocity - xd) + gains.kp * (reference.position - x) - jacobian_dot_qd(model, q, qd);
    let task = &pinv * DVector::from_column_slice(a.as_slice());
    let null = DMatrix::<f64>::identity(n, n) - &pinv * &jac;
    Some(task - gains.null_damping * (null * qd_v))
}

/// Computed torque τ = Ĥ(q) u + Ĉ(q,q̇) q̇ + ĝ(q) + τ_comp [N·m] with `model` the controller's
/// model of the arm (friction excluded: that is what `tau_comp` is for).
pub fn computed_torque(model: &ArmParams, q: &[f64], qd: &[f64], u: &DVector<f64>, tau_comp: &[f64]) -> DVector<f64> {
    inverse_dynamics_rnea(model, q, qd, u.as_slice()) + DVector::from_column_slice(tau_comp)
}

/// Joint-space P control with gravity compensation: τ = ĝ + K_p (q_d − q) [N·m].
pub fn joint_p_torque(q: &[f64], q_target: &[f64], kp: f64, gravity_comp: &[f64]) -> DVector<f64> {
    DVector::from_fn(q.len(), |i, _| gravity_comp[i] + kp * (q_target[i] - q[i]))
}

/// Joint angles [rad] that put the end effector at `target` [m], found by Newton steps with
/// the pseudo-inverse from `seed` (so the answer is the solution reached by the smallest
/// joint motion from there, to first order). `None` if it does not converge to 1e-12 m or
/// meets a singular pose.
pub fn inverse_kinematics(model: &ArmParams, target: Vector2<f64>, seed: &[f64]) -> Option<Vec<f64>> {
    let mut q = seed.to_vec();
    for _ in 0..100 {
        let e = target - crate::arm::end_effector_position(model, &q);
        if e.norm() < 1e-12 {
            return Some(q);
        }
        let step = pseudo_inverse(&jacobian(model, &q))? * DVector::from_column_slice(e.as_slice());
        for (qi, d) in q.iter_mut().zip(step.iter()) {
            *qi += d;
        }
    }
    None
}
