//! Levenberg–Marquardt training with the semantics of MATLAB's `trainlm`: steps of
//! (JᵀJ + μI) δ = Jᵀe on the mean squared error, μ ×dec on success and ×inc on failure, stops
//! on epochs, goal, minimum gradient, μ max and validation failures, and the weights of the
//! best validation error returned.
//!
//! # Where the time goes, and the structure used
//! For a K-output net the Jacobian has K rows per sample, but its hidden-layer part is the
//! same per-sample vector z = (1 − a²) ⊗ [x; 1] scaled per output by the layer weights. So
//! the hidden block of JᵀJ is (ZᵀZ) ⊙ (LWᵀLW ⊗ 1), one Gram matrix of the Q×H(N+1) matrix Z
//! instead of K of them; each output's block is the same ÃÃᵀ (Ã = [a; 1]), and the cross
//! blocks are rows of ZᵀÃᵀ scaled by the layer weights. All three come out of one Gram
//! matrix of the rows [z; ã], of which only the upper triangle is formed (by tiles, each one
//! GEMM over all samples). All buffers are made once per training; the only allocations in
//! an epoch are the GEMM library's (matrixmultiply) packing buffers, one per GEMM call.
//!
//! # Threads
//! The per-sample work (activations, Jacobian rows, Jᵀe, trial errors) is split into fixed
//! chunks of samples, the Gram matrix and JᵀJ into fixed tiles, and the blocked Cholesky
//! factorisation into fixed column pieces ([`crate::linalg::cholesky_shifted`]); threads take
//! these tasks as they come free and sums over chunks are added in chunk order. So the result
//! is bitwise the same for any number of threads ([`train_with_threads`]; [`train`] uses
//! [`default_threads`]). With trainlm's rule, once an epoch has needed two damped steps the
//! next epoch's first two (μ and μ·mu_inc) are tried at once, one per thread.
//!
//! # Damping
//! [`Damping::Trainlm`] (the default) is `trainlm`'s rule. [`Damping::Nielsen`] scales μ by
//! the gain ratio ρ of each step, the actual reduction of the squared error over the one the
//! linear model predicts (H. B. Nielsen, "Damping parameter in Marquardt's method", IMM
//! DTU 1999; Madsen, Nielsen & Tingleff, "Methods for non-linear least squares problems",
//! 2004, §3.2).
//!
//! Training works on scaled data (inputs and targets in [-1, 1]); the reported errors are
//! mean squared errors in the targets' own units.

use nalgebra::DMatrix;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::linalg::{cholesky_shifted, cholesky_solve_factored};
use crate::mlp::{MinMaxScaling, Mlp};
use crate::parallel::{default_threads, ParallelFor, Pool, Serial, SharedSlice};
use std::sync::Mutex;

/// How μ changes from epoch to epoch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Damping {
    /// MATLAB `trainlm`: μ ×`mu_dec` after a successful step, ×`mu_inc` after a failed one.
    #[default]
    Trainlm,
    /// Nielsen's rule: after a step with gain ratio ρ > 0 (the step is taken), μ ×
    /// max(1/3, 1 − (2ρ − 1)³) and ν = 2; after a failed step, μ ×ν and ν ×2. μ falls fast
    /// while the linear model predicts well and rises gently after a near miss, so fewer
    /// steps fail and fewer are too short. `mu_dec` and `mu_inc` are not used; `mu` and
    /// `mu_max` are.
    Nielsen,
}

