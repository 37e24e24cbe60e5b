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
//! factorisation into fixed column pieces ([`crate::linalg::cholesky_shifted`]); the threads
//! of a [`Pool`] take these tasks as they come free and sums over chunks are added in chunk
//! order. So the result is bitwise the same for any number of threads ([`train_with_threads`];
//! [`train`] uses [`default_threads`]). With trainlm's rule, once an epoch has needed two
//! damped steps the next epoch's first two (μ and μ·mu_inc) are tried at once, one per thread.
//!
//! # Files
//! `settings` (what a run is given and reports, the checks before it starts), `data` (the
//! split and the scaled parts), `forward` (activations and errors), `workspace` (the buffers),
//! `jacobian` (an epoch's linearisation: Jᵀe, the Gram matrix, JᵀJ), `step` (damped steps),
//! `restarts` (the epochs of each restart, and the restart kept).
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

mod data;
mod forward;
mod jacobian;
mod restarts;
mod settings;
mod step;
mod workspace;

use nalgebra::DMatrix;

pub use data::split;
use data::Part;
pub use jacobian::{gemm_calls, normal_equations, output_jacobian};
use restarts::train_restarts;
pub use settings::{
    check_settings, minimum_samples, time_series_warning, weight_count, workspace_bytes, Damping, EpochInfo, StopReason, TrainError,
    TrainReport, TrainSettings, MAX_HIDDEN, MAX_WEIGHTS, MAX_WORKSPACE_BYTES, MIN_CHECK_SAMPLES, MIN_TRAINING_SAMPLES,
};
use workspace::Workspace;

use crate::mlp::{MinMaxScaling, Mlp};
use crate::parallel::{default_threads, Pool};

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
    let s = settings;
    check_data(inputs, targets, s)?;
    let q = inputs.ncols();
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

/// Checks the data and the settings for it: samples in both, all finite, the settings within
/// [`check_settings`], no constant input.
fn check_data(inputs: &DMatrix<f64>, targets: &DMatrix<f64>, s: &TrainSettings) -> Result<(), TrainError> {
    let q = inputs.ncols();
    if q == 0 || targets.ncols() != q {
        return Err(TrainError::Data(format!("{q} input samples and {} target samples", targets.ncols())));
    }
    if inputs.iter().chain(targets.iter()).any(|v| !v.is_finite()) {
        return Err(TrainError::Data("the data holds NaN or infinite values".into()));
    }
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
    Ok(())
}
