//! `neurarm simulate`: the arm under a torque table or playing a plan, or a system file's
//! co-simulation of FMUs through the master; writes the trajectory or the recording.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;
use neurarm::output::describe;
use neurarm::simulate::{simulate, TorqueInput};
use neurarm::table::write_atomic;
use neurarm_physics::arm::ArmState;

use super::common::{ArmSource, Interrupted};

/// The arguments of `neurarm simulate`. Its help text is the doc of `Command::Simulate` in
/// main.rs, which clap shows instead of this one.
#[derive(Args)]
pub struct SimulateArgs {
    /// A system file (TOML: [[fmu]], [[connection]], [simulation]) to run instead of the arm.
    system: Option<PathBuf>,
    /// Torque input CSV.
    #[arg(long, short = 't', conflicts_with_all = ["system", "plan"], required_unless_present_any = ["system", "plan"])]
    torque: Option<PathBuf>,
    /// A plan of `neurarm plan` to play instead, as a robot whose own controller holds and
    /// tracks the joints (computed torque from the configured arm on the measured angles).
    #[arg(long, conflicts_with = "system")]
    plan: Option<PathBuf>,
    /// With --plan: the controller's step [s].
    #[arg(long, default_value_t = 0.001, requires = "plan")]
    step: f64,
    /// With --plan: write every K-th step only.
    #[arg(long, default_value_t = 1, requires = "plan", value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
    every: u64,
    /// With --plan: write what a robot logs, time and the measured q_i, qd_i with tau_i, each
    /// rounded to 1e-6 (rad, rad/s, N·m).
    #[arg(long, requires = "plan")]
    robot_log: bool,
    /// The arm's base angle [rad] instead of the configuration's (π/2: gravity in the plane).
    #[arg(long, allow_hyphen_values = true)]
    base_angle: Option<f64>,
    #[command(flatten)]
    arm: ArmSource,
    /// Output trajectory CSV (`-`: standard output); written only if the whole simulation
    /// succeeds. For a system file, the recording, written also when a unit fails, discards
    /// a step or Ctrl-C ends the run (then with the rows so far).
    #[arg(long, short = 'o')]
    output: PathBuf,
    /// For a system file: what a unit that discards a step (fmi2Discard) does, `stop` (end
    /// the run there with a notice, exit 0) or `error` (fail); overrides the file's
    /// `[simulation] on_discard` (default stop).
    #[arg(long, value_parser = parse_on_discard, requires = "system")]
    on_discard: Option<neurarm_cosim::OnDiscard>,
}

/// Runs `neurarm simulate`.
pub fn run(args: SimulateArgs) -> Result<()> {
    match args {
        SimulateArgs { system: Some(system), output, on_discard, .. } => {
            use neurarm::system_run::{run_system_file, SystemRunEnd};
            let run = run_system_file(&system, &output, on_discard)?;
            for notice in &run.notices {
                eprintln!("notice: {notice}");
            }
            let last = run.last_time.map_or(String::new(), |t| format!(", the last at t = {t} s"));
            match run.end {
                SystemRunEnd::Completed | SystemRunEnd::Discarded => eprintln!("wrote {} rows to {}{last}", run.rows, describe(&output)),
                SystemRunEnd::Interrupted(t) => {
                    return Err(
                        Interrupted(format!("interrupted at t = {t} s; the {} rows so far are in {}", run.rows, describe(&output))).into()
                    )
                }
                SystemRunEnd::Failed(failure) => return Err(FailedRun { failure, rows: run.rows, output: describe(&output) }.into()),
            }
        }
        SimulateArgs { plan: Some(plan), arm, output, step, every, base_angle, robot_log, .. } => {
            let (mut config, initial) = arm.load()?;
            if let Some(angle) = base_angle {
                config.arm = config.arm.with_base_angle(angle);
            }
            if !(step > 0.0 && step.is_finite()) {
                bail!("--step must be a positive number of seconds (got {step})");
            }
            let plan = neurarm::simulate::Plan::read_csv(&plan, config.arm.dof())?;
            let initial = ArmState { q: plan.start(&initial.q), qd: initial.qd };
            let mut trajectory = neurarm::simulate::simulate_plan(&config, &initial, &plan, step, every as usize)?;
            if robot_log {
                trajectory = trajectory.as_robot_log();
            }
            let rows = trajectory.rows.len();
            write_atomic(&output, &trajectory.names, trajectory.rows.into_iter())
                .with_context(|| format!("writing {}", describe(&output)))?;
            eprintln!("wrote {rows} rows to {}", describe(&output));
        }
        SimulateArgs { torque, arm, output, base_angle, .. } => {
            let torque = torque.expect("clap requires --torque without a system file");
            let (mut config, initial) = arm.load()?;
            if let Some(angle) = base_angle {
                config.arm = config.arm.with_base_angle(angle);
            }
            let input = TorqueInput::read_csv(&torque, config.arm.dof())?;
            let trajectory = simulate(&config, &initial, &input)?;
            write_atomic(&output, &trajectory.names, trajectory.rows.into_iter())
                .with_context(|| format!("writing {}", describe(&output)))?;
            eprintln!("wrote {} rows to {}", input.time.len(), describe(&output));
        }
    }
    Ok(())
}

/// A unit failed mid-run: the master's error, and where the rows recorded before it went. The
/// message holds the master's, so it is kept here rather than as the source (which would print
/// it twice).
#[derive(Debug, thiserror::Error)]
#[error("{failure}\n(the {rows} rows recorded before the failure are in {output})")]
struct FailedRun {
    failure: neurarm_cosim::MasterError,
    rows: usize,
    output: String,
}

/// Parses a discard policy for clap.
fn parse_on_discard(text: &str) -> Result<neurarm_cosim::OnDiscard> {
    match text {
        "stop" => Ok(neurarm_cosim::OnDiscard::Stop),
        "error" => Ok(neurarm_cosim::OnDiscard::Error),
        _ => bail!("'{text}': use stop or error"),
    }
}
