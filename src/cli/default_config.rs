//! `neurarm default-config`: the built-in arm's configuration as TOML, a starting point for
//! one's own arm.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use neurarm::output::describe;
use neurarm::table::write_text_atomic;
use neurarm_physics::config::ArmConfig;

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
    let DefaultConfigArgs { output } = args;
    write_text_atomic(&output, &ArmConfig::default().to_toml_string()).with_context(|| format!("writing {}", describe(&output)))?;
    if !neurarm::output::is_stdout(&output) {
        eprintln!("wrote {}", output.display());
    }
    Ok(())
}
