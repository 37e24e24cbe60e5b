//! Dense linear algebra of the trainer that must not allocate: the blocked, shifted Cholesky
//! factorisation of JᵀJ + μI (GEMM updates by matrixmultiply, column pieces as tasks of a
//! [`ParallelFor`]), its triangular solves, and a measure of the GEMM's speed for benchmarks.
//! The triangular solves are shared with `neurarm-physics`, whose small unblocked
//! factorisation of the mass matrix ends in the same solves.

use crate::parallel::{ParallelFor, SharedSlice};

/// Dot product with four independent accumulators (lets the compiler pipeline and vectorise
/// what a single running sum would serialise).
#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (mut s0, mut s1, mut s2, mut s3) = (0.0, 0.0, 0.0, 0.0);
    let chunks = n / 4;
    for c in 0..chunks {
        let i = 4 * c;
        s0 += a[i] * b[i];
        s1 += a[i + 1] * b[i + 1];
        s2 += a[i + 2] * b[i + 2];
        s3 += a[i + 3] * b[i + 3];
    }
    let mut s = (s0 + s1) + (s2 + s3);
    for i in 4 * chunks..n {
        s += a[i] * b[i];
    }
    s
}

/// Rows per block of [`cholesky_shifted`]: the GEMM updates run with at least this many rows,
/// and the unblocked work inside a block (≈ m²·NB/2 flops in all) stays small.
const CHOLESKY_BLOCK: usize = 32;
/// Columns per task of [`cholesky_shifted`]'s block-row updates.
const CHOLESKY_PIECE: usize = 128;

/// Cholesky factor U (A + shift·I = UᵀU) of the symmetric matrix A (row-major m×m, only its
/// upper triangle read) into the upper triangle of `u` (its lower triangle is left
/// meaningless). Returns false if A + shift·I is not numerically positive definite.
///
/// Left-looking by block rows, each updated by one GEMM over the finished rows (GEMM speed, not
/// axpy speed), in column pieces run as tasks on `par`. Every element is computed by the same
/// operations whatever thread runs it, so the factor does not depend on `par`.
pub fn cholesky_shifted(a: &[f64], shift: f64, u: &mut [f64], m: usize, par: &dyn ParallelFor) -> bool {
    assert!(a.len() >= m * m && u.len() >= m * m);
    let u = SharedSlice::new(&mut u[..m * m]);
    for k0 in (0..m).step_by(CHOLESKY_BLOCK) {
        let rows = BlockRow { a, shift, u, m, k0, k1: (k0 + CHOLESKY_BLOCK).min(m) };
        // The diagonal block first: the pieces right of it are solved with it.
        // SAFETY: no task is running; rows < k0 are final.
        if !unsafe { rows.factor_diagonal() } {
            return false;
        }
        let pieces = (m - rows.k1).div_ceil(CHOLESKY_PIECE);
        par.run(pieces, &|t| {
            let c0 = rows.k1 + t * CHOLESKY_PIECE;
            let c1 = (c0 + CHOLESKY_PIECE).min(m);
            // SAFETY: columns c0..c1 of the block row are this task's alone; the diagonal
            // block and rows < k0 are final and only read.
            unsafe { rows.solve_piece(c0, c1) };
        });
    }
    true
}

/// Block row k0..k1 of [`cholesky_shifted`]: A + shift·I into the factor `u` (row-major m×m),
/// whose rows < k0 are final.
#[derive(Clone, Copy)]
struct BlockRow<'a> {
    a: &'a [f64],
    shift: f64,
    u: SharedSlice<'a>,
    m: usize,
    k0: usize,
    k1: usize,
}

