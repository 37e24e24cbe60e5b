//! The samples as the trainer holds them: split into training, validation and test parts, each
//! scaled and sample-major, worked on in fixed chunks.

use nalgebra::DMatrix;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Sample indices of the train, validation and test parts.
pub fn split(samples: usize, fractions: [f64; 3], seed: u64) -> [Vec<usize>; 3] {
    let mut order: Vec<usize> = (0..samples).collect();
    order.shuffle(&mut ChaCha8Rng::seed_from_u64(seed));
    let total: f64 = fractions.iter().sum();
    let n_val = (samples as f64 * fractions[1] / total).round() as usize;
    let n_test = (samples as f64 * fractions[2] / total).round() as usize;
    let n_train = samples.saturating_sub(n_val + n_test);
    let test = order.split_off(n_train + n_val);
    let val = order.split_off(n_train);
    [order, val, test]
}

/// Samples per chunk of the per-sample work (activations, Jacobian rows, Jᵀe, errors). The
/// chunks, not the threads, are the unit of work: each chunk's sums are made in sample order
/// and the chunks' sums are added in chunk order, so results do not depend on the number of
/// threads.
pub(super) const SAMPLE_CHUNK: usize = 128;

/// Scaled samples of one part of the data, sample-major: x̃ = [x; 1] and t.
pub(super) struct Part {
    /// x̃ of every sample, one after the other.
    pub(super) x: Vec<f64>,
    /// t of every sample, one after the other.
    pub(super) t: Vec<f64>,
    /// Number of samples.
    pub(super) count: usize,
}

impl Part {
    /// The samples `idx` (columns of `x` and `t`).
    pub(super) fn new(x: &DMatrix<f64>, t: &DMatrix<f64>, idx: &[usize]) -> Self {
        let (n, k) = (x.nrows(), t.nrows());
        let mut px = Vec::with_capacity(idx.len() * (n + 1));
        let mut pt = Vec::with_capacity(idx.len() * k);
        for &p in idx {
            px.extend(x.column(p).iter());
            px.push(1.0);
            pt.extend(t.column(p).iter());
        }
        Self { x: px, t: pt, count: idx.len() }
    }

    /// Number of chunks.
    pub(super) fn chunks(&self) -> usize {
        self.count.div_ceil(SAMPLE_CHUNK)
    }

    /// Samples of chunk `c`.
    pub(super) fn chunk(&self, c: usize) -> std::ops::Range<usize> {
        c * SAMPLE_CHUNK..((c + 1) * SAMPLE_CHUNK).min(self.count)
    }
}
