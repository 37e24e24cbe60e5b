//! Open-loop simulation of an arm under a torque table: what `neurarm simulate` runs.
//!
//! The input CSV has a `time` column [s], strictly increasing, and one column per joint,
//! `tau_1` … `tau_n` [N·m]. The torque of a row is held until the next row's time (zero-order
//! hold). The output has one row per input time with the state at that time (the first row
//! is the initial state), the end-effector position and velocity, and the torque command of
//! that row; measured angles and velocities are added when the configuration distorts them.

use std::path::Path;

use crate::table::{NumericTable, TableError};
use neurarm_physics::arm::{end_effector_state, ArmState, StepError};
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

/// Simulates the configured arm from `initial` under `input`.
pub fn simulate(config: &ArmConfig, initial: &ArmState, input: &TorqueInput) -> Result<Trajectory, SimulateError> {
    let n = config.arm.dof();
    let (mut sim, mut sensors) = config.build().map_err(SimulateError::Config)?;
    let measured = config.hardware.distorts_measurements();
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
    let mut state = initial.clone();
    let mut tau = vec![0.0; n];
    let (mut q_meas, mut qd_meas) = (vec![0.0; n], vec![0.0; n]);
    let mut rows = Vec::with_capacity(input.time.len());
    for (r, &t) in input.time.iter().enumerate() {
        for (i, column) in input.torque.iter().enumerate() {
            tau[i] = column[r];
        }
        let mut row = Vec::with_capacity(names.len());
        row.push(t);
        row.extend(&state.q);
        row.extend(&state.qd);
        row.extend(end_effector_state(&config.arm, &state.q, &state.qd));
        row.extend(&tau);
        if measured {
            sensors.measure(&state, &mut q_meas, &mut qd_meas);
            row.extend(&q_meas);
            row.extend(&qd_meas);
        }
        rows.push(row);
        if let Some(&next) = input.time.get(r + 1) {
            sim.step(&mut state, &tau, next - t).map_err(|source| SimulateError::Step { time: t, source })?;
        }
    }
    Ok(Trajectory { names, rows })
}

/// Why a simulation stopped.
#[derive(Debug, thiserror::Error)]
pub enum SimulateError {
    /// The configuration is invalid.
    #[error("invalid configuration: {0}")]
    Config(neurarm_physics::arm::ParamError),
    /// A step was refused.
    #[error("at t = {time} s: {source}")]
    Step {
        /// Start of the refused step [s].
        time: f64,
        /// Why.
        source: StepError,
    },
}
