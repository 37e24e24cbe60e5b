//! The linearisation of an epoch: the rows [z; ã] of every sample and Jᵀe, the Gram matrix of
//! those rows, and JᵀJ assembled from it; and the naive Jacobian and normal equations the tests
//! compare it with.

use nalgebra::DMatrix;

use super::data::Part;
use super::forward::{activate, output_errors};
use super::workspace::Workspace;
use crate::mlp::Mlp;
use crate::parallel::{ParallelFor, Pool, SharedSlice};

/// Rows per task of the JᵀJ assembly.
const ASSEMBLY_ROWS: usize = 32;

/// The Gram matrix's GEMM tasks for rows [z; ã] of width `pw`: (first row, end row, first
/// column, end column). Row panels of the upper triangle, each from its diagonal to the last
/// column: wide GEMMs, because matrixmultiply packs both operands of every call (over all
/// samples), and narrow tiles spend as long packing as multiplying. Four panels or more (of a
/// multiple of 8 rows, at most 128), taken largest first, keep two threads balanced within a
/// few per cent.
pub(super) fn gram_panels(pw: usize) -> Vec<[usize; 4]> {
    let rows = pw.div_ceil(4).next_multiple_of(8).clamp(8, 128);
    (0..pw).step_by(rows).map(|r0| [r0, (r0 + rows).min(pw), r0, pw]).collect()
}

/// The GEMM calls of one epoch of a net with `inputs`, `hidden` and `outputs`, as (calls in
/// the linearisation, calls per damped step tried). matrixmultiply allocates a packing buffer
/// in each, the only allocations in an epoch; for the tests that count them.
pub fn gemm_calls(inputs: usize, hidden: usize, outputs: usize) -> (usize, usize) {
    let ph = hidden * (inputs + 1);
    (gram_panels(ph + hidden + 1).len(), crate::linalg::cholesky_gemm_calls(ph + outputs * (hidden + 1)))
}

impl Workspace {
    /// Forward pass on the training part storing activations and errors, then JᵀJ (upper
    /// triangle) and Jᵀe.
    pub(super) fn linearise(&mut self, theta: &[f64], part: &Part, par: &Pool) {
        self.sample_rows(theta, part, par);
        self.add_gradient_chunks(part);
        self.gram_upper(part.count, par);
        self.layer_products(theta);
        self.assemble_jtj(theta, par);
    }

    /// Every training sample's activations (unless current), errors and row of W, and Jᵀe per
    /// chunk of samples (into `g_chunks`).
    fn sample_rows(&mut self, theta: &[f64], part: &Part, par: &Pool) {
        let (n, h, k, ph, p) = (self.n, self.h, self.k, self.ph, self.p);
        let pw = ph + h + 1;
        let compute_a = !self.a_current;
        let a = SharedSlice::new(&mut self.a);
        let e = SharedSlice::new(&mut self.e);
        let w = SharedSlice::new(&mut self.w);
        let g = SharedSlice::new(&mut self.g_chunks);
        par.run(part.chunks(), &|c| {
            let samples = part.chunk(c);
            let (s0, len) = (samples.start, samples.len());
            // SAFETY: chunk c's rows of a, e and W and its Jᵀe belong to this task alone.
            let (a, e, w, g) =
                unsafe { (a.part(s0 * (h + 1), len * (h + 1)), e.part(s0 * k, len * k), w.part(s0 * pw, len * pw), g.part(c * p, p)) };
            g.fill(0.0);
            for (r, s) in samples.enumerate() {
                let x = &part.x[s * (n + 1)..(s + 1) * (n + 1)];
                let a = &mut a[r * (h + 1)..(r + 1) * (h + 1)];
                if compute_a {
                    activate(n, theta, x, &mut a[..h]);
                    a[h] = 1.0;
                }
                let e = &mut e[r * k..(r + 1) * k];
                output_errors(ph, h, theta, a, &part.t[s * k..(s + 1) * k], e);
                jacobian_row((n, h, k, ph), &theta[ph..], x, a, e, &mut w[r * pw..(r + 1) * pw], g);
            }
        });
    }

