//! `neurarm export arm|compensator|controller task-space|joint|fmi3`: FMI 2.0 or FMI 3.0
//! Co-Simulation FMUs of the arm, the compensators (NN, ideal, adaptive) and the paper's
//! controllers, and the FMI 3.0 twin of an FMI 2.0 FMU neurarm made.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use clap::{Args, Subcommand};
use neurarm::export::{export_fmi3_twin, export_fmu_as, FmiVersion};
use neurarm_models::{
    AdaptationLaw, FmuSpec, IdealCompensatorSpec, JointControllerSpec, ModelSpec, NnCompensatorSpec, PlanarArmSpec, TaskSpaceControllerSpec,
};
use neurarm_nn::{NetKind, WeightsFile};
use neurarm_physics::control::{ReferencePlacement, TaskSpaceGains};

use super::common::{identifier_for, load_config, ArmSource, PlatformArgs};

/// `neurarm export`: what to export, and for which platforms.
#[derive(Args)]
pub struct ExportArgs {
    #[command(subcommand)]
    what: Export,
    #[command(flatten)]
    platforms: PlatformArgs,
    /// FMI version of the FMU written: 2 (FMI 2.0) or 3 (FMI 3.0 Co-Simulation, the same model
    /// and binary).
    #[arg(long, default_value = "2", global = true)]
    fmi: FmiVersion,
}

/// The subcommands of `neurarm export`. Its help text is the doc of `Command::Export` in
/// main.rs, which clap shows instead of this one.
#[derive(Subcommand)]
pub enum Export {
    /// The arm as an FMU (`PlanarArm`): torque inputs; angle, velocity and end-effector outputs;
    /// every parameter of the configuration as an FMU parameter.
    Arm {
        /// The arm; its initial state becomes the FMU parameters q0_i, qd0_i.
        #[command(flatten)]
        arm: ArmSource,
        /// Model identifier (default: the output file's name, e.g. MyArm for MyArm.fmu).
        #[arg(long)]
        name: Option<String>,
        /// Output .fmu file (`-` is refused: pipe it with /dev/stdout).
        #[arg(long, short = 'o')]
        output: PathBuf,
    },
    /// The NN compensator as an FMU (`NnCompensator`): inputs q_i, qd_i; outputs the friction,
    /// gravity and total compensating torques; Boolean parameters enable each part.
    ///
    /// `--ideal`: `IdealCompensator`, the true torques of the arm in `-c` (default: built-in);
    /// `--friction`/`--gravity` without files pick the parts (both if neither). `--adaptive`:
    /// `AdaptiveCompensator`, whose nets' output layers learn from the controller's signal
    /// (inputs s_i; parameters adapt, gain_friction, gain_gravity, leakage, bound_*).
    Compensator {
        /// Friction net of each joint (1 input: velocity, 1 output: torque), in joint order;
        /// with `--ideal`, no files: switch the true friction on.
        #[arg(long, value_delimiter = ',', num_args = 0..)]
        friction: Option<Vec<PathBuf>>,
        /// Gravity net (n angle inputs, n torque outputs); with `--ideal`, no file: switch the
        /// true gravity on.
        #[arg(long, num_args = 0..=1)]
        gravity: Option<Option<PathBuf>>,
        /// The arm's true friction and gravity instead of nets.
        #[arg(long, conflicts_with = "adaptive")]
        ideal: bool,
        /// Nets whose output layers adapt while running.
        #[arg(long)]
        adaptive: bool,
        /// With `--ideal`: the arm configuration (TOML); the built-in arm if omitted.
        #[arg(long, short = 'c', requires = "ideal")]
        config: Option<PathBuf>,
        /// Model identifier (default: the output file's name).
        #[arg(long)]
        name: Option<String>,
        /// Output .fmu file (`-` is refused: pipe it with /dev/stdout).
        #[arg(long, short = 'o')]
        output: PathBuf,
    },
    /// A controller of the paper's loops as an FMU, for an arm of 1 to 64 joints; the variable
    /// names are those the loops of `neurarm paper` connect.
    #[command(subcommand)]
    Controller(Controller),
    /// The FMI 3.0 twin of an FMI 2.0 FMU made by neurarm: the same model, resources and
    /// binaries, with an FMI 3.0 model description and platform folders.
    Fmi3 {
        /// The FMI 2.0 FMU.
        input: PathBuf,
        /// Output .fmu file (`-` is refused: pipe it with /dev/stdout).
        #[arg(long, short = 'o')]
        output: PathBuf,
    },
}

