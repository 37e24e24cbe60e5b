//! `neurarm paper`: the paper's experiments end to end (identification, training, Table 1,
//! gravity compensation) through the master and the FMUs, into one output folder.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{bail, Context, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use neurarm::experiments::paper::{compute, PaperRun, Table1};
use neurarm::experiments::{Arms, GravityDesign, Progress, Settings};
use neurarm_nn::InputEncoding;
use neurarm_physics::config::ArmConfig;
use neurarm_physics::control::{ReferencePlacement, TaskSpaceGains};

use super::common::{load_config, parse_angle_encoding, PlatformArgs};

/// The arguments of `neurarm paper`. Its help text is the doc of `Command::Paper` in
/// main.rs, which clap shows instead of this one.
#[derive(Args)]
pub struct PaperArgs {
    /// Arm configuration (TOML, see `neurarm default-config`); the built-in 4-joint arm if
    /// omitted.
    #[arg(long, short = 'c')]
    config: Option<PathBuf>,
    /// The "real" arm: your belief of the real robot (other friction, noise, quantisation),
    /// same joint count. Without it, the real arm is emulated from the arm (labelled so).
    #[arg(long)]
    real: Option<PathBuf>,
    /// Output folder (absent, empty, or an earlier run's, which is replaced; through a
    /// symbolic link, the folder it points to is replaced and the link stays).
    #[arg(long, short = 'o', default_value = "out")]
    output: PathBuf,
    #[command(flatten)]
    platforms: PlatformArgs,
    /// Also write the FMI 3.0 twin of every FMU into fmu/fmi3/ (same models and binaries; the
    /// loops of the run use the FMI 2.0 ones).
    #[arg(long)]
    fmi3: bool,
    /// A reduced run (3⁴ gravity grid, coarse friction levels, one period of tracking).
    #[arg(long)]
    quick: bool,
    /// Worker threads (default: the cores, at most 4).
    #[arg(long)]
    threads: Option<usize>,
    /// Seed of the training runs and the random test configurations (default 1); the
    /// simulations themselves are deterministic.
    #[arg(long)]
    seed: Option<u64>,
    /// Centre of the task-space reference [m], x,y (default: (0.45 R, 0.10 R), R the reach).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    centre: Option<Vec<f64>>,
    /// Scale of the reference, 1 = the paper's 0.4 m × 0.3 m (default: the reach in m).
    #[arg(long)]
    scale: Option<f64>,
    /// Task-space gains K_p [1/s²], K_d [1/s] and optionally the null-space damping of a
    /// redundant arm's self-motion k [1/s] (default 1000,160,10).
    #[arg(long, value_delimiter = ',')]
    tracking_gains: Option<Vec<f64>>,
    /// Joint-space loop gains K_p [N·m/rad], K_d [N·m·s/rad], taken as given (default: 50,2
    /// scaled by the arm's gravity load relative to the built-in arm).
    #[arg(long, value_delimiter = ',')]
    joint_gains: Option<Vec<f64>>,
    /// Measure gravity at this many poses (10 to 20 000) drawn over the whole turn (default:
    /// the paper's 7ⁿ grid up to 4 joints, 7⁴ = 2401 sampled poses beyond).
    #[arg(long, value_parser = clap::value_parser!(u64).range(10..=20_000), conflicts_with = "gravity_grid")]
    gravity_poses: Option<u64>,
    /// Measure gravity on a kⁿ grid, k points per joint (at most 20 000 poses in all).
    #[arg(long, value_parser = clap::value_parser!(u64).range(2..=100))]
    gravity_grid: Option<u64>,
    /// How the gravity net sees the angles: link-angles (default: (cos, sin) of each link's
    /// angle q₁+…+qⱼ, periodic), joint-angles ((cos, sin) of each joint angle, periodic) or
    /// raw (the paper's net, not periodic; a periodic net's run also trains it for comparison).
    #[arg(long, value_parser = parse_angle_encoding)]
    gravity_inputs: Option<InputEncoding>,
    /// Also measure the gravity error against the number of poses (grids and sampled designs
    /// up to N poses, every input encoding) for the report: adds minutes to a full run.
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(30..=20_000))]
    gravity_study: Option<u64>,
    /// Average the gravity passes as measured (the paper's procedure) instead of first
    /// taking the identified friction out of each.
    #[arg(long)]
    gravity_plain_average: bool,
    /// Top speed of the friction runs [rad/s] (default: the paper's 5): the friction nets are
    /// trained and judged up to it; lower it for a joint that cannot reach 5 rad/s.
    #[arg(long, value_name = "RAD_S", value_parser = parse_top_speed, allow_hyphen_values = true)]
    friction_max_speed: Option<f64>,
    /// Feed the task-space loops' compensators (perfect, NN, adaptive alike) the speed the
    /// controller commands H seconds ahead, q̇ + H u (`qd_intended_i` of the controller FMU),
    /// instead of the measured speed (the paper's), so joints at rest are compensated the way
    /// the law moves them; e.g. 0.01. Default: the measured speed.
    #[arg(long, value_name = "H", value_parser = parse_horizon, allow_hyphen_values = true)]
    intent_horizon: Option<f64>,
}

