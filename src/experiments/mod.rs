//! The paper's experiments, run through the master with the FMUs in closed loop: friction
//! identification, gravity identification, the tracking comparison of Table 1 and the
//! joint-space gravity compensation. Every run is seeded, so results repeat exactly.

pub mod paper;

use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

use nalgebra::DMatrix;

use crate::export::export_fmu;
use fmi2_cosim::{Algorithm, ConnectionSpec, FmuEntry, Handle, MasterError, Simulation, SimulationSpec, System, SystemSpec, Value};
use neurarm_models::{
    FmuSpec, IdealCompensatorSpec, JointControllerSpec, ModelSpec, NnCompensatorSpec, PlanarArmSpec, TaskSpaceControllerSpec,
};
use neurarm_physics::arm::{
    inverse_dynamics_rnea_into, jacobian, mass_matrix, ArmData, ArmParams, ArmState, FrictionBranch, JointFriction,
};
use neurarm_physics::config::ArmConfig;
use neurarm_physics::control::{inverse_kinematics, pseudo_inverse, scaled_reference, ReferencePlacement, TaskSpaceGains};
use neurarm_physics::nn::{train, Signal, TrainSettings, WeightsFile};

/// Pose the inverse kinematics for the tracking start is seeded from [rad]: an elbow-up
/// pose whose links are far from aligned.
pub const TRACKING_SEED_POSE: [f64; 4] = [-0.4, 0.9, 0.7, 0.5];

/// RK4 sub-step of the arm in the identification runs [s]: one per 1 ms communication step.
/// Their motions are slow and smooth (PD loops at 40 rad/s, constant speeds), where RK4 at
/// 1 ms keeps the energy to 1e-10 J over 10 s (tests/dynamics.rs); the closed loops of
/// Table 1 keep the default 0.25 ms.
pub const IDENTIFICATION_INTERNAL_STEP_S: f64 = 1e-3;

/// Sizes and durations of the experiments. [`Settings::paper`] is the full run,
/// [`Settings::quick`] a reduced one for tests.
#[derive(Clone, Debug)]
pub struct Settings {
    /// Communication step [s].
    pub step: f64,
    /// Gravity grid points per joint (the paper: 7).
    pub grid: usize,
    /// Largest joint speed of the friction experiment [rad/s] (the paper: 5).
    pub max_velocity: f64,
    /// Wanted spacing of the steady velocities of successive torque levels [rad/s].
    pub velocity_spacing: f64,
    /// Bin width of the friction data [rad/s] (the paper: 0.05).
    pub bin_width: f64,
    /// Length of each tracking run [s].
    pub tracking_duration: f64,
    /// Random configurations the gravity net is tested on.
    pub gravity_test_points: usize,
    /// Epochs of the gravity net's training.
    pub gravity_epochs: usize,
    /// Hidden neurons of the gravity net (the paper: 25).
    pub gravity_hidden: usize,
    /// Position gain of the joint-space gravity-compensation loop [N·m/rad].
    pub joint_kp: f64,
    /// Velocity gain of that loop [N·m·s/rad] (0 in the paper's law).
    pub joint_kd: f64,
    /// Seed of training splits, initial weights and sensor noise.
    pub seed: u64,
    /// Worker threads.
    pub threads: usize,
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
            tracking_duration: 4.0 * PI,
            gravity_test_points: 10_000,
            gravity_epochs: 1000,
            gravity_hidden: 25,
            joint_kp: 50.0,
            joint_kd: 2.0,
            seed: 1,
            threads: std::thread::available_parallelism().map_or(2, |n| n.get()).min(4),
        }
    }

    /// A reduced run for tests: a 3⁴ grid, coarse friction levels, one reference period.
    pub fn quick() -> Self {
        Self { grid: 3, tracking_duration: 2.0 * PI, gravity_test_points: 2000, gravity_epochs: 300, gravity_hidden: 10, ..Self::paper() }
    }
}

