//! `neurarm plan friction|gravity`: the paper's identification experiments as plans a robot's
//! own controller can play (CSV), with instructions (.txt) beside them.

use std::path::PathBuf;

use anyhow::Result;
use clap::Subcommand;
use neurarm::output::describe;

use super::common::load_config;

/// The subcommands of `neurarm plan`. Its help text is the doc of `Command::Plan` in main.rs,
/// which clap shows instead of this one.
#[derive(Subcommand)]
pub enum PlanCommand {
    /// Constant-torque levels per joint and direction, chosen from the arm's expected friction.
    Friction {
        /// The arm (TOML); the built-in arm if omitted.
        #[arg(long, short = 'c')]
        config: Option<PathBuf>,
        /// Joints to plan, comma-separated (default: all).
        #[arg(long, value_delimiter = ',')]
        joints: Option<Vec<usize>>,
        /// Highest speed of the levels [rad/s].
        #[arg(long, default_value_t = 5.0)]
        max_speed: f64,
        /// Spacing of the levels' speeds [rad/s].
        #[arg(long, default_value_t = 0.1)]
        spacing: f64,
        /// Output plan (.csv; the instructions go to a .txt beside it, or to the terminal when the
        /// plan goes to `-` (standard output), a device or a FIFO).
        #[arg(long, short = 'o')]
        output: PathBuf,
    },
    /// Poses (grid or sampled) with slow up and down passes of every joint.
    Gravity {
        /// The arm (TOML), for its joint count; the built-in arm if omitted.
        #[arg(long, short = 'c')]
        config: Option<PathBuf>,
        /// Sampled poses over the whole turn (default: the 7ⁿ grid up to 4 joints, 2401 sampled beyond).
        #[arg(long, conflicts_with = "grid")]
        poses: Option<usize>,
        /// A kⁿ grid.
        #[arg(long)]
        grid: Option<usize>,
        /// Speed of the passes [rad/s].
        #[arg(long, default_value_t = 0.25)]
        speed: f64,
        /// Duration of each pass [s].
        #[arg(long, default_value_t = 2.0)]
        pass_time: f64,
        /// Seed of a sampled design.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Output plan (.csv; the instructions go to a .txt beside it, or to the terminal when the
        /// plan goes to `-` (standard output), a device or a FIFO).
        #[arg(long, short = 'o')]
        output: PathBuf,
    },
}

/// Runs `neurarm plan`.
pub fn run(command: PlanCommand) -> Result<()> {
    match command {
        PlanCommand::Friction { config, joints, max_speed, spacing, output } => {
            let source = config.as_ref().map_or("the built-in arm".to_owned(), |c| c.display().to_string());
            let arm = load_config(config)?.arm;
            let mut settings = neurarm::plan::FrictionPlanSettings::for_joints(arm.dof());
            if let Some(j) = joints {
                settings.joints = j;
            }
            settings.max_speed_rad_s = max_speed;
            settings.spacing_rad_s = spacing;
            let plan = neurarm::plan::friction_plan(&arm, &settings)?;
            let instructions = plan.instructions(&source);
            let notes = neurarm::plan::write_plan(&output, &plan.to_csv(), &instructions)?;
            let what = format!("{} segments, {:.0} s", plan.segments.len(), plan.end_s);
            say_plan_written(&output, &what, notes.as_deref(), &instructions);
        }
        PlanCommand::Gravity { config, poses, grid, speed, pass_time, seed, output } => {
            use neurarm::experiments::GravityDesign;
            let source = config.as_ref().map_or("the built-in arm".to_owned(), |c| c.display().to_string());
            let n = load_config(config)?.arm.dof();
            let design = match (poses, grid) {
                (Some(poses), _) => GravityDesign::Sampled { poses },
                (None, Some(per_joint)) => GravityDesign::Grid { per_joint },
                (None, None) => neurarm::experiments::Settings::paper().design_for(n),
            };
            let settings = neurarm::plan::GravityPlanSettings { design, speed_rad_s: speed, pass_s: pass_time, seed };
            let plan = neurarm::plan::gravity_plan(n, &settings)?;
            let instructions = plan.instructions(&source, &settings);
            let notes = neurarm::plan::write_plan(&output, &plan.to_csv(), &instructions)?;
            say_plan_written(&output, &format!("{} poses, {:.0} s", plan.poses, plan.end_s), notes.as_deref(), &instructions);
        }
    }
    Ok(())
}

/// Says where a plan went; its instructions go to the terminal when there is no file beside it.
fn say_plan_written(output: &std::path::Path, what: &str, notes: Option<&std::path::Path>, instructions: &str) {
    match notes {
        Some(notes) => eprintln!("wrote {} ({what}) and {}", output.display(), notes.display()),
        None => eprintln!("wrote the plan ({what}) to {}; its instructions (no .txt beside it):\n\n{instructions}", describe(output)),
    }
}
