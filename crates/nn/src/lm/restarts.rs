//! The restarts of a training and the epochs of each: trainlm's loop, with early stopping on
//! the validation error and the restart of the best one kept.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::data::Part;
use super::settings::{Damping, EpochInfo, StopReason, TrainError, TrainReport, TrainSettings};
use super::workspace::Workspace;
use super::Trained;
use crate::mlp::{MinMaxScaling, Mlp};
use crate::parallel::{ParallelFor, Pool, Serial};

/// What every restart of one training works on.
struct Run<'a> {
    /// The training, validation and test parts.
    parts: [&'a Part; 3],
    /// The input and output scalings.
    scalings: (&'a MinMaxScaling, &'a MinMaxScaling),
    settings: &'a TrainSettings,
    pool: &'a Pool,
    /// Samples × outputs of the training part: the divisor of its MSE.
    norm_train: f64,
}

impl Run<'_> {
    /// The validation MSE (scaled units) at `theta`; NaN without validation samples.
    fn validation_mse(&self, ws: &mut Workspace, theta: &[f64], per_output: &mut [f64]) -> f64 {
        let val_part = self.parts[1];
        if val_part.count == 0 {
            f64::NAN
        } else {
            ws.forward(theta, val_part, per_output, self.pool) / (val_part.count * ws.k) as f64
        }
    }

    /// The MSE of `theta` on `part` in the targets' units²; none for an empty part.
    fn report_mse(&self, ws: &mut Workspace, theta: &[f64], part: &Part, per_output: &mut [f64]) -> Option<f64> {
        let output_scaling = self.scalings.1;
        (part.count > 0).then(|| {
            ws.forward(theta, part, per_output, self.pool);
            per_output.iter().enumerate().map(|(o, v)| v * output_scaling.error_scale(o)).sum::<f64>() / (part.count * ws.k) as f64
        })
    }
}

/// Where the descent of one restart stands.
struct Descent {
    /// The parameters, ordered as [`Mlp::parameters`].
    theta: Vec<f64>,
    /// μ.
    mu: f64,
    /// Nielsen's factor for the next failed step.
    nu: f64,
    /// Epochs run.
    epoch: usize,
    /// Training MSE at `theta` (scaled units).
    train_mse: f64,
    /// Damped steps tried in the last epoch.
    trials: usize,
}

impl Descent {
    /// The step in `ws.steps[slot]`, of training MSE `mse`, is taken: μ falls (by `mu_dec`, or
    /// by Nielsen's rule from the step's gain ratio) and θ moves.
    fn take(&mut self, ws: &mut Workspace, slot: usize, mse: f64, s: &TrainSettings, norm_train: f64) {
        if s.damping == Damping::Nielsen {
            let rho = ws.gain_ratio(slot, self.train_mse, mse, self.mu, norm_train);
            self.mu *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
            self.nu = 2.0;
        } else {
            self.mu *= s.mu_dec;
        }
        ws.accept_step(slot, &mut self.theta);
        self.train_mse = mse;
    }

    /// A step failed: μ rises (by `mu_inc`, or by ν, which doubles).
    fn refuse(&mut self, s: &TrainSettings) {
        match s.damping {
            Damping::Trainlm => self.mu *= s.mu_inc,
            Damping::Nielsen => {
                self.mu *= self.nu;
                self.nu *= 2.0;
            }
        }
    }
}

/// The best validation error of a restart so far, for early stopping.
struct BestValidation {
    /// Validation MSE (scaled units).
    mse: f64,
    /// The parameters that had it.
    theta: Vec<f64>,
    /// The epoch that reached them.
    epoch: usize,
    /// Epochs in a row since, none better.
    fails: usize,
}

impl BestValidation {
    /// Records an epoch's validation MSE `val` at `d`: kept if better (every epoch's without
    /// validation samples); [`StopReason::ValidationFailures`] after `max_fail` epochs in a
    /// row without a better one.
    fn record(&mut self, val: f64, d: &Descent, val_count: usize, max_fail: usize) -> Option<StopReason> {
        if val_count == 0 || val < self.mse {
            self.mse = val;
            self.theta.copy_from_slice(&d.theta);
            self.epoch = d.epoch;
            self.fails = 0;
        } else {
            self.fails += 1;
            if self.fails >= max_fail {
                return Some(StopReason::ValidationFailures);
            }
        }
        None
    }
}