/// The subcommands of `neurarm export controller`. Its help text is the doc of
/// `Export::Controller`, which clap shows instead of this one.
#[derive(Subcommand)]
pub enum Controller {
    /// `TaskSpaceController`: computed torque tracking the paper's curve, placed for the arm.
    ///
    /// Inputs q_i [rad], qd_i [rad/s], tau_comp_i [N·m]; outputs tau_i [N·m], x_ref, y_ref,
    /// error_x, error_y [m]. The curve is scaled by the arm's reach R (Σ link lengths) and
    /// centred at (0.45 R, 0.10 R) unless `--centre`/`--scale` say otherwise; one the arm cannot
    /// reach is refused. The angle inputs start where the end effector is at the curve's start.
    TaskSpace {
        /// Arm configuration (TOML): the controller's model of the arm (its friction is left
        /// to tau_comp); the built-in arm if omitted.
        #[arg(long, short = 'c')]
        config: Option<PathBuf>,
        /// Position gain K_p [1/s²].
        #[arg(long, default_value_t = 1000.0)]
        kp: f64,
        /// Velocity gain K_d [1/s].
        #[arg(long, default_value_t = 160.0)]
        kd: f64,
        /// Damping of the self-motion of the redundant joints [1/s].
        #[arg(long, default_value_t = neurarm_physics::control::DEFAULT_NULL_DAMPING)]
        null_damping: f64,
        /// Centre of the curve [m], x,y (default: from the reach).
        #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
        centre: Option<Vec<f64>>,
        /// Scale of the curve, 1 = the paper's 0.4 m × 0.3 m (default: the reach in m).
        #[arg(long)]
        scale: Option<f64>,
        /// Model identifier (default: the output file's name).
        #[arg(long)]
        name: Option<String>,
        /// Output .fmu file (`-` is refused: pipe it with /dev/stdout).
        #[arg(long, short = 'o')]
        output: PathBuf,
    },
    /// `JointController`: τ_i = tau_comp_i + kp (q_ref_i − q_i) + kd (qd_ref_i − qd_i).
    ///
    /// Inputs q_i, qd_i, tau_comp_i, q_ref_i, qd_ref_i; outputs tau_i, q_target_i. Gains are
    /// tunable parameters kp_i, kd_i; `--sequence` makes the built-in target sequence of the
    /// paper's gravity loop the default instead of the q_ref/qd_ref inputs.
    Joint {
        /// Arm configuration (TOML), for its joint count; the built-in arm if omitted.
        #[arg(long, short = 'c', conflicts_with = "joints")]
        config: Option<PathBuf>,
        /// Number of joints, instead of a configuration.
        #[arg(long)]
        joints: Option<usize>,
        /// Position gain of every joint [N·m/rad].
        #[arg(long, default_value_t = 50.0)]
        kp: f64,
        /// Velocity gain of every joint [N·m·s/rad] (0 in the paper's law).
        #[arg(long, default_value_t = 0.0)]
        kd: f64,
        /// Follow the built-in target sequence by default.
        #[arg(long)]
        sequence: bool,
        /// Model identifier (default: the output file's name).
        #[arg(long)]
        name: Option<String>,
        /// Output .fmu file (`-` is refused: pipe it with /dev/stdout).
        #[arg(long, short = 'o')]
        output: PathBuf,
    },
}