/// Settings of a training run; the defaults are `trainlm`'s.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrainSettings {
    /// Hidden neurons.
    pub hidden: usize,
    /// Largest number of epochs.
    pub epochs: usize,
    /// Stop when the training MSE (scaled units) reaches this.
    pub goal: f64,
    /// Stop when the gradient norm of the MSE (scaled units) falls below this.
    pub min_grad: f64,
    /// Initial μ.
    pub mu: f64,
    /// μ factor after a successful step ([`Damping::Trainlm`]). trainlm's 0.1 with
    /// `mu_inc` 10 makes nearly every epoch fail once then succeed; "delayed gratification"
    /// factors (0.2 and 2, after Transtrum & Sethna) try more steps per epoch but need far
    /// fewer epochs: on the gravity benches 3–5× fewer, and 2–4× less time to a given error.
    pub mu_dec: f64,
    /// μ factor after a failed step ([`Damping::Trainlm`]).
    pub mu_inc: f64,
    /// Stop when μ exceeds this.
    pub mu_max: f64,
    /// Stop after this many epochs in a row without a better validation error.
    pub max_fail: usize,
    /// Fractions of the samples used for training, validation and test.
    pub split: [f64; 3],
    /// Seed of the split and of the first restart's initial weights.
    pub seed: u64,
    /// Number of trainings from different initial weights (seeds seed, seed+1, …); the one
    /// with the best validation error is kept.
    pub restarts: usize,
    /// How μ changes ([`Damping::Trainlm`] unless set, also when read from older files).
    pub damping: Damping,
}

impl Default for TrainSettings {
    fn default() -> Self {
        Self {
            hidden: 10,
            epochs: 1000,
            goal: 0.0,
            min_grad: 1e-7,
            mu: 1e-3,
            mu_dec: 0.1,
            mu_inc: 10.0,
            mu_max: 1e10,
            max_fail: 6,
            split: [0.70, 0.15, 0.15],
            seed: 1,
            restarts: 1,
            damping: Damping::Trainlm,
        }
    }
}

/// Why training stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// The epoch limit.
    Epochs,
    /// The performance goal.
    Goal,
    /// The gradient fell below `min_grad`.
    MinGradient,
    /// μ exceeded `mu_max`.
    MuMax,
    /// `max_fail` validation failures in a row.
    ValidationFailures,
}

/// Progress of one epoch, for a progress display or a benchmark.
#[derive(Clone, Copy, Debug)]
pub struct EpochInfo<'a> {
    /// Restart index (0-based).
    pub restart: usize,
    /// Epoch (1-based).
    pub epoch: usize,
    /// Training MSE, scaled units.
    pub train_mse: f64,
    /// Validation MSE, scaled units (NaN without a validation set).
    pub validation_mse: f64,
    /// μ after the epoch.
    pub mu: f64,
    /// Damped steps tried in the epoch (Cholesky factorisations attempted), the last one
    /// taken unless training stops with [`StopReason::MuMax`].
    pub trials: usize,
    /// The parameters after the epoch, ordered as [`Mlp::parameters`].
    pub parameters: &'a [f64],
}

/// Outcome of training, with errors in the targets' units (squared).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TrainReport {
    /// Epochs run by the kept restart.
    pub epochs: usize,
    /// Epoch whose weights were kept (best validation).
    pub best_epoch: usize,
    /// Why the kept restart stopped.
    pub stop_reason: StopReason,
    /// Which restart was kept (0-based).
    pub restart: usize,
    /// Training MSE [target units²].
    pub train_mse: f64,
    /// Validation MSE [target units²]; none without validation samples.
    pub validation_mse: Option<f64>,
    /// Test MSE [target units²]; none without test samples.
    pub test_mse: Option<f64>,
    /// Samples in each part of the split.
    pub counts: [usize; 3],
}

/// Why training could not start.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum TrainError {
    /// Inputs and targets differ in sample count, or there are none.
    #[error("{0}")]
    Data(String),
    /// A setting is out of range.
    #[error("invalid training setting: {0}")]
    Settings(String),
}

/// Largest number of hidden neurons [`train`] accepts.
pub const MAX_HIDDEN: usize = 1000;
/// Largest number of weights and biases [`train`] accepts: Levenberg–Marquardt factors a
/// square matrix of this order every step (5000: three 200 MB matrices, seconds per step).
pub const MAX_WEIGHTS: usize = 5000;
/// Largest working memory [`train`] allocates [bytes] (8 GiB).
pub const MAX_WORKSPACE_BYTES: usize = 8 << 30;
/// Fewest samples of the training part.
pub const MIN_TRAINING_SAMPLES: usize = 10;
/// Fewest samples of the validation and of the test part, when its fraction is not 0: fewer
/// make early stopping and the test error a matter of luck.
pub const MIN_CHECK_SAMPLES: usize = 3;

