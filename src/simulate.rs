//! Open-loop simulation of an arm under a torque table: what `neurarm simulate` runs.
//!
//! The input CSV has a `time` column [s], strictly increasing, and one column per joint,
//! `tau_1` … `tau_n` [N·m]. The torque of a row is held until the next row's time (zero-order
//! hold). The output has one row per input time with the state at that time (the first row
//! is the initial state), the end-effector position and velocity, and the torque command of
//! that row; measured angles and velocities are added when the configuration distorts them.

use std::f64::consts::PI;
use std::path::Path;

use crate::table::{NumericTable, TableError};
use neurarm_physics::arm::{end_effector_state, inverse_dynamics_rnea_into, ArmData, ArmParams, ArmState, StepError};
use neurarm_physics::config::ArmConfig;

/// Name of joint `i`'s (0-based) column with prefix `prefix`, e.g. `tau_1`.
pub fn joint_column(prefix: &str, i: usize) -> String {
    format!("{prefix}_{}", i + 1)
}

/// A torque input: times [s] and the torque of each joint [N·m] at each time.
#[derive(Clone, Debug, PartialEq)]
pub struct TorqueInput {
    /// Times, strictly increasing [s].
    pub time: Vec<f64>,
    /// `torque[i]` is joint i's torque column [N·m].
    pub torque: Vec<Vec<f64>>,
}

impl TorqueInput {
    /// Reads a torque table for an arm of `dof` joints.
    pub fn read_csv(path: &Path, dof: usize) -> Result<Self, TableError> {
        let names: Vec<String> = (0..dof).map(|i| joint_column("tau", i)).collect();
        let mut required = vec!["time"];
        required.extend(names.iter().map(String::as_str));
        let table = NumericTable::read(path, &required)?;
        table.require_increasing("time")?;
        Ok(Self {
            time: table.column("time").expect("required").to_vec(),
            torque: names.iter().map(|n| table.column(n).expect("required").to_vec()).collect(),
        })
    }
}

/// A simulated trajectory as named columns and rows.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// Column names.
    pub names: Vec<String>,
    /// Rows, each as long as `names`.
    pub rows: Vec<Vec<f64>>,
}

impl Trajectory {
    /// What a robot logs of this trajectory: `time`, and per joint the measured angle and speed
    /// (`q_meas_i`, `qd_meas_i` when present, else the true ones) as `q_i`, `qd_i`, and `tau_i`;
    /// time rounded to 1 ns, the rest to 1e-6 (a log's resolution, far below the sensors' noise).
    pub fn as_robot_log(&self) -> Trajectory {
        let n = self.names.iter().filter(|c| c.starts_with("tau_")).count();
        let find = |name: &str| self.names.iter().position(|c| c == name);
        let mut names = vec!["time".to_owned()];
        let mut source = vec![find("time").expect("a trajectory has time")];
        for prefix in ["q", "qd", "tau"] {
            for i in 0..n {
                let plain = joint_column(prefix, i);
                source.push(find(&format!("{prefix}_meas_{}", i + 1)).or_else(|| find(&plain)).expect("a trajectory has every joint"));
                names.push(plain);
            }
        }
        // Dividing by the power of ten gives the double nearest the decimal, which prints short.
        let round = |v: f64, scale: f64| (v * scale).round() / scale;
        let rows = self
            .rows
            .iter()
            .map(|row| source.iter().enumerate().map(|(k, &c)| round(row[c], if k == 0 { 1e9 } else { 1e6 })).collect())
            .collect();
        Trajectory { names, rows }
    }
}