    /// Jᵀe (`g`): the chunks' sums added in chunk order.
    fn add_gradient_chunks(&mut self, part: &Part) {
        let p = self.p;
        self.g.fill(0.0);
        for c in 0..part.chunks() {
            for (g, v) in self.g.iter_mut().zip(&self.g_chunks[c * p..(c + 1) * p]) {
                *g += v;
            }
        }
    }

    /// The upper triangle of WᵀW (W: `q` rows [z; ã]) by tiles; each tile is one GEMM over all
    /// samples, so a tile's values are the same whichever thread computes it.
    fn gram_upper(&mut self, q: usize, par: &Pool) {
        let pw = self.ph + self.h + 1;
        let gram_len = self.gram.len();
        let gram = SharedSlice::new(&mut self.gram);
        let (w, tiles) = (&self.w, &self.gram_tiles);
        par.run(tiles.len(), &|t| {
            let [r0, r1, c0, c1] = tiles[t];
            let pwi = pw as isize;
            assert!(r1 <= pw && c1 <= pw && gram_len == pw * pw && w.len() >= q * pw);
            let wp = w.as_ptr();
            // SAFETY: `w` is the q×pw row-major W, read only; the tile rows r0..r1,
            // columns c0..c1 of the pw×pw `gram` (in bounds, checked) are this task's alone.
            unsafe {
                let out = gram.as_ptr().add(r0 * pw + c0);
                matrixmultiply::dgemm(r1 - r0, q, c1 - c0, 1.0, wp.add(r0), 1, pwi, wp.add(c0), pwi, 1, 0.0, out, pwi, 1);
            }
        });
    }

    /// M = LWᵀLW over the hidden columns (into `m`).
    fn layer_products(&mut self, theta: &[f64]) {
        let (h, k, ph) = (self.h, self.k, self.ph);
        let lw = |o: usize, j: usize| theta[ph + o * (h + 1) + j];
        for j in 0..h {
            for jj in 0..h {
                self.m[j * h + jj] = (0..k).map(|o| lw(o, j) * lw(o, jj)).sum();
            }
        }
    }

    /// The upper triangle of JᵀJ from the Gram matrix and M, by tasks of [`ASSEMBLY_ROWS`]
    /// rows: the hidden block (ZᵀZ) ⊙ (M ⊗ 1), the cross blocks rows of ZᵀÃᵀ scaled by the
    /// layer weights, and each output's block ÃÃᵀ.
    fn assemble_jtj(&mut self, theta: &[f64], par: &Pool) {
        let (n, h, k, ph, p) = (self.n, self.h, self.k, self.ph, self.p);
        let pw = ph + h + 1;
        let lw = |o: usize, j: usize| theta[ph + o * (h + 1) + j];
        let (gram, mw) = (&self.gram, &self.m);
        let jtj = SharedSlice::new(&mut self.jtj);
        par.run(p.div_ceil(ASSEMBLY_ROWS), &|t| {
            for r in t * ASSEMBLY_ROWS..((t + 1) * ASSEMBLY_ROWS).min(p) {
                // SAFETY: row r from its diagonal on belongs to this task alone.
                let out = unsafe { jtj.part(r * p + r, p - r) };
                if r < ph {
                    // Hidden block: Gram element times M[j][jj], neuron block by block.
                    let j = r / (n + 1);
                    let src = &gram[r * pw..r * pw + ph];
                    for jj in j..h {
                        let (c0, c1) = ((jj * (n + 1)).max(r), (jj + 1) * (n + 1));
                        let mjj = mw[j * h + jj];
                        for (v, g) in out[c0 - r..c1 - r].iter_mut().zip(&src[c0..c1]) {
                            *v = g * mjj;
                        }
                    }
                    for o in 0..k {
                        let wo = lw(o, j);
                        let base = ph + o * (h + 1);
                        for mm in 0..=h {
                            out[base + mm - r] = wo * gram[r * pw + ph + mm];
                        }
                    }
                } else {
                    // Output o's block is ÃÃᵀ; blocks of different outputs are zero.
                    let (o, mm) = ((r - ph) / (h + 1), (r - ph) % (h + 1));
                    let end = ph + (o + 1) * (h + 1);
                    for c in r..end {
                        out[c - r] = gram[(ph + mm) * pw + ph + (c - ph - o * (h + 1))];
                    }
                    out[end - r..].fill(0.0);
                }
            }
        });
    }
}

