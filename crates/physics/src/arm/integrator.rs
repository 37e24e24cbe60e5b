//! Forward dynamics and a fixed-step RK4 integrator with stick–slip friction.
//!
//! # Stepping
//! [`ArmSimulator::step`] advances the state by `dt` in equal RK4 sub-steps no longer than
//! [`IntegratorSettings::internal_step_s`] (default 0.25 ms, so a 1 ms communication step is
//! four RK4 steps). A step allocates nothing: all scratch space is made once, in
//! [`ArmSimulator::new`].
//!
//! # Stick–slip
//! Friction jumps at zero velocity ([`crate::arm::friction`]). Rather than smoothing the jump,
//! each sub-step fixes a *mode* per joint whose friction is discontinuous, at its start:
//!
//! * **stuck** – the joint is exactly at rest (q̇ = 0) and the friction torque needed to keep it
//!   there, given the applied torques and the motion of the other joints, is within its
//!   breakaway level. Its q̈ is 0 for the whole sub-step; the other joints move with it locked.
//!   Several joints at rest are resolved together: all start stuck, and the one that exceeds its
//!   breakaway level the most is released, until every remaining one holds.
//! * **sliding in direction d** – friction is d·m(max(d·q̇, 0)) throughout the sub-step. If q̇
//!   has reversed by the end of the sub-step, the joint came to rest inside it: q̇ is set to 0
//!   and the next sub-step decides between sticking and breaking away the other way.
//!
//! Joints with continuous friction (no Coulomb or static level) are integrated as they are.
//! The mode switches are resolved to the sub-step, so a stop or a breakaway is placed with an
//! error of at most one sub-step; away from them the scheme is plain fourth-order RK4. A joint
//! driven below its breakaway torque from rest stays bit-for-bit at rest.

use super::dynamics::{mass_matrix_at_angles, rnea_at_angles, ArmData};
use super::params::{ArmParams, ParamError};

/// Settings of the fixed-step integrator.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IntegratorSettings {
    /// Longest RK4 sub-step [s]; a step of `dt` uses ⌈dt / internal_step_s⌉ equal sub-steps.
    pub internal_step_s: f64,
}

impl Default for IntegratorSettings {
    fn default() -> Self {
        Self { internal_step_s: 2.5e-4 }
    }
}

/// Joint angles [rad] and velocities [rad/s] of the arm.
#[derive(Clone, Debug, PartialEq)]
pub struct ArmState {
    /// Relative joint angles [rad].
    pub q: Vec<f64>,
    /// Joint velocities [rad/s].
    pub qd: Vec<f64>,
}

impl ArmState {
    /// The arm at rest at `q` [rad].
    pub fn at_rest(q: Vec<f64>) -> Self {
        let n = q.len();
        Self { q, qd: vec![0.0; n] }
    }
}

/// Why a step was refused; the state is left unchanged.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum StepError {
    /// `dt` was zero, negative or not finite.
    #[error("step size {0} s is invalid: it must be finite and > 0")]
    BadStep(f64),
    /// A vector had the wrong length.
    #[error("{what} has {got} entries, the arm has {expected} joints")]
    WrongLength {
        /// Which vector.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The number of joints.
        expected: usize,
    },
    /// The step needs more RK4 sub-steps than [`MAX_STEP_WORK`] allows for this arm.
    #[error(
        "a step of {} s needs {substeps:.3e} RK4 sub-steps of at most {} s; an arm of {joints} joints takes at most {max} per step (MAX_STEP_WORK): take shorter steps or a longer internal step",
        super::params::show_number(*.dt),
        super::params::show_number(*.internal_step)
    )]
    TooMuchWork {
        /// The step asked for [s].
        dt: f64,
        /// Sub-steps it would need.
        substeps: f64,
        /// The longest sub-step [s].
        internal_step: f64,
        /// The arm's joints.
        joints: usize,
        /// The most sub-steps allowed.
        max: usize,
    },
    /// An input or the state held NaN or an infinity.
    #[error("{what}[{index}] = {value} is not finite")]
    NotFinite {
        /// Which vector.
        what: &'static str,
        /// Index of the offending entry.
        index: usize,
        /// The value.
        value: f64,
    },
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Mode {
    /// Friction is continuous at zero velocity: integrate as is.
    Continuous,
    /// Friction acts against motion in this direction (+1 or −1) for the sub-step.
    Sliding(f64),
    /// At rest and held by static friction for the sub-step.
    Stuck,
}