/// Simulates the configured arm from `initial` under `input`.
pub fn simulate(config: &ArmConfig, initial: &ArmState, input: &TorqueInput) -> Result<Trajectory, SimulateError> {
    let n = config.arm.dof();
    let (mut sim, mut sensors) = config.build().map_err(SimulateError::Config)?;
    let measured = config.hardware.distorts_measurements();
    let names = trajectory_names(n, measured);
    let mut state = initial.clone();
    let mut tau = vec![0.0; n];
    let (mut q_meas, mut qd_meas) = (vec![0.0; n], vec![0.0; n]);
    let mut rows = Vec::with_capacity(input.time.len());
    for (r, &t) in input.time.iter().enumerate() {
        for (i, column) in input.torque.iter().enumerate() {
            tau[i] = column[r];
        }
        if measured {
            sensors.measure(&state, &mut q_meas, &mut qd_meas);
        }
        rows.push(trajectory_row(config, t, &state, &tau, measured.then_some((&q_meas[..], &qd_meas[..]))));
        if let Some(&next) = input.time.get(r + 1) {
            sim.step(&mut state, &tau, next - t).map_err(|cause| SimulateError::Step { time: t, cause })?;
            check_finite(&state, t, next, &tau, sim.settings().internal_step_s)?;
        }
    }
    Ok(Trajectory { names, rows })
}

/// The columns of a trajectory of `n` joints: time, q_i, qd_i, x, y, xd, yd, tau_i, and, when
/// `measured`, q_meas_i and qd_meas_i.
fn trajectory_names(n: usize, measured: bool) -> Vec<String> {
    let mut names = vec!["time".to_owned()];
    for prefix in ["q", "qd"] {
        names.extend((0..n).map(|i| joint_column(prefix, i)));
    }
    names.extend(["x", "y", "xd", "yd"].map(String::from));
    names.extend((0..n).map(|i| joint_column("tau", i)));
    if measured {
        for prefix in ["q_meas", "qd_meas"] {
            names.extend((0..n).map(|i| joint_column(prefix, i)));
        }
    }
    names
}

/// One row of a trajectory (see [`trajectory_names`]) at time `t` [s]: `state`, the end
/// effector's position and velocity, the torques `tau` [N·m] and the `measured` angles and
/// speeds.
fn trajectory_row(config: &ArmConfig, t: f64, state: &ArmState, tau: &[f64], measured: Option<(&[f64], &[f64])>) -> Vec<f64> {
    let n = tau.len();
    let mut row = Vec::with_capacity(1 + 5 * n + 4);
    row.push(t);
    row.extend(&state.q);
    row.extend(&state.qd);
    row.extend(end_effector_state(&config.arm, &state.q, &state.qd));
    row.extend(tau);
    if let Some((q_meas, qd_meas)) = measured {
        row.extend(q_meas);
        row.extend(qd_meas);
    }
    row
}

/// Why a simulation stopped.
#[derive(Debug, thiserror::Error)]
pub enum SimulateError {
    /// The configuration is invalid.
    #[error("invalid configuration: {0}")]
    Config(neurarm_physics::arm::ParamError),
    /// The state stopped being finite (NaN or infinite) in a step.
    #[error(
        "joint {joint}'s {quantity} became {value} in the step from t = {from} s to {to} s, under the torques [{}] N·m \
         integrated in {substeps} RK4 sub-steps of {} s: the motion is too fast for the sub-step; lower the torques \
         or integrator.internal_step_s (now {internal_step_s} s)",
        list(.torque),
        (.to - .from) / *.substeps as f64
    )]
    Diverged {
        /// Start of the step [s].
        from: f64,
        /// End of the step [s].
        to: f64,
        /// Joint (1-based).
        joint: usize,
        /// Which part of the state: "angle" or "velocity".
        quantity: &'static str,
        /// Its value (NaN or ±inf).
        value: f64,
        /// The torque command held over the step [N·m], one per joint.
        torque: Vec<f64>,
        /// The integrator's longest sub-step [s].
        internal_step_s: f64,
        /// Sub-steps the step was split into.
        substeps: usize,
    },
    /// A step was refused.
    #[error("at t = {time} s: {cause}")]
    Step {
        /// Start of the refused step [s].
        time: f64,
        /// Why.
        cause: StepError,
    },
}