/// One sample's row of W into `row`: z = (1 − a²) ⊗ x̃, then ã; and its Jᵀe added into `g`:
/// hidden part (1 − a²)_j (Σ_o e_o LW_oj) x̃_i, output part e_o ã. `lw_all` are the layer
/// weights (θ from H(N+1) on), `x` is x̃, `a` is ã and `e` the errors; dimensions N, H, K,
/// H(N+1).
#[inline]
fn jacobian_row(
    (n, h, k, ph): (usize, usize, usize, usize),
    lw_all: &[f64],
    x: &[f64],
    a: &[f64],
    e: &[f64],
    row: &mut [f64],
    g: &mut [f64],
) {
    let (z, tail) = row.split_at_mut(ph);
    let (g_hidden, g_out) = g.split_at_mut(ph);
    for j in 0..h {
        let d = 1.0 - a[j] * a[j];
        let mut back = 0.0;
        for o in 0..k {
            back += e[o] * lw_all[o * (h + 1) + j];
        }
        let back = back * d;
        let span = j * (n + 1)..(j + 1) * (n + 1);
        for ((zi, gi), xi) in z[span.clone()].iter_mut().zip(&mut g_hidden[span]).zip(x) {
            *zi = d * xi;
            *gi += back * xi;
        }
    }
    tail.copy_from_slice(a);
    for (o, g_o) in g_out.chunks_exact_mut(h + 1).enumerate() {
        let eo = e[o];
        for (gi, ai) in g_o.iter_mut().zip(a.iter()) {
            *gi += eo * ai;
        }
    }
}

/// The Jacobian ∂y/∂θ of the scaled outputs for one scaled sample `x`, row-major K×P, as the
/// trainer's structured JᵀJ assumes it; for tests against finite differences.
pub fn output_jacobian(net: &Mlp, x_scaled: &[f64]) -> Vec<f64> {
    let (n, h, k) = (net.inputs(), net.hidden(), net.outputs());
    let p = net.parameter_count();
    let ph = h * (n + 1);
    let mut jac = vec![0.0; k * p];
    let a: Vec<f64> = (0..h).map(|j| (net.b1[j] + (0..n).map(|i| net.iw[(j, i)] * x_scaled[i]).sum::<f64>()).tanh()).collect();
    for o in 0..k {
        for j in 0..h {
            let d = net.lw[(o, j)] * (1.0 - a[j] * a[j]);
            for i in 0..n {
                jac[o * p + j * (n + 1) + i] = d * x_scaled[i];
            }
            jac[o * p + j * (n + 1) + n] = d;
            jac[o * p + ph + o * (h + 1) + j] = a[j];
        }
        jac[o * p + ph + o * (h + 1) + h] = 1.0;
    }
    jac
}

/// JᵀJ and Jᵀe as the trainer forms them (JᵀJ's upper triangle mirrored into the lower one),
/// on scaled samples (columns of `x`, `t`), on `threads` threads; for tests against the naive
/// products of [`output_jacobian`].
pub fn normal_equations(net: &Mlp, x: &DMatrix<f64>, t: &DMatrix<f64>, threads: usize) -> (Vec<f64>, Vec<f64>) {
    let idx: Vec<usize> = (0..x.ncols()).collect();
    let part = Part::new(x, t, &idx);
    let mut ws = Workspace::new(net.inputs(), net.hidden(), net.outputs(), part.count, 0);
    Pool::scoped(threads, |pool| ws.linearise(&net.parameters(), &part, pool));
    let p = ws.p;
    for r in 0..p {
        for c in 0..r {
            ws.jtj[r * p + c] = ws.jtj[c * p + r];
        }
    }
    (ws.jtj, ws.g)
}
