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
//! matrix of the rows [z; ã]. All buffers are made once per training; the only allocation in
//! an epoch is the GEMM library's (matrixmultiply) packing buffer, once per epoch.
//!
//! Training works on scaled data (inputs and targets in [-1, 1]); the reported errors are
//! mean squared errors in the targets' own units.

use nalgebra::DMatrix;
use rand::seq::SliceRandom;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use super::mlp::{MinMaxScaling, Mlp};
use crate::linalg::cholesky_solve_in_place;

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
    /// μ factor after a successful step.
    pub mu_dec: f64,
    /// μ factor after a failed step.
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
    a: Vec<f64>,
    /// Activations of the last trial step, which become `a` when the step is taken.
    a_trial: Vec<f64>,
    /// Whether `a` holds the activations of the current parameters on the training part.
    a_current: bool,
    e: Vec<f64>,
    /// Rows [z; ã] per sample (width `ph + h + 1`): one Gram matrix gives ZᵀZ, ZᵀÃᵀ and ÃÃᵀ.
    w: Vec<f64>,
    gram: Vec<f64>,
    m: Vec<f64>,
    jtj: Vec<f64>,
    work: Vec<f64>,
    g: Vec<f64>,
    delta: Vec<f64>,
    trial: Vec<f64>,
    hidden: Vec<f64>,
}

impl Workspace {
    fn new(n: usize, h: usize, k: usize, q: usize) -> Self {
        let ph = h * (n + 1);
        let p = ph + k * (h + 1);
        Self {
            n,
            h,
            k,
            ph,
            p,
            a: vec![0.0; q * (h + 1)],
            a_trial: vec![0.0; q * (h + 1)],
            a_current: false,
            e: vec![0.0; q * k],
            w: vec![0.0; q * (ph + h + 1)],
            gram: vec![0.0; (ph + h + 1) * (ph + h + 1)],
            m: vec![0.0; h * h],
            jtj: vec![0.0; p * p],
            work: vec![0.0; p * p],
            g: vec![0.0; p],
            delta: vec![0.0; p],
            trial: vec![0.0; p],
            hidden: vec![0.0; h],
        }
    }

    /// Network output k of the hidden activations in `hidden` for parameters `theta`.
    #[inline]
    fn output(&self, theta: &[f64], hidden: &[f64], k: usize) -> f64 {
        let base = self.ph + k * (self.h + 1);
        let w = &theta[base..base + self.h + 1];
        let mut s = w[self.h];
        for j in 0..self.h {
            s += w[j] * hidden[j];
        }
        s
    }

    /// Hidden activations of sample `x̃` into `hidden`.
    #[inline]
    fn activate(n: usize, h: usize, theta: &[f64], x: &[f64], hidden: &mut [f64]) {
        for j in 0..h {
            let w = &theta[j * (n + 1)..(j + 1) * (n + 1)];
            let mut s = 0.0;
            for i in 0..=n {
                s += w[i] * x[i];
            }
            hidden[j] = tanh(s);
        }
    }

    /// Sum of squared errors of `theta` on `part`, per output (scaled units), into `per_output`.
    fn sse(&mut self, theta: &[f64], part: &Part, per_output: &mut [f64]) -> f64 {
        let (n, h, k) = (self.n, self.h, self.k);
        per_output.fill(0.0);
        let mut hidden = std::mem::take(&mut self.hidden);
        for p in 0..part.count {
            Self::activate(n, h, theta, &part.x[p * (n + 1)..(p + 1) * (n + 1)], &mut hidden);
            for o in 0..k {
                let err = part.t[p * k + o] - self.output(theta, &hidden, o);
                per_output[o] += err * err;
            }
        }
        self.hidden = hidden;
        per_output.iter().sum()
    }

    /// [`Workspace::sse`] on the training part, keeping the activations in `a_trial`.
    fn sse_trial(&mut self, theta: &[f64], part: &Part, per_output: &mut [f64]) -> f64 {
        let (n, h, k) = (self.n, self.h, self.k);
        per_output.fill(0.0);
        let mut a = std::mem::take(&mut self.a_trial);
        for p in 0..part.count {
            let hidden = &mut a[p * (h + 1)..(p + 1) * (h + 1)];
            Self::activate(n, h, theta, &part.x[p * (n + 1)..(p + 1) * (n + 1)], &mut hidden[..h]);
            hidden[h] = 1.0;
            for o in 0..k {
                let err = part.t[p * k + o] - self.output(theta, &hidden[..h], o);
                per_output[o] += err * err;
            }
        }
        self.a_trial = a;
        per_output.iter().sum()
    }

    /// The last trial step was taken: its activations are now the current ones.
    fn accept_trial(&mut self) {
        std::mem::swap(&mut self.a, &mut self.a_trial);
        self.a_current = true;
    }