/// Simulates one arm: parameters, integrator settings and all scratch space.
#[derive(Clone, Debug)]
pub struct ArmSimulator {
    params: ArmParams,
    settings: IntegratorSettings,
    torque_limit_nm: Option<Vec<f64>>,
    ws: ArmData,
    modes: Vec<Mode>,
    mass: Vec<f64>,
    bias: Vec<f64>,
    rhs: Vec<f64>,
    reduced: Vec<f64>,
    free: Vec<usize>,
    tau: Vec<f64>,
    q_stage: Vec<f64>,
    qd_stage: Vec<f64>,
    /// Stage derivatives: 4 × (q̇, q̈), each n long.
    kq: [Vec<f64>; 4],
    kv: [Vec<f64>; 4],
}

impl ArmSimulator {
    /// A simulator for `params`, checked first.
    pub fn new(params: ArmParams, settings: IntegratorSettings) -> Result<Self, ParamError> {
        params.validate()?;
        if !(settings.internal_step_s.is_finite() && settings.internal_step_s > 0.0) {
            return Err(ParamError::Invalid { name: "internal_step_s".into(), value: settings.internal_step_s, why: "must be > 0" });
        }
        let n = params.dof();
        let modes = params.friction.iter().map(|f| if f.is_discontinuous() { Mode::Sliding(1.0) } else { Mode::Continuous }).collect();
        let v = || vec![0.0; n];
        Ok(Self {
            settings,
            torque_limit_nm: None,
            ws: ArmData::new(&params),
            modes,
            mass: vec![0.0; n * n],
            bias: v(),
            rhs: v(),
            reduced: vec![0.0; n * n],
            free: Vec::with_capacity(n),
            tau: v(),
            q_stage: v(),
            qd_stage: v(),
            kq: [v(), v(), v(), v()],
            kv: [v(), v(), v(), v()],
            params,
        })
    }

    /// Limits the applied torque of joint i to ±`limits_nm[i]` [N·m] (actuator saturation);
    /// a limit of 0 leaves that joint unlimited, `None` removes all limits.
    pub fn set_torque_limits(&mut self, limits_nm: Option<Vec<f64>>) -> Result<(), ParamError> {
        if let Some(l) = &limits_nm {
            if l.len() != self.params.dof() {
                return Err(ParamError::Invalid {
                    name: "torque_limit_nm (length)".into(),
                    value: l.len() as f64,
                    why: "needs one limit per joint",
                });
            }
            for (i, &x) in l.iter().enumerate() {
                super::params::check(|| format!("torque_limit_nm[{i}]"), x, x >= 0.0, "must be >= 0 (0: no limit)")?;
            }
        }
        self.torque_limit_nm = limits_nm;
        Ok(())
    }

    /// Replaces the arm's parameters between steps (a drifting or loaded arm, see
    /// [`crate::arm::OperatingChange`]) by a copy of `params`, reusing the storage: no
    /// allocation. Refused, leaving the arm as it was, when `params` is invalid or has another
    /// joint count (the scratch space is sized by it).
    pub fn set_params(&mut self, params: &ArmParams) -> Result<(), ParamError> {
        params.validate()?;
        if params.dof() != self.dof() {
            return Err(ParamError::Invalid {
                name: "links (length)".into(),
                value: params.dof() as f64,
                why: "must keep the simulator's joint count",
            });
        }
        self.params.copy_from(params);
        for (mode, f) in self.modes.iter_mut().zip(&self.params.friction) {
            // A joint whose friction became continuous must not keep a sliding direction.
            if !f.is_discontinuous() {
                *mode = Mode::Continuous;
            }
        }
        Ok(())
    }

    /// The arm's parameters.
    pub fn params(&self) -> &ArmParams {
        &self.params
    }

    /// The integrator settings.
    pub fn settings(&self) -> IntegratorSettings {
        self.settings
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.params.dof()
    }

