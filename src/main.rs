//! The `neurarm` command line: a thin shell over the library.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use neurarm::arm::ArmState;
use neurarm::config::ArmConfig;
use neurarm::models::{export_fmu, FmuSpec, ModelSpec};
use neurarm::simulate::{simulate, TorqueInput};
use neurarm::table::write_atomic;

#[derive(Parser)]
#[command(name = "neurarm", version, about = "Learn robot-joint dynamics with neural networks and ship them as FMI 2.0 components")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate the arm from an initial state under a torque table and write its trajectory.
    ///
    /// The torque CSV has a header with `time` [s, strictly increasing] and `tau_1` … `tau_n`
    /// [N·m]; each row's torque is held until the next row. The output has one row per input
    /// time: time, q_i [rad], qd_i [rad/s], x, y [m], xd, yd [m/s], tau_i, and q_meas_i,
    /// qd_meas_i when the configuration adds hardware-like effects.
    Simulate {
        /// Torque input CSV.
        #[arg(long, short = 't')]
        torque: PathBuf,
        #[command(flatten)]
        arm: ArmSource,
        /// Output trajectory CSV; written only if the whole simulation succeeds.
        #[arg(long, short = 'o')]
        output: PathBuf,
    },
    /// Print the default arm configuration as TOML, a starting point for your own arm.
    DefaultConfig,
    /// Build an FMI 2.0 Co-Simulation FMU.
    #[command(subcommand)]
    Export(Export),
}

#[derive(Subcommand)]
enum Export {
    /// The arm as an FMU (`PlanarArm`): torque inputs; angle, velocity and end-effector outputs;
    /// every parameter of the configuration as an FMU parameter.
    Arm {
        /// The arm; its initial state becomes the FMU parameters q0_i, qd0_i.
        #[command(flatten)]
        arm: ArmSource,
        /// Model identifier (default: the output file's name, e.g. MyArm for MyArm.fmu).
        #[arg(long)]
        name: Option<String>,
        /// Output .fmu file.
        #[arg(long, short = 'o')]
        output: PathBuf,
    },
}

/// Which arm, and from which state: shared by the commands that simulate or export one.
#[derive(Args)]
struct ArmSource {
    /// Arm configuration (TOML); the default 4-link arm if omitted.
    #[arg(long, short = 'c')]
    config: Option<PathBuf>,
    /// Initial joint angles [rad], comma-separated (default: all 0).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    q0: Option<Vec<f64>>,
    /// Initial joint velocities [rad/s], comma-separated (default: all 0).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    qd0: Option<Vec<f64>>,
}

impl ArmSource {
    fn load(self) -> Result<(ArmConfig, ArmState)> {
        let config = match self.config {
            Some(path) => ArmConfig::from_toml_file(&path)?,
            None => ArmConfig::default(),
        };
        let n = config.arm.dof();
        let initial = ArmState { q: initial_vector("q0", self.q0, n)?, qd: initial_vector("qd0", self.qd0, n)? };
        Ok((config, initial))
    }
}

fn initial_vector(name: &str, given: Option<Vec<f64>>, n: usize) -> Result<Vec<f64>> {
    let v = given.unwrap_or_else(|| vec![0.0; n]);
    if v.len() != n {
        bail!("--{name} has {} values, the arm has {n} joints", v.len());
    }
    if let Some((i, x)) = v.iter().enumerate().find(|(_, x)| !x.is_finite()) {
        bail!("--{name}: value {} ({x}) is not a finite number", i + 1);
    }
    Ok(v)
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Simulate { torque, arm, output } => {
            let (config, initial) = arm.load()?;
            let input = TorqueInput::read_csv(&torque, config.arm.dof())?;
            let trajectory = simulate(&config, &initial, &input)?;
            write_atomic(&output, &trajectory.names, trajectory.rows.into_iter())
                .with_context(|| format!("writing {}", output.display()))?;
            eprintln!("wrote {} rows to {}", input.time.len(), output.display());
        }
        Command::DefaultConfig => print!("{}", ArmConfig::default().to_toml_string()),
        Command::Export(Export::Arm { arm, name, output }) => {
            let (config, initial) = arm.load()?;
            let n = config.arm.dof();
            let identifier = match name {
                Some(n) => n,
                None => output.file_stem().and_then(|s| s.to_str()).unwrap_or("PlanarArm").to_owned(),
            };
            let spec = FmuSpec {
                identifier,
                model: ModelSpec::PlanarArm { config, q0: initial.q, qd0: initial.qd },
            };
            export_fmu(&spec, &output).map_err(anyhow::Error::msg)?;
            eprintln!("wrote {} ({}, {n} joints)", output.display(), spec.identifier);
        }
    }
    Ok(())
}

fn main() -> ExitCode {
    match run(Cli::parse()) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