/// A number of `text` within `low..=high` [`unit`], or why not.
fn number_within(text: &str, low: f64, high: f64, unit: &str) -> Result<f64> {
    let v: f64 = text.parse().with_context(|| format!("{text:?} is not a number"))?;
    if !(low..=high).contains(&v) {
        bail!("{v} {unit} is outside {low} to {high} {unit}");
    }
    Ok(v)
}

/// A look-ahead horizon: 0 to 1 s.
fn parse_horizon(text: &str) -> Result<f64> {
    number_within(text, 0.0, 1.0, "s")
}

/// A friction top speed: 0.5 to 50 rad/s.
fn parse_top_speed(text: &str) -> Result<f64> {
    number_within(text, 0.5, 50.0, "rad/s")
}

/// Runs `neurarm paper`.
pub fn run(args: PaperArgs) -> Result<()> {
    let settings = settings_of(&args)?;
    let arms = arms_of(&args)?;
    let output = &args.output;
    let run = run_into(output, &arms, &settings).with_context(|| format!("no run was written to {}", output.display()))?;
    say_table_1(&run.results.table_1);
    eprintln!("wrote {} and {}", output.join("report.md").display(), output.join("results.json").display());
    Ok(())
}

/// The settings `args` ask for: the paper's or the quick run's, with the options given.
fn settings_of(args: &PaperArgs) -> Result<Settings> {
    let mut settings = if args.quick { Settings::quick() } else { Settings::paper() };
    settings.platforms = args.platforms.clone().checked()?;
    settings.fmi3 = args.fmi3;
    if let Some(s) = args.seed {
        settings.seed = s;
    }
    if let Some(t) = args.threads {
        settings.threads = t.max(1);
    }
    if let Some(g) = &args.tracking_gains {
        settings.tracking_gains = tracking_gains(g, settings.tracking_gains)?;
    }
    if let Some(poses) = args.gravity_poses {
        settings.gravity_design = Some(GravityDesign::Sampled { poses: poses as usize });
    }
    if let Some(per_joint) = args.gravity_grid {
        settings.gravity_design = Some(GravityDesign::Grid { per_joint: per_joint as usize });
    }
    if let Some(encoding) = args.gravity_inputs {
        settings.gravity_encoding = encoding;
    }
    settings.gravity_friction_correction = !args.gravity_plain_average;
    settings.intent_horizon = args.intent_horizon;
    if let Some(v) = args.friction_max_speed {
        settings.max_velocity = v;
    }
    settings.gravity_study = args.gravity_study.map(|n| n as usize);
    if let Some(g) = &args.joint_gains {
        (settings.joint_kp, settings.joint_kd) = gain_pair("--joint-gains", g)?;
        settings.scale_joint_gains = false;
    }
    Ok(settings)
}

