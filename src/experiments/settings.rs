//! What a run is made of: its sizes, durations and gains ([`Settings`]) and its arms
//! ([`Arms`]: the nominal one, the real one, emulated or given, and the reference placement).

use std::f64::consts::PI;

use anyhow::{bail, Context, Result};
use serde::Serialize;

use super::{tracking_start, FrictionHold};
use neurarm_nn::InputEncoding;
use neurarm_physics::arm::FrictionBranch;
use neurarm_physics::config::ArmConfig;
use neurarm_physics::control::{ReferencePlacement, TaskSpaceGains};

/// Fewest joints the experiments take: the task-space loop tracks a planar position.
pub const MIN_JOINTS: usize = 2;
/// Most joints the experiments take (the gravity grid and the hold gains grow as kⁿ).
pub const MAX_JOINTS: usize = 8;

/// Sizes, durations and gains of the experiments. [`Settings::paper`] is the full run,
/// [`Settings::quick`] a reduced one for tests.
#[derive(Clone, Debug, Serialize)]
pub struct Settings {
    /// Communication step [s].
    pub step: f64,
    /// Gravity grid points per joint of the default design (the paper: 7); see
    /// [`Settings::design_for`].
    pub grid: usize,
    /// Poses of the gravity identification: a grid or a sampled design; none for the default
    /// of the joint count ([`Settings::design_for`]).
    pub gravity_design: Option<GravityDesign>,
    /// How the gravity net sees the angles: periodic link angles by default; `Raw` is the
    /// paper's net (then also trained beside a periodic one for the report).
    pub gravity_encoding: InputEncoding,
    /// Also run the gravity study (error against measured poses, grid vs sampled, every
    /// encoding) up to this many poses; none to skip it.
    pub gravity_study: Option<usize>,
    /// Take the identified friction out of each gravity pass before averaging (keeps friction
    /// that differs with the direction out of the pairs); false is the paper's plain average.
    pub gravity_friction_correction: bool,
    /// Largest joint speed of the friction experiment [rad/s] (the paper: 5).
    pub max_velocity: f64,
    /// Wanted spacing of the steady velocities of successive torque levels [rad/s].
    pub velocity_spacing: f64,
    /// Bin width of the friction data [rad/s] (the paper: 0.05).
    pub bin_width: f64,
    /// How the friction runs hold the other joints.
    pub friction_hold: FrictionHold,
    /// Length of each tracking run [s].
    pub tracking_duration: f64,
    /// Gains of the task-space controller (acceleration level, so they need no scaling with
    /// the arm).
    pub tracking_gains: TaskSpaceGains,
    /// Look-ahead [s] of the speed the task-space loops' compensators are fed: with `Some(h)`
    /// they get the controller's `qd_intended = q̇ + h u` (u the commanded joint
    /// acceleration) instead of the measured q̇, so a joint at rest is compensated the way
    /// the law accelerates it; `None` (default) is the paper's measured speed.
    pub intent_horizon: Option<f64>,
    /// Random configurations the gravity net is tested on.
    pub gravity_test_points: usize,
    /// Epochs of the gravity net's training.
    pub gravity_epochs: usize,
    /// Hidden neurons of the gravity net (the paper: 25).
    pub gravity_hidden: usize,
    /// Position gain of the joint-space gravity-compensation loop [N·m/rad] for the built-in
    /// arm; scaled for other arms when `scale_joint_gains` (see [`joint_loop_gains`](super::joint_loop_gains)).
    pub joint_kp: f64,
    /// Velocity gain of that loop [N·m·s/rad] (0 in the paper's law), scaled likewise.
    pub joint_kd: f64,
    /// Scale `joint_kp`, `joint_kd` with the arm's gravity load; false takes them as given.
    pub scale_joint_gains: bool,
    /// Seed of training splits, initial weights and sensor noise.
    pub seed: u64,
    /// Worker threads.
    pub threads: usize,
    /// Whether this is the reduced run.
    pub quick: bool,
    /// The online-adaptation runs.
    pub adaptation: super::adaptation::AdaptationSettings,
    /// Platforms every FMU of the run carries (`binaries/<platform>/`): `None` for the host's
    /// and every cross build found, else exactly these (see [`crate::export::fmu_binaries`]).
    pub platforms: Option<Vec<String>>,
    /// Also write the FMI 3.0 twin of every FMU of the run into `fmu/fmi3/` (the loops run on
    /// the FMI 2.0 ones).
    pub fmi3: bool,
}

