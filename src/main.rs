//! The `neurarm` command line: a thin shell over the library.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context, Result};
use clap::{Args, Parser, Subcommand};
use indicatif::{ProgressBar, ProgressStyle};
use nalgebra::DMatrix;
use neurarm::export::export_fmu;
use neurarm::output::{describe, Destination};
use neurarm::simulate::{simulate, TorqueInput};
use neurarm::table::{write_atomic, write_text_atomic, NumericTable};
use neurarm_models::{
    AdaptationLaw, AdaptiveCompensatorSpec, FmuSpec, IdealCompensatorSpec, JointControllerSpec, ModelSpec, NnCompensatorSpec,
    PlanarArmSpec, TaskSpaceControllerSpec,
};
use neurarm_physics::arm::ArmState;
use neurarm_physics::config::ArmConfig;
use neurarm_physics::control::{ReferencePlacement, TaskSpaceGains};
use neurarm_physics::nn::lm::Damping;
use neurarm_physics::nn::{train, InputEncoding, NetKind, Signal, TrainSettings, WeightsFile};
use std::io::IsTerminal;

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
    /// The torque CSV has a header with `time` [s, strictly increasing] and `tau_1` … `tau_n`
    /// [N·m]; each row's torque is held until the next row. The output has one row per input
    /// time: time, q_i [rad], qd_i [rad/s], x, y [m], xd, yd [m/s], tau_i, and q_meas_i,
    /// qd_meas_i when the configuration adds hardware-like effects.
    ///
    /// Given a system file instead (`neurarm simulate system.toml -o out.csv`), runs the
    /// described co-simulation of FMUs through the master and writes the recorded variables;
    /// if a unit fails mid-run, the rows recorded so far are written and the error reported.
    Simulate {
        /// A system file (TOML: [[fmu]], [[connection]], [simulation]) to run instead of the arm.
        system: Option<PathBuf>,
        /// Torque input CSV.
        #[arg(long, short = 't', conflicts_with_all = ["system", "plan"], required_unless_present_any = ["system", "plan"])]
        torque: Option<PathBuf>,
        /// A plan of `neurarm plan` to play instead, as a robot whose own controller holds and
        /// tracks the joints (computed torque from the configured arm on the measured angles).
        #[arg(long, conflicts_with = "system")]
        plan: Option<PathBuf>,
        /// With --plan: the controller's step [s].
        #[arg(long, default_value_t = 0.001, requires = "plan")]
        step: f64,
        /// With --plan: write every K-th step only.
        #[arg(long, default_value_t = 1, requires = "plan", value_parser = clap::value_parser!(u64).range(1..=1_000_000))]
        every: u64,
        /// With --plan: write what a robot logs, time and the measured q_i, qd_i with tau_i, each
        /// rounded to 1e-6 (rad, rad/s, N·m).
        #[arg(long, requires = "plan")]
        robot_log: bool,
        /// The arm's base angle [rad] instead of the configuration's (π/2: gravity in the plane).
        #[arg(long, allow_hyphen_values = true)]
        base_angle: Option<f64>,
        #[command(flatten)]
        arm: ArmSource,
        /// Output trajectory CSV (`-`: standard output); written only if the whole simulation
        /// succeeds. For a system file, the recording, written also when a unit fails, discards
        /// a step or Ctrl-C ends the run (then with the rows so far).
        #[arg(long, short = 'o')]
        output: PathBuf,
        /// For a system file: what a unit that discards a step (fmi2Discard) does, `stop` (end
        /// the run there with a notice, exit 0) or `error` (fail); overrides the file's
        /// `[simulation] on_discard` (default stop).
        #[arg(long, value_parser = parse_on_discard, requires = "system")]
        on_discard: Option<fmi2_cosim::OnDiscard>,
    },
    /// Run the paper's experiments end to end through the master and the FMUs, for the built-in
    /// arm or your own of 2 to 8 joints: friction and gravity identification, training, Table 1,
    /// gravity compensation. Writes the FMUs, data, nets, plots, report.md and results.json
    /// (every figure, for scripts) to the output folder, which appears only when the run has
    /// finished.
    Paper {
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
        /// Task-space gains K_p [1/s²], K_d [1/s] (default 1000,160).
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
        #[arg(long, value_parser = parse_encoding)]
        gravity_inputs: Option<InputEncoding>,
        /// Also measure the gravity error against the number of poses (grids and sampled designs
        /// up to N poses, every input encoding) for the report: adds minutes to a full run.
        #[arg(long, value_name = "N", value_parser = clap::value_parser!(u64).range(30..=20_000))]
        gravity_study: Option<u64>,
        /// Average the gravity passes as measured (the paper's procedure) instead of first
        /// taking the identified friction out of each.
        #[arg(long)]
        gravity_plain_average: bool,
    },
    /// Print the default arm configuration as TOML, a starting point for your own arm.
    DefaultConfig {
        /// Where to write it (default `-`: standard output).
        #[arg(long, short = 'o', default_value = "-")]
        output: PathBuf,
    },
    /// Write the paper's experiments as plans a robot's own controller can play (CSV with units in
    /// the header, and a .txt beside it that says how to run them).
    #[command(subcommand)]
    Plan(PlanCommand),
    /// Make training pairs from a robot's logs (CSV: time and per joint q_i, qd_i, tau_i).
    #[command(subcommand)]
    Identify(IdentifyCommand),
    /// The whole path from logs to an FMU: identify friction (and gravity), train the nets, export
    /// the NnCompensator; every intermediate file is kept in a folder.
    Compensator {
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
    },
    /// Build an FMI 2.0 Co-Simulation FMU.
    #[command(subcommand)]
    Export(Export),
    /// Train a two-layer network (tansig hidden layer, linear output) with Levenberg–Marquardt.
    ///
    /// The data CSV has a header; each row is one sample. Defaults follow MATLAB's trainlm
    /// (μ 0.001, ×0.1 / ×10, 1000 epochs, 6 validation failures, 70/15/15 random split).
    Train {
        /// Training pairs (CSV with a header).
        #[arg(long, short = 'd')]
        data: PathBuf,
        /// Input columns, comma-separated.
        #[arg(long, value_delimiter = ',', required = true)]
        inputs: Vec<String>,
        /// Target columns, comma-separated.
        #[arg(long, value_delimiter = ',', required = true)]
        targets: Vec<String>,
        /// Hidden neurons.
        #[arg(long, default_value_t = 10)]
        hidden: usize,
        /// Trainings from different initial weights; the best on validation is kept.
        #[arg(long, default_value_t = 1)]
        restarts: usize,
        /// Seed of the split and the initial weights.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Largest number of epochs.
        #[arg(long, default_value_t = 1000)]
        epochs: usize,
        /// Validation failures in a row that stop training.
        #[arg(long, default_value_t = 6)]
        max_fail: usize,
        /// Train/validation/test fractions summing to 1: `0.7,0.15,0.15` or `0.7 0.15 0.15`.
        /// Each part used needs a few samples (training 10, validation and test 3 each:
        /// 17 samples at the default split).
        #[arg(long, value_delimiter = ',', num_args = 1..=3, default_values_t = [0.70, 0.15, 0.15])]
        split: Vec<f64>,
        /// What the net computes, recorded in the weights file so that `export compensator`
        /// can check it: friction (one joint's torque from its velocity), gravity (all joints'
        /// torques from all angles) or unspecified. Inferred when omitted: one input `qd_J` →
        /// friction of joint J; inputs `q_1…q_n` and n targets → gravity; else unspecified.
        #[arg(long, value_parser = parse_kind)]
        kind: Option<NetKind>,
        /// The joint (1-based) of a friction net; inferred from an input named `qd_J`.
        #[arg(long)]
        joint: Option<usize>,
        /// How the net sees the inputs: raw, joint-angles ((cos, sin) of each input angle
        /// [rad]) or link-angles ((cos, sin) of the running sums q₁+…+qⱼ); the angle forms are
        /// 2π-periodic in every input.
        #[arg(long, value_parser = parse_encoding, default_value = "raw")]
        encoding: InputEncoding,
        /// How μ changes: trainlm (MATLAB's ×0.1 / ×10, the default) or nielsen (Nielsen's
        /// gain-ratio rule, which needs fewer epochs on the gravity benches).
        #[arg(long, value_parser = parse_damping, default_value = "trainlm")]
        damping: Damping,
        /// Output weights file (JSON; `-`: standard output).
        #[arg(long, short = 'o')]
        output: PathBuf,
    },
    /// Apply a trained network to the input columns of a CSV; writes inputs and outputs.
    Eval {
        /// Weights file (JSON).
        #[arg(long, short = 'n')]
        net: PathBuf,
        /// Input CSV with the net's input columns.
        #[arg(long, short = 'd')]
        data: PathBuf,
        /// Output CSV (`-`: standard output).
        #[arg(long, short = 'o')]
        output: PathBuf,
    },
}

