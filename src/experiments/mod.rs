//! The paper's experiments for any planar arm of 2 to 8 joints, run through the master with
//! the FMUs in closed loop, one module per concern: [`friction`] identification, [`gravity`]
//! identification, [`tracking`] (Table 1) and the [`joint_space`] gravity-compensation loop;
//! [`paper`] runs them all. Experiments compute and return results; `crate::report` writes
//! them. Every run is seeded, so results repeat exactly.

pub mod friction;
pub mod gravity;
pub mod joint_space;
pub mod paper;
pub mod tracking;

use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use serde::Serialize;

use crate::export::export_fmu;
use fmi2_cosim::{Algorithm, ConnectionSpec, FmuEntry, MasterError, SimulationSpec, System, SystemSpec, Value};
use neurarm_models::{
    FmuSpec, IdealCompensatorSpec, JointControllerSpec, ModelSpec, NnCompensatorSpec, PlanarArmSpec, TaskSpaceControllerSpec,
};
use neurarm_physics::arm::{gravity_torques, mass_matrix, ArmParams, ArmState, FrictionBranch};
use neurarm_physics::config::ArmConfig;
use neurarm_physics::control::{ReferencePlacement, TaskSpaceGains};

pub use friction::{bin_friction, friction_run, rest_pair, train_friction_net, FrictionHold, FrictionPair, FrictionRun};
pub use gravity::{gravity_grid, gravity_net_errors, gravity_sweep, train_gravity_net, GravityPair, GRAVITY_SWEEP_SPEED_RAD_S};
pub use joint_space::{gravity_compensation_system, joint_rms_errors, joint_settled_errors};
pub use tracking::{tracking_errors, tracking_mse, tracking_start, tracking_system, TrackingErrors, TRACKING_SEED_POSE};

/// Fewest joints the experiments take: the task-space loop tracks a planar position.
pub const MIN_JOINTS: usize = 2;
/// Most joints the experiments take (the gravity grid and the hold gains grow as kⁿ).
pub const MAX_JOINTS: usize = 8;

/// RK4 sub-step of the arm in the identification runs [s]: one per 1 ms communication step.
/// Their motions are slow and smooth (PD loops at 40 rad/s, constant speeds), where RK4 at
/// 1 ms keeps the energy to 1e-10 J over 10 s (tests/dynamics.rs); the closed loops of
/// Table 1 keep the default 0.25 ms.
pub const IDENTIFICATION_INTERNAL_STEP_S: f64 = 1e-3;

/// Fastest joint speed a closed loop may reach before it is called unstable [rad/s]: 20 × the
/// friction experiment's top speed, far above any motion the paper's loops ask for.
pub const UNSTABLE_SPEED_RAD_S: f64 = 100.0;

/// Sizes, durations and gains of the experiments. [`Settings::paper`] is the full run,
/// [`Settings::quick`] a reduced one for tests.
#[derive(Clone, Debug, Serialize)]
pub struct Settings {
    /// Communication step [s].
    pub step: f64,
    /// Gravity grid points per joint for arms of up to 4 joints (the paper: 7); more joints get
    /// a coarser grid, see [`Settings::grid_for`].
    pub grid: usize,
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
    /// Random configurations the gravity net is tested on.
    pub gravity_test_points: usize,
    /// Epochs of the gravity net's training.
    pub gravity_epochs: usize,
    /// Hidden neurons of the gravity net (the paper: 25).
    pub gravity_hidden: usize,
    /// Position gain of the joint-space gravity-compensation loop [N·m/rad] for the built-in
    /// arm; scaled for other arms when `scale_joint_gains` (see [`joint_loop_gains`]).
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
}

impl Settings {
    /// The full experiments.
    pub fn paper() -> Self {
        Self {
            step: 1e-3,
            grid: 7,
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
            threads: std::thread::available_parallelism().map_or(2, |n| n.get()).min(4),
            quick: false,
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
            ..Self::paper()
        }
    }