/// Weights and biases of a two-layer net with `n` inputs, `h` hidden neurons and `k`
/// outputs; none if the count overflows.
pub fn weight_count(n: usize, h: usize, k: usize) -> Option<usize> {
    h.checked_mul(n.checked_add(1)?)?.checked_add(k.checked_mul(h.checked_add(1)?)?)
}

/// The working memory of training such a net on `q` samples [bytes]; none if it overflows.
pub fn workspace_bytes(n: usize, h: usize, k: usize, q: usize) -> Option<usize> {
    let p = weight_count(n, h, k)?;
    let pw = h.checked_mul(n + 1)?.checked_add(h + 1)?;
    // Three P×P matrices (JᵀJ, two factors), the Gram matrix, per-sample rows, activations
    // (four copies), errors, and the chunked sums.
    let square = p.checked_mul(p)?.checked_mul(3)?.checked_add(pw.checked_mul(pw)?)?;
    let per_sample = pw.checked_add(h.checked_add(1)?.checked_mul(4)?)?.checked_add(k)?.checked_mul(q)?;
    let chunks = q.div_ceil(SAMPLE_CHUNK).checked_mul(p.checked_add(3 * k)?)?;
    square.checked_add(per_sample)?.checked_add(chunks)?.checked_mul(8)
}

/// Checks `s` for a net with `n` inputs and `k` outputs trained on `q` samples: positive
/// hidden size, epochs, validation failures and restarts; damping factors in range; split
/// fractions finite, ≥ 0 and summing to 1; the net within [`MAX_HIDDEN`], [`MAX_WEIGHTS`]
/// and [`MAX_WORKSPACE_BYTES`]; the split's parts no smaller than [`MIN_TRAINING_SAMPLES`]
/// and [`MIN_CHECK_SAMPLES`] (as [`split`] makes them).
pub fn check_settings(s: &TrainSettings, n: usize, k: usize, q: usize) -> Result<(), TrainError> {
    let bad = |what: String| Err(TrainError::Settings(what));
    if s.hidden == 0 || s.hidden > MAX_HIDDEN {
        return bad(format!("hidden must be 1 to {MAX_HIDDEN} neurons, not {}", s.hidden));
    }
    for (name, value) in [("epochs", s.epochs), ("max_fail", s.max_fail), ("restarts", s.restarts)] {
        if value == 0 {
            return bad(format!("{name} must be >= 1 (0 would keep the untrained initial weights)"));
        }
    }
    if !(s.mu > 0.0 && s.mu_dec > 0.0 && s.mu_dec < 1.0 && s.mu_inc > 1.0 && s.mu_max >= s.mu) {
        return bad("need mu > 0, 0 < mu_dec < 1 < mu_inc, mu_max >= mu".into());
    }
    if !(s.goal >= 0.0 && s.min_grad >= 0.0) {
        return bad(format!("goal and min_grad must be >= 0 (got {}, {})", s.goal, s.min_grad));
    }
    let sum: f64 = s.split.iter().sum();
    if s.split.iter().any(|f| !(f.is_finite() && *f >= 0.0)) || (sum - 1.0).abs() > 1e-9 {
        let [a, b, c] = s.split;
        return bad(format!("the split fractions (train, validation, test) must be >= 0 and sum to 1, not {a}, {b}, {c} (sum {sum})"));
    }
    let weights = weight_count(n, s.hidden, k).filter(|&w| w <= MAX_WEIGHTS);
    let Some(weights) = weights else {
        return bad(format!(
            "a net of {n} inputs, {} hidden neurons and {k} outputs has more than {MAX_WEIGHTS} weights, the most this trainer factors",
            s.hidden
        ));
    };
    match workspace_bytes(n, s.hidden, k, q) {
        Some(bytes) if bytes <= MAX_WORKSPACE_BYTES => {}
        bytes => {
            let shown = bytes.map_or("more than the address space".to_owned(), |b| format!("{:.1} GiB", b as f64 / (1u64 << 30) as f64));
            return bad(format!(
                "training {weights} weights on {q} samples needs {shown} of memory; the limit is {} GiB: use fewer hidden neurons or samples",
                MAX_WORKSPACE_BYTES >> 30
            ));
        }
    }
    let counts = split(q, s.split, s.seed).map(|p| p.len());
    let short = [
        ("training", counts[0], MIN_TRAINING_SAMPLES, true),
        ("validation", counts[1], MIN_CHECK_SAMPLES, s.split[1] > 0.0),
        ("test", counts[2], MIN_CHECK_SAMPLES, s.split[2] > 0.0),
    ]
    .into_iter()
    .find(|&(_, count, min, used)| used && count < min);
    if let Some((part, count, min, _)) = short {
        let need = minimum_samples(s.split);
        let [a, b, c] = s.split;
        return Err(TrainError::Data(format!(
            "{q} samples give the {part} part {count} at the split {a}/{b}/{c}; it needs at least {min}: give at least {need} samples{}",
            if part == "training" { "" } else { " (or a split without that part)" }
        )));
    }
    Ok(())
}