impl BlockRow<'_> {
    /// Rows k0..k1, columns c0..c1 of U before their own block's elimination: copied from A,
    /// shifted on the diagonal, minus the finished rows' contribution (one GEMM).
    ///
    /// # Safety
    /// No other live reference may touch rows k0..k1, columns c0..c1 of `u`, nor write rows
    /// < k0.
    unsafe fn update(&self, c0: usize, c1: usize) {
        let (a, m, k0, k1) = (self.a, self.m, self.k0, self.k1);
        for r in k0..k1 {
            let lo = c0.max(r);
            // SAFETY: rows k0..k1, columns c0..c1 belong to this call alone (the caller's
            // promise); rows < k0 are only read.
            let row = unsafe { self.u.part(r * m + lo, c1 - lo) };
            row.copy_from_slice(&a[r * m + lo..r * m + c1]);
            if lo == r {
                row[0] += self.shift;
            }
        }
        if k0 > 0 {
            let base = self.u.as_ptr();
            // SAFETY: A = U[0..k0, k0..k1]ᵀ and B = U[0..k0, c0..c1] are finished rows
            // (read only); C = rows k0..k1, columns c0..c1 is this call's. The elements of
            // C below the diagonal are written but never read.
            unsafe {
                matrixmultiply::dgemm(
                    k1 - k0,
                    k0,
                    c1 - c0,
                    -1.0,
                    base.add(k0),
                    1,
                    m as isize,
                    base.add(c0),
                    m as isize,
                    1,
                    1.0,
                    base.add(k0 * m + c0),
                    m as isize,
                    1,
                );
            }
        }
    }

    /// Updates and factors the diagonal block (rows and columns k0..k1); false if it is not
    /// numerically positive definite.
    ///
    /// # Safety
    /// No other live reference may touch rows k0..k1 of `u`, nor write rows < k0.
    unsafe fn factor_diagonal(&self) -> bool {
        let (m, k0, k1) = (self.m, self.k0, self.k1);
        // SAFETY: the caller's promise covers columns k0..k1 of rows k0..k1.
        unsafe { self.update(k0, k1) };
        for i in k0..k1 {
            // SAFETY: rows k0..k1 of the diagonal block are ours (the caller's promise).
            let d = unsafe { self.u.part(i * m + i, 1) }[0];
            if !(d > 0.0 && d.is_finite()) {
                return false;
            }
            let pivot = d.sqrt();
            // SAFETY: as above; the row part k0..k1 of row i and, below, of rows r > i are
            // disjoint.
            let row_i = unsafe { self.u.part(i * m + i, k1 - i) };
            row_i[0] = pivot;
            let inv = 1.0 / pivot;
            for v in &mut row_i[1..] {
                *v *= inv;
            }
            for r in i + 1..k1 {
                let f = row_i[r - i];
                // SAFETY: row r's part r..k1 overlaps no part of row i.
                let row_r = unsafe { self.u.part(r * m + r, k1 - r) };
                for (x, v) in row_r.iter_mut().zip(&row_i[r - i..]) {
                    *x -= f * v;
                }
            }
        }
        true
    }

    /// Updates columns c0..c1 of the block row and solves them with the factored diagonal
    /// block: Uᵀ_KK X = C by rows, row i of X final once the rows above are subtracted.
    ///
    /// # Safety
    /// No other live reference may touch rows k0..k1, columns c0..c1 of `u`, nor write the
    /// diagonal block or rows < k0, which must be final.
    unsafe fn solve_piece(&self, c0: usize, c1: usize) {
        let (m, k0, k1) = (self.m, self.k0, self.k1);
        // SAFETY: the caller's promise.
        unsafe { self.update(c0, c1) };
        for i in k0..k1 {
            // SAFETY: the diagonal block is finished (read only); columns c0..c1 of rows
            // k0..k1 are this call's, and rows i and r below are different rows.
            let (diag, row_i) = unsafe { (self.u.view(i * m + i, k1 - i), self.u.part(i * m + c0, c1 - c0)) };
            let inv = 1.0 / diag[0];
            for v in row_i.iter_mut() {
                *v *= inv;
            }
            for r in i + 1..k1 {
                let f = diag[r - i];
                if f != 0.0 {
                    // SAFETY: as above.
                    let row_r = unsafe { self.u.part(r * m + c0, c1 - c0) };
                    for (x, v) in row_r.iter_mut().zip(row_i.iter()) {
                        *x -= f * v;
                    }
                }
            }
        }
    }
}

/// The number of GEMM calls [`cholesky_shifted`] makes for an m×m matrix (matrixmultiply
/// allocates a packing buffer in each; for the tests that count allocations).
pub fn cholesky_gemm_calls(m: usize) -> usize {
    (0..m).step_by(CHOLESKY_BLOCK).filter(|&k0| k0 > 0).map(|k0| 1 + (m - (k0 + CHOLESKY_BLOCK).min(m)).div_ceil(CHOLESKY_PIECE)).sum()
}

/// Solves UᵀU x = b for the upper-triangular factor U in `u` (row-major m×m, as
/// [`cholesky_shifted`] leaves it), x replacing b.
pub fn cholesky_solve_factored(u: &[f64], m: usize, b: &mut [f64]) {
    // Uᵀ y = b, forward, by columns of Uᵀ (rows of U).
    for k in 0..m {
        let row = &u[k * m..k * m + m];
        b[k] /= row[k];
        let bk = b[k];
        for (x, v) in b[k + 1..m].iter_mut().zip(&row[k + 1..]) {
            *x -= bk * v;
        }
    }
    // U x = y, backward.
    for i in (0..m).rev() {
        let row = &u[i * m..i * m + m];
        b[i] = (b[i] - dot(&row[i + 1..], &b[i + 1..m])) / row[i];
    }
}