/// Numbers as a comma-separated list, for messages.
fn list(values: &[f64]) -> String {
    values.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(", ")
}

/// Fails with [`SimulateError::Diverged`], naming the first joint whose angle or velocity is no
/// longer finite after the step from `from` to `to` [s] under `torque` [N·m].
fn check_finite(state: &ArmState, from: f64, to: f64, torque: &[f64], internal_step_s: f64) -> Result<(), SimulateError> {
    let bad = state.q.iter().zip(&state.qd).enumerate().find_map(|(i, (&q, &qd))| {
        if !q.is_finite() {
            Some((i, "angle", q))
        } else if !qd.is_finite() {
            Some((i, "velocity", qd))
        } else {
            None
        }
    });
    match bad {
        None => Ok(()),
        Some((i, quantity, value)) => Err(SimulateError::Diverged {
            from,
            to,
            joint: i + 1,
            quantity,
            value,
            torque: torque.to_vec(),
            internal_step_s,
            substeps: neurarm_physics::arm::integrator::substep_count(to - from, internal_step_s),
        }),
    }
}

/// A plan of `neurarm plan` (see [`crate::plan`]) read back for playing.
#[derive(Clone, Debug, PartialEq)]
pub enum Plan {
    /// Constant torques on one joint, the others held.
    Friction {
        /// Segment start times [s]; the last row marks the end.
        time: Vec<f64>,
        /// `torque[i][r]`: joint i's torque from row r [N·m].
        torque: Vec<Vec<f64>>,
        /// `hold[i][r]`: whether joint i is held from row r.
        hold: Vec<Vec<bool>>,
    },
    /// Moves and constant-speed passes of every joint.
    Gravity {
        /// Segment start times [s]; the last row holds the final angles.
        time: Vec<f64>,
        /// Pass of each row: 0 a move, ±1 a pass.
        pass: Vec<i8>,
        /// `q[i][r]`: joint i's angle at the start of row r [rad].
        q: Vec<Vec<f64>>,
        /// `qd[i][r]`: joint i's speed in row r [rad/s].
        qd: Vec<Vec<f64>>,
    },
}

impl Plan {
    /// Reads a friction plan (it has `hold_i` columns) or a gravity plan (a `pass` column) for
    /// an arm of `dof` joints.
    pub fn read_csv(path: &Path, dof: usize) -> Result<Self, TableError> {
        let probe = NumericTable::read(path, &["time"])?;
        let col = |t: &NumericTable, n: &str| t.column(n).expect("required").to_vec();
        if probe.column("hold_1").is_some() {
            let names: Vec<[String; 2]> = (0..dof).map(|i| [joint_column("tau", i), joint_column("hold", i)]).collect();
            let mut required = vec!["time"];
            required.extend(names.iter().flat_map(|n| n.iter().map(String::as_str)));
            let table = NumericTable::read(path, &required)?;
            table.require_increasing("time")?;
            Ok(Plan::Friction {
                time: col(&table, "time"),
                torque: names.iter().map(|n| col(&table, &n[0])).collect(),
                hold: names.iter().map(|n| col(&table, &n[1]).iter().map(|&h| h != 0.0).collect()).collect(),
            })
        } else if probe.column("pass").is_some() {
            let names: Vec<[String; 2]> = (0..dof).map(|i| [joint_column("q", i), joint_column("qd", i)]).collect();
            let mut required = vec!["time", "pass"];
            required.extend(names.iter().flat_map(|n| n.iter().map(String::as_str)));
            let table = NumericTable::read(path, &required)?;
            table.require_increasing("time")?;
            let pass: Vec<f64> = col(&table, "pass");
            if let Some(r) = pass.iter().position(|p| ![-1.0, 0.0, 1.0].contains(p)) {
                return Err(TableError {
                    path: path.to_path_buf(),
                    line: Some(table.lines[r]),
                    column: None,
                    message: format!("pass must be -1, 0 or 1, not {}", pass[r]),
                });
            }
            Ok(Plan::Gravity {
                time: col(&table, "time"),
                pass: pass.iter().map(|&p| p as i8).collect(),
                q: names.iter().map(|n| col(&table, &n[0])).collect(),
                qd: names.iter().map(|n| col(&table, &n[1])).collect(),
            })
        } else {
            Err(TableError {
                path: path.to_path_buf(),
                line: Some(1),
                column: None,
                message: "not a plan of `neurarm plan`: it has neither hold_i columns (friction) nor a pass column (gravity)".into(),
            })
        }
    }

