//! `neurarm default-config`: the built-in arm's configuration as TOML, a starting point for
//! one's own arm.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use neurarm_physics::config::ArmConfig;

use super::common::write_config;

/// The arguments of `neurarm default-config`. Its help text is the doc of `Command::DefaultConfig` in
/// main.rs, which clap shows instead of this one.
#[derive(Args)]
pub struct DefaultConfigArgs {
    /// Where to write it (default `-`: standard output).
    #[arg(long, short = 'o', default_value = "-")]
    output: PathBuf,
}

/// Runs `neurarm default-config`.
pub fn run(args: DefaultConfigArgs) -> Result<()> {
    write_config(&args.output, &ArmConfig::default())
}