/// The speed of the GEMM the trainer and [`cholesky_shifted`] use (matrixmultiply's dgemm)
/// [GFLOP/s, a multiply-add counted as 2]: `threads` threads at once each multiply their own
/// m×m matrices `reps` times; the sum of their rates, best of three tries. For benchmarks
/// that state a floor (FLOPs / this speed) beside a measured time.
pub fn measure_gemm_gflops(m: usize, reps: usize, threads: usize) -> f64 {
    let run = || {
        let a: Vec<f64> = (0..m * m).map(|i| (i % 7) as f64 * 0.1).collect();
        let b: Vec<f64> = (0..m * m).map(|i| (i % 5) as f64 * 0.1).collect();
        let mut c = vec![0.0; m * m];
        let mut gemm = || {
            // SAFETY: three m×m row-major matrices.
            unsafe {
                matrixmultiply::dgemm(
                    m,
                    m,
                    m,
                    1.0,
                    a.as_ptr(),
                    m as isize,
                    1,
                    b.as_ptr(),
                    m as isize,
                    1,
                    0.0,
                    c.as_mut_ptr(),
                    m as isize,
                    1,
                );
            }
        };
        gemm(); // warm up
        let t0 = std::time::Instant::now();
        for _ in 0..reps {
            gemm();
        }
        2.0 * (m * m * m * reps) as f64 / t0.elapsed().as_secs_f64() / 1e9
    };
    let once = || -> f64 {
        std::thread::scope(|s| {
            let handles: Vec<_> = (0..threads.max(1)).map(|_| s.spawn(run)).collect();
            handles.into_iter().map(|h| h.join().expect("GEMM thread")).sum()
        })
    };
    (0..3).map(|_| once()).fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parallel::Serial;

    /// A = B Bᵀ (positive semi-definite, rank m − 1 at most for the odd sizes) and a
    /// right-hand side, for the shifted factorisation.
    fn gram(m: usize) -> Vec<f64> {
        let bm: Vec<f64> = (0..m * m).map(|i| ((i * 37 % 11) as f64 - 5.0) / 7.0).collect();
        let mut a = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                a[i * m + j] = (0..m).map(|k| bm[i * m + k] * bm[j * m + k]).sum::<f64>();
            }
        }
        a
    }

    /// Runs tasks in reverse and from two threads, to show the order does not matter.
    struct Scrambled;
    impl ParallelFor for Scrambled {
        fn run(&self, tasks: usize, task: &(dyn Fn(usize) + Sync)) {
            std::thread::scope(|s| {
                s.spawn(|| (0..tasks).rev().filter(|i| i % 2 == 0).for_each(task));
                (0..tasks).rev().filter(|i| i % 2 == 1).for_each(task);
            });
        }
    }

    #[test]
    fn blocked_shifted_cholesky_solves_and_ignores_the_lower_triangle() {
        for m in [1, 2, 31, 32, 33, 70, 150, 229] {
            let mut a = gram(m);
            let shift = m as f64;
            let x_true: Vec<f64> = (0..m).map(|i| (i as f64 * 0.7).sin()).collect();
            let b: Vec<f64> = (0..m).map(|i| (0..m).map(|k| a[i * m + k] * x_true[k]).sum::<f64>() + shift * x_true[i]).collect();
            for i in 0..m {
                for j in 0..i {
                    a[i * m + j] = f64::NAN; // never read
                }
            }
            let mut u = vec![0.0; m * m];
            let mut x = b.clone();
            assert!(cholesky_shifted(&a, shift, &mut u, m, &Serial));
            cholesky_solve_factored(&u, m, &mut x);
            for i in 0..m {
                assert!((x[i] - x_true[i]).abs() < 1e-11, "m = {m}: x[{i}] = {} vs {}", x[i], x_true[i]);
            }
            let mut u2 = vec![0.0; m * m];
            assert!(cholesky_shifted(&a, shift, &mut u2, m, &Scrambled));
            for i in 0..m {
                for j in i..m {
                    assert_eq!(u[i * m + j].to_bits(), u2[i * m + j].to_bits(), "m = {m}: U[{i}][{j}]");
                }
            }
        }
    }

    #[test]
    fn blocked_shifted_cholesky_rejects_indefinite_matrices() {
        let a = gram(40);
        let mut u = vec![0.0; 40 * 40];
        assert!(!cholesky_shifted(&a, -1.0, &mut u, 40, &Serial));
        assert!(!cholesky_shifted(&[1.0, 2.0, 2.0, 1.0], 0.0, &mut u, 2, &Serial));
    }
}