    /// The number of RK4 sub-steps a step of `dt` [s] takes, or why it cannot be taken: `dt`
    /// not finite and positive, or more sub-steps than [`max_substeps`] allows for this arm.
    pub fn check_step(&self, dt: f64) -> Result<usize, StepError> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(StepError::BadStep(dt));
        }
        let internal_step = self.settings.internal_step_s;
        let joints = self.dof();
        let max = max_substeps(joints);
        // Compared as a ratio first: a huge `dt` must not be turned into a count at all.
        let ratio = dt / internal_step;
        if !(ratio <= max as f64) {
            return Err(StepError::TooMuchWork { dt, substeps: ratio.ceil(), internal_step, joints, max });
        }
        Ok(substep_count(dt, internal_step))
    }

    /// Advances `state` by `dt` [s] under joint torques `tau` [N·m], held constant over the step.
    /// On error (see [`ArmSimulator::check_step`]) the state is untouched.
    pub fn step(&mut self, state: &mut ArmState, tau: &[f64], dt: f64) -> Result<(), StepError> {
        let n = self.dof();
        let substeps = self.check_step(dt)?;
        for (what, v) in [("tau", tau), ("q", &state.q[..]), ("qd", &state.qd[..])] {
            if v.len() != n {
                return Err(StepError::WrongLength { what, got: v.len(), expected: n });
            }
            if let Some((index, &value)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
                return Err(StepError::NotFinite { what, index, value });
            }
        }
        for i in 0..n {
            self.tau[i] = match &self.torque_limit_nm {
                Some(l) if l[i] > 0.0 => tau[i].clamp(-l[i], l[i]),
                Some(_) => tau[i],
                None => tau[i],
            };
        }
        let h = dt / substeps as f64;
        for _ in 0..substeps {
            self.substep(state, h);
        }
        Ok(())
    }

    /// Joint accelerations [rad/s²] at `state` under `tau` [N·m] (not saturated), with
    /// stick–slip decided as at the start of a sub-step (a joint at rest within its breakaway
    /// torque gets 0).
    ///
    /// # Panics
    /// If `tau`, `state.q` or `state.qd` does not have one entry per joint.
    pub fn forward_dynamics(&mut self, state: &ArmState, tau: &[f64]) -> Vec<f64> {
        self.tau.copy_from_slice(tau);
        self.q_stage.copy_from_slice(&state.q);
        self.qd_stage.copy_from_slice(&state.qd);
        self.choose_modes();
        self.kv[0].clone()
    }

    fn substep(&mut self, state: &mut ArmState, h: f64) {
        let n = self.dof();
        self.q_stage.copy_from_slice(&state.q);
        self.qd_stage.copy_from_slice(&state.qd);
        // Stage 1 comes out of the mode choice.
        self.choose_modes();
        for stage in 1..4 {
            let c = if stage == 3 { h } else { 0.5 * h };
            for i in 0..n {
                self.q_stage[i] = state.q[i] + c * self.kq[stage - 1][i];
                self.qd_stage[i] = state.qd[i] + c * self.kv[stage - 1][i];
            }
            self.evaluate(stage);
        }
        for i in 0..n {
            let dq = self.kq[0][i] + 2.0 * (self.kq[1][i] + self.kq[2][i]) + self.kq[3][i];
            let dv = self.kv[0][i] + 2.0 * (self.kv[1][i] + self.kv[2][i]) + self.kv[3][i];
            state.q[i] += h / 6.0 * dq;
            let qd_new = state.qd[i] + h / 6.0 * dv;
            state.qd[i] = match self.modes[i] {
                // Reversal inside the sub-step: the joint stopped; the next sub-step decides.
                Mode::Sliding(d) if d * qd_new < 0.0 => 0.0,
                _ => qd_new,
            };
        }
    }

    /// Sets each joint's mode for a sub-step starting at the stage state, and leaves that
    /// state's derivative in stage slot 0.
    fn choose_modes(&mut self) {
        let n = self.dof();
        for i in 0..n {
            if self.params.friction[i].is_discontinuous() {
                let v = self.qd_stage[i];
                self.modes[i] = if v == 0.0 { Mode::Stuck } else { Mode::Sliding(v.signum()) };
            }
        }
        loop {
            self.evaluate(0);
            // Friction each stuck joint needs to stay at rest: τ − b − (H q̈)ⱼ.
            let mut worst: Option<(usize, f64, f64)> = None;
            for j in 0..n {
                if self.modes[j] != Mode::Stuck {
                    continue;
                }
                let hq: f64 = (0..n).map(|k| self.mass[j * n + k] * self.kv[0][k]).sum();
                let holding = self.tau[j] - self.bias[j] - hq;
                let direction = if holding >= 0.0 { 1.0 } else { -1.0 };
                let excess = holding.abs() - self.params.friction[j].breakaway(direction);
                if excess > 0.0 && worst.is_none_or(|(_, e, _)| excess > e) {
                    worst = Some((j, excess, direction));
                }
            }
            match worst {
                Some((j, _, direction)) => self.modes[j] = Mode::Sliding(direction),
                None => break,
            }
        }
    }

    /// Evaluates (q̇, q̈) at the stage state into stage slot `k`.
    fn evaluate(&mut self, k: usize) {
        let n = self.dof();
        let p = &self.params;
        self.ws.set_angles(&self.q_stage);
        mass_matrix_at_angles(p, &mut self.ws, &mut self.mass);
        rnea_at_angles(p, &self.qd_stage, None, p.in_plane_gravity(), &mut self.ws, &mut self.bias);
        self.free.clear();
        for i in 0..n {
            let friction = match self.modes[i] {
                Mode::Continuous => p.friction[i].torque(self.qd_stage[i]),
                Mode::Sliding(d) => p.friction[i].torque_in_direction(d, self.qd_stage[i]),
                Mode::Stuck => continue,
            };
            self.rhs[self.free.len()] = self.tau[i] - self.bias[i] - friction;
            self.free.push(i);
        }
        let m = self.free.len();
        for (a, &i) in self.free.iter().enumerate() {
            for (b, &j) in self.free.iter().enumerate() {
                self.reduced[a * m + b] = self.mass[i * n + j];
            }
        }
        // H is positive definite for valid parameters, so is its principal submatrix.
        crate::linalg::cholesky_solve_in_place(&mut self.reduced[..m * m], m, &mut self.rhs[..m]);
        self.kv[k].fill(0.0);
        for (a, &i) in self.free.iter().enumerate() {
            self.kv[k][i] = self.rhs[a];
        }
        for i in 0..n {
            self.kq[k][i] = if self.modes[i] == Mode::Stuck { 0.0 } else { self.qd_stage[i] };
        }
    }
}

