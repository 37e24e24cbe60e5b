//! Damped steps: (JᵀJ + μI) δ = Jᵀe solved by the blocked Cholesky factorisation, the training
//! error at θ + δ, and the step taken.

use super::data::Part;
use super::forward::forward_into;
use super::workspace::Workspace;
use crate::linalg::{cholesky_shifted, cholesky_solve_factored};
use crate::parallel::ParallelFor;

impl Workspace {
    /// The damped step of μ from `theta` into `steps[slot]`: factor JᵀJ + μI, solve for δ,
    /// evaluate the training MSE at θ + δ. Takes `&self` so that two slots can be tried at
    /// once, each on one thread.
    pub(super) fn try_step(&self, slot: usize, theta: &[f64], mu: f64, part: &Part, par: &dyn ParallelFor) {
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
    pub(super) fn accept_step(&mut self, slot: usize, theta: &mut [f64]) {
        let step = self.steps[slot].get_mut().unwrap_or_else(|e| e.into_inner());
        theta.copy_from_slice(&step.theta);
        std::mem::swap(&mut self.a, &mut step.a);
        self.a_current = true;
    }

    /// The training MSE (scaled units) of the step tried in `steps[slot]`; none if JᵀJ + μI
    /// was not positive definite.
    pub(super) fn trial_mse(&mut self, slot: usize) -> Option<f64> {
        self.steps[slot].get_mut().unwrap_or_else(|e| e.into_inner()).mse
    }

    /// The gain ratio ρ of the step in `steps[slot]` from `train_mse` to its `mse` (scaled units;
    /// `norm` is samples × outputs): the actual reduction of the squared error over the one the
    /// linear model predicts, ‖e‖² − ‖e − Jδ‖² = 2δᵀJᵀe − δᵀJᵀJδ = δᵀJᵀe + μ‖δ‖², as
    /// (JᵀJ + μI)δ = Jᵀe.
    pub(super) fn gain_ratio(&mut self, slot: usize, train_mse: f64, mse: f64, mu: f64, norm: f64) -> f64 {
        let step = self.steps[slot].get_mut().unwrap_or_else(|e| e.into_inner());
        let dg: f64 = step.delta.iter().zip(&self.g).map(|(d, g)| d * g).sum();
        let dd: f64 = step.delta.iter().map(|d| d * d).sum();
        (train_mse - mse) * norm / (dg + mu * dd)
    }
}