/// The emulated "real" arm: the nominal geometry with friction the nominal model does not
/// have (asymmetric in the sign of the velocity, Stribeck break-away, viscous friction that
/// falls with speed at joints 2 and 3, as the paper saw on its robot), noisy measurements
/// (0.0005 rad, 0.02 rad/s) and 16-bit encoders.
pub fn emulated_real_arm() -> ArmConfig {
    let mut c = ArmConfig::default();
    for (i, f) in c.arm.friction.iter_mut().enumerate() {
        let nominal = JointFriction::default_for_joint(i);
        let (fc, b) = (nominal.positive.coulomb_nm, nominal.positive.viscous_nms_rad);
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
    c.hardware.encoder_counts_per_rev = Some(vec![65536.0; 4]);
    c.hardware.seed = 7;
    c
}

/// The FMUs every experiment is built from. Compensators are exported with the switches each
/// loop needs as start values, so the loops' system and SSP files set no Boolean parameter
/// (fmpy's `simulate_ssp` sets every Boolean parameter of an SSP to true).
#[derive(Clone, Debug)]
pub struct Fmus {
    /// The nominal (simulated) arm, horizontal unless its `base_angle` is set.
    pub arm: PathBuf,
    /// The emulated real arm.
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

/// Exports the base FMUs into `dir`.
pub fn build_fmus(dir: &Path) -> Result<Fmus, String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let nominal = ArmConfig::default();
    let export = |id: &str, model: ModelSpec| -> Result<PathBuf, String> {
        let path = dir.join(format!("{id}.fmu"));
        export_fmu(&FmuSpec { identifier: id.into(), model }, &[], &path)?;
        Ok(path)
    };
    let placement = ReferencePlacement::for_arm(&nominal.arm);
    let ArmState { q: q_start, .. } = tracking_start(&nominal.arm, &placement)?;
    Ok(Fmus {
        arm: export("PlanarArm", ModelSpec::PlanarArm(PlanarArmSpec { config: nominal.clone(), q0: vec![0.0; 4], qd0: vec![0.0; 4] }))?,
        arm_real: export(
            "PlanarArmReal",
            ModelSpec::PlanarArm(PlanarArmSpec { config: emulated_real_arm(), q0: vec![0.0; 4], qd0: vec![0.0; 4] }),
        )?,
        task_controller: export(
            "TaskSpaceController",
            ModelSpec::TaskSpaceController(TaskSpaceControllerSpec {
                model: nominal.arm.clone().frictionless(),
                gains: TaskSpaceGains::default(),
                centre: [placement.centre.x, placement.centre.y],
                scale: placement.scale,
                q_start,
            }),
        )?,
        joint_controller: export(
            "JointController",
            ModelSpec::JointController(JointControllerSpec { joints: 4, kp: 50.0, kd: 0.0, use_sequence: true }),
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

/// The state the tracking runs start from: on the reference placed by `placement` at t = 0,
/// with its velocity, so no start-up transient enters the error. The pose comes from inverse
/// kinematics seeded with [`TRACKING_SEED_POSE`] (joint i takes entry i mod 4). Fails, saying
/// why, when the arm cannot hold the curve or the inverse kinematics finds no pose.
pub fn tracking_start(arm: &ArmParams, placement: &ReferencePlacement) -> Result<ArmState, String> {
    placement.check(arm).map_err(|e| e.to_string())?;
    let (x0, xd0, _) = scaled_reference(0.0, placement.centre, placement.scale);
    let seed: Vec<f64> = (0..arm.dof()).map(|i| TRACKING_SEED_POSE[i % 4]).collect();
    let q0 = inverse_kinematics(arm, x0, &seed)
        .ok_or_else(|| format!("no joint angles put the end effector at the reference's start ({:.3}, {:.3}) m", x0.x, x0.y))?;
    let pinv = pseudo_inverse(&jacobian(arm, &q0)).ok_or("singular start pose")?;
    let qd0: Vec<f64> = (&pinv * nalgebra::DVector::from_column_slice(xd0.as_slice())).iter().copied().collect();
    Ok(ArmState { q: q0, qd: qd0 })
}

fn master(e: MasterError) -> String {
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

// ---------------------------------------------------------------------------------------
// Friction identification

/// A training pair of a friction net: (velocity [rad/s], mean torque [N·m], samples averaged).
pub type FrictionPair = (f64, f64, usize);

/// Steady states of one joint under constant torques: (torque [N·m], mean measured velocity
/// [rad/s]) per level, and the samples of each level's last window.
#[derive(Clone, Debug, Default)]
pub struct FrictionRun {
    /// Joint index (0-based).
    pub joint: usize,
    /// (torque, mean velocity) per torque level that moved the joint.
    pub levels: Vec<(f64, f64)>,
    /// (velocity sample, torque) of the steady windows: the binned data.
    pub samples: Vec<(f64, f64)>,
    /// Simulated time [s].
    pub simulated_s: f64,
    /// The largest torque level that did not move the joint [N·m] (signed), and how many
    /// levels did not.
    pub breakaway: (f64, usize),
}

/// The training pair at rest: (0 rad/s, midpoint of the breakaway torques of the two
/// directions, number of levels that did not move the joint). At rest friction takes any value
/// between the two breakaway torques; the midpoint is the compensation that pushes neither
/// way. Without it no pair lies in the stick band (|q̇| below the first moving level,
/// ~0.1 rad/s), and where a net puts its jump inside that band is left to chance: with seeds
/// 1–5 the sim NN/perfect tracking ratio ranged 0.98–4.2. (Pairs at ±ε with the breakaway
/// torques, to sharpen the jump, made the nets overshoot between ε and the first level.)
pub fn rest_pair(runs: &[&FrictionRun]) -> Option<(f64, f64, usize)> {
    let up = runs.iter().find(|r| r.breakaway.0 > 0.0)?;
    let down = runs.iter().find(|r| r.breakaway.0 < 0.0)?;
    Some((0.0, 0.5 * (up.breakaway.0 + down.breakaway.0), up.breakaway.1 + down.breakaway.1))
}

/// Gains of the joint PD loops of the identification experiments: critically damped at
/// 40 rad/s for the smallest inertia each joint can present, 1/(H⁻¹)_ii over poses on a grid
/// (the other joints' coupling makes it much smaller than H_ii), so the sampled loop stays
/// stable in every pose.
fn hold_gains(arm: &ArmParams) -> Vec<(f64, f64)> {
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
    // Stiffer or more damped settings (150 rad/s, or damping ratio 3) made the coupled sampled
    // loop unstable in some poses of the gravity sweep.
    let (w, zeta) = (40.0, 1.0);
    inertia.iter().map(|m| (m * w * w, 2.0 * zeta * m * w)).collect()
}

fn joint_loop(
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

/// Drives joint `joint` of the arm in `arm_fmu` with constant torques in `direction` (±1),
/// the others held at 0 by the joint controller, raising the torque level by level until
/// the steady speed passes `settings.max_velocity`. Each level lasts until the measured
/// velocity's 0.1 s means change by less than the noise allows (at most 20 s). The step
/// between levels aims at `velocity_spacing` from the local slope of the levels so far.
pub fn friction_run(arm_fmu: &Path, controller: &Path, joint: usize, direction: f64, settings: &Settings) -> Result<FrictionRun, String> {
    let arm = ArmConfig::default().arm;
    let mut gains = hold_gains(&arm);
    gains[joint] = (0.0, 0.0);
    let mut s = joint_loop(arm_fmu, controller, &[("internal_step", Value::Real(IDENTIFICATION_INTERNAL_STEP_S))], &gains, None)?;
    s.set("ctl", "use_sequence", Value::Boolean(false)).map_err(master)?;
    let mut sim = s.initialize(0.0, settings.step, Algorithm::GaussSeidel, &[]).map_err(master)?;
    let drive = [sim.real_handle(&format!("ctl.tau_comp_{}", joint + 1)).map_err(master)?];
    let speed = [sim.real_handle(&format!("arm.qd_meas_{}", joint + 1)).map_err(master)?];
    let window = (0.1 / settings.step).round() as usize;
    let mut run = FrictionRun { joint, ..Default::default() };
    let mut tau = 0.0;
    let mut increment = 0.02;
    let mut buf = vec![0.0; window];
    let mut v = [0.0];
    loop {
        tau += direction * increment;
        sim.set_reals(&drive, &[tau]).map_err(master)?;
        let mut previous = f64::NAN;
        let started = sim.time();
        let mean = loop {
            for slot in buf.iter_mut() {
                sim.step().map_err(master)?;
                sim.get_reals(&speed, &mut v).map_err(master)?;
                *slot = v[0];
            }
            let mean = buf.iter().sum::<f64>() / window as f64;
            let spread = (buf.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / window as f64).sqrt();
            let tolerance = 2e-4 + 3.0 * spread / (window as f64).sqrt();
            if (mean - previous).abs() < tolerance || sim.time() - started > 20.0 {
                break mean;
            }
            previous = mean;
        };
        let moving = mean * direction > 2.0 * settings.bin_width.min(0.05);
        if moving {
            if let Some(&(t0, v0)) = run.levels.last() {
                let slope = (tau - t0) / (mean - v0);
                if slope.is_finite() && slope > 0.0 {
                    increment = (slope * settings.velocity_spacing).clamp(1e-3, 0.5);
                }
            }
            run.levels.push((tau, mean));
            run.samples.extend(buf.iter().map(|&x| (x, tau)));
        } else if run.levels.is_empty() {
            run.breakaway = (tau, run.breakaway.1 + 1);
        }
        if mean * direction >= settings.max_velocity {
            break;
        }
        if tau.abs() > 100.0 {
            return Err(format!("joint {}: no speed of {} rad/s below 100 N·m", joint + 1, settings.max_velocity));
        }
    }
    run.simulated_s = sim.time();
    Ok(run)
}

/// Bins velocity samples of width `width` over ±`limit` and averages each bin: returns
/// (mean velocity, mean torque, count) per non-empty bin, by velocity.
pub fn bin_friction(samples: &[(f64, f64)], width: f64, limit: f64) -> Vec<FrictionPair> {
    let bins = (2.0 * limit / width).round() as usize;
    let mut acc = vec![(0.0, 0.0, 0usize); bins];
    for &(v, t) in samples {
        if v.abs() >= limit || !v.is_finite() {
            continue;
        }
        let k = (((v + limit) / width).floor() as usize).min(bins - 1);
        acc[k].0 += v;
        acc[k].1 += t;
        acc[k].2 += 1;
    }
    acc.into_iter().filter(|b| b.2 > 0).map(|(v, t, n)| (v / n as f64, t / n as f64, n)).collect()
}

/// Trains one friction net (velocity → torque) on binned pairs.
pub fn train_friction_net(joint: usize, pairs: &[(f64, f64, usize)], seed: u64) -> Result<WeightsFile, String> {
    let x = DMatrix::from_fn(1, pairs.len(), |_, c| pairs[c].0);
    let t = DMatrix::from_fn(1, pairs.len(), |_, c| pairs[c].1);
    // A few hundred pairs with a jump at zero: 6 validation failures in a row stop most
    // starts in the first epochs, so this allows 20. Of 10 starts, each stopped early on its own
    // validation part, the one that fits all pairs best is kept: scoring on the validation
    // part alone picks nets whose jump is anywhere, as it rarely holds a pair near q̇ = 0.
    const STARTS: u64 = 10;
    let mut best: Option<(f64, TrainSettings, neurarm_physics::nn::Trained)> = None;
    for start in 0..STARTS {
        let mut settings =
            TrainSettings { hidden: 10, restarts: 1, max_fail: 20, seed: seed + joint as u64 + 7919 * start, ..TrainSettings::default() };
        // The pair at rest is the only one in the stick band: keep it in the training part
        // (the first split seed from there that does), or the jump lands anywhere in the band.
        if let Some(rest) = pairs.iter().position(|p| p.0 == 0.0) {
            for _ in 0..1000 {
                if neurarm_physics::nn::lm::split(pairs.len(), settings.split, settings.seed)[0].contains(&rest) {
                    break;
                }
                settings.seed += 1000;
            }
        }
        let trained = train(&x, &t, &settings, &mut |_| {}).map_err(|e| format!("friction net of joint {}: {e}", joint + 1))?;
        let sse: f64 = pairs.iter().map(|p| (trained.net.evaluate(&[p.0])[0] - p.1).powi(2)).sum();
        if best.as_ref().is_none_or(|b| sse < b.0) {
            best = Some((sse, settings, trained));
        }
    }
    let (_, settings, trained) = best.expect("at least one start");
    let name = format!("{}", joint + 1);
    Ok(WeightsFile::new(
        &trained.net,
        vec![Signal { name: format!("qd_{name}"), unit: "rad/s".into() }],
        vec![Signal { name: format!("tau_friction_{name}"), unit: "N.m".into() }],
        settings,
        trained.report,
    ))
}

// ---------------------------------------------------------------------------------------
// Gravity identification

/// One averaged measurement: the mean of the up and down passes' angles [rad] and torques [N·m].
pub type GravityPair = (Vec<f64>, Vec<f64>);

/// Points of a `grid`ⁿ grid over 0 … 2π(grid−1)/grid in snake order, so that successive
/// points differ in one joint by one grid step.
pub fn gravity_grid(grid: usize, joints: usize) -> Vec<Vec<f64>> {
    let step = 2.0 * PI / grid as f64;
    let mut points: Vec<Vec<usize>> = vec![vec![]];
    for _ in 0..joints {
        let mut next = Vec::new();
        for (k, p) in points.iter().enumerate() {
            // Reverse every other run of the new innermost index (boustrophedon).
            let idx: Vec<usize> = if k % 2 == 0 { (0..grid).collect() } else { (0..grid).rev().collect() };
            for i in idx {
                let mut q = p.clone();
                q.push(i);
                next.push(q);
            }
        }
        points = next;
    }
    points.into_iter().map(|p| p.iter().map(|&i| i as f64 * step).collect()).collect()
}

/// Speed of the gravity sweep's passes [rad/s].
pub const GRAVITY_SWEEP_SPEED_RAD_S: f64 = 0.25;
const SWEEP_SPEED: f64 = GRAVITY_SWEEP_SPEED_RAD_S;

/// Moves the arm (base turned 90°) through `points` in order: a smooth rest-to-rest move to
/// just below each point, then every joint slowly up through it and back down at
/// `SWEEP_SPEED`; at the middle of each pass the measured angles and commanded torques are
/// averaged over ±20 ms, and the up and down results are averaged, which cancels friction
/// that is odd in the velocity. The inertia term is zero at constant speed.
///
/// The joints are held on the moves by an inertia-scaled PD, τ = Ĥ(q)(q̈_d + K_d ė + K_p e) +
/// Ĉ(q, q̇)q̇ with K_p = 1600 1/s², K_d = 80 1/s (critically damped at 40 rad/s in every pose),
/// computed here from the nominal rigid-body model *without gravity* (that is what is being
/// identified) and passed to the joint controller's `tau_comp` input, its own gains at 0. A
/// diagonal PD cannot do this: tuned for the lightest pose it is underdamped in the heavy ones
/// and its oscillation put errors of up to 7 N·m into the pairs. The speed is 0.25 rad/s:
/// Coriolis and centrifugal torques grow with its square and do not cancel between passes.
pub fn gravity_sweep(
    arm_fmu: &Path,
    controller: &Path,
    points: &[Vec<f64>],
    settings: &Settings,
) -> Result<(Vec<GravityPair>, f64), String> {
    const PASS_S: f64 = 0.4;
    const HOLD_RAD_S: f64 = 40.0;
    let arm = ArmConfig::default().arm;
    let n = arm.dof();
    // Gravity-free nominal model of the hold: the horizontal arm's inverse dynamics.
    let rigid_body = arm.clone().frictionless();
    let offset = SWEEP_SPEED * PASS_S / 2.0;
    let first: Vec<f64> = points[0].iter().map(|q| q - offset).collect();
    let mut parameters: Vec<(String, Value)> =
        vec![("base_angle".into(), Value::Real(PI / 2.0)), ("internal_step".into(), Value::Real(IDENTIFICATION_INTERNAL_STEP_S))];
    for (i, q) in first.iter().enumerate() {
        parameters.push((format!("q0_{}", i + 1), Value::Real(*q)));
    }
    let p: Vec<(&str, Value)> = parameters.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
    let mut s = joint_loop(arm_fmu, controller, &p, &vec![(0.0, 0.0); n], None)?;
    s.set("ctl", "use_sequence", Value::Boolean(false)).map_err(master)?;
    let mut sim = s.initialize(0.0, settings.step, Algorithm::GaussSeidel, &[]).map_err(master)?;
    let handles = |sim: &Simulation, f: &dyn Fn(usize) -> String| -> Result<Vec<Handle>, String> {
        (0..n).map(|i| sim.real_handle(&f(i)).map_err(master)).collect()
    };
    let reference: Vec<Handle> =
        [handles(&sim, &|i| format!("ctl.q_ref_{}", i + 1))?, handles(&sim, &|i| format!("ctl.qd_ref_{}", i + 1))?].concat();
    let measured: Vec<Handle> =
        [handles(&sim, &|i| format!("arm.q_meas_{}", i + 1))?, handles(&sim, &|i| format!("ctl.tau_{}", i + 1))?].concat();
    let state: Vec<Handle> =
        [handles(&sim, &|i| format!("arm.q_meas_{}", i + 1))?, handles(&sim, &|i| format!("arm.qd_meas_{}", i + 1))?].concat();
    let hold_torque = handles(&sim, &|i| format!("ctl.tau_comp_{}", i + 1))?;
    let mut x = vec![0.0; 2 * n];
    let mut u = vec![0.0; n];
    let (mut rigid_data, mut tau) = (ArmData::new(&rigid_body), vec![0.0; n]);
    // One step with the reference (angles, velocities) in `r` and acceleration `a`.
    let mut step = |sim: &mut Simulation, r: &[f64], a: &[f64]| -> Result<(), String> {
        sim.set_reals(&reference, r).map_err(master)?;
        sim.get_reals(&state, &mut x).map_err(master)?;
        for i in 0..n {
            u[i] = a[i] + 2.0 * HOLD_RAD_S * (r[n + i] - x[n + i]) + HOLD_RAD_S * HOLD_RAD_S * (r[i] - x[i]);
        }
        inverse_dynamics_rnea_into(&rigid_body, &mut rigid_data, &x[..n], &x[n..], &u, &mut tau);
        sim.set_reals(&hold_torque, &tau).map_err(master)?;
        sim.step().map_err(master)
    };
    let mut accel = vec![0.0; n];
    let no_accel = vec![0.0; n];
    let h = settings.step;
    let half_window = (0.02 / h).round() as usize;
    let pass_steps = (PASS_S / h).round() as usize;
    let mut set_ref = vec![0.0; 2 * n];
    let mut read = vec![0.0; 2 * n];
    let mut current = first.clone();
    let mut pairs = Vec::with_capacity(points.len());
    for point in points {
        // Rest-to-rest cosine move to the start of the up pass.
        let start: Vec<f64> = point.iter().map(|q| q - offset).collect();
        let distance = current.iter().zip(&start).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        if distance > 0.0 {
            let duration = (distance / 1.5).max(0.3);
            let steps = (duration / h).ceil() as usize;
            for k in 1..=steps {
                let s = k as f64 / steps as f64;
                let blend = 0.5 - 0.5 * (PI * s).cos();
                let rate = 0.5 * PI * (PI * s).sin() / duration;
                let rate_change = 0.5 * PI * PI * (PI * s).cos() / (duration * duration);
                for i in 0..n {
                    set_ref[i] = current[i] + (start[i] - current[i]) * blend;
                    set_ref[n + i] = (start[i] - current[i]) * rate;
                    accel[i] = (start[i] - current[i]) * rate_change;
                }
                step(&mut sim, &set_ref, &accel)?;
            }
        }
        let mut passes = Vec::with_capacity(2);
        for direction in [1.0, -1.0] {
            let from: Vec<f64> = point.iter().map(|q| q - direction * offset).collect();
            let mut sum = vec![0.0; 2 * n];
            let mut count = 0;
            for k in 1..=pass_steps {
                for i in 0..n {
                    set_ref[i] = from[i] + direction * SWEEP_SPEED * k as f64 * h;
                    set_ref[n + i] = direction * SWEEP_SPEED;
                }
                step(&mut sim, &set_ref, &no_accel)?;
                if k.abs_diff(pass_steps / 2) <= half_window {
                    sim.get_reals(&measured, &mut read).map_err(master)?;
                    for (a, r) in sum.iter_mut().zip(&read) {
                        *a += r;
                    }
                    count += 1;
                }
            }
            passes.push(sum.iter().map(|x| x / count as f64).collect::<Vec<f64>>());
        }
        let avg: Vec<f64> = (0..2 * n).map(|j| 0.5 * (passes[0][j] + passes[1][j])).collect();
        pairs.push((avg[..n].to_vec(), avg[n..].to_vec()));
        current = point.iter().map(|q| q - offset).collect();
    }
    Ok((pairs, sim.time()))
}

/// Trains the gravity net (angles → torques) on the averaged pairs.
pub fn train_gravity_net(pairs: &[GravityPair], settings: &Settings, on_epoch: &mut dyn FnMut(usize)) -> Result<WeightsFile, String> {
    let n = pairs[0].0.len();
    let x = DMatrix::from_fn(n, pairs.len(), |r, c| pairs[c].0[r]);
    let t = DMatrix::from_fn(n, pairs.len(), |r, c| pairs[c].1[r]);
    let train_settings = TrainSettings {
        hidden: settings.gravity_hidden,
        epochs: settings.gravity_epochs,
        max_fail: 20,
        restarts: 3,
        seed: settings.seed + 1,
        ..TrainSettings::default()
    };
    let trained = train(&x, &t, &train_settings, &mut |e| on_epoch(e.epoch)).map_err(|e| format!("gravity net: {e}"))?;
    let signals = |prefix: &str, unit: &str| (0..n).map(|i| Signal { name: format!("{prefix}_{}", i + 1), unit: unit.into() }).collect();
    Ok(WeightsFile::new(&trained.net, signals("q", "rad"), signals("tau_gravity", "N.m"), train_settings, trained.report))
}

// ---------------------------------------------------------------------------------------
// Closed loops

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
}

/// A path as a system file writes it: '/'-separated on every platform.
fn spec_path(p: &Path) -> String {
    p.to_string_lossy().replace('\\', "/")
}

/// The units and connections every closed loop shares: `arm` measured by the controller
/// `ctl`, whose torques drive the arm; with a compensator `comp`, fed the same measurements,
/// adding `tau_comp` in the controller. Paths as the system file will hold them.
fn closed_loop(
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

/// The task-space tracking loop of Table 1 as a system: the arm in `arm` started on the
/// reference ([`tracking_start`]), the task-space controller, and the compensator FMU if
/// any, for `settings.tracking_duration` at `settings.step`. FMU paths are taken as given
/// (relative to where the system file will be, or absolute).
pub fn tracking_system(arm: &Path, controller: &Path, compensator: Option<&Path>, settings: &Settings) -> Result<SystemSpec, String> {
    let nominal = ArmConfig::default().arm;
    let ArmState { q: q0, qd: qd0 } = tracking_start(&nominal, &ReferencePlacement::for_arm(&nominal))?;
    let mut arm_parameters = BTreeMap::new();
    for i in 0..q0.len() {
        arm_parameters.insert(format!("q0_{}", i + 1), Value::Real(q0[i]));
        arm_parameters.insert(format!("qd0_{}", i + 1), Value::Real(qd0[i]));
    }
    let mut spec = closed_loop(arm, controller, compensator, arm_parameters, BTreeMap::new());
    let mut record: Vec<String> =
        ["ctl.error_x", "ctl.error_y", "ctl.x_ref", "ctl.y_ref", "arm.x", "arm.y"].iter().map(|s| s.to_string()).collect();
    record.extend((1..=q0.len()).map(|i| format!("arm.q_{i}")));
    record.extend((1..=q0.len()).map(|i| format!("arm.qd_{i}")));
    record.extend((1..=q0.len()).map(|i| format!("ctl.tau_{i}")));
    spec.simulation.stop = settings.tracking_duration;
    spec.simulation.step = settings.step;
    spec.simulation.record = record;
    Ok(spec)
}

/// The joint-space loop with gravity compensation as a system: the arm with its base turned
/// 90° starting at the hanging pose, the joint controller on its built-in sequence with
/// `settings.joint_kp`/`joint_kd` on every joint, and the compensator FMU if any.
pub fn gravity_compensation_system(arm: &Path, controller: &Path, compensator: Option<&Path>, settings: &Settings) -> SystemSpec {
    let n = 4;
    let arm_parameters = BTreeMap::from([("base_angle".to_owned(), Value::Real(PI / 2.0)), ("q0_1".to_owned(), Value::Real(-PI / 2.0))]);
    let mut gains = BTreeMap::new();
    for i in 1..=n {
        gains.insert(format!("kp_{i}"), Value::Real(settings.joint_kp));
        gains.insert(format!("kd_{i}"), Value::Real(settings.joint_kd));
    }
    let mut spec = closed_loop(arm, controller, compensator, arm_parameters, gains);
    let mut record: Vec<String> = (1..=n).map(|i| format!("ctl.q_target_{i}")).collect();
    record.extend((1..=n).map(|i| format!("arm.q_{i}")));
    record.extend((1..=n).map(|i| format!("ctl.tau_{i}")));
    spec.simulation.stop = neurarm_models::joint::SEQUENCE_SEGMENT_S * neurarm_models::joint::JOINT_SEQUENCE.len() as f64;
    spec.simulation.step = settings.step;
    spec.simulation.record = record;
    spec
}

/// Runs a closed-loop system (FMU paths relative to `base`), recording every step.
pub fn run_loop(spec: &SystemSpec, base: &Path) -> Result<LoopRun, String> {
    let s = System::from_spec(spec, base).map_err(master)?;
    let sim = &spec.simulation;
    let mut run = s.initialize(sim.start, sim.step, sim.algorithm, &sim.record).map_err(master)?;
    run.record_every(sim.record_every);
    run.run_until(sim.stop).map_err(master)?;
    Ok(LoopRun { columns: run.columns(), rows: run.take_rows() })
}

/// Mean squared tracking error of a run [m²]: the mean over samples and both coordinates
/// of (x_d − x)².
pub fn tracking_mse(run: &LoopRun) -> f64 {
    let ex = run.column("ctl.error_x").unwrap_or_default();
    let ey = run.column("ctl.error_y").unwrap_or_default();
    ex.iter().zip(&ey).map(|(a, b)| a * a + b * b).sum::<f64>() / (2.0 * ex.len().max(1) as f64)
}

/// RMS of q_target − q per joint over a joint-space run [rad].
pub fn joint_rms_errors(run: &LoopRun, joints: usize) -> Vec<f64> {
    (1..=joints)
        .map(|i| {
            let t = run.column(&format!("ctl.q_target_{i}")).unwrap_or_default();
            let q = run.column(&format!("arm.q_{i}")).unwrap_or_default();
            (t.iter().zip(&q).map(|(a, b)| (a - b).powi(2)).sum::<f64>() / t.len().max(1) as f64).sqrt()
        })
        .collect()
}

/// Mean |q_target − q| per joint over the last 0.5 s of each target segment [rad]: the
/// error the loop settles to, which gravity left uncompensated dominates.
pub fn joint_settled_errors(run: &LoopRun, joints: usize) -> Vec<f64> {
    let time = run.column("time").unwrap_or_default();
    let segment = neurarm_models::joint::SEQUENCE_SEGMENT_S;
    let settled: Vec<bool> =
        time.iter().map(|t| t.rem_euclid(segment) >= segment - 0.5 || (*t > 0.0 && t.rem_euclid(segment) == 0.0)).collect();
    (1..=joints)
        .map(|i| {
            let t = run.column(&format!("ctl.q_target_{i}")).unwrap_or_default();
            let q = run.column(&format!("arm.q_{i}")).unwrap_or_default();
            let (sum, count) =
                t.iter().zip(&q).zip(&settled).filter(|(_, &s)| s).fold((0.0, 0usize), |(s, c), ((a, b), _)| (s + (a - b).abs(), c + 1));
            sum / count.max(1) as f64
        })
        .collect()
}