/// Runs `neurarm export`.
pub fn run(args: ExportArgs) -> Result<()> {
    let command = args.what;
    // The twin takes its binaries from the FMU it is made from, not from this build.
    let platforms = if matches!(command, Export::Fmi3 { .. }) { None } else { args.platforms.checked()? };
    let target = Target { platforms: platforms.as_deref(), version: args.fmi };
    match command {
        Export::Fmi3 { input, output } => {
            export_fmi3_twin(&input, &output)?;
            eprintln!("wrote {} (FMI 3.0 twin of {})", output.display(), input.display());
        }
        Export::Arm { arm, name, output } => {
            let (config, initial) = arm.load()?;
            let n = config.arm.dof();
            let identifier = identifier_for(name, &output, "PlanarArm");
            let model = ModelSpec::PlanarArm(PlanarArmSpec { config, q0: initial.q, qd0: initial.qd });
            target.write(FmuSpec { identifier, model }, &[], &output, n)?;
        }
        Export::Compensator { friction, gravity, ideal: true, adaptive: _, config, name, output } => {
            ideal_compensator(friction, gravity, config, name, &output, &target)?;
        }
        Export::Compensator { friction, gravity, ideal: false, adaptive, config: _, name, output } => {
            nn_compensator(friction.unwrap_or_default(), gravity.flatten(), adaptive, name, &output, &target)?;
        }
        Export::Controller(Controller::TaskSpace { config, kp, kd, null_damping, centre, scale, name, output }) => {
            task_space_controller(
                config,
                TaskSpaceGains { kp, kd, null_damping, ..TaskSpaceGains::default() },
                centre,
                scale,
                name,
                &output,
                &target,
            )?;
        }
        Export::Controller(Controller::Joint { config, joints, kp, kd, sequence, name, output }) => {
            let joints = match joints {
                Some(n) => n,
                None => load_config(config)?.arm.dof(),
            };
            let identifier = identifier_for(name, &output, "JointController");
            let model = ModelSpec::JointController(JointControllerSpec { joints, kp, kd, use_sequence: sequence });
            target.write(FmuSpec { identifier, model }, &[], &output, joints)?;
        }
    }
    Ok(())
}

/// `export compensator --ideal`: the arm's true friction and gravity, the parts chosen by
/// `--friction` and `--gravity` without files (both if neither is given).
fn ideal_compensator(
    friction: Option<Vec<PathBuf>>,
    gravity: Option<Option<PathBuf>>,
    config: Option<PathBuf>,
    name: Option<String>,
    output: &Path,
    target: &Target<'_>,
) -> Result<()> {
    if friction.as_ref().is_some_and(|f| !f.is_empty()) || gravity.as_ref().is_some_and(|g| g.is_some()) {
        bail!("--ideal takes no weights files: it computes the arm's true torques (--friction and --gravity alone choose the parts)");
    }
    let arm = load_config(config)?.arm;
    let n = arm.dof();
    let (enable_friction, enable_gravity) = match (friction.is_some(), gravity.is_some()) {
        (false, false) => (true, true),
        chosen => chosen,
    };
    let identifier = identifier_for(name, output, "IdealCompensator");
    let model = ModelSpec::IdealCompensator(IdealCompensatorSpec { arm, enable_friction, enable_gravity });
    target.write(FmuSpec { identifier, model }, &[], output, n)
}

