//! The buffers of one training, made once: activations, errors, the rows [z; ã], the Gram
//! matrix, JᵀJ and Jᵀe, and two damped steps.

use std::sync::Mutex;

use super::data::{Part, SAMPLE_CHUNK};
use super::forward::forward_into;
use super::jacobian::gram_panels;
use crate::parallel::Pool;

/// Shapes and buffers of one training.
pub(super) struct Workspace {
    pub(super) n: usize,
    pub(super) h: usize,
    pub(super) k: usize,
    /// Number of hidden-layer parameters H(N+1).
    pub(super) ph: usize,
    /// All parameters.
    pub(super) p: usize,
    /// Activations ã = [a; 1] per training sample.
    pub(super) a: Vec<f64>,
    /// Activations of whatever part was last evaluated (validation, test, reports).
    pub(super) a_eval: Vec<f64>,
    /// Whether `a` holds the activations of the current parameters on the training part.
    pub(super) a_current: bool,
    pub(super) e: Vec<f64>,
    /// Rows [z; ã] per sample (width `ph + h + 1`): one Gram matrix gives ZᵀZ, ZᵀÃᵀ and ÃÃᵀ.
    pub(super) w: Vec<f64>,
    /// Upper triangle of WᵀW (the rest is partly written, never read).
    pub(super) gram: Vec<f64>,
    /// The Gram matrix's GEMM tasks: (first row, end row, first column, end column).
    pub(super) gram_tiles: Vec<[usize; 4]>,
    pub(super) m: Vec<f64>,
    /// Upper triangle of JᵀJ (the lower one is not formed).
    pub(super) jtj: Vec<f64>,
    pub(super) g: Vec<f64>,
    /// Jᵀe per sample chunk, added in chunk order into `g`.
    pub(super) g_chunks: Vec<f64>,
    /// Squared errors per output per sample chunk (evaluations other than trial steps).
    pub(super) sse_chunks: Vec<f64>,
    /// Buffers of two damped steps, so that two can be tried at once (see [`Workspace::try_step`]).
    pub(super) steps: [Mutex<Step>; 2],
}

/// The buffers of one damped step.
pub(super) struct Step {
    /// Cholesky factor of JᵀJ + μI.
    pub(super) factor: Vec<f64>,
    pub(super) delta: Vec<f64>,
    pub(super) theta: Vec<f64>,
    /// Activations at `theta` on the training part, which become the current ones when the
    /// step is taken.
    pub(super) a: Vec<f64>,
    pub(super) sse_chunks: Vec<f64>,
    pub(super) per_output: Vec<f64>,
    /// Training MSE (scaled units) at `theta`; none if JᵀJ + μI was not positive definite.
    pub(super) mse: Option<f64>,
}

impl Step {
    fn new(p: usize, q: usize, h: usize, k: usize) -> Self {
        Self {
            factor: vec![0.0; p * p],
            delta: vec![0.0; p],
            theta: vec![0.0; p],
            a: vec![0.0; q * (h + 1)],
            sse_chunks: vec![0.0; q.div_ceil(SAMPLE_CHUNK) * k],
            per_output: vec![0.0; k],
            mse: None,
        }
    }
}

impl Workspace {
    /// Buffers for a net of `n` inputs, `h` hidden neurons and `k` outputs, trained on `q`
    /// samples and evaluated on parts of at most `q_eval`.
    pub(super) fn new(n: usize, h: usize, k: usize, q: usize, q_eval: usize) -> Self {
        let ph = h * (n + 1);
        let p = ph + k * (h + 1);
        let pw = ph + h + 1;
        let gram_tiles = gram_panels(pw);
        let chunks = q.max(q_eval).div_ceil(SAMPLE_CHUNK);
        Self {
            n,
            h,
            k,
            ph,
            p,
            a: vec![0.0; q * (h + 1)],
            a_eval: vec![0.0; q.max(q_eval) * (h + 1)],
            a_current: false,
            e: vec![0.0; q * k],
            w: vec![0.0; q * pw],
            gram: vec![0.0; pw * pw],
            gram_tiles,
            m: vec![0.0; h * h],
            jtj: vec![0.0; p * p],
            g: vec![0.0; p],
            g_chunks: vec![0.0; q.div_ceil(SAMPLE_CHUNK) * p],
            sse_chunks: vec![0.0; chunks * k],
            steps: [(); 2].map(|_| Mutex::new(Step::new(p, q, h, k))),
        }
    }

    /// Squared errors of `theta` on `part` (activations kept in `a_eval`), per output
    /// (scaled units) into `per_output`; returns their sum.
    pub(super) fn forward(&mut self, theta: &[f64], part: &Part, per_output: &mut [f64], par: &Pool) -> f64 {
        let dims = (self.n, self.h, self.k, self.ph);
        forward_into(dims, theta, part, &mut self.a_eval, &mut self.sse_chunks, per_output, par)
    }
}