#[derive(Subcommand)]
enum PlanCommand {
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

/// The column names of a log; `{i}` stands for the joint number.
#[derive(Args, Clone)]
struct LogColumnArgs {
    /// Time column [s].
    #[arg(long, default_value = "time")]
    time_column: String,
    /// Angle columns [rad].
    #[arg(long, default_value = "q_{i}")]
    q_column: String,
    /// Speed columns [rad/s].
    #[arg(long, default_value = "qd_{i}")]
    qd_column: String,
    /// Torque columns [N·m].
    #[arg(long, default_value = "tau_{i}")]
    tau_column: String,
}

impl LogColumnArgs {
    fn columns(&self) -> neurarm::identify::LogColumns {
        neurarm::identify::LogColumns {
            time: self.time_column.clone(),
            q: self.q_column.clone(),
            qd: self.qd_column.clone(),
            tau: self.tau_column.clone(),
        }
    }
}

#[derive(Subcommand)]
enum IdentifyCommand {
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
        /// Output .fmu file (`-` is refused: pipe it with /dev/stdout).
        #[arg(long, short = 'o')]
        output: PathBuf,
    },
    /// The NN compensator as an FMU (`NnCompensator`): inputs q_i, qd_i; outputs the friction,
    /// gravity and total compensating torques; Boolean parameters enable each part.
    ///
    /// With `--ideal`, the ideal compensator instead (`IdealCompensator`): the true friction and
    /// gravity torques of the arm in `-c` (default: the built-in arm), with the same ports;
    /// `--friction` and `--gravity`, without files, choose the parts switched on (both if
    /// neither is given).
    ///
    /// With `--adaptive`, the adaptive compensator (`AdaptiveCompensator`): the same nets as
    /// its start, whose output layers keep learning from the controller's learning signal
    /// `s_i` (inputs `s_i`; parameters adapt, gain_friction, gain_gravity, leakage,
    /// bound_friction, bound_gravity).
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
}

