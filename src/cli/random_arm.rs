//! `neurarm random-arm`: the TOML configuration of one arm of the seeded random family (the
//! arms the family test and `scripts/bench-family` run), the same for the same seed and joint
//! count.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use neurarm_physics::family::random_arm;

use super::common::write_config;

/// The arguments of `neurarm random-arm`. Its help text is the doc of `Command::RandomArm` in
/// main.rs, which clap shows instead of this one.
#[derive(Args)]
pub struct RandomArmArgs {
    /// Seed of the arm.
    #[arg(long)]
    seed: u64,
    /// Number of joints, 2 to 8.
    // `random_arm` panics outside 2..=8: clap refuses those counts, naming the range.
    #[arg(long, value_parser = clap::value_parser!(u64).range(2..=8))]
    joints: u64,
    /// Output TOML (`-`: standard output).
    #[arg(long, short = 'o', default_value = "-")]
    output: PathBuf,
}

/// Runs `neurarm random-arm`.
pub fn run(args: RandomArmArgs) -> Result<()> {
    write_config(&args.output, &random_arm(args.seed, args.joints as usize))
}
