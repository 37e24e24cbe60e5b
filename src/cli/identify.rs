//! `neurarm identify friction|gravity`: training pairs from a robot's logs, with every
//! level's or pose's verdict printed and written beside the pairs.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Subcommand;
use neurarm::output::describe;
use neurarm_physics::config::ArmConfig;

use super::common::LogColumnArgs;

/// The subcommands of `neurarm identify`. Its help text is the doc of `Command::Identify` in
/// main.rs, which clap shows instead of this one.
#[derive(Subcommand)]
pub enum IdentifyCommand {
    /// Friction pairs of one joint from constant-torque runs: finds the levels (runs of constant
    /// torque), keeps those that reached a steady speed (drift of the speed over the last window
    /// at most --drift beyond noise, spread at most --spread), bins them by speed and adds the
    /// pair at rest from the breakaway probes. Prints every level's verdict; writes the pairs
    /// (CSV) and the verdicts (JSON beside it).
    Friction {
        /// The log (CSV).
        #[arg(long)]
        log: PathBuf,
        /// The joint (from 1).
        #[arg(long)]
        joint: usize,
        #[command(flatten)]
        columns: LogColumnArgs,
        /// Width of the speed bins [rad/s].
        #[arg(long, default_value_t = 0.05)]
        bin_width: f64,
        /// Measuring window at the end of each level [s].
        #[arg(long, default_value_t = 0.5)]
        window: f64,
        /// Largest drift of the speed over the window beyond noise [rad/s].
        #[arg(long, default_value_t = 0.01)]
        drift: f64,
        /// Largest spread of the speed about its trend [rad/s] (or 10 % of the speed).
        #[arg(long, default_value_t = 0.1)]
        spread: f64,
        /// The joint's inertia with the others held [kg·m²]: takes what is left of the approach out.
        #[arg(long)]
        inertia: Option<f64>,
        /// Output pairs (.csv; `-`: standard output); the verdicts go to a .json beside a file.
        #[arg(long, short = 'o')]
        output: PathBuf,
    },
    /// Gravity pairs from slow passes: finds the up and down passes through each pose, averages
    /// them at the pose and refuses a pose passed in one direction only.
    Gravity {
        /// The log (CSV).
        #[arg(long)]
        log: PathBuf,
        #[command(flatten)]
        columns: LogColumnArgs,
        /// Friction pairs of every joint (identify friction's files), in joint order: their
        /// friction is taken out of each pass.
        #[arg(long, value_delimiter = ',')]
        friction: Option<Vec<PathBuf>>,
        /// The arm (TOML): its velocity terms are taken out of each pass.
        #[arg(long, short = 'c')]
        config: Option<PathBuf>,
        /// Speed of the passes [rad/s].
        #[arg(long, default_value_t = 0.25)]
        speed: f64,
        /// Measuring window at the middle of each pass [s].
        #[arg(long, default_value_t = 0.5)]
        window: f64,
        /// Output pairs (.csv; `-`: standard output); the verdicts go to a .json beside a file.
        #[arg(long, short = 'o')]
        output: PathBuf,
    },
}

/// Runs `neurarm identify`.
pub fn run(command: IdentifyCommand) -> Result<()> {
    match command {
        IdentifyCommand::Friction { log, joint, columns, bin_width, window, drift, spread, inertia, output } => {
            let columns = columns.columns();
            columns.check()?;
            let options = neurarm::identify::FrictionOptions {
                bin_width_rad_s: bin_width,
                window_s: window,
                drift_rad_s: drift,
                spread_rad_s: spread,
                inertia_kgm2: inertia,
                ..Default::default()
            };
            options.check()?;
            neurarm::logs::report_path(&output)?;
            let robot_log = neurarm::identify::RobotLog::read_joint(&log, &columns, joint)?;
            let found = neurarm::identify::identify_friction_log(&robot_log, joint, &options)?;
            eprint!("{}", neurarm::logs::friction_summary(joint, &found));
            let report = neurarm::logs::write_friction_pairs(&output, joint, &found)?;
            say_pairs_written(&output, found.pairs.len(), report.as_deref());
        }
        IdentifyCommand::Gravity { log, columns, friction, config, speed, window, output } => {
            let columns = columns.columns();
            columns.check()?;
            let options = neurarm::identify::GravityOptions { speed_rad_s: speed, window_s: window, ..Default::default() };
            options.check()?;
            neurarm::logs::report_path(&output)?;
            let model = match config {
                Some(c) => Some(ArmConfig::from_toml_file(&c)?.arm.with_base_angle(0.0).frictionless()),
                None => None,
            };
            let mut curves = Vec::new();
            for (k, path) in friction.unwrap_or_default().iter().enumerate() {
                let (joint, pairs) = neurarm::logs::read_friction_pairs(path)?;
                if joint != k + 1 {
                    bail!(
                        "--friction: {} holds joint {joint}'s pairs but is given as joint {}'s; give them in joint order",
                        path.display(),
                        k + 1
                    );
                }
                curves.push(neurarm::identify::FrictionCurve::new(&pairs));
            }
            let robot_log = neurarm::identify::RobotLog::read_all(&log, &columns, model.as_ref().map(|m| m.dof()))?;
            let correction = neurarm::identify::GravityCorrection { friction: &curves, model: model.as_ref() };
            let found = neurarm::identify::identify_gravity_log(&robot_log, &options, &correction)?;
            eprint!("{}", neurarm::logs::gravity_summary(&found));
            let report = neurarm::logs::write_gravity_pairs(&output, &found)?;
            say_pairs_written(&output, found.pairs.len(), report.as_deref());
        }
    }
    Ok(())
}

/// Says where identified pairs went, and where their verdicts went.
fn say_pairs_written(output: &std::path::Path, pairs: usize, report: Option<&std::path::Path>) {
    match report {
        Some(report) => eprintln!("wrote {pairs} pairs to {} and the verdicts to {}", output.display(), report.display()),
        None => eprintln!("wrote {pairs} pairs to {} (no .json of verdicts beside it: the summary above has them)", describe(output)),
    }
}