/// The restarts of [`train_with_threads`](super::train_with_threads) on prepared data; the one
/// with the best validation error (training error without validation samples) is kept.
pub(super) fn train_restarts(
    ws: &mut Workspace,
    parts: [&Part; 3],
    scalings: (&MinMaxScaling, &MinMaxScaling),
    s: &TrainSettings,
    pool: &Pool,
    on_epoch: &mut dyn FnMut(&EpochInfo<'_>),
) -> Result<Trained, TrainError> {
    let run = Run { parts, scalings, settings: s, pool, norm_train: (parts[0].count * ws.k) as f64 };
    let mut per_output = vec![0.0; ws.k];
    let mut best: Option<(f64, Mlp, TrainReport)> = None;
    for restart in 0..s.restarts {
        let (net, report) = train_restart(ws, &run, restart, &mut per_output, on_epoch);
        let score = report.validation_mse.unwrap_or(report.train_mse);
        if best.as_ref().is_none_or(|(b, _, _)| score < *b) {
            best = Some((score, net, report));
        }
    }
    let (_, net, report) = best.expect("at least one restart");
    Ok(Trained { net, report })
}

/// One restart: initial weights from the seed plus `restart`, epochs until a stop, and the net
/// with the weights of the best validation error (the last ones without validation samples).
fn train_restart(
    ws: &mut Workspace,
    run: &Run<'_>,
    restart: usize,
    per_output: &mut [f64],
    on_epoch: &mut dyn FnMut(&EpochInfo<'_>),
) -> (Mlp, TrainReport) {
    let (s, [train_part, val_part, test_part]) = (run.settings, run.parts);
    let mut rng = ChaCha8Rng::seed_from_u64(s.seed.wrapping_add(restart as u64));
    let mut net = Mlp::nguyen_widrow(s.hidden, run.scalings.0.clone(), run.scalings.1.clone(), &mut rng);
    let theta = net.parameters();
    ws.a_current = false;
    let train_mse = ws.forward(&theta, train_part, per_output, run.pool) / run.norm_train;
    let best_val = run.validation_mse(ws, &theta, per_output);
    let mut best = BestValidation { mse: best_val, theta: theta.clone(), epoch: 0, fails: 0 };
    let mut d = Descent { theta, mu: s.mu, nu: 2.0, epoch: 0, train_mse, trials: 0 };
    let stop = run_epochs(ws, run, restart, &mut d, &mut best, per_output, on_epoch);
    if val_part.count == 0 {
        best.theta.copy_from_slice(&d.theta);
        best.epoch = d.epoch;
    }
    net.set_parameters(&best.theta);
    let report = TrainReport {
        epochs: d.epoch,
        best_epoch: best.epoch,
        stop_reason: stop,
        restart,
        train_mse: run.report_mse(ws, &best.theta, train_part, per_output).expect("training samples exist"),
        validation_mse: run.report_mse(ws, &best.theta, val_part, per_output),
        test_mse: run.report_mse(ws, &best.theta, test_part, per_output),
        counts: [train_part.count, val_part.count, test_part.count],
    };
    (net, report)
}

/// Epochs from `d` until one of the stops: the epoch limit, the goal, the minimum gradient,
/// μ beyond `mu_max`, or `max_fail` validation failures in a row. Each epoch linearises at θ,
/// takes one damped step and is shown to `on_epoch`.
fn run_epochs(
    ws: &mut Workspace,
    run: &Run<'_>,
    restart: usize,
    d: &mut Descent,
    best: &mut BestValidation,
    per_output: &mut [f64],
    on_epoch: &mut dyn FnMut(&EpochInfo<'_>),
) -> StopReason {
    let s = run.settings;
    loop {
        if d.epoch >= s.epochs {
            return StopReason::Epochs;
        }
        if d.train_mse <= s.goal {
            return StopReason::Goal;
        }
        ws.linearise(&d.theta, run.parts[0], run.pool);
        let grad = 2.0 * ws.g.iter().map(|g| g * g).sum::<f64>().sqrt() / run.norm_train;
        if grad < s.min_grad {
            return StopReason::MinGradient;
        }
        d.epoch += 1;
        let improved = damped_steps(ws, run, d);
        let val = run.validation_mse(ws, &d.theta, per_output);
        let (epoch, train_mse, mu, trials) = (d.epoch, d.train_mse, d.mu, d.trials);
        on_epoch(&EpochInfo { restart, epoch, train_mse, validation_mse: val, mu, trials, parameters: &d.theta });
        if !improved {
            return StopReason::MuMax;
        }
        if let Some(stop) = best.record(val, d, run.parts[1].count, s.max_fail) {
            return stop;
        }
    }
}

/// One epoch's damped steps: steps of growing μ are tried until one lowers the training error
/// and is taken (true), or μ exceeds `mu_max` (false). `d.trials` counts them.
fn damped_steps(ws: &mut Workspace, run: &Run<'_>, d: &mut Descent) -> bool {
    let (s, pool, train_part) = (run.settings, run.pool, run.parts[0]);
    let last_trials = d.trials;
    d.trials = 0;
    while d.mu <= s.mu_max {
        // trainlm's second step of an epoch is the first one's μ ×mu_inc. Once an epoch has
        // needed two, the next one likely will too (μ falls ×mu_dec after each success, then
        // its first step fails): then two threads try both at once, each alone, which is
        // faster than one after the other with both threads in each (the small factorisation
        // has serial parts). The outcome is the same as trying them in turn; only a second
        // step not needed is wasted.
        let (mu, mu_next) = (d.mu, d.mu * s.mu_inc);
        let pair = s.damping == Damping::Trainlm && pool.workers() > 0 && last_trials >= 2 && mu_next <= s.mu_max;
        if pair {
            let (ws, theta) = (&*ws, &d.theta);
            pool.run(2, &|slot| ws.try_step(slot, theta, [mu, mu_next][slot], train_part, &Serial));
        } else {
            ws.try_step(0, &d.theta, mu, train_part, pool);
        }
        for slot in 0..if pair { 2 } else { 1 } {
            d.trials += 1;
            if let Some(mse) = ws.trial_mse(slot).filter(|&m| m < d.train_mse) {
                d.take(ws, slot, mse, s, run.norm_train);
                return true;
            }
            d.refuse(s);
        }
    }
    false
}