    /// Start and end of the plan [s].
    pub fn span(&self) -> (f64, f64) {
        let t = match self {
            Plan::Friction { time, .. } | Plan::Gravity { time, .. } => time,
        };
        (t[0], t[t.len() - 1])
    }

    /// The plan's start angles: a gravity plan's first row, or `fallback`.
    pub fn start(&self, fallback: &[f64]) -> Vec<f64> {
        match self {
            Plan::Gravity { q, .. } => q.iter().map(|c| c[0]).collect(),
            Plan::Friction { .. } => fallback.to_vec(),
        }
    }
}

/// Bandwidth of the emulated controller's holds in a friction plan [rad/s] (computed torque,
/// critically damped): soft, so sensor noise does not shake the held joints.
pub const PLAN_HOLD_RAD_S: f64 = 20.0;
/// Bandwidth of the emulated controller's tracking in a gravity plan [rad/s].
pub const PLAN_TRACK_RAD_S: f64 = 20.0;

/// Plays `plan` on the configured arm from `initial`, as a robot whose own controller runs at
/// `step` [s] on the measured angles and speeds: held and tracked joints get computed torque
/// from the configured arm's rigid-body model (gravity included, friction not), a driven joint
/// its planned torque. Writes every `every`-th step, as [`simulate`] writes its rows.
pub fn simulate_plan(config: &ArmConfig, initial: &ArmState, plan: &Plan, step: f64, every: usize) -> Result<Trajectory, SimulateError> {
    let n = config.arm.dof();
    let (mut sim, mut sensors) = config.build().map_err(SimulateError::Config)?;
    let mut player = PlanPlayer::new(config, plan, step);
    let measured = config.hardware.distorts_measurements();
    let names = trajectory_names(n, measured);
    let (start, end) = plan.span();
    let steps = ((end - start) / step).round() as usize;
    let mut state = initial.clone();
    let (mut q_meas, mut qd_meas) = (vec![0.0; n], vec![0.0; n]);
    let mut rows = Vec::with_capacity(steps / every.max(1) + 1);
    for k in 0..=steps {
        let t = start + k as f64 * step;
        sensors.measure(&state, &mut q_meas, &mut qd_meas);
        let tau = player.torque(t, &q_meas, &qd_meas);
        if k % every.max(1) == 0 {
            rows.push(trajectory_row(config, t, &state, tau, measured.then_some((&q_meas[..], &qd_meas[..]))));
        }
        if k < steps {
            sim.step(&mut state, tau, step).map_err(|cause| SimulateError::Step { time: t, cause })?;
            check_finite(&state, t, t + step, tau, sim.settings().internal_step_s)?;
        }
    }
    Ok(Trajectory { names, rows })
}

/// The emulated controller of [`simulate_plan`]: the plan's current row, and computed torque
/// from the arm's rigid-body model (friction left out).
struct PlanPlayer<'a> {
    plan: &'a Plan,
    model: ArmParams,
    data: ArmData,
    /// The controller's step [s].
    step: f64,
    /// The plan's row in force.
    row: usize,
    /// Where each held joint is held [rad], from the start of its hold.
    hold_at: Vec<Option<f64>>,
    /// Commanded accelerations [rad/s²], speeds the model sees [rad/s] and torques [N·m].
    u: Vec<f64>,
    qd_use: Vec<f64>,
    tau: Vec<f64>,
}

