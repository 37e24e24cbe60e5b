//! `neurarm compensator`: the whole path from a robot's logs to an NnCompensator FMU (identify,
//! train, export), every intermediate file kept in a work folder.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use clap::Args;
use neurarm::output::Destination;
use neurarm_physics::config::ArmConfig;

use super::common::{identifier_for, EpochBar, LogColumnArgs, PlatformArgs};

/// The arguments of `neurarm compensator`. Its help text is the doc of `Command::Compensator` in
/// main.rs, which clap shows instead of this one.
#[derive(Args)]
pub struct CompensatorArgs {
    /// Log of the friction plan (every joint's runs).
    #[arg(long)]
    friction_log: PathBuf,
    /// Log of the gravity plan.
    #[arg(long)]
    gravity_log: Option<PathBuf>,
    /// The arm (TOML), to take its velocity terms out of the gravity passes.
    #[arg(long, short = 'c')]
    config: Option<PathBuf>,
    /// Folder for the pairs, reports and nets (default: beside the FMU, NAME-files).
    #[arg(long)]
    work: Option<PathBuf>,
    /// Seed of the trainings.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Model identifier (default: the output file's name).
    #[arg(long)]
    name: Option<String>,
    #[command(flatten)]
    columns: LogColumnArgs,
    /// Speed of the gravity passes [rad/s].
    #[arg(long, default_value_t = 0.25)]
    pass_speed: f64,
    /// Output .fmu file (`-` is refused: pipe it with /dev/stdout).
    #[arg(long, short = 'o')]
    output: PathBuf,
    #[command(flatten)]
    platforms: PlatformArgs,
}

/// Runs `neurarm compensator`.
pub fn run(args: CompensatorArgs) -> Result<()> {
    let CompensatorArgs { friction_log, gravity_log, config, work, seed, name, columns, pass_speed, output, platforms } = args;
    let platforms = platforms.checked()?;
    let model = match config {
        Some(c) => Some(ArmConfig::from_toml_file(&c)?.arm),
        None => None,
    };
    neurarm::export::refuse_stdout(&output)?;
    let identifier = identifier_for(name, &output, "NnCompensator");
    let work = match work {
        Some(work) => work,
        None if Destination::of(&output).with_context(|| output.display().to_string())?.is_file() => {
            output.with_file_name(format!("{identifier}-files"))
        }
        None => {
            bail!("{} is not a file, so there is no folder beside it: give --work for the intermediate files", output.display())
        }
    };
    let job = neurarm::logs::CompensatorJob {
        friction_log,
        gravity_log,
        columns: columns.columns(),
        friction: Default::default(),
        gravity: neurarm::identify::GravityOptions { speed_rad_s: pass_speed, ..Default::default() },
        model,
        work: work.clone(),
        output: output.clone(),
        identifier,
        seed,
        platforms,
    };
    let bar = EpochBar::new(None);
    let summary =
        neurarm::logs::compensator_from_logs(&job, &mut |line| bar.println(&format!("[compensator] {line}")), &mut |e| bar.show(e));
    bar.finish();
    let summary = summary?;
    eprintln!(
        "wrote {} ({} joints; friction pairs {:?}, gravity pairs {}); intermediate files in {}",
        output.display(),
        summary.joints,
        summary.friction_pairs,
        summary.gravity_pairs.map_or("-".into(), |g| g.to_string()),
        work.display()
    );
    Ok(())
}
