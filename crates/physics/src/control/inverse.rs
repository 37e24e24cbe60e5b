//! Inverses of the 2×n task Jacobian: the Moore–Penrose pseudo-inverse (rank-cut at singular
//! poses), the damped inverse of the task-space law near singular poses, and inverse kinematics
//! by Newton steps with the pseudo-inverse.

use nalgebra::{DMatrix, DVector, Matrix2, Vector2};

use crate::arm::{jacobian, ArmParams};

/// Moore–Penrose pseudo-inverse J⁺ (n×2) of a 2×n Jacobian `jac` into `out`, with `jac_t`
/// (n×2) and `jjt_inverse` (2×2) as scratch. Away from singular poses this is Jᵀ (J Jᵀ)⁻¹;
/// where J loses rank (σ_min < 1e-6 σ_max) it is Jᵀ (J Jᵀ)⁺ with the lost direction dropped
/// (the identity J⁺ = Jᵀ (J Jᵀ)⁺ holds for any J), from the closed-form eigenvectors of the
/// 2×2 matrix J Jᵀ. So J⁺ exists at every pose: any master that starts its connections at
/// zero (q = 0 is the stretched, singular pose) gets a bounded answer. Returns false, leaving
/// `out` meaningless, only when J is not finite.
pub fn pseudo_inverse_into(jac: &DMatrix<f64>, jac_t: &mut DMatrix<f64>, jjt_inverse: &mut DMatrix<f64>, out: &mut DMatrix<f64>) -> bool {
    if !jac.iter().all(|v| v.is_finite()) {
        return false;
    }
    let m = jacobian_product_into(jac, jac_t);
    pseudo_inverse_from(&m, jac_t, jjt_inverse, out);
    true
}

/// Jᵀ into `jac_t` and J Jᵀ returned.
fn jacobian_product_into(jac: &DMatrix<f64>, jac_t: &mut DMatrix<f64>) -> Matrix2<f64> {
    jac.transpose_to(jac_t);
    let mut m = Matrix2::zeros();
    jac.mul_to(jac_t, &mut m);
    m
}

/// J⁺ = Jᵀ (J Jᵀ)⁺ into `out` from `m` = J Jᵀ and `jac_t` = Jᵀ ([`pseudo_inverse_into`]).
fn pseudo_inverse_from(m: &Matrix2<f64>, jac_t: &DMatrix<f64>, jjt_inverse: &mut DMatrix<f64>, out: &mut DMatrix<f64>) {
    // det(JJᵀ)/‖JJᵀ‖² ≈ (σ₂/σ₁)²: the fast form while σ₂/σ₁ > 1e-6.
    let regular = m.determinant().abs() > 1e-12 * m.norm_squared();
    match m.try_inverse().filter(|_| regular) {
        Some(inv) => jjt_inverse.copy_from(&inv),
        None => jjt_inverse.copy_from(&rank_cut_inverse(m)),
    }
    jac_t.mul_to(jjt_inverse, out);
}

/// The eigenvalues (λ₁, λ₂), λ₁ ≥ λ₂ ≥ 0, of the symmetric positive semi-definite 2×2 `m`
/// (J Jᵀ: σ₁², σ₂²), in closed form.
fn eigenvalues(m: &Matrix2<f64>) -> (f64, f64) {
    let (a, b, c) = (m[(0, 0)], 0.5 * (m[(0, 1)] + m[(1, 0)]), m[(1, 1)]);
    let half_gap = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    (0.5 * (a + c) + half_gap, (0.5 * (a + c) - half_gap).max(0.0))
}

/// (J Jᵀ)⁺ of the symmetric positive semi-definite 2×2 `m` = J Jᵀ, keeping the eigenvalue
/// λ₂ only if σ₂ = √λ₂ exceeds 1e-6 σ₁.
fn rank_cut_inverse(m: &Matrix2<f64>) -> Matrix2<f64> {
    let (a, b, c) = (m[(0, 0)], 0.5 * (m[(0, 1)] + m[(1, 0)]), m[(1, 1)]);
    let (largest, smallest) = eigenvalues(m);
    if !(largest > 0.0) {
        return Matrix2::zeros();
    }
    // Eigenvector of the largest eigenvalue from the better-conditioned row of m − λ₁I.
    let v = if a >= c { Vector2::new(largest - c, b) } else { Vector2::new(b, largest - a) };
    let v = if v.norm() > 0.0 { v.normalize() } else { Vector2::new(1.0, 0.0) };
    let w = Vector2::new(-v.y, v.x);
    let mut inverse = v * v.transpose() / largest;
    if smallest > 1e-12 * largest {
        inverse += w * w.transpose() / smallest;
    }
    inverse
}

/// Moore–Penrose pseudo-inverse J⁺ (n×2) of a 2×n Jacobian: [`pseudo_inverse_into`] into a
/// new matrix. `None` only when J is not finite.
pub fn pseudo_inverse(jac: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let n = jac.ncols();
    let (mut jac_t, mut jjt_inverse, mut out) = (DMatrix::zeros(n, 2), DMatrix::zeros(2, 2), DMatrix::zeros(n, 2));
    pseudo_inverse_into(jac, &mut jac_t, &mut jjt_inverse, &mut out).then_some(out)
}

/// The singular-value margin ε of the task-space law's inverse as a share of the arm's reach
/// (ε = 0.05 R [m/rad]; see [`damped_inverse_into`]).
pub const SINGULAR_MARGIN_SHARE: f64 = 0.05;

/// The task-space law's inverse J# (n×2) of a 2×n Jacobian into `out`: the Moore–Penrose
/// pseudo-inverse ([`pseudo_inverse_into`], the same numbers) while J's smallest singular value
/// σ₂ is at least `margin` ε [m/rad], and within ε of a singular pose the damped least-squares
/// inverse Jᵀ (J Jᵀ + λ² I)⁻¹ with λ² = ε² − σ₂². J# is continuous at σ₂ = ε and ‖J#‖ ≤ 1/ε, so
/// the joint accelerations stay bounded where a redundant arm's self-motion reaches a singular
/// pose (docs/decisions/0008-damped-inverse.md). Returns false, leaving `out` meaningless, only
/// when J is not finite.
pub fn damped_inverse_into(
    jac: &DMatrix<f64>,
    margin: f64,
    jac_t: &mut DMatrix<f64>,
    jjt_inverse: &mut DMatrix<f64>,
    out: &mut DMatrix<f64>,
) -> bool {
    if !jac.iter().all(|v| v.is_finite()) {
        return false;
    }
    let mut m = jacobian_product_into(jac, jac_t);
    let damping = margin * margin - eigenvalues(&m).1;
    if !(damping > 0.0) {
        pseudo_inverse_from(&m, jac_t, jjt_inverse, out);
        return true;
    }
    m[(0, 0)] += damping;
    m[(1, 1)] += damping;
    match m.try_inverse() {
        Some(inv) => jjt_inverse.copy_from(&inv),
        None => return false,
    }
    jac_t.mul_to(jjt_inverse, out);
    true
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
