//! Forward kinematics of the planar arm: end-effector position x, its Jacobian J and the term
//! J̇·q̇ that task-space control needs (ẍ = J q̈ + J̇ q̇).
//!
//! All functions take relative joint angles `q` [rad] and velocities `qd` [rad/s]; positions
//! are in metres in the arm's plane, with the first joint at the origin.

use nalgebra::{DMatrix, Vector2};

use super::params::ArmParams;

/// Absolute link angles θᵢ = q₁ + … + qᵢ [rad] written into `theta` (same length as `q`).
#[inline]
pub fn absolute_angles_into(q: &[f64], theta: &mut [f64]) {
    let mut sum = 0.0;
    for (t, &qi) in theta.iter_mut().zip(q) {
        sum += qi;
        *t = sum;
    }
}

/// End-effector position (x, y) [m].
pub fn end_effector_position(params: &ArmParams, q: &[f64]) -> Vector2<f64> {
    let mut theta = 0.0;
    let mut pos = Vector2::zeros();
    for (link, &qi) in params.links.iter().zip(q) {
        theta += qi;
        pos += link.length_m * Vector2::new(theta.cos(), theta.sin());
    }
    pos
}

/// End-effector velocity ẋ = J q̇ [m/s].
pub fn end_effector_velocity(params: &ArmParams, q: &[f64], qd: &[f64]) -> Vector2<f64> {
    let mut theta = 0.0;
    let mut omega = 0.0;
    let mut vel = Vector2::zeros();
    for ((link, &qi), &qdi) in params.links.iter().zip(q).zip(qd) {
        theta += qi;
        omega += qdi;
        vel += link.length_m * omega * Vector2::new(-theta.sin(), theta.cos());
    }
    vel
}

/// End-effector position (x, y) [m] and velocity (ẋ, ẏ) [m/s] in one pass (one sine and
/// cosine per joint), as `[x, y, ẋ, ẏ]`.
pub fn end_effector_state(params: &ArmParams, q: &[f64], qd: &[f64]) -> [f64; 4] {
    let (mut theta, mut omega) = (0.0, 0.0);
    let mut out = [0.0; 4];
    for ((link, &qi), &qdi) in params.links.iter().zip(q).zip(qd) {
        theta += qi;
        omega += qdi;
        let (s, c) = theta.sin_cos();
        let l = link.length_m;
        out[0] += l * c;
        out[1] += l * s;
        out[2] -= l * omega * s;
        out[3] += l * omega * c;
    }
    out
}

/// The 2×n Jacobian of the end-effector position [m/rad]: column j is ∂x/∂q_j.
pub fn jacobian(params: &ArmParams, q: &[f64]) -> DMatrix<f64> {
    let n = params.dof();
    let mut jac = DMatrix::zeros(2, n);
    jacobian_into(params, q, jac.as_mut_slice());
    jac
}

/// Writes the Jacobian into `out`, column-major 2×n (`out.len() == 2n`), without allocating.
pub fn jacobian_into(params: &ArmParams, q: &[f64], out: &mut [f64]) {
    let n = params.dof();
    // Column j sums the contributions of links j..n; build it from the tip inwards.
    let mut theta_total: f64 = q.iter().sum();
    let (mut jx, mut jy) = (0.0, 0.0);
    for j in (0..n).rev() {
        let l = params.links[j].length_m;
        jx -= l * theta_total.sin();
        jy += l * theta_total.cos();
        out[2 * j] = jx;
        out[2 * j + 1] = jy;
        theta_total -= q[j];
    }
}

/// The term J̇·q̇ [m/s²]: the end-effector acceleration at q̈ = 0.
pub fn jacobian_dot_qd(params: &ArmParams, q: &[f64], qd: &[f64]) -> Vector2<f64> {
    let mut theta = 0.0;
    let mut omega = 0.0;
    let mut acc = Vector2::zeros();
    for ((link, &qi), &qdi) in params.links.iter().zip(q).zip(qd) {
        theta += qi;
        omega += qdi;
        acc -= link.length_m * omega * omega * Vector2::new(theta.cos(), theta.sin());
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jacobian_matches_finite_differences_of_position() {
        let p = ArmParams::default_four_link();
        let q = [0.3, -1.1, 0.7, 2.0];
        let jac = jacobian(&p, &q);
        let eps = 1e-6;
        for j in 0..4 {
            let mut qp = q;
            let mut qm = q;
            qp[j] += eps;
            qm[j] -= eps;
            let d = (end_effector_position(&p, &qp) - end_effector_position(&p, &qm)) / (2.0 * eps);
            assert!((d[0] - jac[(0, j)]).abs() < 1e-9);
            assert!((d[1] - jac[(1, j)]).abs() < 1e-9);
        }
    }

    #[test]
    fn end_effector_state_equals_position_and_velocity() {
        let p = ArmParams::default_four_link();
        let (q, qd) = ([0.3, -1.1, 0.7, 2.0], [1.2, -0.4, 2.5, -3.0]);
        let s = end_effector_state(&p, &q, &qd);
        let (x, v) = (end_effector_position(&p, &q), end_effector_velocity(&p, &q, &qd));
        for (a, b) in s.iter().zip([x[0], x[1], v[0], v[1]]) {
            assert!((a - b).abs() < 1e-15);
        }
    }

    #[test]
    fn jacobian_dot_qd_matches_finite_differences_of_velocity() {
        // d/dt (J q̇) at q̈ = 0 is J̇ q̇: differentiate ẋ(q + q̇ t, q̇) in t.
        let p = ArmParams::default_four_link();
        let q = [0.3, -1.1, 0.7, 2.0];
        let qd = [1.2, -0.4, 2.5, -3.0];
        let eps = 1e-6;
        let shifted = |s: f64| -> Vec<f64> { q.iter().zip(&qd).map(|(a, b)| a + s * b).collect() };
        let d = (end_effector_velocity(&p, &shifted(eps), &qd) - end_effector_velocity(&p, &shifted(-eps), &qd)) / (2.0 * eps);
        let exact = jacobian_dot_qd(&p, &q, &qd);
        assert!((d - exact).norm() < 1e-7, "{d} vs {exact}");
    }
}