#[derive(Subcommand)]
enum Controller {
    /// `TaskSpaceController`: computed torque tracking the paper's curve, placed for the arm.
    ///
    /// Inputs q_i [rad], qd_i [rad/s], tau_comp_i [N·m]; outputs tau_i [N·m], x_ref, y_ref and
    /// error_x, error_y [m]. The curve is scaled by the arm's reach R (the sum of its link
    /// lengths, scale R / 1 m) and centred at (0.45 R, 0.10 R), so it stays between 0.23 R
    /// and 0.84 R from the first joint; `--centre` and `--scale` override that, and a curve the
    /// arm cannot reach is refused with the reach it needs. The angle inputs start at the pose
    /// that puts the end effector at the curve's start.
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
        #[arg(long, default_value_t = 10.0)]
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
        let config = load_config(self.config)?;
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
        Command::Simulate { system: Some(system), output, on_discard, .. } => {
            use neurarm::system_run::{run_system_file, SystemRunEnd};
            let run = run_system_file(&system, &output, on_discard)?;
            for notice in &run.notices {
                eprintln!("notice: {notice}");
            }
            let last = run.last_time.map_or(String::new(), |t| format!(", the last at t = {t} s"));
            match run.end {
                SystemRunEnd::Completed | SystemRunEnd::Discarded => eprintln!("wrote {} rows to {}{last}", run.rows, describe(&output)),
                SystemRunEnd::Interrupted(t) => {
                    return Err(
                        Interrupted(format!("interrupted at t = {t} s; the {} rows so far are in {}", run.rows, describe(&output))).into()
                    )
                }
                SystemRunEnd::Failed(e) => bail!("{e}\n(the {} rows recorded before the failure are in {})", run.rows, describe(&output)),
            }
        }
        Command::Paper {
            config,
            real,
            output,
            quick,
            threads,
            seed,
            centre,
            scale,
            tracking_gains,
            joint_gains,
            gravity_poses,
            gravity_grid,
            gravity_inputs,
            gravity_study,
            gravity_plain_average,
        } => {
            use neurarm::experiments::{paper::run_paper, Arms, GravityDesign, Settings};
            let mut settings = if quick { Settings::quick() } else { Settings::paper() };
            if let Some(s) = seed {
                settings.seed = s;
            }
            if let Some(t) = threads {
                settings.threads = t.max(1);
            }
            if let Some(g) = tracking_gains {
                let (kp, kd) = gain_pair("--tracking-gains", &g)?;
                settings.tracking_gains.kp = kp;
                settings.tracking_gains.kd = kd;
            }
            if let Some(poses) = gravity_poses {
                settings.gravity_design = Some(GravityDesign::Sampled { poses: poses as usize });
            }
            if let Some(per_joint) = gravity_grid {
                settings.gravity_design = Some(GravityDesign::Grid { per_joint: per_joint as usize });
            }
            if let Some(encoding) = gravity_inputs {
                settings.gravity_encoding = encoding;
            }
            settings.gravity_friction_correction = !gravity_plain_average;
            settings.gravity_study = gravity_study.map(|n| n as usize);
            if let Some(g) = joint_gains {
                (settings.joint_kp, settings.joint_kd) = gain_pair("--joint-gains", &g)?;
                settings.scale_joint_gains = false;
            }
            let nominal = load_config(config.clone())?;
            let real = match real {
                Some(path) => Some((ArmConfig::from_toml_file(&path)?, path.display().to_string())),
                None => None,
            };
            let placement = match (centre, scale) {
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
            let arm_name = config.map_or("the built-in arm".to_owned(), |c| c.display().to_string());
            let arms = Arms::new(nominal, real, placement).map_err(|e| anyhow::anyhow!("{arm_name}: {e}"))?;
            let run = run_paper(&output, &arms, &settings, &mut |line| eprintln!("[paper] {line}"))
                .map_err(|e| anyhow::anyhow!("{e}\n(no run was written to {})", output.display()))?;
            let t = &run.results.table_1;
            let (m, q) = (&t.mse_m2, &t.ratios);
            eprintln!(
                "Table 1 MSE [m²]: sim perfect {:.3e}, NN {:.3e}, none {:.3e}; real NN {:.3e}, none {:.3e}\nratios: sim NN/perfect {:.3}, none/perfect {:.1}; real NN/none {:.3}",
                m.sim_perfect, m.sim_nn, m.sim_none, m.real_nn, m.real_none, q.sim_nn_over_perfect, q.sim_none_over_perfect, q.real_nn_over_none
            );
            eprintln!("wrote {} and {}", output.join("report.md").display(), output.join("results.json").display());
        }
        Command::Simulate { plan: Some(plan), arm, output, step, every, base_angle, robot_log, .. } => {
            let (mut config, initial) = arm.load()?;
            if let Some(angle) = base_angle {
                config.arm = config.arm.with_base_angle(angle);
            }
            if !(step > 0.0 && step.is_finite()) {
                bail!("--step must be a positive number of seconds (got {step})");
            }
            let plan = neurarm::simulate::Plan::read_csv(&plan, config.arm.dof())?;
            let initial = ArmState { q: plan.start(&initial.q), qd: initial.qd };
            let mut trajectory = neurarm::simulate::simulate_plan(&config, &initial, &plan, step, every as usize)?;
            if robot_log {
                trajectory = trajectory.as_robot_log();
            }
            let rows = trajectory.rows.len();
            write_atomic(&output, &trajectory.names, trajectory.rows.into_iter())
                .with_context(|| format!("writing {}", describe(&output)))?;
            eprintln!("wrote {rows} rows to {}", describe(&output));
        }
        Command::Simulate { torque, arm, output, base_angle, .. } => {
            let torque = torque.expect("clap requires --torque without a system file");
            let (mut config, initial) = arm.load()?;
            if let Some(angle) = base_angle {
                config.arm = config.arm.with_base_angle(angle);
            }
            let input = TorqueInput::read_csv(&torque, config.arm.dof())?;
            let trajectory = simulate(&config, &initial, &input)?;
            write_atomic(&output, &trajectory.names, trajectory.rows.into_iter())
                .with_context(|| format!("writing {}", describe(&output)))?;
            eprintln!("wrote {} rows to {}", input.time.len(), describe(&output));
        }
        Command::DefaultConfig { output } => {
            write_text_atomic(&output, &ArmConfig::default().to_toml_string()).with_context(|| format!("writing {}", describe(&output)))?;
            if !neurarm::output::is_stdout(&output) {
                eprintln!("wrote {}", output.display());
            }
        }
        Command::Plan(PlanCommand::Friction { config, joints, max_speed, spacing, output }) => {
            let source = config.as_ref().map_or("the built-in arm".to_owned(), |c| c.display().to_string());
            let arm = load_config(config)?.arm;
            let mut settings = neurarm::plan::FrictionPlanSettings::for_joints(arm.dof());
            if let Some(j) = joints {
                settings.joints = j;
            }
            settings.max_speed_rad_s = max_speed;
            settings.spacing_rad_s = spacing;
            let plan = neurarm::plan::friction_plan(&arm, &settings).map_err(anyhow::Error::msg)?;
            let instructions = plan.instructions(&source);
            let notes = neurarm::plan::write_plan(&output, &plan.to_csv(), &instructions).map_err(anyhow::Error::msg)?;
            let what = format!("{} segments, {:.0} s", plan.segments.len(), plan.end_s);
            say_plan_written(&output, &what, notes.as_deref(), &instructions);
        }
        Command::Plan(PlanCommand::Gravity { config, poses, grid, speed, pass_time, seed, output }) => {
            use neurarm::experiments::GravityDesign;
            let source = config.as_ref().map_or("the built-in arm".to_owned(), |c| c.display().to_string());
            let n = load_config(config)?.arm.dof();
            let design = match (poses, grid) {
                (Some(poses), _) => GravityDesign::Sampled { poses },
                (None, Some(per_joint)) => GravityDesign::Grid { per_joint },
                (None, None) => neurarm::experiments::Settings::paper().design_for(n),
            };
            let settings = neurarm::plan::GravityPlanSettings { design, speed_rad_s: speed, pass_s: pass_time, seed };
            let plan = neurarm::plan::gravity_plan(n, &settings).map_err(anyhow::Error::msg)?;
            let instructions = plan.instructions(&source, &settings);
            let notes = neurarm::plan::write_plan(&output, &plan.to_csv(), &instructions).map_err(anyhow::Error::msg)?;
            say_plan_written(&output, &format!("{} poses, {:.0} s", plan.poses, plan.end_s), notes.as_deref(), &instructions);
        }
        Command::Identify(IdentifyCommand::Friction { log, joint, columns, bin_width, window, drift, spread, inertia, output }) => {
            let columns = columns.columns();
            columns.check().map_err(anyhow::Error::msg)?;
            let options = neurarm::identify::FrictionOptions {
                bin_width_rad_s: bin_width,
                window_s: window,
                drift_rad_s: drift,
                spread_rad_s: spread,
                inertia_kgm2: inertia,
                ..Default::default()
            };
            options.check().map_err(anyhow::Error::msg)?;
            neurarm::logs::report_path(&output).map_err(anyhow::Error::msg)?;
            let robot_log = neurarm::identify::RobotLog::read_joint(&log, &columns, joint)?;
            let found = neurarm::identify::identify_friction_log(&robot_log, joint, &options).map_err(anyhow::Error::msg)?;
            eprint!("{}", neurarm::logs::friction_summary(joint, &found));
            let report = neurarm::logs::write_friction_pairs(&output, joint, &found).map_err(anyhow::Error::msg)?;
            say_pairs_written(&output, found.pairs.len(), report.as_deref());
        }
        Command::Identify(IdentifyCommand::Gravity { log, columns, friction, config, speed, window, output }) => {
            let columns = columns.columns();
            columns.check().map_err(anyhow::Error::msg)?;
            let options = neurarm::identify::GravityOptions { speed_rad_s: speed, window_s: window, ..Default::default() };
            options.check().map_err(anyhow::Error::msg)?;
            neurarm::logs::report_path(&output).map_err(anyhow::Error::msg)?;
            let model = match config {
                Some(c) => Some(ArmConfig::from_toml_file(&c)?.arm.with_base_angle(0.0).frictionless()),
                None => None,
            };
            let mut curves = Vec::new();
            for (k, path) in friction.unwrap_or_default().iter().enumerate() {
                let (joint, pairs) = neurarm::logs::read_friction_pairs(path).map_err(anyhow::Error::msg)?;
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
            let found = neurarm::identify::identify_gravity_log(&robot_log, &options, &correction).map_err(anyhow::Error::msg)?;
            eprint!("{}", neurarm::logs::gravity_summary(&found));
            let report = neurarm::logs::write_gravity_pairs(&output, &found).map_err(anyhow::Error::msg)?;
            say_pairs_written(&output, found.pairs.len(), report.as_deref());
        }
        Command::Compensator { friction_log, gravity_log, config, work, seed, name, columns, pass_speed, output } => {
            let model = match config {
                Some(c) => Some(ArmConfig::from_toml_file(&c)?.arm),
                None => None,
            };
            neurarm::export::refuse_stdout(&output).map_err(anyhow::Error::msg)?;
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
            };
            let bar = EpochBar::new(None);
            let summary =
                neurarm::logs::compensator_from_logs(&job, &mut |line| bar.println(&format!("[compensator] {line}")), &mut |e| bar.show(e))
                    .map_err(anyhow::Error::msg);
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
        }
        Command::Train {
            data,
            inputs,
            targets,
            hidden,
            restarts,
            seed,
            epochs,
            max_fail,
            split,
            kind,
            joint,
            encoding,
            damping,
            output,
        } => {
            let [a, b, c] = split[..] else {
                bail!("--split takes three fractions (train, validation, test), e.g. 0.7,0.15,0.15; got {}", split.len())
            };
            let settings = TrainSettings { hidden, restarts, seed, epochs, max_fail, split: [a, b, c], damping, ..Default::default() };
            let (kind, joint) = net_kind(kind, joint, &inputs, &targets)?;
            let weights = train_from_csv(&data, &inputs, &targets, encoding, settings)?;
            let weights = match kind {
                NetKind::Friction => weights.friction_of_joint(joint.expect("a friction net has a joint")),
                NetKind::Gravity => weights.gravity(),
                NetKind::Unspecified => weights,
            };
            weights.network().map_err(|e| anyhow::anyhow!("--kind {}: {e}", kind.name()))?;
            write_text_atomic(&output, &weights.to_json()).with_context(|| format!("writing {}", describe(&output)))?;
            let r = &weights.report;
            let rms = |v: Option<f64>| v.map_or("-".into(), |v| format!("{:.3e}", v.sqrt()));
            let unit = weights.outputs[0].unit.as_str();
            eprintln!(
                "wrote {} ({}): {} epochs (best {}), stopped by {}; RMS error train {}, validation {}, test {} [{}] on {}/{}/{} samples",
                describe(&output),
                weights.describe(),
                r.epochs,
                r.best_epoch,
                stop_reason_text(r.stop_reason),
                rms(Some(r.train_mse)),
                rms(r.validation_mse),
                rms(r.test_mse),
                if unit.is_empty() { "target units" } else { unit },
                r.counts[0],
                r.counts[1],
                r.counts[2]
            );
        }
        Command::Eval { net, data, output } => {
            let weights = WeightsFile::read(&net)?;
            let mlp = weights.network().map_err(anyhow::Error::msg)?;
            let names: Vec<&str> = weights.inputs.iter().map(|s| s.name.as_str()).collect();
            let table = NumericTable::read(&data, &names)?;
            let columns: Vec<&[f64]> = names.iter().map(|n| table.column(n).expect("required")).collect();
            let mut header: Vec<String> = names.iter().map(|s| s.to_string()).collect();
            header.extend(weights.outputs.iter().map(|s| s.name.clone()));
            let mut rows = Vec::with_capacity(table.rows());
            for r in 0..table.rows() {
                let x: Vec<f64> = columns.iter().map(|c| c[r]).collect();
                let y = mlp.evaluate(&x);
                // Checked before anything is written: an input far outside the net's training
                // range can overflow it, and a table with inf in it is no result.
                if let Some(k) = y.iter().position(|v| !v.is_finite()) {
                    bail!(
                        "{}, line {}: the net's output '{}' is {} for these inputs (far outside the range it was trained on?); nothing was written",
                        data.display(),
                        table.line(r),
                        weights.outputs[k].name,
                        neurarm_physics::arm::show_number(y[k])
                    );
                }
                let mut row = x;
                row.extend(y);
                rows.push(row);
            }
            write_atomic(&output, &header, rows.into_iter()).with_context(|| format!("writing {}", describe(&output)))?;
            eprintln!("wrote {} rows to {}", table.rows(), describe(&output));
        }
        Command::Export(Export::Compensator { friction, gravity, ideal: true, adaptive: _, config, name, output }) => {
            if friction.as_ref().is_some_and(|f| !f.is_empty()) || gravity.as_ref().is_some_and(|g| g.is_some()) {
                bail!(
                    "--ideal takes no weights files: it computes the arm's true torques (--friction and --gravity alone choose the parts)"
                );
            }
            let arm = load_config(config)?.arm;
            let n = arm.dof();
            let (enable_friction, enable_gravity) = match (friction.is_some(), gravity.is_some()) {
                (false, false) => (true, true),
                chosen => chosen,
            };
            let identifier = identifier_for(name, &output, "IdealCompensator");
            let model = ModelSpec::IdealCompensator(IdealCompensatorSpec { arm, enable_friction, enable_gravity });
            export(FmuSpec { identifier, model }, &[], &output, n)?;
        }
        Command::Export(Export::Compensator { friction, gravity, ideal: false, adaptive, config: _, name, output }) => {
            let friction = friction.unwrap_or_default();
            let gravity = gravity.flatten();
            let identifier = identifier_for(name, &output, if adaptive { "AdaptiveCompensator" } else { "NnCompensator" });
            if friction.is_empty() && gravity.is_none() {
                bail!("give --friction nets, a --gravity net, or both (or --ideal for the arm's true torques)");
            }
            // Checked here, by the user's file names, before anything is packed.
            let friction_files = friction.iter().map(|p| WeightsFile::read(p)).collect::<Result<Vec<_>, _>>()?;
            let gravity_file = gravity.as_ref().map(|g| WeightsFile::read(g)).transpose()?;
            let names: Vec<String> = friction.iter().chain(&gravity).map(|p| p.display().to_string()).collect();
            let named: Vec<(&str, &WeightsFile)> = names.iter().map(String::as_str).zip(&friction_files).collect();
            let joints =
                neurarm_models::check_compensator_nets(&named, names.get(friction.len()).map(String::as_str).zip(gravity_file.as_ref()))
                    .map_err(anyhow::Error::msg)?;
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
            let spec = NnCompensatorSpec {
                joints,
                friction: (1..=friction.len()).map(|i| format!("friction_{i}.json")).collect(),
                gravity: gravity.as_ref().map(|_| "gravity.json".to_owned()),
                enable_friction: !friction.is_empty(),
                enable_gravity: gravity.is_some(),
            };
            let model = if adaptive {
                ModelSpec::AdaptiveCompensator(AdaptiveCompensatorSpec {
                    joints: spec.joints,
                    friction: spec.friction,
                    gravity: spec.gravity,
                    enable_friction: spec.enable_friction,
                    enable_gravity: spec.enable_gravity,
                    law: AdaptationLaw::default(),
                })
            } else {
                ModelSpec::NnCompensator(spec)
            };
            export(FmuSpec { identifier, model }, &sources, &output, joints)?;
        }
        Command::Export(Export::Controller(Controller::TaskSpace { config, kp, kd, null_damping, centre, scale, name, output })) => {
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
            let start = neurarm::experiments::tracking_start(&arm, &placement).map_err(anyhow::Error::msg)?;
            let model = ModelSpec::TaskSpaceController(TaskSpaceControllerSpec {
                model: arm.frictionless(),
                gains: TaskSpaceGains { kp, kd, null_damping, ..TaskSpaceGains::default() },
                centre: [placement.centre.x, placement.centre.y],
                scale: placement.scale,
                q_start: start.q,
            });
            let identifier = identifier_for(name, &output, "TaskSpaceController");
            export(FmuSpec { identifier, model }, &[], &output, n)?;
        }
        Command::Export(Export::Controller(Controller::Joint { config, joints, kp, kd, sequence, name, output })) => {
            let joints = match joints {
                Some(n) => n,
                None => load_config(config)?.arm.dof(),
            };
            let identifier = identifier_for(name, &output, "JointController");
            let model = ModelSpec::JointController(JointControllerSpec { joints, kp, kd, use_sequence: sequence });
            export(FmuSpec { identifier, model }, &[], &output, joints)?;
        }
        Command::Export(Export::Arm { arm, name, output }) => {
            let (config, initial) = arm.load()?;
            let n = config.arm.dof();
            let identifier = identifier_for(name, &output, "PlanarArm");
            let model = ModelSpec::PlanarArm(PlanarArmSpec { config, q0: initial.q, qd0: initial.qd });
            export(FmuSpec { identifier, model }, &[], &output, n)?;
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

/// Says where identified pairs went, and where their verdicts went.
fn say_pairs_written(output: &std::path::Path, pairs: usize, report: Option<&std::path::Path>) {
    match report {
        Some(report) => eprintln!("wrote {pairs} pairs to {} and the verdicts to {}", output.display(), report.display()),
        None => eprintln!("wrote {pairs} pairs to {} (no .json of verdicts beside it: the summary above has them)", describe(output)),
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

/// The arm configuration in `path`, or the built-in arm.
fn load_config(path: Option<PathBuf>) -> Result<ArmConfig> {
    Ok(match path {
        Some(path) => ArmConfig::from_toml_file(&path)?,
        None => ArmConfig::default(),
    })
}

/// Writes the FMU of `spec` and says so.
fn export(spec: FmuSpec, sources: &[(String, PathBuf)], output: &std::path::Path, joints: usize) -> Result<()> {
    export_fmu(&spec, sources, output).map_err(anyhow::Error::msg)?;
    eprintln!("wrote {} ({}, {joints} joints)", output.display(), spec.identifier);
    Ok(())
}

/// The model identifier: as given, or the output file's name.
fn identifier_for(name: Option<String>, output: &std::path::Path, fallback: &str) -> String {
    name.unwrap_or_else(|| output.file_stem().and_then(|s| s.to_str()).unwrap_or(fallback).to_owned())
}

/// A unit guessed from a column name by the project's naming: q… rad, qd… rad/s, tau… N.m.
fn unit_of(name: &str) -> String {
    let unit = if name.starts_with("qd") {
        "rad/s"
    } else if name.starts_with('q') {
        "rad"
    } else if name.starts_with("tau") {
        "N.m"
    } else {
        ""
    };
    unit.to_owned()
}

/// Training progress on a terminal (restart, epoch, errors, μ); nothing otherwise.
struct EpochBar {
    bar: ProgressBar,
    epochs: usize,
}

impl EpochBar {
    /// A bar over `epochs × restarts` epochs, or a counter when the length is not known.
    fn new(length: Option<(usize, usize)>) -> Self {
        let terminal = std::io::stderr().is_terminal();
        let (bar, epochs) = match (terminal, length) {
            (false, _) => (ProgressBar::hidden(), 0),
            (true, Some((epochs, restarts))) => (ProgressBar::new(epochs.saturating_mul(restarts) as u64), epochs),
            (true, None) => (ProgressBar::new_spinner(), 0),
        };
        let template = if length.is_some() { "{bar:30} restart {prefix} {msg}" } else { "{spinner} training: restart {prefix} {msg}" };
        bar.set_style(ProgressStyle::with_template(template).expect("valid template"));
        Self { bar, epochs }
    }

    /// Shows one epoch (errors in scaled units, as the trainer sees them).
    fn show(&self, e: &neurarm_physics::nn::EpochInfo<'_>) {
        self.bar.set_prefix((e.restart + 1).to_string());
        if self.epochs > 0 {
            self.bar.set_position((e.restart * self.epochs + e.epoch) as u64);
        } else {
            self.bar.tick();
        }
        self.bar.set_message(format!("epoch {} MSE {:.3e} val {:.3e} mu {:.0e} (scaled)", e.epoch, e.train_mse, e.validation_mse, e.mu));
    }

    /// A line above the bar.
    fn println(&self, line: &str) {
        if self.bar.is_hidden() {
            eprintln!("{line}");
        } else {
            self.bar.println(line);
        }
    }

    fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// Reads the pairs, checks them, trains with progress on a terminal, and wraps the result.
fn train_from_csv(
    data: &std::path::Path,
    inputs: &[String],
    targets: &[String],
    encoding: InputEncoding,
    settings: TrainSettings,
) -> Result<WeightsFile> {
    let required: Vec<&str> = inputs.iter().chain(targets).map(String::as_str).collect();
    if let Some(name) = required.iter().enumerate().find_map(|(i, n)| required[..i].contains(n).then_some(n)) {
        bail!("column '{name}' is named twice in --inputs/--targets");
    }
    let table = NumericTable::read(data, &required)?;
    for name in inputs {
        let column = table.column(name).expect("required");
        if column.iter().all(|&v| v == column[0]) {
            bail!(
                "{}: input column '{name}' is constant ({} in all {} rows): it carries nothing to learn from",
                data.display(),
                column[0],
                table.rows()
            );
        }
    }
    let matrix = |names: &[String]| {
        let cols: Vec<&[f64]> = names.iter().map(|n| table.column(n).expect("required")).collect();
        DMatrix::from_fn(names.len(), table.rows(), |r, c| cols[r][c])
    };
    let raw = matrix(inputs);
    neurarm_physics::nn::lm::check_settings(&settings, encoding.features(inputs.len()), targets.len(), table.rows())
        .map_err(|e| anyhow::anyhow!("{}: {e}", data.display()))?;
    if let Some(warning) = neurarm_physics::nn::lm::time_series_warning(&raw) {
        eprintln!("warning: {}: {warning}", data.display());
    }
    let weights = neurarm_physics::nn::lm::weight_count(encoding.features(inputs.len()), settings.hidden, targets.len()).unwrap_or(0);
    let training_values = neurarm_physics::nn::lm::split(table.rows(), settings.split, settings.seed)[0].len() * targets.len();
    if weights > training_values {
        eprintln!(
            "notice: the net has {weights} weights for {training_values} training target values: it can fit noise; validation stopping is what holds it"
        );
    }
    let (x, t) = (encoding.encode_all(&raw), matrix(targets));
    let bar = EpochBar::new(Some((settings.epochs, settings.restarts)));
    let trained = train(&x, &t, &settings, &mut |e| bar.show(e));
    bar.finish();
    let trained = trained?;
    // A unit in the header (`qd_1 [rad/s]`) is the unit; otherwise it is guessed from the name.
    let signals = |names: &[String]| {
        names.iter().map(|n| Signal { name: n.clone(), unit: table.unit(n).map_or_else(|| unit_of(n), str::to_owned) }).collect()
    };
    Ok(WeightsFile::new(&trained.net, signals(inputs), signals(targets), settings, trained.report).with_encoding(encoding))
}

/// Parses a damping rule for clap.
fn parse_on_discard(text: &str) -> std::result::Result<fmi2_cosim::OnDiscard, String> {
    match text {
        "stop" => Ok(fmi2_cosim::OnDiscard::Stop),
        "error" => Ok(fmi2_cosim::OnDiscard::Error),
        _ => Err(format!("'{text}': use stop or error")),
    }
}

fn parse_damping(text: &str) -> std::result::Result<Damping, String> {
    match text.trim() {
        "trainlm" => Ok(Damping::Trainlm),
        "nielsen" => Ok(Damping::Nielsen),
        other => Err(format!("unknown damping '{other}': use trainlm or nielsen")),
    }
}

/// Parses a net kind for clap.
fn parse_kind(text: &str) -> std::result::Result<NetKind, String> {
    NetKind::parse(text)
}

/// A stop reason as words.
fn stop_reason_text(reason: neurarm_physics::nn::StopReason) -> &'static str {
    use neurarm_physics::nn::StopReason::*;
    match reason {
        Epochs => "the epoch limit",
        Goal => "the error goal",
        MinGradient => "a vanishing gradient",
        MuMax => "mu reaching its limit",
        ValidationFailures => "validation failures",
    }
}

/// The joint J of a column named `<prefix>J`.
fn joint_of(name: &str, prefix: &str) -> Option<usize> {
    name.strip_prefix(prefix)?.parse().ok().filter(|&j| j >= 1)
}

/// The kind and joint of a net to be trained: as given, or inferred from the column names
/// (documented on `train --kind`).
fn net_kind(kind: Option<NetKind>, joint: Option<usize>, inputs: &[String], targets: &[String]) -> Result<(NetKind, Option<usize>)> {
    let friction_joint = match inputs {
        [only] if targets.len() == 1 => joint_of(only, "qd_"),
        _ => None,
    };
    let is_gravity = inputs.len() == targets.len() && inputs.iter().enumerate().all(|(i, n)| joint_of(n, "q_") == Some(i + 1));
    let kind = kind.unwrap_or(if friction_joint.is_some() || joint.is_some() {
        NetKind::Friction
    } else if is_gravity {
        NetKind::Gravity
    } else {
        NetKind::Unspecified
    });
    match kind {
        NetKind::Friction => {
            if inputs.len() != 1 || targets.len() != 1 {
                bail!(
                    "a friction net has one input (the joint's velocity) and one target (its torque), not {} and {}",
                    inputs.len(),
                    targets.len()
                );
            }
            match (joint, friction_joint) {
                (Some(0), _) => bail!("--joint 0: joints are numbered from 1"),
                (Some(j), Some(named)) if j != named => {
                    bail!("--joint {j} but the input is '{}', the velocity of joint {named}", inputs[0])
                }
                (Some(j), _) | (None, Some(j)) => Ok((kind, Some(j))),
                (None, None) => {
                    bail!("a friction net needs its joint: give --joint J (the input '{}' does not name it as qd_J)", inputs[0])
                }
            }
        }
        _ if joint.is_some() => bail!("--joint is for friction nets; this one is {}", kind.name()),
        NetKind::Gravity if inputs.len() != targets.len() => {
            bail!("a gravity net has one torque target per angle input, not {} inputs and {} targets", inputs.len(), targets.len())
        }
        _ => Ok((kind, None)),
    }
}

/// Parses an input encoding for clap.
fn parse_encoding(text: &str) -> std::result::Result<InputEncoding, String> {
    InputEncoding::parse(text)
}

/// A run ended by Ctrl-C: its message, and exit status 130 (128 + SIGINT) as a shell gives.
#[derive(Debug)]
struct Interrupted(String);

impl std::fmt::Display for Interrupted {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Interrupted {}

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
