//! Small dense linear algebra that must not allocate, for the arm's steps (the mass matrix's
//! solves in the integrator and the control laws), where nalgebra's decompositions would take
//! owned matrices. The trainer's blocked factorisation lives in `neurarm-nn`, whose triangular
//! solves this one shares.

use neurarm_nn::linalg::cholesky_solve_factored;

/// Solves A x = b for symmetric positive definite A (row-major m×m; its upper triangle is
/// overwritten by the Cholesky factor U, A = UᵀU), x replacing b. Returns false, leaving `b`
/// meaningless, if A is not numerically positive definite.
///
/// Right-looking, so the inner loops are updates of contiguous rows (axpy), which the
/// compiler vectorises; only the upper triangle of A is read.
pub fn cholesky_solve_in_place(a: &mut [f64], m: usize, b: &mut [f64]) -> bool {
    for k in 0..m {
        let (head, tail) = a.split_at_mut((k + 1) * m);
        let row_k = &mut head[k * m..];
        let d = row_k[k];
        if !(d > 0.0 && d.is_finite()) {
            return false;
        }
        let pivot = d.sqrt();
        row_k[k] = pivot;
        let inv = 1.0 / pivot;
        for v in &mut row_k[k + 1..] {
            *v *= inv;
        }
        // Trailing update of the upper triangle: A[i][i..] -= U[k][i] · U[k][i..].
        for i in k + 1..m {
            let f = row_k[i];
            if f != 0.0 {
                let row_i = &mut tail[(i - k - 1) * m + i..(i - k - 1) * m + m];
                for (x, u) in row_i.iter_mut().zip(&row_k[i..]) {
                    *x -= f * u;
                }
            }
        }
    }
    // UᵀU x = b: a forward and a backward substitution.
    cholesky_solve_factored(a, m, b);
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_spd_systems_of_many_sizes() {
        for m in [1, 2, 3, 5, 8, 17, 40] {
            // A = B Bᵀ + m I is SPD; compare A x with b.
            let bm: Vec<f64> = (0..m * m).map(|i| ((i * 37 % 11) as f64 - 5.0) / 7.0).collect();
            let mut a = vec![0.0; m * m];
            for i in 0..m {
                for j in 0..m {
                    a[i * m + j] = (0..m).map(|k| bm[i * m + k] * bm[j * m + k]).sum::<f64>() + if i == j { m as f64 } else { 0.0 };
                }
            }
            let x_true: Vec<f64> = (0..m).map(|i| (i as f64 * 0.7).sin()).collect();
            let mut b: Vec<f64> = (0..m).map(|i| (0..m).map(|k| a[i * m + k] * x_true[k]).sum()).collect();
            let mut f = a.clone();
            assert!(cholesky_solve_in_place(&mut f, m, &mut b));
            for i in 0..m {
                assert!((b[i] - x_true[i]).abs() < 1e-12, "m = {m}");
            }
        }
    }

    #[test]
    fn rejects_indefinite_matrices() {
        let mut a = [1.0, 2.0, 2.0, 1.0];
        let mut b = [1.0, 1.0];
        assert!(!cholesky_solve_in_place(&mut a, 2, &mut b));
    }
}