impl Settings {
    /// The full experiments.
    pub fn paper() -> Self {
        Self {
            step: 1e-3,
            grid: 7,
            gravity_design: None,
            gravity_encoding: InputEncoding::LinkAngles,
            gravity_friction_correction: true,
            gravity_study: None,
            max_velocity: 5.0,
            velocity_spacing: 0.1,
            bin_width: 0.05,
            friction_hold: FrictionHold::Rigid,
            tracking_duration: 4.0 * PI,
            tracking_gains: TaskSpaceGains::default(),
            gravity_test_points: 10_000,
            gravity_epochs: 1000,
            gravity_hidden: 25,
            joint_kp: 50.0,
            joint_kd: 2.0,
            scale_joint_gains: true,
            seed: 1,
            intent_horizon: None,
            threads: std::thread::available_parallelism().map_or(2, |n| n.get()).min(4),
            quick: false,
            adaptation: super::adaptation::AdaptationSettings::full(),
            platforms: None,
            fmi3: false,
        }
    }

    /// A reduced run for tests: a 3⁴ grid, coarse friction levels, one reference period.
    pub fn quick() -> Self {
        Self {
            grid: 3,
            tracking_duration: 2.0 * PI,
            gravity_test_points: 2000,
            gravity_epochs: 300,
            gravity_hidden: 10,
            quick: true,
            adaptation: super::adaptation::AdaptationSettings::quick(),
            ..Self::paper()
        }
    }

    /// The gravity design for an arm of `joints` joints: the one given, else the paper's
    /// `grid`ⁿ grid up to 4 joints and, beyond, `grid`⁴ poses sampled over the whole turn (the
    /// 4-joint grid's count): a 7ⁿ grid is 117 649 poses for 6 joints. Either has at least
    /// [`Settings::fewest_gravity_poses`]: a grid gets more points per joint where `grid`ⁿ
    /// would be fewer (the paper's 7² = 49 poses for 2 joints become 14² = 196).
    pub fn design_for(&self, joints: usize) -> GravityDesign {
        let fewest = self.fewest_gravity_poses(joints);
        match self.gravity_design {
            Some(design) => design,
            None if joints <= 4 => {
                let mut per_joint = self.grid.max(2);
                while per_joint.saturating_pow(joints as u32) < fewest {
                    per_joint += 1;
                }
                GravityDesign::Grid { per_joint }
            }
            None => GravityDesign::Sampled { poses: self.grid.pow(4).max(fewest) },
        }
    }

    /// Fewest poses of a default gravity design for `joints` joints: the measured pairs (one
    /// torque per joint and pose) outnumber the gravity net's weights twice. With fewer the
    /// fit is underdetermined: a 2-joint arm's 25-neuron net (177 weights) fitted to the
    /// paper's 7² poses (98 torques) was 4.5 % RMS off over the whole turn, 10² poses 0.002 %.
    pub fn fewest_gravity_poses(&self, joints: usize) -> usize {
        let inputs = self.gravity_encoding.features(joints);
        let weights = self.gravity_hidden * (inputs + 1) + joints * (self.gravity_hidden + 1);
        (2 * weights).div_ceil(joints.max(1))
    }
}

/// The poses the gravity identification measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum GravityDesign {
    /// The paper's kⁿ grid: k points per joint, 0, 2π/k, …, 2π(k−1)/k.
    Grid {
        /// Points per joint, k.
        per_joint: usize,
    },
    /// `poses` poses drawn uniformly over the whole turn [0, 2π)ⁿ (seeded), visited in a
    /// nearest-neighbour order (see `gravity::sampled_poses`).
    Sampled {
        /// Number of poses.
        poses: usize,
    },
}

impl Default for GravityDesign {
    /// The paper's 7ⁿ grid.
    fn default() -> Self {
        GravityDesign::Grid { per_joint: 7 }
    }
}

/// Most poses a gravity design may have (the sampled path's ordering is quadratic in them).
pub const MAX_GRAVITY_POSES: usize = 20_000;

impl GravityDesign {
    /// Number of poses for an arm of `joints` joints (saturating).
    pub fn poses(&self, joints: usize) -> usize {
        match *self {
            GravityDesign::Grid { per_joint } => per_joint.saturating_pow(joints as u32),
            GravityDesign::Sampled { poses } => poses,
        }
    }

    /// Refuses a design of fewer than 2 points per joint or 10 poses, or more than
    /// [`MAX_GRAVITY_POSES`] poses, naming the option to change.
    pub fn check(&self, joints: usize) -> Result<()> {
        match *self {
            GravityDesign::Grid { per_joint } if per_joint < 2 => {
                bail!("a gravity grid of {per_joint} point per joint: use at least 2 (--gravity-grid)")
            }
            GravityDesign::Grid { per_joint } if self.poses(joints) > MAX_GRAVITY_POSES => bail!(
                "a {per_joint}ⁿ gravity grid is {} poses for {joints} joints, more than {MAX_GRAVITY_POSES}: take a coarser grid \
                 (--gravity-grid) or sampled poses (--gravity-poses)",
                self.poses(joints)
            ),
            GravityDesign::Sampled { poses } if !(10..=MAX_GRAVITY_POSES).contains(&poses) => {
                bail!("{poses} gravity poses: use 10 to {MAX_GRAVITY_POSES} (--gravity-poses)")
            }
            _ => Ok(()),
        }
    }
}