    /// Forward pass on the training part storing activations and errors, then JᵀJ and Jᵀe.
    fn linearise(&mut self, theta: &[f64], part: &Part) {
        let (n, h, k, ph, p) = (self.n, self.h, self.k, self.ph, self.p);
        let q = part.count;
        let pw = ph + h + 1;
        for s in 0..q {
            let x = &part.x[s * (n + 1)..(s + 1) * (n + 1)];
            let a = &mut self.a[s * (h + 1)..(s + 1) * (h + 1)];
            if !self.a_current {
                Self::activate(n, h, theta, x, &mut a[..h]);
                a[h] = 1.0;
            }
            for o in 0..k {
                let base = ph + o * (h + 1);
                let y: f64 = theta[base..base + h + 1].iter().zip(a.iter()).map(|(w, v)| w * v).sum();
                self.e[s * k + o] = part.t[s * k + o] - y;
            }
            // Row s of W: z = (1 − a²) ⊗ x̃, then ã.
            let row = &mut self.w[s * pw..(s + 1) * pw];
            for j in 0..h {
                let d = 1.0 - a[j] * a[j];
                for i in 0..=n {
                    row[j * (n + 1) + i] = d * x[i];
                }
            }
            row[ph..].copy_from_slice(a);
        }
        // SAFETY: `w` holds the q×pw row-major matrix W and `gram` has room for pw×pw.
        unsafe {
            let (wp, pwi) = (self.w.as_ptr(), pw as isize);
            matrixmultiply::dgemm(pw, q, pw, 1.0, wp, 1, pwi, wp, pwi, 1, 0.0, self.gram.as_mut_ptr(), pwi, 1);
        }
        let gram = &self.gram;
        let zta = |r: usize, m: usize| gram[r * pw + ph + m];
        let ata = |m: usize, m2: usize| gram[(ph + m) * pw + ph + m2];
        // M = LWᵀLW over the hidden columns.
        let lw = |o: usize, j: usize| theta[ph + o * (h + 1) + j];
        for j in 0..h {
            for jj in 0..h {
                self.m[j * h + jj] = (0..k).map(|o| lw(o, j) * lw(o, jj)).sum();
            }
        }
        let jtj = &mut self.jtj;
        for r in 0..ph {
            let j = r / (n + 1);
            let (out, src) = (&mut jtj[r * p..r * p + ph], &gram[r * pw..r * pw + ph]);
            for jj in 0..h {
                let mjj = self.m[j * h + jj];
                let span = jj * (n + 1)..(jj + 1) * (n + 1);
                for (o, g) in out[span.clone()].iter_mut().zip(&src[span]) {
                    *o = g * mjj;
                }
            }
            for o in 0..k {
                let w = lw(o, j);
                for mm in 0..=h {
                    let col = ph + o * (h + 1) + mm;
                    let v = w * zta(r, mm);
                    jtj[r * p + col] = v;
                    jtj[col * p + r] = v;
                }
            }
        }
        for o in 0..k {
            for mm in 0..=h {
                let row = ph + o * (h + 1) + mm;
                let out = &mut jtj[row * p + ph..row * p + p];
                out.fill(0.0);
                let block = &mut out[o * (h + 1)..(o + 1) * (h + 1)];
                for (m2, v) in block.iter_mut().enumerate() {
                    *v = ata(mm, m2);
                }
            }
        }
        // Jᵀe: hidden part Σ_s (1 − a²)_j (Σ_o e_o LW_oj) x̃_i; output part Σ_s e_o ã.
        self.g.fill(0.0);
        for s in 0..q {
            let a = &self.a[s * (h + 1)..(s + 1) * (h + 1)];
            let x = &part.x[s * (n + 1)..(s + 1) * (n + 1)];
            let e = &self.e[s * k..(s + 1) * k];
            for j in 0..h {
                let back: f64 = (0..k).map(|o| e[o] * lw(o, j)).sum::<f64>() * (1.0 - a[j] * a[j]);
                for i in 0..=n {
                    self.g[j * (n + 1) + i] += back * x[i];
                }
            }
            for o in 0..k {
                for mm in 0..=h {
                    self.g[ph + o * (h + 1) + mm] += e[o] * a[mm];
                }
            }
        }
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
/// units) to `targets` (one row per output). `on_epoch` sees every epoch's progress.
pub fn train(
    inputs: &DMatrix<f64>,
    targets: &DMatrix<f64>,
    settings: &TrainSettings,
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
    let bad = |what: &str| Err(TrainError::Settings(what.to_owned()));
    if s.hidden == 0 {
        return bad("hidden must be >= 1");
    }
    if !(s.mu > 0.0 && s.mu_dec > 0.0 && s.mu_dec < 1.0 && s.mu_inc > 1.0 && s.mu_max >= s.mu) {
        return bad("need mu > 0, 0 < mu_dec < 1 < mu_inc, mu_max >= mu");
    }
    if s.split.iter().any(|f| !(*f >= 0.0)) || !(s.split[0] > 0.0) {
        return bad("split fractions must be >= 0 with a positive training fraction");
    }
    if s.restarts == 0 {
        return bad("restarts must be >= 1");
    }
    let input_scaling = MinMaxScaling::fit(inputs);
    let output_scaling = MinMaxScaling::fit(targets);
    let (xs, ts) = (input_scaling.apply_all(inputs), output_scaling.apply_all(targets));
    let parts = split(q, s.split, s.seed);
    if parts[0].is_empty() {
        return Err(TrainError::Data(format!("{q} samples leave none for training")));
    }
    let [train_part, val_part, test_part] = [0, 1, 2].map(|i| Part::new(&xs, &ts, &parts[i]));
    let (n, k) = (inputs.nrows(), targets.nrows());
    let mut ws = Workspace::new(n, s.hidden, k, train_part.count);
    let mut per_output = vec![0.0; k];
    let mut best: Option<(f64, Mlp, TrainReport)> = None;

    for restart in 0..s.restarts {
        let mut rng = ChaCha8Rng::seed_from_u64(s.seed.wrapping_add(restart as u64));
        let mut net = Mlp::nguyen_widrow(s.hidden, input_scaling.clone(), output_scaling.clone(), &mut rng);
        let mut theta = net.parameters();
        ws.a_current = false;
        let (mut mu, mut epoch, mut fails) = (s.mu, 0, 0);
        let norm_train = (train_part.count * k) as f64;
        let mut train_mse = ws.sse(&theta, &train_part, &mut per_output) / norm_train;
        let val_of = |ws: &mut Workspace, theta: &[f64], po: &mut [f64]| {
            if val_part.count == 0 {
                f64::NAN
            } else {
                ws.sse(theta, &val_part, po) / (val_part.count * k) as f64
            }
        };
        let mut best_val = val_of(&mut ws, &theta, &mut per_output);
        let mut best_theta = theta.clone();
        let mut best_epoch = 0;
        let stop = loop {
            if epoch >= s.epochs {
                break StopReason::Epochs;
            }
            if train_mse <= s.goal {
                break StopReason::Goal;
            }
            ws.linearise(&theta, &train_part);
            let grad = 2.0 * ws.g.iter().map(|g| g * g).sum::<f64>().sqrt() / norm_train;
            if grad < s.min_grad {
                break StopReason::MinGradient;
            }
            epoch += 1;
            let mut improved = false;
            while mu <= s.mu_max {
                ws.work.copy_from_slice(&ws.jtj);
                for d in 0..ws.p {
                    ws.work[d * ws.p + d] += mu;
                }
                ws.delta.copy_from_slice(&ws.g);
                if cholesky_solve_in_place(&mut ws.work, ws.p, &mut ws.delta) {
                    for ((t, &th), &d) in ws.trial.iter_mut().zip(&theta).zip(&ws.delta) {
                        *t = th + d;
                    }
                    let trial = std::mem::take(&mut ws.trial);
                    let mse = ws.sse_trial(&trial, &train_part, &mut per_output) / norm_train;
                    ws.trial = trial;
                    if mse < train_mse {
                        theta.copy_from_slice(&ws.trial);
                        ws.accept_trial();
                        train_mse = mse;
                        mu *= s.mu_dec;
                        improved = true;
                        break;
                    }
                }
                mu *= s.mu_inc;
            }
            let val = val_of(&mut ws, &theta, &mut per_output);
            on_epoch(&EpochInfo { restart, epoch, train_mse, validation_mse: val, mu, parameters: &theta });
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
        let report_mse = |ws: &mut Workspace, part: &Part, po: &mut Vec<f64>| {
            (part.count > 0).then(|| {
                ws.sse(&best_theta, part, po);
                po.iter().enumerate().map(|(o, v)| v * output_scaling.error_scale(o)).sum::<f64>() / (part.count * k) as f64
            })
        };
        let report = TrainReport {
            epochs: epoch,
            best_epoch,
            stop_reason: stop,
            restart,
            train_mse: report_mse(&mut ws, &train_part, &mut per_output).expect("training samples exist"),
            validation_mse: report_mse(&mut ws, &val_part, &mut per_output),
            test_mse: report_mse(&mut ws, &test_part, &mut per_output),
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

/// JᵀJ and Jᵀe as the trainer forms them, on scaled samples (columns of `x`, `t`); for tests
/// against the naive products of [`output_jacobian`].
pub fn normal_equations(net: &Mlp, x: &DMatrix<f64>, t: &DMatrix<f64>) -> (Vec<f64>, Vec<f64>) {
    let idx: Vec<usize> = (0..x.ncols()).collect();
    let part = Part::new(x, t, &idx);
    let mut ws = Workspace::new(net.inputs(), net.hidden(), net.outputs(), part.count);
    ws.linearise(&net.parameters(), &part);
    (ws.jtj, ws.g)
}
