//! The paper's experiments for any planar arm of 2 to 8 joints, run through the master with
//! the FMUs in closed loop, one module per concern: [`friction`] identification, [`gravity`]
//! identification, [`tracking`] (Table 1) and the [`joint_space`] gravity-compensation loop,
//! with the arms and sizes of a run in [`settings`]; [`paper`] runs them all, in stages, into
//! the figures of [`results`]. Experiments compute and return results; writing them up is the
//! caller's, and so is showing progress (through [`Progress`]). Every run is seeded, so
//! results repeat exactly.

pub mod adaptation;
pub mod friction;
pub mod gravity;
pub mod gravity_study;
pub mod joint_space;
pub mod paper;
pub mod progress;
pub mod results;
pub mod settings;
pub mod tracking;

use neurarm_nn::parallel::{ParallelFor, Pool};
use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;

use anyhow::{bail, Context, Result};

use crate::export::export_fmu_for;
use neurarm_cosim::{
    Algorithm, ConnectionSpec, FmuEntry, Handle, MasterError, RunEnd, Simulation, SimulationSpec, System, SystemSpec, Value,
};
use neurarm_models::names::{self, all_joints, path};
use neurarm_models::{
    FmuSpec, IdealCompensatorSpec, JointControllerSpec, ModelSpec, NnCompensatorSpec, PlanarArmSpec, TaskSpaceControllerSpec,
};
use neurarm_physics::arm::{gravity_torques, mass_matrix, ArmParams, ArmState};

pub use friction::{
    friction_run, friction_step_width, held_inertia, pairs_of_runs, run_options, train_friction_net, FrictionHold, FrictionPair,
    FrictionRun, LevelRecord,
};
pub use gravity::{
    design_poses, gravity_grid, gravity_net_errors, gravity_sweep, measure_gravity, sampled_poses, train_gravity_net, GravityPair,
    GravitySweep, GRAVITY_SWEEP_SPEED_RAD_S,
};
pub use joint_space::{gravity_compensation_system, joint_rms_errors, joint_settled_errors};
pub use paper::LOW_SPEED_RANGE_RAD_S;
pub use progress::{NoProgress, Progress};
pub use settings::{emulated_real_arm, Arms, GravityDesign, RealOrigin, Settings, MAX_GRAVITY_POSES, MAX_JOINTS, MIN_JOINTS};
pub use tracking::{tracking_errors, tracking_mse, tracking_start, tracking_system, TrackingErrors, TRACKING_SEED_POSE};

/// The arm's unit in the closed loops' systems.
pub const ARM_UNIT: &str = "arm";
/// The controller's unit in the closed loops' systems.
pub const CONTROLLER_UNIT: &str = "ctl";
/// The compensator's unit in the closed loops' systems.
pub const COMPENSATOR_UNIT: &str = "comp";

/// Longest RK4 sub-step of the arm in the identification runs [s]: one per 1 ms communication
/// step. Their motions are slow and smooth (PD loops at 40 rad/s, constant speeds), where RK4
/// at 1 ms keeps the energy to 1e-10 J over 10 s (tests/dynamics.rs); the closed loops of
/// Table 1 keep the default 0.25 ms. Arms whose viscous friction is stiff for their inertia
/// get a shorter one ([`identification_internal_step`]).
pub const IDENTIFICATION_INTERNAL_STEP_S: f64 = 1e-3;

/// Poses [`identification_internal_step`] looks at.
const STIFFNESS_POSES: usize = 256;

/// The arm's RK4 sub-step in the identification runs [s]: [`IDENTIFICATION_INTERNAL_STEP_S`],
/// or 1 ms / k (k whole) where that would leave RK4 unstable on the arm's viscous friction:
/// h × rate ≤ 2 (RK4's bound is 2.785) for the fastest rate of
/// [`neurarm_physics::arm::largest_viscous_rate`] over 256 seeded random poses and the
/// stretched arm, taken twice for the poses not seen (docs/decisions/0003-identification-substep.md).
pub fn identification_internal_step(arm: &ArmParams) -> f64 {
    use rand::{Rng, SeedableRng};
    let n = arm.dof();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0x5717);
    let mut fastest = neurarm_physics::arm::largest_viscous_rate(arm, &vec![0.0; n]).unwrap_or(0.0);
    for _ in 0..STIFFNESS_POSES {
        let q: Vec<f64> = (0..n).map(|_| rng.gen_range(-PI..PI)).collect();
        fastest = fastest.max(neurarm_physics::arm::largest_viscous_rate(arm, &q).unwrap_or(0.0));
    }
    let longest = 2.0 / (2.0 * fastest);
    if longest >= IDENTIFICATION_INTERNAL_STEP_S {
        return IDENTIFICATION_INTERNAL_STEP_S;
    }
    IDENTIFICATION_INTERNAL_STEP_S / (IDENTIFICATION_INTERNAL_STEP_S / longest).ceil()
}