/// `gains` with the values of `--tracking-gains`: kp,kd or kp,kd,null_damping.
fn tracking_gains(values: &[f64], mut gains: TaskSpaceGains) -> Result<TaskSpaceGains> {
    let (pair, null_damping) = match values.len() {
        2 => (values, None),
        3 => (&values[..2], Some(values[2])),
        n => bail!("--tracking-gains takes kp,kd or kp,kd,null_damping; got {n} numbers"),
    };
    (gains.kp, gains.kd) = gain_pair("--tracking-gains", pair)?;
    if let Some(null) = null_damping {
        if !(null.is_finite() && null >= 0.0) {
            bail!("--tracking-gains: the null-space damping must be >= 0 (got {null})");
        }
        gains.null_damping = null;
    }
    Ok(gains)
}

/// The arms `args` ask for: the arm (the built-in one without `--config`), the real arm if
/// given, the reference placed as given.
fn arms_of(args: &PaperArgs) -> Result<Arms> {
    let nominal = load_config(args.config.clone())?;
    let real = match &args.real {
        Some(path) => Some((ArmConfig::from_toml_file(path)?, path.display().to_string())),
        None => None,
    };
    let placement = match (&args.centre, args.scale) {
        (None, None) => None,
        (centre, scale) => {
            let mut p = ReferencePlacement::for_arm(&nominal.arm);
            if let Some(c) = centre {
                let [x, y] = c[..] else { bail!("--centre takes two numbers, x,y [m]; got {}", c.len()) };
                p.centre = nalgebra::Vector2::new(x, y);
            }
            if let Some(s) = scale {
                p.scale = s;
            }
            Some(p)
        }
    };
    let arm_name = args.config.as_ref().map_or("the built-in arm".to_owned(), |c| c.display().to_string());
    Arms::new(nominal, real, placement).context(arm_name)
}

/// Runs the paper's experiments on `arms` with `settings` and writes their report into
/// `out`. Everything is written into a staging folder beside `out` that replaces `out` only
/// when the whole run has succeeded, so a failed run leaves no folder that looks finished (and
/// an earlier run in `out` untouched). `out` must be absent, empty, or an earlier run's folder
/// (it has a `results.json`); through a symbolic link, the folder it points to is replaced.
fn run_into(out: &Path, arms: &Arms, settings: &Settings) -> Result<PaperRun> {
    settings.design_for(arms.joints()).check(arms.joints())?;
    let out = &run_folder(out)?;
    let staging = staging_folder(out)?;
    let run = compute(staging.path(), arms, settings, &StageBars::default(), &mut |line| eprintln!("[paper] {line}"))?;
    neurarm::report::write_report(staging.path(), &run)?;
    let staged = staging.keep();
    replace_folder(&staged, out).inspect_err(|_| {
        let _ = std::fs::remove_dir_all(&staged);
    })?;
    Ok(run)
}

/// The folder a run goes to, `out` or, through symbolic links, the folder it points to;
/// refused unless absent, empty or an earlier run's.
fn run_folder(out: &Path) -> Result<PathBuf> {
    if neurarm::output::is_stdout(out) {
        bail!("the run is a folder (report, data, nets, FMUs, plots): give the folder's name, not '-'");
    }
    let out = neurarm::output::follow_links(out).with_context(|| out.display().to_string())?;
    if out.exists() && !out.is_dir() {
        bail!("{} is not a folder: give a folder for the run", out.display());
    }
    if out.exists() {
        let empty = std::fs::read_dir(&out).with_context(|| out.display().to_string())?.next().is_none();
        if !empty && !out.join("results.json").is_file() {
            bail!("{} exists and is not the folder of an earlier run (no results.json): choose another output folder", out.display());
        }
    }
    Ok(out)
}