/// The fewest samples whose split into `fractions` meets [`MIN_TRAINING_SAMPLES`] and
/// [`MIN_CHECK_SAMPLES`] (17 at the default 70/15/15).
pub fn minimum_samples(fractions: [f64; 3]) -> usize {
    (1..1_000_000)
        .find(|&q| {
            let c = split(q, fractions, 0).map(|p| p.len());
            c[0] >= MIN_TRAINING_SAMPLES
                && (fractions[1] == 0.0 || c[1] >= MIN_CHECK_SAMPLES)
                && (fractions[2] == 0.0 || c[2] >= MIN_CHECK_SAMPLES)
        })
        .unwrap_or(usize::MAX)
}

/// A warning when `inputs` (one column per sample) look like a recorded time series rather
/// than identified pairs: more than 200 samples of which, in file order, the typical step
/// from one sample to the next is below 0.1 % of every input's range. A net trained on such
/// data learns the transients and the sampling, not the steady relation; identify pairs
/// first (`neurarm identify`).
pub fn time_series_warning(inputs: &DMatrix<f64>) -> Option<String> {
    let q = inputs.ncols();
    if q <= 200 {
        return None;
    }
    let ranges: Vec<f64> = inputs.row_iter().map(|r| r.max() - r.min()).collect();
    let mut steps: Vec<f64> = (1..q)
        .map(|c| {
            (0..inputs.nrows())
                .filter(|&r| ranges[r] > 0.0)
                .map(|r| (inputs[(r, c)] - inputs[(r, c - 1)]).abs() / ranges[r])
                .fold(0.0, f64::max)
        })
        .collect();
    steps.sort_by(f64::total_cmp);
    let median = steps[steps.len() / 2];
    (median < 1e-3).then(|| {
        format!(
            "the {q} samples look like a recorded time series, not identified pairs: from one sample to the next the inputs typically move {:.2e} of their range; a net trained on them learns transients; make pairs with `neurarm identify` first",
            median
        )
    })
}

/// tanh through one `exp` (libm's tanh goes through the slower `expm1`): a few ulp from
/// libm for |x| ≳ 0.01, relative error below 1e-13 down to |x| = 1e-3 and ~1e-16/|x|
/// beneath, where it only perturbs training, never the evaluation of a trained net.
#[inline]
fn tanh(x: f64) -> f64 {
    let e = (-2.0 * x.abs()).exp();
    ((1.0 - e) / (1.0 + e)).copysign(x)
}

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
const SAMPLE_CHUNK: usize = 128;
/// Rows per task of the JᵀJ assembly.
const ASSEMBLY_ROWS: usize = 32;

/// Scaled samples of one part of the data, sample-major: x̃ = [x; 1] and t.
struct Part {
    x: Vec<f64>,
    t: Vec<f64>,
    count: usize,
}