/// Fastest joint speed a closed loop may reach before it is called unstable [rad/s]: 20 × the
/// friction experiment's top speed, far above any motion the paper's loops ask for.
pub const UNSTABLE_SPEED_RAD_S: f64 = 100.0;

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
/// loop on `arm`: `settings.joint_kp`, `joint_kd` on every joint, or, with
/// `settings.scale_joint_gains`, those times [`gravity_scale`] (so uncompensated gravity leaves
/// alike errors on light and heavy arms), capped so no joint is faster than the built-in arm's
/// fastest: √(K_p/m) ≤ [`JOINT_LOOP_MAX_RAD_S`], K_d h/m ≤ [`JOINT_LOOP_MAX_DAMPING_STEP`] with
/// m the joint's [`lightest_inertias`] (the caps do not bind on the built-in arm).
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
    /// Ideal friction compensator of the real arm, its true friction law (its `enable_gravity`
    /// starts false): what perfect friction compensation is on the real arm.
    pub ideal_friction_real: PathBuf,
    /// Ideal gravity compensator of the nominal arm with its base turned 90° (its
    /// `enable_friction` starts false).
    pub ideal_gravity: PathBuf,
}

/// Exports the base FMUs of `arms` into `dir`.
pub fn build_fmus(dir: &Path, arms: &Arms, settings: &Settings) -> Result<Fmus> {
    std::fs::create_dir_all(dir).with_context(|| dir.display().to_string())?;
    let nominal = &arms.nominal;
    let n = arms.joints();
    let export = |id: &str, model: ModelSpec| -> Result<PathBuf> {
        let path = dir.join(format!("{id}.fmu"));
        export_fmu_for(&FmuSpec { identifier: id.into(), model }, &[], &path, settings.platforms.as_deref())?;
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
        ideal_friction_real: export(
            "IdealFrictionCompensatorReal",
            ModelSpec::IdealCompensator(IdealCompensatorSpec { arm: arms.real.arm.clone(), enable_friction: true, enable_gravity: false }),
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
/// name in the FMU, source path) and the gravity net, if any, each part switched on, with the
/// binaries of `platforms` (see [`crate::export::fmu_binaries`]).
pub fn export_nn_compensator(
    path: &Path,
    identifier: &str,
    joints: usize,
    friction: &[(String, PathBuf)],
    gravity: Option<&Path>,
    platforms: Option<&[String]>,
) -> Result<PathBuf> {
    let mut sources = friction.to_vec();
    if let Some(g) = gravity {
        sources.push(("gravity.json".into(), g.to_path_buf()));
    }
    let model = ModelSpec::NnCompensator(NnCompensatorSpec::of_nets(
        joints,
        friction.iter().map(|(n, _)| n.clone()).collect(),
        gravity.map(|_| "gravity.json".to_owned()),
    ));
    export_fmu_for(&FmuSpec { identifier: identifier.into(), model }, &sources, path, platforms)?;
    Ok(path.to_path_buf())
}

/// Runs `tasks` on `threads` threads (the nets' pool, [`Pool::scoped`]); results come back in
/// task order. `done` is called after each task; after a failure no further task starts.
pub fn parallel<T: Send, R: Send>(
    tasks: Vec<T>,
    threads: usize,
    work: impl Fn(T) -> Result<R> + Sync,
    done: impl Fn() + Sync,
) -> Result<Vec<R>> {
    let n = tasks.len();
    let tasks: Vec<Mutex<Option<T>>> = tasks.into_iter().map(|t| Mutex::new(Some(t))).collect();
    let results: Mutex<Vec<Option<Result<R>>>> = Mutex::new((0..n).map(|_| None).collect());
    let failed = AtomicBool::new(false);
    Pool::scoped(threads.max(1).min(n.max(1)), |pool| {
        pool.run(n, &|i| {
            if failed.load(Ordering::Relaxed) {
                return;
            }
            let task = tasks[i].lock().expect("task").take().expect("each task runs once");
            let r = work(task);
            failed.fetch_or(r.is_err(), Ordering::Relaxed);
            results.lock().expect("results")[i] = Some(r);
            done();
        });
    });
    let results = results.into_inner().expect("results");
    let mut out = Vec::with_capacity(n);
    for r in results {
        match r {
            Some(Ok(v)) => out.push(v),
            Some(Err(e)) => return Err(e),
            None => bail!("a task did not run because an earlier one failed"),
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
) -> Result<System, MasterError> {
    let mut s = System::new();
    s.add_fmu(ARM_UNIT, arm_fmu)?.add_fmu(CONTROLLER_UNIT, controller)?;
    for (name, v) in arm_parameters {
        s.set(ARM_UNIT, name, v.clone())?;
    }
    for (i, (kp, kd)) in kp_kd.iter().enumerate() {
        s.set(CONTROLLER_UNIT, &names::joint(names::KP, i + 1), Value::Real(*kp))?;
        s.set(CONTROLLER_UNIT, &names::joint(names::KD, i + 1), Value::Real(*kd))?;
    }
    if let Some(c) = compensator {
        s.add_fmu(COMPENSATOR_UNIT, c)?;
    }
    for (from, to) in loop_connections(compensator.is_some()) {
        s.connect(&from, &to)?;
    }
    Ok(s)
}

/// The connections (from, to) of every closed loop: the arm's measurements to the controller,
/// its torques to the arm and, with a compensator, the measurements to the compensator and its
/// torques to the controller's `tau_comp`.
fn loop_connections(compensator: bool) -> Vec<(String, String)> {
    let every = |unit: &str, family: &str| path(unit, &all_joints(family));
    let (arm, ctl, comp) = (ARM_UNIT, CONTROLLER_UNIT, COMPENSATOR_UNIT);
    let mut connections = vec![
        (every(arm, names::MEASURED_ANGLE), every(ctl, names::ANGLE)),
        (every(arm, names::MEASURED_VELOCITY), every(ctl, names::VELOCITY)),
        (every(ctl, names::TORQUE), every(arm, names::TORQUE)),
    ];
    if compensator {
        connections.extend([
            (every(arm, names::MEASURED_ANGLE), every(comp, names::ANGLE)),
            (every(arm, names::MEASURED_VELOCITY), every(comp, names::VELOCITY)),
            (every(comp, names::COMPENSATION_TORQUE), every(ctl, names::COMPENSATION_TORQUE)),
        ]);
    }
    connections
}

/// The handles of the Real variables of `family` of joints 1 … n of `unit` in `sim`.
pub(crate) fn real_handles(sim: &Simulation, n: usize, unit: &str, family: &str) -> Result<Vec<Handle>, MasterError> {
    names::joint_paths(unit, family, n).iter().map(|p| sim.real_handle(p)).collect()
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
                let is_speed = c.starts_with(&path(ARM_UNIT, &names::joint_prefix(names::VELOCITY)));
                (is_speed || c.starts_with(&path(ARM_UNIT, &names::joint_prefix(names::ANGLE)))).then_some((k, is_speed))
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
    let mut fmu = vec![
        FmuEntry { name: ARM_UNIT.into(), path: spec_path(arm), parameters: arm_parameters },
        FmuEntry { name: CONTROLLER_UNIT.into(), path: spec_path(controller), parameters: controller_parameters },
    ];
    if let Some(c) = compensator {
        fmu.push(FmuEntry { name: COMPENSATOR_UNIT.into(), path: spec_path(c), parameters: BTreeMap::new() });
    }
    let connection = loop_connections(compensator.is_some()).into_iter().map(|(from, to)| ConnectionSpec { from, to }).collect();
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
            on_discard: neurarm_cosim::OnDiscard::Stop,
        },
        event: Vec::new(),
    }
}

/// Why a closed loop failed: the master's error, if any, is the source.
#[derive(Debug, thiserror::Error)]
pub enum LoopError {
    /// The system could not be built, started or given its events.
    #[error(transparent)]
    Setup(Box<MasterError>),
    /// The arm's state blew up (see [`LoopRun::instability`]).
    #[error("the loop went unstable at t = {time:.3} s: {column} = {value:.3e} (limit ±{UNSTABLE_SPEED_RAD_S} rad/s); lower its gains")]
    Unstable {
        /// When [s].
        time: f64,
        /// The recorded column.
        column: String,
        /// Its value [rad or rad/s].
        value: f64,
    },
    /// A unit failed during the run.
    #[error("the loop failed after t = {time:.3} s")]
    Failed {
        /// What the master said: the unit, the variable and the time.
        source: Box<MasterError>,
        /// The last recorded time [s] (the start if none was).
        time: f64,
    },
    /// The run stopped before its end without an error.
    #[error("the loop ended early: {0:?}")]
    EndedEarly(RunEnd),
}

impl From<MasterError> for LoopError {
    fn from(e: MasterError) -> Self {
        LoopError::Setup(Box::new(e))
    }
}

impl LoopError {
    /// The line a run records for a loop it carries on without (results.json, report.md):
    /// a failed unit's error followed by the time the loop had reached, else the error itself.
    pub fn recorded(&self) -> String {
        match self {
            LoopError::Failed { source, time } => format!("{source} (at t = {time:.3} s)"),
            other => other.to_string(),
        }
    }
}

/// Runs a closed-loop system (FMU paths relative to `base`), recording every step. A loop
/// whose arm state blows up (see [`LoopRun::instability`]) or whose units fail is an error
/// that says when and where.
pub fn run_loop(spec: &SystemSpec, base: &Path) -> Result<LoopRun, LoopError> {
    let s = System::from_spec(spec, base)?;
    let sim = &spec.simulation;
    let mut run = s.initialize(sim.start, sim.step, sim.algorithm, &sim.record)?;
    run.record_every(sim.record_every);
    // The paper's loops never expect a unit to stop early: a discarded step is a failure.
    run.on_discard(neurarm_cosim::OnDiscard::Error);
    run.schedule(&spec.event)?;
    let outcome = run.run_until(sim.stop);
    let recorded = LoopRun { columns: run.columns(), rows: run.take_rows() };
    if let Some((time, column, value)) = recorded.instability() {
        return Err(LoopError::Unstable { time, column, value });
    }
    let end = outcome.map_err(|e| LoopError::Failed { source: Box::new(e), time: recorded.rows.last().map_or(sim.start, |r| r[0]) })?;
    if end != RunEnd::Completed {
        return Err(LoopError::EndedEarly(end));
    }
    Ok(recorded)
}

#[cfg(test)]
mod tests {
    use super::*;
    use neurarm_physics::config::ArmConfig;
    use neurarm_physics::control::ReferencePlacement;

    #[test]
    fn parallel_keeps_task_order_and_stops_at_a_failure() {
        for threads in [1, 3] {
            let done = std::sync::atomic::AtomicUsize::new(0);
            let squares = parallel(
                (0..20u64).collect(),
                threads,
                |i| Ok(i * i),
                || {
                    done.fetch_add(1, Ordering::Relaxed);
                },
            );
            assert_eq!(squares.unwrap(), (0..20u64).map(|i| i * i).collect::<Vec<_>>(), "{threads} threads");
            assert_eq!(done.load(Ordering::Relaxed), 20);
            let failed = parallel((0..20u64).collect(), threads, |i| if i == 5 { bail!("task {i} failed") } else { Ok(i) }, || {});
            assert_eq!(failed.unwrap_err().to_string(), "task 5 failed", "{threads} threads: the first failure in task order");
        }
    }

    #[test]
    fn arms_of_more_than_four_joints_get_as_many_sampled_poses_as_the_four_joint_grid() {
        let paper = Settings::paper();
        for n in 3..=4 {
            assert_eq!(paper.design_for(n), GravityDesign::Grid { per_joint: 7 });
        }
        // 7² = 49 poses, 98 torques, would not determine the 177 weights of a 2-joint net.
        assert_eq!(paper.fewest_gravity_poses(2), 177);
        assert_eq!(paper.design_for(2), GravityDesign::Grid { per_joint: 14 });
        let raw = Settings { gravity_encoding: neurarm_nn::InputEncoding::Raw, ..Settings::paper() };
        assert_eq!(raw.fewest_gravity_poses(2), 127);
        assert_eq!(raw.design_for(2), GravityDesign::Grid { per_joint: 12 });
        for n in 5..=8 {
            assert_eq!(paper.design_for(n), GravityDesign::Sampled { poses: 2401 });
        }
        assert_eq!(Settings::quick().design_for(6), GravityDesign::Sampled { poses: 81 });
        let given = Settings { gravity_design: Some(GravityDesign::Grid { per_joint: 3 }), ..Settings::paper() };
        assert_eq!(given.design_for(6), GravityDesign::Grid { per_joint: 3 });
        assert!(GravityDesign::Grid { per_joint: 7 }.check(6).unwrap_err().to_string().contains("117649 poses"));
        assert!(GravityDesign::Grid { per_joint: 1 }.check(3).is_err());
        assert!(GravityDesign::Sampled { poses: 9 }.check(3).is_err());
        assert!(GravityDesign::Sampled { poses: 3000 }.check(6).is_ok());
    }

    #[test]
    fn the_friction_curve_passes_through_its_pairs_and_is_linear_between_them() {
        let pairs: Vec<FrictionPair> = vec![(-1.0, -2.0, 5), (-0.1, -1.1, 5), (0.0, 0.1, 3), (0.1, 1.0, 5), (1.0, 1.9, 5)];
        let curve = friction::FrictionCurve::new(&pairs);
        for p in &pairs {
            assert!((curve.torque(p.0) - p.1).abs() < 1e-12, "at {}: {} vs {}", p.0, curve.torque(p.0), p.1);
        }
        assert!((curve.torque(0.55) - 1.45).abs() < 1e-12);
        assert!((curve.torque(-0.05) - (-0.5)).abs() < 1e-12);
        assert_eq!(curve.torque(3.0), 1.9, "the end pair's value beyond it");
        assert_eq!(curve.torque(-3.0), -2.0);
        assert_eq!(friction::FrictionCurve::new(&[]).torque(0.3), 0.0);
    }

    #[test]
    fn sampled_poses_cover_the_turn_and_the_path_moves_at_most_half_a_turn_per_joint() {
        let poses = sampled_poses(500, 3, 5);
        assert_eq!(poses.len(), 500);
        for w in poses.windows(2) {
            assert!(w[0].iter().zip(&w[1]).all(|(a, b)| (a - b).abs() <= PI + 1e-12), "{:?} → {:?}", w[0], w[1]);
        }
        // Wrapped back, the poses fill the turn: every joint has poses in each quarter.
        for j in 0..3 {
            let mut quarters = [0usize; 4];
            for p in &poses {
                quarters[(p[j].rem_euclid(2.0 * PI) / (PI / 2.0)) as usize % 4] += 1;
            }
            assert!(quarters.iter().all(|&c| c > 80), "joint {j}: {quarters:?}");
        }
        // The nearest-neighbour order travels far less than the drawing order would.
        let travel = |path: &[Vec<f64>]| -> f64 {
            path.windows(2).map(|w| w[0].iter().zip(&w[1]).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max)).sum()
        };
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        use rand::{Rng, SeedableRng};
        let drawn: Vec<Vec<f64>> = (0..500).map(|_| (0..3).map(|_| rng.gen::<f64>() * 2.0 * PI).collect()).collect();
        assert!(travel(&poses) < 0.5 * travel(&drawn), "{} vs {}", travel(&poses), travel(&drawn));
        assert_eq!(sampled_poses(500, 3, 5), poses, "seeded");
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
        let e = format!("{:#}", Arms::new(one, None, None).unwrap_err());
        assert!(e.contains("1 joint;") && e.contains("2 to 8"), "{e}");
        let mut nine = ArmConfig::default();
        for _ in 0..5 {
            nine.arm.links.push(nine.arm.links[3].clone());
            nine.arm.friction.push(nine.arm.friction[3]);
        }
        assert!(Arms::new(nine, None, None).unwrap_err().to_string().contains("9 joints"));
        let mut three = ArmConfig::default();
        three.arm.links.truncate(3);
        three.arm.friction.truncate(3);
        let e = format!("{:#}", Arms::new(ArmConfig::default(), Some((three, "real3.toml".into())), None).unwrap_err());
        assert!(e.contains("real3.toml") && e.contains("3 joints") && e.contains("has 4"), "{e}");
        let far = ReferencePlacement { scale: 3.0, ..ReferencePlacement::for_arm(&ArmParams::default_four_link()) };
        let e = format!("{:#}", Arms::new(ArmConfig::default(), None, Some(far)).unwrap_err());
        assert!(e.contains("reach"), "{e}");
    }
}