    /// Gravity grid points per joint for an arm of `joints` joints: `grid` up to 4 joints;
    /// beyond, the largest k with kⁿ ≤ grid⁴ (the 4-joint grid's size), but at least 3, so a
    /// 6-joint arm gets 3⁶ = 729 poses instead of 7⁶ = 117 649. A full grid is what the paper
    /// did; it does not scale, and the report says when the grid is coarser.
    pub fn grid_for(&self, joints: usize) -> usize {
        if joints <= 4 {
            return self.grid;
        }
        let budget = self.grid.pow(4);
        let mut k = 3;
        while (k + 1usize).pow(joints as u32) <= budget {
            k += 1;
        }
        k.min(self.grid)
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
    pub fn new(nominal: ArmConfig, real: Option<(ArmConfig, String)>, placement: Option<ReferencePlacement>) -> Result<Self, String> {
        nominal.validate().map_err(|e| format!("the arm: {e}"))?;
        let n = nominal.arm.dof();
        if !(MIN_JOINTS..=MAX_JOINTS).contains(&n) {
            return Err(format!(
                "the arm has {n} joint{}; the experiments take {MIN_JOINTS} to {MAX_JOINTS} (the task-space loop needs two to place the end effector in the plane; the gravity grid and the hold gains grow as kⁿ)",
                if n == 1 { "" } else { "s" }
            ));
        }
        let (real, real_origin) = match real {
            Some((real, source)) => {
                real.validate().map_err(|e| format!("the real arm ({source}): {e}"))?;
                if real.arm.dof() != n {
                    return Err(format!(
                        "the real arm ({source}) has {} joints, the arm has {n}: give one of the same joint count",
                        real.arm.dof()
                    ));
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

/// The arm's gravity load relative to the built-in arm's: the gravity torque at joint 1 with
/// the base turned 90° and the arm stretched horizontally (its largest), divided by the
/// same for the built-in arm. Exactly 1 for the built-in arm.
pub fn gravity_scale(arm: &ArmParams) -> f64 {
    let load = |a: &ArmParams| gravity_torques(&a.clone().with_base_angle(PI / 2.0), &vec![0.0; a.dof()])[0].abs();
    load(arm) / load(&ArmParams::default_four_link())
}

/// The smallest inertia each joint can present [kg·m²]: 1/(H⁻¹)_ii, the inertia a joint
/// feels when the others move freely (the coupling makes it much smaller than H_ii), least
/// over the poses of a 4ⁿ⁻¹ grid (joint 1 does not change H).
pub fn lightest_inertias(arm: &ArmParams) -> Vec<f64> {
    let n = arm.dof();
    let mut inertia = vec![f64::INFINITY; n];
    for k in 0..4usize.pow(n as u32 - 1) {
        let q: Vec<f64> = (0..n).map(|i| if i == 0 { 0.0 } else { ((k / 4usize.pow(i as u32 - 1)) % 4) as f64 * PI / 2.0 }).collect();
        if let Some(inv) = mass_matrix(arm, &q).try_inverse() {
            for i in 0..n {
                inertia[i] = inertia[i].min(1.0 / inv[(i, i)]);
            }
        }
    }
    inertia
}

/// Fastest natural frequency a joint of the scaled joint-space loop gets, √(K_p/m) [rad/s]:
/// just above the built-in arm's fastest joint (121 rad/s, joint 4).
pub const JOINT_LOOP_MAX_RAD_S: f64 = 125.0;
/// Largest K_d·h/m of a joint of the scaled joint-space loop (h the communication step): just
/// above the built-in arm's (0.59, joint 4). Near 1 the sampled derivative term rings.
pub const JOINT_LOOP_MAX_DAMPING_STEP: f64 = 0.6;

/// Gains (K_p [N·m/rad], K_d [N·m·s/rad]) per joint of the joint-space gravity-compensation
/// loop on `arm`. With `settings.scale_joint_gains`: `settings.joint_kp`, `joint_kd` times
/// [`gravity_scale`], so the error gravity leaves uncompensated, and the share the gains
/// correct, are alike for a light arm and a heavy one; then capped per joint so that no joint
/// is faster than the built-in arm's fastest, √(K_p/m) ≤ [`JOINT_LOOP_MAX_RAD_S`] and
/// K_d h/m ≤ [`JOINT_LOOP_MAX_DAMPING_STEP`] with m the joint's [`lightest_inertias`] (the
/// caps do not bind on the built-in arm, whose gains are 50 and 2 on every joint). Without
/// scaling the gains are taken as given on every joint.
pub fn joint_loop_gains(arm: &ArmParams, settings: &Settings) -> Vec<(f64, f64)> {
    if !settings.scale_joint_gains {
        return vec![(settings.joint_kp, settings.joint_kd); arm.dof()];
    }
    let s = gravity_scale(arm);
    lightest_inertias(arm)
        .iter()
        .map(|m| {
            let kp = (settings.joint_kp * s).min(JOINT_LOOP_MAX_RAD_S * JOINT_LOOP_MAX_RAD_S * m);
            let kd = (settings.joint_kd * s).min(JOINT_LOOP_MAX_DAMPING_STEP * m / settings.step);
            (kp, kd)
        })
        .collect()
}

/// The FMUs every experiment is built from. Compensators are exported with the switches each
/// loop needs as start values, so the loops' system and SSP files set no Boolean parameter
/// (fmpy's `simulate_ssp` sets every Boolean parameter of an SSP to true).
#[derive(Clone, Debug)]
pub struct Fmus {
    /// The nominal (simulated) arm, horizontal unless its `base_angle` is set.
    pub arm: PathBuf,
    /// The real arm (emulated or the user's).
    pub arm_real: PathBuf,
    /// The task-space controller.
    pub task_controller: PathBuf,
    /// The joint controller.
    pub joint_controller: PathBuf,
    /// Ideal friction compensator of the nominal arm (its `enable_gravity` starts false).
    pub ideal_friction: PathBuf,
    /// Ideal gravity compensator of the nominal arm with its base turned 90° (its
    /// `enable_friction` starts false).
    pub ideal_gravity: PathBuf,
}

/// Exports the base FMUs of `arms` into `dir`.
pub fn build_fmus(dir: &Path, arms: &Arms, settings: &Settings) -> Result<Fmus, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let nominal = &arms.nominal;
    let n = arms.joints();
    let export = |id: &str, model: ModelSpec| -> Result<PathBuf, String> {
        let path = dir.join(format!("{id}.fmu"));
        export_fmu(&FmuSpec { identifier: id.into(), model }, &[], &path)?;
        Ok(path)
    };
    let ArmState { q: q_start, .. } = tracking_start(&nominal.arm, &arms.placement)?;
    let (kp, kd) = joint_loop_gains(&nominal.arm, settings)[0];
    Ok(Fmus {
        arm: export("PlanarArm", ModelSpec::PlanarArm(PlanarArmSpec { config: nominal.clone(), q0: vec![0.0; n], qd0: vec![0.0; n] }))?,
        arm_real: export(
            "PlanarArmReal",
            ModelSpec::PlanarArm(PlanarArmSpec { config: arms.real.clone(), q0: vec![0.0; n], qd0: vec![0.0; n] }),
        )?,
        task_controller: export(
            "TaskSpaceController",
            ModelSpec::TaskSpaceController(TaskSpaceControllerSpec {
                model: nominal.arm.clone().frictionless(),
                gains: settings.tracking_gains,
                centre: [arms.placement.centre.x, arms.placement.centre.y],
                scale: arms.placement.scale,
                q_start,
            }),
        )?,
        joint_controller: export(
            "JointController",
            ModelSpec::JointController(JointControllerSpec { joints: n, kp, kd, use_sequence: true }),
        )?,
        ideal_friction: export(
            "IdealFrictionCompensator",
            ModelSpec::IdealCompensator(IdealCompensatorSpec { arm: nominal.arm.clone(), enable_friction: true, enable_gravity: false }),
        )?,
        ideal_gravity: export(
            "IdealGravityCompensator",
            ModelSpec::IdealCompensator(IdealCompensatorSpec {
                arm: nominal.arm.clone().with_base_angle(PI / 2.0),
                enable_friction: false,
                enable_gravity: true,
            }),
        )?,
    })
}

/// Exports an NN compensator FMU of `joints` joints to `path` from the friction nets (file
/// name in the FMU, source path) and the gravity net, if any, each part switched on.
pub fn export_nn_compensator(
    path: &Path,
    identifier: &str,
    joints: usize,
    friction: &[(String, PathBuf)],
    gravity: Option<&Path>,
) -> Result<PathBuf, String> {
    let mut sources = friction.to_vec();
    if let Some(g) = gravity {
        sources.push(("gravity.json".into(), g.to_path_buf()));
    }
    let model = ModelSpec::NnCompensator(NnCompensatorSpec {
        joints,
        friction: friction.iter().map(|(n, _)| n.clone()).collect(),
        gravity: gravity.map(|_| "gravity.json".to_owned()),
        enable_friction: !friction.is_empty(),
        enable_gravity: gravity.is_some(),
    });
    export_fmu(&FmuSpec { identifier: identifier.into(), model }, &sources, path)?;
    Ok(path.to_path_buf())
}

pub(crate) fn master(e: MasterError) -> String {
    e.to_string()
}

/// Runs `tasks` on `threads` workers; results come back in task order. `done` is called
/// after each task.
pub fn parallel<T: Send, R: Send>(
    tasks: Vec<T>,
    threads: usize,
    work: impl Fn(T) -> Result<R, String> + Sync,
    done: impl Fn() + Sync,
) -> Result<Vec<R>, String> {
    let n = tasks.len();
    let queue: Mutex<Vec<(usize, T)>> = Mutex::new(tasks.into_iter().enumerate().rev().collect());
    let results: Mutex<Vec<Option<Result<R, String>>>> = Mutex::new((0..n).map(|_| None).collect());
    let next = AtomicUsize::new(0);
    std::thread::scope(|s| {
        for _ in 0..threads.max(1).min(n.max(1)) {
            s.spawn(|| loop {
                let Some((i, task)) = queue.lock().expect("queue").pop() else { break };
                let r = work(task);
                let failed = r.is_err();
                results.lock().expect("results")[i] = Some(r);
                next.fetch_add(1, Ordering::Relaxed);
                done();
                if failed {
                    queue.lock().expect("queue").clear();
                }
            });
        }
    });
    let results = results.into_inner().expect("results");
    let mut out = Vec::with_capacity(n);
    for r in results {
        match r {
            Some(Ok(v)) => out.push(v),
            Some(Err(e)) => return Err(e),
            None => return Err("a task did not run because an earlier one failed".into()),
        }
    }
    Ok(out)
}

/// The joint loop of the identification runs: `arm` measured by the joint controller `ctl`
/// with gains `kp_kd` per joint, optionally a compensator `comp` feeding `tau_comp`.
pub(crate) fn joint_loop(
    arm_fmu: &Path,
    controller: &Path,
    arm_parameters: &[(&str, Value)],
    kp_kd: &[(f64, f64)],
    compensator: Option<&Path>,
) -> Result<System, String> {
    let mut s = System::new();
    s.add_fmu("arm", arm_fmu).map_err(master)?.add_fmu("ctl", controller).map_err(master)?;
    for (name, v) in arm_parameters {
        s.set("arm", name, v.clone()).map_err(master)?;
    }
    for (i, (kp, kd)) in kp_kd.iter().enumerate() {
        s.set("ctl", &format!("kp_{}", i + 1), Value::Real(*kp)).map_err(master)?;
        s.set("ctl", &format!("kd_{}", i + 1), Value::Real(*kd)).map_err(master)?;
    }
    s.connect("arm.q_meas_*", "ctl.q_*").map_err(master)?;
    s.connect("arm.qd_meas_*", "ctl.qd_*").map_err(master)?;
    s.connect("ctl.tau_*", "arm.tau_*").map_err(master)?;
    if let Some(c) = compensator {
        s.add_fmu("comp", c).map_err(master)?;
        s.connect("arm.q_meas_*", "comp.q_*").map_err(master)?;
        s.connect("arm.qd_meas_*", "comp.qd_*").map_err(master)?;
        s.connect("comp.tau_comp_*", "ctl.tau_comp_*").map_err(master)?;
    }
    Ok(s)
}

/// A recorded closed-loop run.
#[derive(Clone, Debug)]
pub struct LoopRun {
    /// Column names, "time" first.
    pub columns: Vec<String>,
    /// Rows every communication step.
    pub rows: Vec<Vec<f64>>,
}

impl LoopRun {
    /// A column by name.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let k = self.columns.iter().position(|c| c == name)?;
        Some(self.rows.iter().map(|r| r[k]).collect())
    }

    /// The first sign of instability: (time [s], column, value) of the first recorded joint
    /// angle or velocity of the arm that is not finite or, for a velocity, beyond
    /// [`UNSTABLE_SPEED_RAD_S`].
    pub fn instability(&self) -> Option<(f64, String, f64)> {
        let watched: Vec<(usize, bool)> = self
            .columns
            .iter()
            .enumerate()
            .filter_map(|(k, c)| {
                let is_speed = c.starts_with("arm.qd_");
                (is_speed || c.starts_with("arm.q_")).then_some((k, is_speed))
            })
            .collect();
        for row in &self.rows {
            for &(k, is_speed) in &watched {
                let v = row[k];
                if !v.is_finite() || (is_speed && v.abs() > UNSTABLE_SPEED_RAD_S) {
                    return Some((row[0], self.columns[k].clone(), v));
                }
            }
        }
        None
    }
}

/// A path as a system file writes it: '/'-separated on every platform.
fn spec_path(p: &Path) -> String {
    p.to_string_lossy().replace('\\', "/")
}

/// The units and connections every closed loop shares: `arm` measured by the controller
/// `ctl`, whose torques drive the arm; with a compensator `comp`, fed the same measurements,
/// adding `tau_comp` in the controller. Paths as the system file will hold them.
pub(crate) fn closed_loop(
    arm: &Path,
    controller: &Path,
    compensator: Option<&Path>,
    arm_parameters: BTreeMap<String, Value>,
    controller_parameters: BTreeMap<String, Value>,
) -> SystemSpec {
    let connect = |from: &str, to: &str| ConnectionSpec { from: from.into(), to: to.into() };
    let mut fmu = vec![
        FmuEntry { name: "arm".into(), path: spec_path(arm), parameters: arm_parameters },
        FmuEntry { name: "ctl".into(), path: spec_path(controller), parameters: controller_parameters },
    ];
    let mut connection = vec![connect("arm.q_meas_*", "ctl.q_*"), connect("arm.qd_meas_*", "ctl.qd_*"), connect("ctl.tau_*", "arm.tau_*")];
    if let Some(c) = compensator {
        fmu.push(FmuEntry { name: "comp".into(), path: spec_path(c), parameters: BTreeMap::new() });
        connection.extend([
            connect("arm.q_meas_*", "comp.q_*"),
            connect("arm.qd_meas_*", "comp.qd_*"),
            connect("comp.tau_comp_*", "ctl.tau_comp_*"),
        ]);
    }
    SystemSpec {
        fmu,
        connection,
        simulation: SimulationSpec {
            start: 0.0,
            stop: 0.0,
            step: 0.0,
            algorithm: Algorithm::GaussSeidel,
            record: Vec::new(),
            record_every: 1,
        },
    }
}

/// Runs a closed-loop system (FMU paths relative to `base`), recording every step. A loop
/// whose arm state blows up (see [`LoopRun::instability`]) or whose units fail is an error
/// that says when and where.
pub fn run_loop(spec: &SystemSpec, base: &Path) -> Result<LoopRun, String> {
    let s = System::from_spec(spec, base).map_err(master)?;
    let sim = &spec.simulation;
    let mut run = s.initialize(sim.start, sim.step, sim.algorithm, &sim.record).map_err(master)?;
    run.record_every(sim.record_every);
    let outcome = run.run_until(sim.stop);
    let recorded = LoopRun { columns: run.columns(), rows: run.take_rows() };
    if let Some((t, column, value)) = recorded.instability() {
        return Err(format!(
            "the loop went unstable at t = {t:.3} s: {column} = {value:.3e} (limit ±{UNSTABLE_SPEED_RAD_S} rad/s); lower its gains"
        ));
    }
    outcome.map_err(|e| format!("{} (at t = {:.3} s)", master(e), recorded.rows.last().map_or(sim.start, |r| r[0])))?;
    Ok(recorded)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arms_of_more_than_four_joints_get_a_coarser_grid_of_at_most_the_four_joint_size() {
        let paper = Settings::paper();
        let sizes: Vec<usize> = (2..=8).map(|n| paper.grid_for(n)).collect();
        assert_eq!(sizes, [7, 7, 7, 4, 3, 3, 3]);
        for n in 5..=7 {
            assert!(paper.grid_for(n).pow(n as u32) <= 7usize.pow(4));
        }
        assert_eq!(Settings::quick().grid_for(6), 3);
    }

    #[test]
    fn the_builtin_arm_keeps_the_papers_joint_gains_and_others_are_capped() {
        let settings = Settings::paper();
        let builtin = ArmParams::default_four_link();
        assert_eq!(gravity_scale(&builtin), 1.0);
        assert!(joint_loop_gains(&builtin, &settings).iter().all(|&g| g == (50.0, 2.0)));
        // A light distal link: its gains are capped by its inertia, not the arm's load.
        let mut light = builtin.clone();
        light.links.push(neurarm_physics::arm::LinkParams::uniform_rod(0.05, 0.05));
        light.friction.push(light.friction[3]);
        let gains = joint_loop_gains(&light, &settings);
        let inertia = lightest_inertias(&light);
        let (kp, kd) = gains[4];
        assert!(kp < 50.0 && (kp / inertia[4]).sqrt() <= JOINT_LOOP_MAX_RAD_S * (1.0 + 1e-12));
        assert!(kd * settings.step / inertia[4] <= JOINT_LOOP_MAX_DAMPING_STEP * (1.0 + 1e-12));
    }

    #[test]
    fn arms_outside_two_to_eight_joints_and_mismatched_real_arms_are_refused() {
        let mut one = ArmConfig::default();
        one.arm.links.truncate(1);
        one.arm.friction.truncate(1);
        let e = Arms::new(one, None, None).unwrap_err();
        assert!(e.contains("1 joint;") && e.contains("2 to 8"), "{e}");
        let mut nine = ArmConfig::default();
        for _ in 0..5 {
            nine.arm.links.push(nine.arm.links[3].clone());
            nine.arm.friction.push(nine.arm.friction[3]);
        }
        assert!(Arms::new(nine, None, None).unwrap_err().contains("9 joints"));
        let mut three = ArmConfig::default();
        three.arm.links.truncate(3);
        three.arm.friction.truncate(3);
        let e = Arms::new(ArmConfig::default(), Some((three, "real3.toml".into())), None).unwrap_err();
        assert!(e.contains("real3.toml") && e.contains("3 joints") && e.contains("has 4"), "{e}");
        let far = ReferencePlacement { scale: 3.0, ..ReferencePlacement::for_arm(&ArmParams::default_four_link()) };
        let e = Arms::new(ArmConfig::default(), None, Some(far)).unwrap_err();
        assert!(e.contains("reach"), "{e}");
    }
}
