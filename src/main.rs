//! The `neurarm` command line: a thin shell over the library.

#![forbid(unsafe_code)]

mod cli;

use std::process::ExitCode;

use anyhow::Result;
use clap::{Parser, Subcommand};
use cli::common::Interrupted;
use cli::{compensator, default_config, eval, export, identify, paper, plan, random_arm, simulate, train};

#[derive(Parser)]
#[command(
    name = "neurarm",
    version,
    about = "Learn robot-joint dynamics with neural networks and ship them as FMI 2.0 components",
    after_help = "Outputs (-o): a file is written whole to a temporary file beside it and renamed over it, so it \
                  appears complete or not at all; through a symbolic link the link's target is replaced and the link stays. \
                  `-` is standard output (text and CSV; refused for an .fmu). A device or FIFO (/dev/null, /dev/stdout, a \
                  named pipe) is written directly. Side files (a plan's .txt, identify's .json) are written only beside a file."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate the arm from an initial state under a torque table and write its trajectory.
    ///
    /// Torque CSV: `time` [s, strictly increasing] and `tau_1` … `tau_n` [N·m], each row held
    /// until the next. Output per input time: time, q_i [rad], qd_i [rad/s], x, y [m], xd, yd
    /// [m/s], tau_i, and q_meas_i, qd_meas_i with hardware-like effects. Given a system file
    /// instead (`neurarm simulate system.toml -o out.csv`), runs that co-simulation of FMUs and
    /// writes the recorded variables (the rows so far, and the error, if a unit fails mid-run).
    Simulate(simulate::SimulateArgs),
    /// Run the paper's experiments end to end through the master and the FMUs, for the built-in
    /// arm or your own of 2 to 8 joints: friction and gravity identification, training, Table 1,
    /// gravity compensation. Writes the FMUs, data, nets, plots, report.md and results.json
    /// (every figure, for scripts) to the output folder, which appears only when the run has
    /// finished.
    Paper(paper::PaperArgs),
    /// Print the default arm configuration as TOML, a starting point for your own arm.
    DefaultConfig(default_config::DefaultConfigArgs),
    /// Write the arm of the seeded random family (the arms the family test and
    /// `scripts/bench-family` run): link lengths 0.1–1 m, masses, centres of mass and inertias
    /// varied, a tilted or flat base, friction mixing Coulomb, viscous, Stribeck, asymmetric and
    /// falling viscous laws. The same seed and joint count always give the same arm.
    RandomArm(random_arm::RandomArmArgs),
    /// Write the paper's experiments as plans a robot's own controller can play (CSV with units in
    /// the header, and a .txt beside it that says how to run them).
    #[command(subcommand)]
    Plan(plan::PlanCommand),
    /// Make training pairs from a robot's logs (CSV: time and per joint q_i, qd_i, tau_i).
    #[command(subcommand)]
    Identify(identify::IdentifyCommand),
    /// The whole path from logs to an FMU: identify friction (and gravity), train the nets, export
    /// the NnCompensator; every intermediate file is kept in a folder.
    Compensator(compensator::CompensatorArgs),
    /// Build an FMI 2.0 (or, with --fmi 3, FMI 3.0) Co-Simulation FMU.
    Export(export::ExportArgs),
    /// Train a two-layer network (tansig hidden layer, linear output) with Levenberg–Marquardt.
    ///
    /// The data CSV has a header; each row is one sample. Defaults follow MATLAB's trainlm
    /// (μ 0.001, ×0.1 / ×10, 1000 epochs, 6 validation failures, 70/15/15 random split).
    Train(train::TrainArgs),
    /// Apply a trained network to the input columns of a CSV; writes inputs and outputs.
    Eval(eval::EvalArgs),
}

/// Runs the command given.
fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Simulate(args) => simulate::run(args),
        Command::Paper(args) => paper::run(args),
        Command::DefaultConfig(args) => default_config::run(args),
        Command::RandomArm(args) => random_arm::run(args),
        Command::Plan(command) => plan::run(command),
        Command::Identify(command) => identify::run(command),
        Command::Compensator(args) => compensator::run(args),
        Command::Export(command) => export::run(command),
        Command::Train(args) => train::run(args),
        Command::Eval(args) => eval::run(args),
    }
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is::<Interrupted>() => {
            eprintln!("{e}");
            ExitCode::from(130)
        }
        // A reader that stopped early (`-o - | head`) is not a failure of ours: end quietly, as
        // a program that SIGPIPE ends would, without an error message.
        Err(e) if e.chain().any(|c| c.downcast_ref::<std::io::Error>().is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)) => {
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