/// `export compensator` of nets: the friction nets of joints 1, 2, … and the gravity net,
/// checked together by the user's file names before anything is packed; adapting with
/// `--adaptive`.
fn nn_compensator(
    friction: Vec<PathBuf>,
    gravity: Option<PathBuf>,
    adaptive: bool,
    name: Option<String>,
    output: &Path,
    target: &Target<'_>,
) -> Result<()> {
    let identifier = identifier_for(name, output, if adaptive { "AdaptiveCompensator" } else { "NnCompensator" });
    if friction.is_empty() && gravity.is_none() {
        bail!("give --friction nets, a --gravity net, or both (or --ideal for the arm's true torques)");
    }
    let friction_files = friction.iter().map(|p| WeightsFile::read(p)).collect::<Result<Vec<_>, _>>()?;
    let gravity_file = gravity.as_ref().map(|g| WeightsFile::read(g)).transpose()?;
    let names: Vec<String> = friction.iter().chain(&gravity).map(|p| p.display().to_string()).collect();
    let named: Vec<(&str, &WeightsFile)> = names.iter().map(String::as_str).zip(&friction_files).collect();
    let joints = neurarm_models::check_compensator_nets(&named, names.get(friction.len()).map(String::as_str).zip(gravity_file.as_ref()))?;
    for (name, file) in names.iter().zip(friction_files.iter().chain(&gravity_file)) {
        if file.kind == NetKind::Unspecified {
            eprintln!("notice: {name} records no kind (trained before weights version 3, or with --kind unspecified): checked by its shape and names only");
        }
    }
    let mut sources: Vec<(String, PathBuf)> =
        friction.iter().enumerate().map(|(i, p)| (format!("friction_{}.json", i + 1), p.clone())).collect();
    if let Some(g) = &gravity {
        sources.push(("gravity.json".into(), g.clone()));
    }
    let spec = NnCompensatorSpec::of_nets(
        joints,
        (1..=friction.len()).map(|i| format!("friction_{i}.json")).collect(),
        gravity.as_ref().map(|_| "gravity.json".to_owned()),
    );
    let model =
        if adaptive { ModelSpec::AdaptiveCompensator(spec.adaptive(AdaptationLaw::default())) } else { ModelSpec::NnCompensator(spec) };
    target.write(FmuSpec { identifier, model }, &sources, output, joints)
}

/// `export controller task-space`: the curve placed for the arm of `config` (`centre` and
/// `scale` overriding), the controller starting at the pose at the curve's start.
fn task_space_controller(
    config: Option<PathBuf>,
    gains: TaskSpaceGains,
    centre: Option<Vec<f64>>,
    scale: Option<f64>,
    name: Option<String>,
    output: &Path,
    target: &Target<'_>,
) -> Result<()> {
    let arm = load_config(config)?.arm;
    let n = arm.dof();
    if n < 2 {
        bail!("task-space control of a planar position needs at least 2 joints; the arm has {n}");
    }
    let mut placement = ReferencePlacement::for_arm(&arm);
    if let Some(c) = centre {
        let [x, y] = c[..] else { bail!("--centre takes two numbers, x,y [m]; got {}", c.len()) };
        placement.centre = nalgebra::Vector2::new(x, y);
    }
    if let Some(s) = scale {
        placement.scale = s;
    }
    // `tracking_start` (the experiments') says what is wrong in words.
    let start = neurarm::experiments::tracking_start(&arm, &placement)?;
    let model = ModelSpec::TaskSpaceController(TaskSpaceControllerSpec {
        model: arm.frictionless(),
        gains,
        centre: [placement.centre.x, placement.centre.y],
        scale: placement.scale,
        q_start: start.q,
    });
    let identifier = identifier_for(name, output, "TaskSpaceController");
    target.write(FmuSpec { identifier, model }, &[], output, n)
}

/// What every FMU of one `neurarm export` is written for: the platforms it carries and its FMI
/// version.
struct Target<'a> {
    platforms: Option<&'a [String]>,
    version: FmiVersion,
}

impl Target<'_> {
    /// Writes the FMU of `spec` (of `joints` joints) and says so.
    fn write(&self, spec: FmuSpec, sources: &[(String, PathBuf)], output: &Path, joints: usize) -> Result<()> {
        export_fmu_as(&spec, sources, output, self.platforms, self.version)?;
        eprintln!("wrote {} ({}, {joints} joints, FMI {})", output.display(), spec.identifier, self.version.number());
        Ok(())
    }
}