impl Part {
    fn new(x: &DMatrix<f64>, t: &DMatrix<f64>, idx: &[usize]) -> Self {
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

    fn chunks(&self) -> usize {
        self.count.div_ceil(SAMPLE_CHUNK)
    }

    /// Samples of chunk `c`.
    fn chunk(&self, c: usize) -> std::ops::Range<usize> {
        c * SAMPLE_CHUNK..((c + 1) * SAMPLE_CHUNK).min(self.count)
    }
}

/// Hidden activations of one scaled sample `x̃` into `hidden` (length H). Four neurons at a
/// time: each sum is a chain of dependent adds, so four independent chains keep the FPU busy
/// (each sum still runs over i in order).
#[inline]
fn activate(n: usize, theta: &[f64], x: &[f64], hidden: &mut [f64]) {
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
fn output_errors(ph: usize, h: usize, theta: &[f64], a: &[f64], t: &[f64], e: &mut [f64]) {
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

/// The Gram matrix's GEMM tasks for rows [z; ã] of width `pw`: (first row, end row, first
/// column, end column). Row panels of the upper triangle, each from its diagonal to the last
/// column: wide GEMMs, because matrixmultiply packs both operands of every call (over all
/// samples), and narrow tiles spend as long packing as multiplying. Four panels or more (of a
/// multiple of 8 rows, at most 128), taken largest first, keep two threads balanced within a
/// few per cent.
fn gram_panels(pw: usize) -> Vec<[usize; 4]> {
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

/// Shapes and buffers of one training.
struct Workspace {
    n: usize,
    h: usize,
    k: usize,
    /// Number of hidden-layer parameters H(N+1).
    ph: usize,
    /// All parameters.
    p: usize,
    /// Activations ã = [a; 1] per training sample.
    a: Vec<f64>,
    /// Activations of whatever part was last evaluated (validation, test, reports).
    a_eval: Vec<f64>,
    /// Whether `a` holds the activations of the current parameters on the training part.
    a_current: bool,
    e: Vec<f64>,
    /// Rows [z; ã] per sample (width `ph + h + 1`): one Gram matrix gives ZᵀZ, ZᵀÃᵀ and ÃÃᵀ.
    w: Vec<f64>,
    /// Upper triangle of WᵀW (the rest is partly written, never read).
    gram: Vec<f64>,
    /// The Gram matrix's GEMM tasks: (first row, end row, first column, end column).
    gram_tiles: Vec<[usize; 4]>,
    m: Vec<f64>,
    /// Upper triangle of JᵀJ (the lower one is not formed).
    jtj: Vec<f64>,
    g: Vec<f64>,
    /// Jᵀe per sample chunk, added in chunk order into `g`.
    g_chunks: Vec<f64>,
    /// Squared errors per output per sample chunk (evaluations other than trial steps).
    sse_chunks: Vec<f64>,
    /// Buffers of two damped steps, so that two can be tried at once (see [`Workspace::try_step`]).
    steps: [Mutex<Step>; 2],
}

/// The buffers of one damped step.
struct Step {
    /// Cholesky factor of JᵀJ + μI.
    factor: Vec<f64>,
    delta: Vec<f64>,
    theta: Vec<f64>,
    /// Activations at `theta` on the training part, which become the current ones when the
    /// step is taken.
    a: Vec<f64>,
    sse_chunks: Vec<f64>,
    per_output: Vec<f64>,
    /// Training MSE (scaled units) at `theta`; none if JᵀJ + μI was not positive definite.
    mse: Option<f64>,
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

/// Squared errors of `theta` on `part` (dimensions N, H, K, H(N+1)), the activations into
/// `a_out` and the sums per chunk into `sse_chunks`, then per output (scaled units) into
/// `per_output`, chunk by chunk in order; returns their sum.
#[allow(clippy::too_many_arguments)]
fn forward_into(
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

impl Workspace {
    fn new(n: usize, h: usize, k: usize, q: usize, q_eval: usize) -> Self {
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
    fn forward(&mut self, theta: &[f64], part: &Part, per_output: &mut [f64], par: &Pool) -> f64 {
        let dims = (self.n, self.h, self.k, self.ph);
        forward_into(dims, theta, part, &mut self.a_eval, &mut self.sse_chunks, per_output, par)
    }

    /// The damped step of μ from `theta` into `steps[slot]`: factor JᵀJ + μI, solve for δ,
    /// evaluate the training MSE at θ + δ. Takes `&self` so that two slots can be tried at
    /// once, each on one thread.
    fn try_step(&self, slot: usize, theta: &[f64], mu: f64, part: &Part, par: &dyn ParallelFor) {
        let mut step = self.steps[slot].lock().unwrap_or_else(|e| e.into_inner());
        let step = &mut *step;
        step.mse = None;
        if cholesky_shifted(&self.jtj, mu, &mut step.factor, self.p, par) {
            step.delta.copy_from_slice(&self.g);
            cholesky_solve_factored(&step.factor, self.p, &mut step.delta);
            for ((t, &th), &d) in step.theta.iter_mut().zip(theta).zip(&step.delta) {
                *t = th + d;
            }
            let dims = (self.n, self.h, self.k, self.ph);
            let sse = forward_into(dims, &step.theta, part, &mut step.a, &mut step.sse_chunks, &mut step.per_output, par);
            step.mse = Some(sse / (part.count * self.k) as f64);
        }
    }

    /// The step in `steps[slot]` was taken: its parameters go to `theta`, its activations
    /// become the current ones.
    fn accept_step(&mut self, slot: usize, theta: &mut [f64]) {
        let step = self.steps[slot].get_mut().unwrap_or_else(|e| e.into_inner());
        theta.copy_from_slice(&step.theta);
        std::mem::swap(&mut self.a, &mut step.a);
        self.a_current = true;
    }

    /// Forward pass on the training part storing activations and errors, then JᵀJ (upper
    /// triangle) and Jᵀe.
    fn linearise(&mut self, theta: &[f64], part: &Part, par: &Pool) {
        let (n, h, k, ph, p) = (self.n, self.h, self.k, self.ph, self.p);
        let q = part.count;
        let pw = ph + h + 1;
        let lw = |o: usize, j: usize| theta[ph + o * (h + 1) + j];
        let lw_all = &theta[ph..];
        {
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
                    // Row s of W: z = (1 − a²) ⊗ x̃, then ã; and Jᵀe, hidden part
                    // (1 − a²)_j (Σ_o e_o LW_oj) x̃_i, output part e_o ã.
                    let row = &mut w[r * pw..(r + 1) * pw];
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
            });
        }
        self.g.fill(0.0);
        for c in 0..part.chunks() {
            for (g, v) in self.g.iter_mut().zip(&self.g_chunks[c * p..(c + 1) * p]) {
                *g += v;
            }
        }
        {
            // The upper triangle of WᵀW by tiles; each tile is one GEMM over all samples, so a
            // tile's values are the same whichever thread computes it.
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
        // M = LWᵀLW over the hidden columns.
        for j in 0..h {
            for jj in 0..h {
                self.m[j * h + jj] = (0..k).map(|o| lw(o, j) * lw(o, jj)).sum();
            }
        }
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
/// A trained network and how training went.
#[derive(Clone, Debug)]
pub struct Trained {
    /// The network with the kept weights.
    pub net: Mlp,
    /// The report.
    pub report: TrainReport,
}

/// Trains a net mapping `inputs` (one row per input, one column per sample, original
/// units) to `targets` (one row per output) on [`default_threads`] threads. `on_epoch` sees
/// every epoch's progress.
pub fn train(
    inputs: &DMatrix<f64>,
    targets: &DMatrix<f64>,
    settings: &TrainSettings,
    on_epoch: &mut dyn FnMut(&EpochInfo<'_>),
) -> Result<Trained, TrainError> {
    train_with_threads(inputs, targets, settings, default_threads(), on_epoch)
}

/// [`train`] on `threads` threads (the calling one and `threads − 1` workers that live for
/// this call; 0 counts as 1). The result is bitwise the same for every number of threads.
pub fn train_with_threads(
    inputs: &DMatrix<f64>,
    targets: &DMatrix<f64>,
    settings: &TrainSettings,
    threads: usize,
    on_epoch: &mut dyn FnMut(&EpochInfo<'_>),
) -> Result<Trained, TrainError> {
    let q = inputs.ncols();
    if q == 0 || targets.ncols() != q {
        return Err(TrainError::Data(format!("{q} input samples and {} target samples", targets.ncols())));
    }
    if inputs.iter().chain(targets.iter()).any(|v| !v.is_finite()) {
        return Err(TrainError::Data("the data holds NaN or infinite values".into()));
    }
    let s = settings;
    check_settings(s, inputs.nrows(), targets.nrows(), q)?;
    if let Some(row) = (0..inputs.nrows()).find(|&r| {
        let row = inputs.row(r);
        row.iter().all(|&v| v == row[0])
    }) {
        return Err(TrainError::Data(format!(
            "input {} is constant ({} in every sample): it carries nothing to learn from",
            row + 1,
            inputs[(row, 0)]
        )));
    }
    let input_scaling = MinMaxScaling::fit(inputs);
    let output_scaling = MinMaxScaling::fit(targets);
    let (xs, ts) = (input_scaling.apply_all(inputs), output_scaling.apply_all(targets));
    let parts = split(q, s.split, s.seed);
    let [train_part, val_part, test_part] = [0, 1, 2].map(|i| Part::new(&xs, &ts, &parts[i]));
    let (n, k) = (inputs.nrows(), targets.nrows());
    let mut ws = Workspace::new(n, s.hidden, k, train_part.count, val_part.count.max(test_part.count));
    let parts = [&train_part, &val_part, &test_part];
    Pool::scoped(threads, |pool| train_restarts(&mut ws, parts, (&input_scaling, &output_scaling), s, pool, on_epoch))
}

/// The restarts of [`train_with_threads`] on prepared data.
fn train_restarts(
    ws: &mut Workspace,
    [train_part, val_part, test_part]: [&Part; 3],
    (input_scaling, output_scaling): (&MinMaxScaling, &MinMaxScaling),
    s: &TrainSettings,
    pool: &Pool,
    on_epoch: &mut dyn FnMut(&EpochInfo<'_>),
) -> Result<Trained, TrainError> {
    let k = ws.k;
    let mut per_output = vec![0.0; k];
    let mut best: Option<(f64, Mlp, TrainReport)> = None;

    for restart in 0..s.restarts {
        let mut rng = ChaCha8Rng::seed_from_u64(s.seed.wrapping_add(restart as u64));
        let mut net = Mlp::nguyen_widrow(s.hidden, input_scaling.clone(), output_scaling.clone(), &mut rng);
        let mut theta = net.parameters();
        ws.a_current = false;
        let (mut mu, mut epoch, mut fails) = (s.mu, 0, 0);
        // Nielsen's factor for the next failed step.
        let mut nu = 2.0;
        let mut last_trials = 0;
        let norm_train = (train_part.count * k) as f64;
        let mut train_mse = ws.forward(&theta, train_part, &mut per_output, pool) / norm_train;
        let val_of = |ws: &mut Workspace, theta: &[f64], po: &mut [f64]| {
            if val_part.count == 0 {
                f64::NAN
            } else {
                ws.forward(theta, val_part, po, pool) / (val_part.count * k) as f64
            }
        };
        let mut best_val = val_of(ws, &theta, &mut per_output);
        let mut best_theta = theta.clone();
        let mut best_epoch = 0;
        let stop = loop {
            if epoch >= s.epochs {
                break StopReason::Epochs;
            }
            if train_mse <= s.goal {
                break StopReason::Goal;
            }
            ws.linearise(&theta, train_part, pool);
            let grad = 2.0 * ws.g.iter().map(|g| g * g).sum::<f64>().sqrt() / norm_train;
            if grad < s.min_grad {
                break StopReason::MinGradient;
            }
            epoch += 1;
            let mut improved = false;
            let mut trials = 0;
            'steps: while mu <= s.mu_max {
                // trainlm's second step of an epoch is the first one's μ ×mu_inc. Once an
                // epoch has needed two, the next one likely will too (μ falls ×mu_dec after
                // each success, then its first step fails): then two threads try both at once,
                // each alone, which is faster than one after the other with both threads in
                // each (the small factorisation has serial parts). The outcome is the same as
                // trying them in turn; only a second step not needed is wasted.
                let mu_next = mu * s.mu_inc;
                let pair = s.damping == Damping::Trainlm && pool.workers() > 0 && last_trials >= 2 && mu_next <= s.mu_max;
                if pair {
                    let ws = &*ws;
                    let theta = &theta;
                    pool.run(2, &|slot| ws.try_step(slot, theta, [mu, mu_next][slot], train_part, &Serial));
                } else {
                    ws.try_step(0, &theta, mu, train_part, pool);
                }
                for slot in 0..if pair { 2 } else { 1 } {
                    trials += 1;
                    let step = ws.steps[slot].get_mut().unwrap_or_else(|e| e.into_inner());
                    if let Some(mse) = step.mse.filter(|&m| m < train_mse) {
                        if s.damping == Damping::Nielsen {
                            // Predicted reduction of the squared error by the linear model:
                            // ‖e‖² − ‖e − Jδ‖² = 2δᵀJᵀe − δᵀJᵀJδ = δᵀJᵀe + μ‖δ‖², as
                            // (JᵀJ + μI)δ = Jᵀe.
                            let dg: f64 = step.delta.iter().zip(&ws.g).map(|(d, g)| d * g).sum();
                            let dd: f64 = step.delta.iter().map(|d| d * d).sum();
                            let rho = (train_mse - mse) * norm_train / (dg + mu * dd);
                            mu *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
                            nu = 2.0;
                        } else {
                            mu *= s.mu_dec;
                        }
                        ws.accept_step(slot, &mut theta);
                        train_mse = mse;
                        improved = true;
                        break 'steps;
                    }
                    match s.damping {
                        Damping::Trainlm => mu *= s.mu_inc,
                        Damping::Nielsen => {
                            mu *= nu;
                            nu *= 2.0;
                        }
                    }
                }
            }
            last_trials = trials;
            let val = val_of(ws, &theta, &mut per_output);
            on_epoch(&EpochInfo { restart, epoch, train_mse, validation_mse: val, mu, trials, parameters: &theta });
            if !improved {
                break StopReason::MuMax;
            }
            if val_part.count == 0 || val < best_val {
                best_val = val;
                best_theta.copy_from_slice(&theta);
                best_epoch = epoch;
                fails = 0;
            } else {
                fails += 1;
                if fails >= s.max_fail {
                    break StopReason::ValidationFailures;
                }
            }
        };
        if val_part.count == 0 {
            best_theta.copy_from_slice(&theta);
            best_epoch = epoch;
        }
        net.set_parameters(&best_theta);
        let mut report_mse = |part: &Part| {
            (part.count > 0).then(|| {
                ws.forward(&best_theta, part, &mut per_output, pool);
                per_output.iter().enumerate().map(|(o, v)| v * output_scaling.error_scale(o)).sum::<f64>() / (part.count * k) as f64
            })
        };
        let report = TrainReport {
            epochs: epoch,
            best_epoch,
            stop_reason: stop,
            restart,
            train_mse: report_mse(train_part).expect("training samples exist"),
            validation_mse: report_mse(val_part),
            test_mse: report_mse(test_part),
            counts: [train_part.count, val_part.count, test_part.count],
        };
        // Keep the restart with the best validation error (training error without validation).
        let score = report.validation_mse.unwrap_or(report.train_mse);
        if best.as_ref().is_none_or(|(b, _, _)| score < *b) {
            best = Some((score, net, report));
        }
    }
    let (_, net, report) = best.expect("at least one restart");
    Ok(Trained { net, report })
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
