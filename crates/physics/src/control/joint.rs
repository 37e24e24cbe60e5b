//! Joint-space P control with gravity compensation.

use nalgebra::DVector;

/// Joint-space P control with gravity compensation: τ = ĝ + K_p (q_d − q) [N·m].
pub fn joint_p_torque(q: &[f64], q_target: &[f64], kp: f64, gravity_comp: &[f64]) -> DVector<f64> {
    DVector::from_fn(q.len(), |i, _| gravity_comp[i] + kp * (q_target[i] - q[i]))
}
