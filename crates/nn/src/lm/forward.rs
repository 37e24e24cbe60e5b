//! The forward pass: hidden activations, output errors and squared errors of a part, chunk by
//! chunk.

use super::data::Part;
use crate::parallel::{ParallelFor, SharedSlice};

/// tanh through one `exp` (libm's tanh goes through the slower `expm1`): a few ulp from
/// libm for |x| ≳ 0.01, relative error below 1e-13 down to |x| = 1e-3 and ~1e-16/|x|
/// beneath, where it only perturbs training, never the evaluation of a trained net.
#[inline]
fn tanh(x: f64) -> f64 {
    let e = (-2.0 * x.abs()).exp();
    ((1.0 - e) / (1.0 + e)).copysign(x)
}

/// Hidden activations of one scaled sample `x̃` into `hidden` (length H). Four neurons at a
/// time: each sum is a chain of dependent adds, so four independent chains keep the FPU busy
/// (each sum still runs over i in order).
#[inline]
pub(super) fn activate(n: usize, theta: &[f64], x: &[f64], hidden: &mut [f64]) {
    let n1 = n + 1;
    let x = &x[..n1];
    let mut groups = hidden.chunks_exact_mut(4);
    let mut j = 0;
    for group in &mut groups {
        let w = &theta[j * n1..(j + 4) * n1];
        let (mut s0, mut s1, mut s2, mut s3) = (0.0, 0.0, 0.0, 0.0);
        for i in 0..n1 {
            s0 += w[i] * x[i];
            s1 += w[n1 + i] * x[i];
            s2 += w[2 * n1 + i] * x[i];
            s3 += w[3 * n1 + i] * x[i];
        }
        group.copy_from_slice(&[tanh(s0), tanh(s1), tanh(s2), tanh(s3)]);
        j += 4;
    }
    for a in groups.into_remainder() {
        let w = &theta[j * n1..(j + 1) * n1];
        let mut s = 0.0;
        for i in 0..n1 {
            s += w[i] * x[i];
        }
        *a = tanh(s);
        j += 1;
    }
}

/// Errors t − y of the K outputs for the activations ã = [a; 1] into `e`, four outputs at a
/// time (independent chains, as in [`activate`]; each sum in the order bias, then j).
#[inline]
pub(super) fn output_errors(ph: usize, h: usize, theta: &[f64], a: &[f64], t: &[f64], e: &mut [f64]) {
    let h1 = h + 1;
    let lw = &theta[ph..];
    let mut o = 0;
    let k = e.len();
    while o + 4 <= k {
        let w = &lw[o * h1..(o + 4) * h1];
        let (mut s0, mut s1, mut s2, mut s3) = (w[h], w[h1 + h], w[2 * h1 + h], w[3 * h1 + h]);
        for j in 0..h {
            s0 += w[j] * a[j];
            s1 += w[h1 + j] * a[j];
            s2 += w[2 * h1 + j] * a[j];
            s3 += w[3 * h1 + j] * a[j];
        }
        e[o..o + 4].copy_from_slice(&[t[o] - s0, t[o + 1] - s1, t[o + 2] - s2, t[o + 3] - s3]);
        o += 4;
    }
    for o in o..k {
        let w = &lw[o * h1..(o + 1) * h1];
        let mut s = w[h];
        for j in 0..h {
            s += w[j] * a[j];
        }
        e[o] = t[o] - s;
    }
}

/// Squared errors of `theta` on `part` (dimensions N, H, K, H(N+1)), the activations into
/// `a_out` and the sums per chunk into `sse_chunks`, then per output (scaled units) into
/// `per_output`, chunk by chunk in order; returns their sum.
#[allow(clippy::too_many_arguments)]
pub(super) fn forward_into(
    (n, h, k, ph): (usize, usize, usize, usize),
    theta: &[f64],
    part: &Part,
    a_out: &mut [f64],
    sse_chunks: &mut [f64],
    per_output: &mut [f64],
    par: &dyn ParallelFor,
) -> f64 {
    let a_out = SharedSlice::new(&mut a_out[..part.count * (h + 1)]);
    let sse = SharedSlice::new(&mut sse_chunks[..part.chunks() * k]);
    par.run(part.chunks(), &|c| {
        let samples = part.chunk(c);
        // SAFETY: chunk c's rows and sums belong to this task alone.
        let (a_rows, sse) = unsafe { (a_out.part(samples.start * (h + 1), samples.len() * (h + 1)), sse.part(c * k, k)) };
        sse.fill(0.0);
        let mut err = [0.0; 16];
        for (s, a) in samples.zip(a_rows.chunks_exact_mut(h + 1)) {
            activate(n, theta, &part.x[s * (n + 1)..(s + 1) * (n + 1)], &mut a[..h]);
            a[h] = 1.0;
            for o0 in (0..k).step_by(16) {
                let o1 = (o0 + 16).min(k);
                let err = &mut err[..o1 - o0];
                output_errors(ph + o0 * (h + 1), h, theta, a, &part.t[s * k + o0..s * k + o1], err);
                for (acc, e) in sse[o0..o1].iter_mut().zip(err.iter()) {
                    *acc += e * e;
                }
            }
        }
    });
    per_output.fill(0.0);
    for c in 0..part.chunks() {
        for o in 0..k {
            per_output[o] += sse_chunks[c * k + o];
        }
    }
    per_output.iter().sum()
}
