//! The joint-space learning signal of task-space computed torque, along which an adaptive
//! compensator's weights move.

use nalgebra::DMatrix;

use super::reference::TaskReference;
use crate::arm::{jacobian_into, ArmData, ArmParams};

/// Scratch space of [`task_learning_signal_into`] for one arm, made once.
#[derive(Clone, Debug)]
pub struct LearningSignalData {
    arm: ArmData,
    mass: DMatrix<f64>,
    jacobian: Vec<f64>,
}

impl LearningSignalData {
    /// Scratch space for the arm of `model`.
    pub fn new(model: &ArmParams) -> Self {
        let n = model.dof();
        Self { arm: ArmData::new(model), mass: DMatrix::zeros(n, n), jacobian: vec![0.0; 2 * n] }
    }
}

/// The joint-space learning signal of task-space computed torque, `s = Ĥ⁻¹ Jᵀ (ė + λ e)` with
/// `e = x_d − x`, `ė = ẋ_d − J q̇` [1/(kg·s)], into `out` (one entry per joint). An error
/// `δ` in the compensating torque enters the task-space error dynamics as `J Ĥ⁻¹ δ`; along `s`
/// the Lyapunov function of those dynamics falls when a compensator's weights move with
/// `φ s` (see the adaptive compensator). `lambda` [1/s] must lie in (0, K_d). Allocates
/// nothing; returns false, leaving `out` alone, when the inputs are not finite or Ĥ is not
/// positive definite.
pub fn task_learning_signal_into(
    model: &ArmParams,
    data: &mut LearningSignalData,
    q: &[f64],
    qd: &[f64],
    reference: &TaskReference,
    lambda: f64,
    out: &mut [f64],
) -> bool {
    let n = model.dof();
    if !q.iter().chain(qd).all(|v| v.is_finite()) {
        return false;
    }
    let x = crate::arm::end_effector_position(model, q);
    jacobian_into(model, q, &mut data.jacobian);
    let (mut xd_x, mut xd_y) = (0.0, 0.0);
    for j in 0..n {
        xd_x += data.jacobian[2 * j] * qd[j];
        xd_y += data.jacobian[2 * j + 1] * qd[j];
    }
    let vx = reference.velocity.x - xd_x + lambda * (reference.position.x - x.x);
    let vy = reference.velocity.y - xd_y + lambda * (reference.position.y - x.y);
    let mut rhs = [0.0; crate::arm::MAX_JOINTS];
    for j in 0..n {
        rhs[j] = data.jacobian[2 * j] * vx + data.jacobian[2 * j + 1] * vy;
    }
    crate::arm::mass_matrix_into(model, &mut data.arm, q, &mut data.mass);
    if !crate::linalg::cholesky_solve_in_place(data.mass.as_mut_slice(), n, &mut rhs[..n]) {
        return false;
    }
    out[..n].copy_from_slice(&rhs[..n]);
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arm::inverse_dynamics_rnea;
    use nalgebra::Vector2;

    #[test]
    fn the_learning_signal_solves_h_s_equal_jt_v_by_recursive_newton_euler() {
        // Independent of the mass-matrix formulation: on the arm without gravity and friction
        // RNEA(q, 0, s) = H s, and Jᵀ v from finite differences of the forward kinematics.
        let model = ArmParams::default_four_link().frictionless();
        let q = [0.4, -0.9, 1.2, 0.3];
        let qd = [0.5, -0.2, 0.8, -1.1];
        let reference =
            TaskReference { position: Vector2::new(0.5, 0.2), velocity: Vector2::new(-0.1, 0.3), acceleration: Vector2::zeros() };
        let lambda = 20.0;
        let mut data = LearningSignalData::new(&model);
        let mut s = [0.0; 4];
        assert!(task_learning_signal_into(&model, &mut data, &q, &qd, &reference, lambda, &mut s));
        let hs = inverse_dynamics_rnea(&model, &q, &[0.0; 4], &s);
        let fk = |q: &[f64]| crate::arm::end_effector_position(&model, q);
        let eps = 1e-6;
        let columns: Vec<Vector2<f64>> = (0..4)
            .map(|j| {
                let (mut up, mut down) = (q, q);
                up[j] += eps;
                down[j] -= eps;
                (fk(&up) - fk(&down)) / (2.0 * eps)
            })
            .collect();
        let x = fk(&q);
        let xdot: Vector2<f64> = columns.iter().zip(&qd).map(|(c, v)| c * *v).sum();
        let v = reference.velocity - xdot + lambda * (reference.position - x);
        for j in 0..4 {
            let jt_v = columns[j].dot(&v);
            assert!((hs[j] - jt_v).abs() < 1e-7 * (1.0 + jt_v.abs()), "joint {j}: H s = {} vs Jᵀv = {jt_v}", hs[j]);
        }
        assert!(!task_learning_signal_into(&model, &mut data, &[f64::NAN, 0.0, 0.0, 0.0], &qd, &reference, lambda, &mut s));
    }
}