/// Where the run's "real" arm comes from.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum RealOrigin {
    /// Emulated from the nominal arm by [`emulated_real_arm`].
    Emulated,
    /// The user's own configuration: their belief of the real robot.
    Given {
        /// Where it was read from.
        source: String,
    },
}

/// The arms of a run: the nominal one (the model the controllers use, and the simulated
/// arm), the "real" one, and where the task-space reference lies.
#[derive(Clone, Debug)]
pub struct Arms {
    /// The nominal arm.
    pub nominal: ArmConfig,
    /// The "real" arm, the same joint count.
    pub real: ArmConfig,
    /// Where `real` comes from.
    pub real_origin: RealOrigin,
    /// Placement of the task-space reference.
    pub placement: ReferencePlacement,
}

impl Arms {
    /// The built-in 4-joint arm with its emulated real arm and the paper's placement.
    pub fn builtin() -> Self {
        Self::new(ArmConfig::default(), None, None).expect("the built-in arm holds the reference")
    }

    /// The arms of a run on `nominal`: `real` is the user's real arm (with where it was read
    /// from), or the emulation of [`emulated_real_arm`]; `placement` overrides the reference's
    /// placement by the reach ([`ReferencePlacement::for_arm`]). Refuses, naming the cause,
    /// an arm of fewer than 2 or more than 8 joints, a real arm of another joint count, and
    /// a reference the nominal arm cannot reach from a start pose.
    pub fn new(nominal: ArmConfig, real: Option<(ArmConfig, String)>, placement: Option<ReferencePlacement>) -> Result<Self> {
        nominal.validate().context("the arm")?;
        let n = nominal.arm.dof();
        if !(MIN_JOINTS..=MAX_JOINTS).contains(&n) {
            bail!(
                "the arm has {n} joint{}; the experiments take {MIN_JOINTS} to {MAX_JOINTS} (the task-space loop needs two to place the end effector in the plane; the gravity grid and the hold gains grow as kⁿ)",
                if n == 1 { "" } else { "s" }
            );
        }
        let (real, real_origin) = match real {
            Some((real, source)) => {
                real.validate().with_context(|| format!("the real arm ({source})"))?;
                if real.arm.dof() != n {
                    bail!("the real arm ({source}) has {} joints, the arm has {n}: give one of the same joint count", real.arm.dof());
                }
                (real, RealOrigin::Given { source })
            }
            None => (emulated_real_arm(&nominal), RealOrigin::Emulated),
        };
        let placement = placement.unwrap_or_else(|| ReferencePlacement::for_arm(&nominal.arm));
        tracking_start(&nominal.arm, &placement)?;
        Ok(Self { nominal, real, real_origin, placement })
    }

    /// Number of joints.
    pub fn joints(&self) -> usize {
        self.nominal.arm.dof()
    }
}

/// The emulated "real" arm of `nominal`: its geometry with friction the nominal model does not
/// have, derived from each joint's nominal Coulomb level F_c and viscous coefficient b (means of
/// the two directions): +: Coulomb 1.1 F_c, static 1.4 F_c (Stribeck velocity 0.1 rad/s),
/// viscous 1.2 b; −: 0.8 F_c, 1.1 F_c (0.15 rad/s), 0.9 b; at joints 2 and 3 viscous friction
/// that falls with speed (halved slope at 2 rad/s), as the paper saw on its robot; noisy
/// measurements (0.0005 rad, 0.02 rad/s) and 16-bit encoders.
pub fn emulated_real_arm(nominal: &ArmConfig) -> ArmConfig {
    let mut c = nominal.clone();
    for (i, f) in c.arm.friction.iter_mut().enumerate() {
        let fc = 0.5 * (f.positive.coulomb_nm + f.negative.coulomb_nm);
        let b = 0.5 * (f.positive.viscous_nms_rad + f.negative.viscous_nms_rad);
        let falloff = if i == 1 || i == 2 { Some(2.0) } else { None };
        f.positive = FrictionBranch {
            coulomb_nm: 1.1 * fc,
            static_nm: 1.4 * fc,
            stribeck_velocity_rad_s: 0.1,
            viscous_nms_rad: 1.2 * b,
            viscous_falloff_rad_s: falloff,
        };
        f.negative = FrictionBranch {
            coulomb_nm: 0.8 * fc,
            static_nm: 1.1 * fc,
            stribeck_velocity_rad_s: 0.15,
            viscous_nms_rad: 0.9 * b,
            viscous_falloff_rad_s: falloff,
        };
    }
    c.hardware.q_noise_std_rad = 5e-4;
    c.hardware.qd_noise_std_rad_s = 0.02;
    c.hardware.encoder_counts_per_rev = Some(vec![65536.0; c.arm.dof()]);
    c.hardware.seed = 7;
    c
}
