//! What a training run is given and what it reports: the settings (trainlm's defaults), the
//! checks and limits applied before training starts, and the report of how it went.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use super::data::{split, SAMPLE_CHUNK};

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
    /// The parameters after the epoch, ordered as [`Mlp::parameters`](crate::Mlp::parameters).
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

/// Largest number of hidden neurons [`train`](super::train) accepts.
pub const MAX_HIDDEN: usize = 1000;
/// Largest number of weights and biases [`train`](super::train) accepts: Levenberg–Marquardt factors a
/// square matrix of this order every step (5000: three 200 MB matrices, seconds per step).
pub const MAX_WEIGHTS: usize = 5000;
/// Largest working memory [`train`](super::train) allocates [bytes] (8 GiB).
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