impl<'a> PlanPlayer<'a> {
    fn new(config: &ArmConfig, plan: &'a Plan, step: f64) -> Self {
        let n = config.arm.dof();
        let model = config.arm.clone().frictionless();
        let data = ArmData::new(&model);
        Self { plan, model, data, step, row: 0, hold_at: vec![None; n], u: vec![0.0; n], qd_use: vec![0.0; n], tau: vec![0.0; n] }
    }

    /// The torques [N·m] at time `t` [s] from the measured angles [rad] and speeds [rad/s].
    fn torque(&mut self, t: f64, q_meas: &[f64], qd_meas: &[f64]) -> &[f64] {
        let times = match self.plan {
            Plan::Friction { time, .. } | Plan::Gravity { time, .. } => time,
        };
        while self.row + 1 < times.len() && times[self.row + 1] <= t + 1e-9 {
            self.row += 1;
        }
        match self.plan {
            Plan::Friction { torque, hold, .. } => self.hold_or_drive(torque, hold, q_meas, qd_meas),
            Plan::Gravity { time, pass, q, qd } => {
                let w = PLAN_TRACK_RAD_S;
                for i in 0..self.tau.len() {
                    let (reference, rate, accel) = gravity_reference(time, pass, &q[i], &qd[i], self.row, t, self.step);
                    self.u[i] = accel + 2.0 * w * (rate - qd_meas[i]) + w * w * (reference - q_meas[i]);
                }
                inverse_dynamics_rnea_into(&self.model, &mut self.data, q_meas, qd_meas, &self.u, &mut self.tau);
            }
        }
        &self.tau
    }

    /// A friction plan's row: each held joint held where its hold began, each driven joint
    /// given its planned torque.
    fn hold_or_drive(&mut self, torque: &[Vec<f64>], hold: &[Vec<bool>], q_meas: &[f64], qd_meas: &[f64]) {
        let (r, w) = (self.row, PLAN_HOLD_RAD_S);
        for i in 0..self.tau.len() {
            if hold[i][r] {
                let target = *self.hold_at[i].get_or_insert(q_meas[i]);
                self.u[i] = w * w * (target - q_meas[i]) - 2.0 * w * qd_meas[i];
            } else {
                self.hold_at[i] = None;
                self.u[i] = 0.0;
            }
            self.qd_use[i] = qd_meas[i];
        }
        inverse_dynamics_rnea_into(&self.model, &mut self.data, q_meas, &self.qd_use, &self.u, &mut self.tau);
        for i in 0..self.tau.len() {
            if !hold[i][r] {
                self.tau[i] = torque[i][r];
            }
        }
    }
}

/// A gravity plan's reference for one joint (its angles `q` [rad] and speeds `qd` [rad/s] by
/// row) in row `r` at time `t` [s]: angle [rad], speed [rad/s] and acceleration [rad/s²] of
/// the pass at constant speed, or of the rest-to-rest cosine move to the next row's angle
/// (lasting at least the controller's `step` [s]).
fn gravity_reference(time: &[f64], pass: &[i8], q: &[f64], qd: &[f64], r: usize, t: f64, step: f64) -> (f64, f64, f64) {
    let (t0, t1) = (time[r], time.get(r + 1).copied().unwrap_or(time[r]));
    if pass[r] != 0 || r + 1 == time.len() {
        let moving = if r + 1 == time.len() { 0.0 } else { qd[r] };
        (q[r] + moving * (t - t0), moving, 0.0)
    } else {
        let (a, b, d) = (q[r], q[r + 1], (t1 - t0).max(step));
        let s = ((t - t0) / d).clamp(0.0, 1.0);
        (
            a + (b - a) * (0.5 - 0.5 * (PI * s).cos()),
            (b - a) * 0.5 * PI * (PI * s).sin() / d,
            (b - a) * 0.5 * PI * PI * (PI * s).cos() / (d * d),
        )
    }
}