/// The work one step of [`ArmSimulator::step`] may do, in RK4 sub-steps times joints squared
/// (a sub-step costs about n² for the mass matrix and the recursions, n³/6 for its
/// factorisation): a 4-joint arm may take a step thousands of times a co-simulation's usual one.
/// The longest step allowed returns within a fraction of a second, so a host stays responsive,
/// and an absurd step (1e300 s) is an error at once, not a call that never returns
/// (docs/decisions/0009-step-work-limit.md).
pub const MAX_STEP_WORK: usize = 400_000;

/// The most RK4 sub-steps one step of an arm of `joints` joints may take ([`MAX_STEP_WORK`]).
pub fn max_substeps(joints: usize) -> usize {
    (MAX_STEP_WORK / joints.max(1).saturating_mul(joints.max(1))).max(1)
}

/// Number of equal sub-steps no longer than `max_step` that make up `dt`. A ratio within
/// rounding of a whole number counts as that number (1 ms / 0.25 ms is 4, not 5).
pub fn substep_count(dt: f64, max_step: f64) -> usize {
    let ratio = dt / max_step;
    let nearest = ratio.round();
    let count = if (ratio - nearest).abs() <= 1e-9 * nearest.max(1.0) { nearest } else { ratio.ceil() };
    count.max(1.0) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn substep_count_rounds_whole_ratios() {
        assert_eq!(substep_count(1e-3, 2.5e-4), 4);
        assert_eq!(substep_count(1e-3, 1e-3), 1);
        assert_eq!(substep_count(1.1e-3, 1e-3), 2);
        assert_eq!(substep_count(1e-5, 1e-3), 1);
    }
}