/// A new, hidden staging folder beside `out` (removed when dropped).
fn staging_folder(out: &Path) -> Result<tempfile::TempDir> {
    let name = out.file_name().with_context(|| format!("{}: not a folder name", out.display()))?.to_string_lossy().into_owned();
    let parent = match out.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    std::fs::create_dir_all(&parent).with_context(|| parent.display().to_string())?;
    tempfile::Builder::new()
        .prefix(&format!(".{name}.partial-"))
        .tempdir_in(&parent)
        .with_context(|| format!("cannot create a staging folder in {}", parent.display()))
}

/// Moves the finished run in `staged` to `out`, replacing an earlier run there.
fn replace_folder(staged: &Path, out: &Path) -> Result<()> {
    if out.exists() {
        std::fs::remove_dir_all(out).with_context(|| format!("removing the earlier run in {}", out.display()))?;
    }
    std::fs::rename(staged, out).with_context(|| format!("moving the finished run to {}", out.display()))
}

/// Says Table 1's figures, what the real arm's sensors cost, and the diagnostic loops that
/// failed.
fn say_table_1(t: &Table1) {
    let (m, q) = (&t.mse_m2, &t.ratios);
    eprintln!(
        "Table 1 MSE [m²]: sim perfect {:.3e}, NN {:.3e}, none {:.3e}; real NN {:.3e}, none {:.3e}\nratios: sim NN/perfect {:.3}, none/perfect {:.1}; real NN/none {:.3}",
        m.sim_perfect, m.sim_nn, m.sim_none, m.real_nn, m.real_none, q.sim_nn_over_perfect, q.sim_none_over_perfect, q.real_nn_over_none
    );
    let sensors = &t.real_sensors;
    let quiet = sensors.quiet_nn_over_none.map_or(String::new(), |r| format!("; sensor noise off: real NN/none {r:.3}"));
    let law = sensors.perfect_over_none.map_or("failed".to_owned(), |r| format!("{r:.3}"));
    eprintln!(
        "real arm, true positions: NN/none {:.3}, true friction law/none {law}{quiet}",
        t.true_mse_m2.real_nn / t.true_mse_m2.real_none
    );
    for failure in &t.diagnostic_failures {
        eprintln!("warning: diagnostic loop {failure}");
    }
}

/// The stages of the paper run as progress bars on standard error, when it is a terminal.
#[derive(Default)]
struct StageBars {
    /// The bar of the stage under way.
    bar: Mutex<Option<ProgressBar>>,
}

impl StageBars {
    fn bar(&self) -> std::sync::MutexGuard<'_, Option<ProgressBar>> {
        self.bar.lock().unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

impl Progress for StageBars {
    fn start(&self, what: &str, steps: u64) {
        let b = if std::io::stderr().is_terminal() { ProgressBar::new(steps) } else { ProgressBar::hidden() };
        b.set_style(ProgressStyle::with_template("{prefix:>28} {bar:30} {pos}/{len} {elapsed}").expect("valid template"));
        b.set_prefix(what.to_owned());
        *self.bar() = Some(b);
    }

    fn advance(&self) {
        if let Some(b) = self.bar().as_ref() {
            b.inc(1);
        }
    }

    fn finish(&self) {
        if let Some(b) = self.bar().take() {
            b.finish_and_clear();
        }
    }
}

/// Two positive gains from an option's values.
fn gain_pair(option: &str, values: &[f64]) -> Result<(f64, f64)> {
    let [kp, kd] = values[..] else { bail!("{option} takes two numbers, kp,kd; got {}", values.len()) };
    if !(kp.is_finite() && kd.is_finite() && kp > 0.0 && kd >= 0.0) {
        bail!("{option}: kp must be > 0 and kd >= 0 (got {kp}, {kd})");
    }
    Ok((kp, kd))
}
