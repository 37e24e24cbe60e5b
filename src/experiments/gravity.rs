//! Gravity identification: slow up and down passes through the poses of a grid or a sampled
//! design with the base turned 90°, the identified friction taken out of each pass and the
//! two passes averaged; one multi-input net; its error on random poses.

use std::f64::consts::PI;
use std::path::Path;

use anyhow::{bail, Context, Result};
use nalgebra::DMatrix;
use rand::{Rng, SeedableRng};

use super::friction::FrictionCurve;
use super::{identification_internal_step, joint_loop, parallel, real_handles, GravityDesign, Settings, ARM_UNIT, CONTROLLER_UNIT};
use crate::identify::{gravity_pair, GravityCorrection, GravityMeasurement, GravityOptions, PassFault, PassWindow};
use neurarm_cosim::{Algorithm, Handle, Simulation, Value};
use neurarm_models::names;
use neurarm_nn::{train, EpochInfo, InputEncoding, Signal, TrainSettings, WeightsFile};
use neurarm_physics::arm::{gravity_torques, ArmData, ArmParams};
use neurarm_physics::control::holds::gravity_hold_torques_into;

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

/// `poses` poses drawn uniformly over [0, 2π)ⁿ from `seed`, ordered for the sweep: from each
/// pose to the nearest one not yet visited (largest joint difference, each angle taken modulo
/// 2π), and each pose shifted by whole turns to the representative nearest the previous one, so
/// the arm never travels more than half a turn per joint between poses. Gravity is
/// 2π-periodic in every angle, so the shifted poses measure the same torques; wrap the
/// measured angles back into [0, 2π) before training.
pub fn sampled_poses(poses: usize, joints: usize, seed: u64) -> Vec<Vec<f64>> {
    sampled_poses_drawn(poses, joints, seed).into_iter().map(|(_, pose)| pose).collect()
}

/// [`sampled_poses`] with each pose's place in the draw: the poses drawn first N of a larger
/// design are themselves a uniform design of N poses (what [`gravity_study`](super::gravity_study::gravity_study) uses).
pub fn sampled_poses_drawn(poses: usize, joints: usize, seed: u64) -> Vec<(usize, Vec<f64>)> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut left: Vec<(usize, Vec<f64>)> = (0..poses).map(|i| (i, (0..joints).map(|_| rng.gen::<f64>() * 2.0 * PI).collect())).collect();
    let nearest_turn = |a: f64, b: f64| b + ((a - b) / (2.0 * PI)).round() * 2.0 * PI;
    let mut path: Vec<(usize, Vec<f64>)> = Vec::with_capacity(poses);
    while !left.is_empty() {
        let next = match path.last() {
            None => 0,
            Some((_, current)) => {
                let distance = |p: &Vec<f64>| p.iter().zip(current).map(|(b, a)| (nearest_turn(*a, *b) - a).abs()).fold(0.0, f64::max);
                (0..left.len()).min_by(|&i, &j| distance(&left[i].1).total_cmp(&distance(&left[j].1))).expect("poses left")
            }
        };
        let (index, mut pose) = left.swap_remove(next);
        if let Some((_, current)) = path.last() {
            for (b, a) in pose.iter_mut().zip(current) {
                *b = nearest_turn(*a, *b);
            }
        }
        path.push((index, pose));
    }
    path
}

/// The poses of `design` for `joints` joints in sweep order, and the span of each trained
/// angle [rad] (the grid's 2π(k−1)/k, or the whole turn).
pub fn design_poses(design: GravityDesign, joints: usize, seed: u64) -> (Vec<Vec<f64>>, f64) {
    let poses = match design {
        GravityDesign::Grid { per_joint } => gravity_grid(per_joint, joints),
        GravityDesign::Sampled { poses } => sampled_poses(poses, joints, seed),
    };
    (poses, design_span(design))
}

/// The span of each angle a design's poses cover [rad]: 2π(k−1)/k for a kⁿ grid, the whole
/// turn for a sampled design.
pub fn design_span(design: GravityDesign) -> f64 {
    match design {
        GravityDesign::Grid { per_joint } => 2.0 * PI * (per_joint as f64 - 1.0) / per_joint as f64,
        GravityDesign::Sampled { .. } => 2.0 * PI,
    }
}

/// Measures `poses` (in sweep order) with [`gravity_sweep`], split over `settings.threads`
/// workers; `wrap` brings the measured angles back into [0, 2π) (for paths shifted by whole
/// turns). `done` is called as each worker's part finishes.
#[allow(clippy::too_many_arguments)]
pub fn measure_gravity(
    arm_fmu: &Path,
    controller: &Path,
    model: &ArmParams,
    poses: &[Vec<f64>],
    wrap: bool,
    correction: Option<&[FrictionCurve]>,
    settings: &Settings,
    done: &(dyn Fn() + Sync),
) -> Result<GravitySweep> {
    let chunk = poses.len().div_ceil(settings.threads.max(1)).max(1);
    let chunks: Vec<Vec<Vec<f64>>> = poses.chunks(chunk).map(|c| c.to_vec()).collect();
    let swept = parallel(
        chunks,
        settings.threads,
        |points| gravity_sweep(arm_fmu, controller, model, &points, correction, settings).context("gravity identification"),
        done,
    )?;
    let mut all = GravitySweep::default();
    for (k, sweep) in swept.into_iter().enumerate() {
        all.pairs.extend(sweep.pairs);
        all.pairs_uncorrected.extend(sweep.pairs_uncorrected);
        all.pose_index.extend(sweep.pose_index.iter().map(|i| i + k * chunk));
        all.time_s += sweep.time_s;
        all.repeated += sweep.repeated;
        all.dropped.extend(sweep.dropped);
    }
    if wrap {
        // Gravity is 2π-periodic in each angle.
        for (q, _) in all.pairs.iter_mut().chain(all.pairs_uncorrected.iter_mut()) {
            q.iter_mut().for_each(|a| *a = a.rem_euclid(2.0 * PI));
        }
    }
    Ok(all)
}

/// Speed of the gravity sweep's passes [rad/s].
pub const GRAVITY_SWEEP_SPEED_RAD_S: f64 = 0.25;
const SWEEP_SPEED: f64 = GRAVITY_SWEEP_SPEED_RAD_S;

/// The pairs of one sweep.
#[derive(Clone, Debug, Default)]
pub struct GravitySweep {
    /// Up and down passes averaged after each pass's torque had the identified friction at
    /// the measured speeds taken out (as `pairs_uncorrected` without friction nets).
    pub pairs: Vec<GravityPair>,
    /// Up and down passes averaged as they were measured (the paper's procedure).
    pub pairs_uncorrected: Vec<GravityPair>,
    /// Index of each pair's pose in the poses given.
    pub pose_index: Vec<usize>,
    /// Simulated time of the sweep [s].
    pub time_s: f64,
    /// Pass pairs measured again, with passes twice as long, because a joint's speed left
    /// ±[`STEADY_SHARE`] of the pass speed in a measuring window.
    pub repeated: usize,
    /// Poses (angles in [0, 2π)) left out after [`STEADY_RETRIES`] such repeats.
    pub dropped: Vec<Vec<f64>>,
}

/// A pass is steady when every joint's measured speed stays within this share of the pass
/// speed throughout the measuring window. A light joint can stick and slip through a pass
/// (seen on 1–4 % of the 6-joint example's passes, with torques off by up to 0.25 N·m).
pub const STEADY_SHARE: f64 = 0.2;
/// Repeats of an unsteady pass pair, each with passes twice as long as the last.
pub const STEADY_RETRIES: u32 = 2;

/// Bandwidth of the gravity sweep's hold [rad/s]: the inertia-scaled PD that keeps the joints
/// on their moves is critically damped at it.
pub use neurarm_physics::control::holds::GRAVITY_HOLD_RAD_S;

/// Length of a pass at its first attempt [s].
const PASS_S: f64 = 0.4;

/// Moves the arm (base turned 90°) to just below each of `points` [rad] in turn, then every joint
/// up through it and back down at `SWEEP_SPEED`; a pair is the mean of the two passes' angles and
/// commanded torques over ±20 ms at each middle, in which friction odd in the speed cancels.
/// With `correction` each pass first loses the model's Coriolis and centrifugal torques and the
/// friction of the given curves (none if empty); `pairs_uncorrected` are the plain means. The
/// joints are held by [`gravity_hold_torques_into`] at [`GRAVITY_HOLD_RAD_S`] through `tau_comp`
/// (docs/decisions/0005-gravity-sweep.md).
pub fn gravity_sweep(
    arm_fmu: &Path,
    controller: &Path,
    model: &ArmParams,
    points: &[Vec<f64>],
    correction: Option<&[FrictionCurve]>,
    settings: &Settings,
) -> Result<GravitySweep> {
    let n = model.dof();
    if let Some(curves) = correction.filter(|c| !c.is_empty() && c.len() != n) {
        bail!("friction curves of {} joints for {n} joints", curves.len());
    }
    let offset = SWEEP_SPEED * PASS_S / 2.0;
    let first: Vec<f64> = points[0].iter().map(|q| q - offset).collect();
    let mut rig = SweepRig::new(arm_fmu, controller, model, &first, settings)?;
    let half_window = (0.02 / settings.step).round() as usize;
    // The pass pairs are judged and averaged by the code `neurarm identify gravity` runs on logs.
    let options = GravityOptions {
        speed_rad_s: SWEEP_SPEED,
        share: STEADY_SHARE,
        window_s: 2.0 * half_window as f64 * settings.step,
        // Noise-free 1 kHz samples: a short average still sees a joint that sticks.
        smoothing_s: 0.01,
        ..GravityOptions::default()
    };
    // Gravity-free nominal model of the hold: the horizontal arm's inverse dynamics.
    let rigid_body = model.clone().with_base_angle(0.0).frictionless();
    let correction_terms = match correction {
        Some(curves) => GravityCorrection { friction: curves, model: Some(&rigid_body) },
        None => GravityCorrection::default(),
    };
    let mut current = first;
    let mut sweep = GravitySweep::default();
    for (index, point) in points.iter().enumerate() {
        let pose = PoseMeasure { point, half_window, options: &options, correction: &correction_terms };
        match pose.measure(&mut rig, &mut current, &mut sweep.repeated).with_context(|| format!("pose {}", index + 1))? {
            Some(m) => {
                sweep.pairs.push((m.q.clone(), m.torque));
                sweep.pairs_uncorrected.push((m.q, m.torque_uncorrected));
                sweep.pose_index.push(index);
            }
            None => sweep.dropped.push(point.iter().map(|q| q.rem_euclid(2.0 * PI)).collect()),
        }
    }
    sweep.time_s = rig.sim.time();
    Ok(sweep)
}

/// The gravity sweep's loop: the arm (base turned 90°) and the joint controller through the
/// master, the controller's gains at 0 and the hold's torque fed to its `tau_comp` input.
struct SweepRig {
    sim: Simulation,
    /// The controller's reference angles, then speeds.
    reference: Vec<Handle>,
    /// Measured angles, commanded torques, measured speeds: what a pass records.
    measured: Vec<Handle>,
    /// Measured angles, then speeds: what the hold reads.
    state: Vec<Handle>,
    /// The controller's `tau_comp_i`.
    hold_torque: Vec<Handle>,
    /// The gravity-free nominal model of the hold.
    rigid_body: ArmParams,
    data: ArmData,
    /// Measured state, hold accelerations [rad/s²], hold torques [N·m].
    x: Vec<f64>,
    u: Vec<f64>,
    tau: Vec<f64>,
    /// Communication step [s].
    h: f64,
}

impl SweepRig {
    /// The loop for `model`'s arm in `arm_fmu`, starting at the angles `first` [rad].
    fn new(arm_fmu: &Path, controller: &Path, model: &ArmParams, first: &[f64], settings: &Settings) -> Result<Self> {
        let n = model.dof();
        let mut parameters: Vec<(String, Value)> = vec![
            (names::BASE_ANGLE.into(), Value::Real(PI / 2.0)),
            (names::INTERNAL_STEP.into(), Value::Real(identification_internal_step(model))),
        ];
        for (i, q) in first.iter().enumerate() {
            parameters.push((names::joint(names::START_ANGLE, i + 1), Value::Real(*q)));
        }
        let p: Vec<(&str, Value)> = parameters.iter().map(|(k, v)| (k.as_str(), v.clone())).collect();
        let mut s = joint_loop(arm_fmu, controller, &p, &vec![(0.0, 0.0); n], None)?;
        s.set(CONTROLLER_UNIT, names::USE_SEQUENCE, Value::Boolean(false))?;
        let sim = s.initialize(0.0, settings.step, Algorithm::GaussSeidel, &[])?;
        let handles = |unit: &str, family: &str| real_handles(&sim, n, unit, family);
        let reference = [handles(CONTROLLER_UNIT, names::REFERENCE_ANGLE)?, handles(CONTROLLER_UNIT, names::REFERENCE_VELOCITY)?].concat();
        let (angles, speeds) = (handles(ARM_UNIT, names::MEASURED_ANGLE)?, handles(ARM_UNIT, names::MEASURED_VELOCITY)?);
        let measured = [angles.clone(), handles(CONTROLLER_UNIT, names::TORQUE)?, speeds.clone()].concat();
        let state = [angles, speeds].concat();
        let hold_torque = handles(CONTROLLER_UNIT, names::COMPENSATION_TORQUE)?;
        let rigid_body = model.clone().with_base_angle(0.0).frictionless();
        let data = ArmData::new(&rigid_body);
        Ok(Self {
            sim,
            reference,
            measured,
            state,
            hold_torque,
            rigid_body,
            data,
            x: vec![0.0; 2 * n],
            u: vec![0.0; n],
            tau: vec![0.0; n],
            h: settings.step,
        })
    }

    /// One step with the reference (angles [rad], velocities [rad/s]) in `r` and acceleration
    /// `a` [rad/s²].
    fn step(&mut self, r: &[f64], a: &[f64]) -> Result<()> {
        self.sim.set_reals(&self.reference, r)?;
        self.sim.get_reals(&self.state, &mut self.x)?;
        gravity_hold_torques_into(&self.rigid_body, &mut self.data, r, a, &self.x, &mut self.u, &mut self.tau);
        self.sim.set_reals(&self.hold_torque, &self.tau)?;
        self.sim.step()?;
        Ok(())
    }

    /// Rest-to-rest cosine move from the angles `from` to `to` [rad]: at 1.5 rad/s of the
    /// farthest joint on average, at least 0.3 s.
    fn move_between(&mut self, from: &[f64], to: &[f64]) -> Result<()> {
        let n = from.len();
        let h = self.h;
        let distance = from.iter().zip(to).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        if !(distance > 0.0) {
            return Ok(());
        }
        let (mut set_ref, mut accel) = (vec![0.0; 2 * n], vec![0.0; n]);
        let duration = (distance / 1.5).max(0.3);
        let steps = (duration / h).ceil() as usize;
        for k in 1..=steps {
            let s = k as f64 / steps as f64;
            let blend = 0.5 - 0.5 * (PI * s).cos();
            let rate = 0.5 * PI * (PI * s).sin() / duration;
            let rate_change = 0.5 * PI * PI * (PI * s).cos() / (duration * duration);
            for i in 0..n {
                set_ref[i] = from[i] + (to[i] - from[i]) * blend;
                set_ref[n + i] = (to[i] - from[i]) * rate;
                accel[i] = (to[i] - from[i]) * rate_change;
            }
            self.step(&set_ref, &accel)?;
        }
        Ok(())
    }

    /// One pass of `pass_steps` steps at `SWEEP_SPEED` in `direction` (±1) through `point`
    /// [rad], starting `offset` [rad] before it; records the steps within `half_window` of the
    /// middle.
    fn pass(&mut self, point: &[f64], direction: f64, offset: f64, pass_steps: usize, half_window: usize) -> Result<PassWindow> {
        let n = point.len();
        let h = self.h;
        let (mut set_ref, no_accel, mut read) = (vec![0.0; 2 * n], vec![0.0; n], vec![0.0; 3 * n]);
        let from: Vec<f64> = point.iter().map(|q| q - direction * offset).collect();
        let mut window = PassWindow::new(n);
        for k in 1..=pass_steps {
            for i in 0..n {
                set_ref[i] = from[i] + direction * SWEEP_SPEED * k as f64 * h;
                set_ref[n + i] = direction * SWEEP_SPEED;
            }
            self.step(&set_ref, &no_accel)?;
            if k.abs_diff(pass_steps / 2) <= half_window {
                self.sim.get_reals(&self.measured, &mut read)?;
                window.push(self.sim.time(), &read[..n], &read[2 * n..], &read[n..2 * n]);
            }
        }
        Ok(window)
    }
}

/// The measurement of one pose of the sweep: its angles [rad], the measuring window's half
/// length [steps], and how the passes are judged and corrected.
struct PoseMeasure<'a> {
    point: &'a [f64],
    half_window: usize,
    options: &'a GravityOptions,
    correction: &'a GravityCorrection<'a>,
}

impl PoseMeasure<'_> {
    /// Moves from the angles `current` to below the pose, passes up and down through it and
    /// averages the passes; an unsteady pass pair is measured again with passes twice as long
    /// (counted in `repeated`), at most [`STEADY_RETRIES`] times. `current` ends where the
    /// last pass started. Returns the pair, or none if the passes stayed unsteady.
    fn measure(&self, rig: &mut SweepRig, current: &mut Vec<f64>, repeated: &mut usize) -> Result<Option<GravityMeasurement>> {
        for attempt in 0..=STEADY_RETRIES {
            let pass_s = PASS_S * (1 << attempt) as f64;
            let (offset, pass_steps) = (SWEEP_SPEED * pass_s / 2.0, (pass_s / rig.h).round() as usize);
            // Rest-to-rest cosine move to the start of the up pass.
            let start: Vec<f64> = self.point.iter().map(|q| q - offset).collect();
            rig.move_between(current, &start)?;
            let up = rig.pass(self.point, 1.0, offset, pass_steps, self.half_window)?;
            let down = rig.pass(self.point, -1.0, offset, pass_steps, self.half_window)?;
            *current = start;
            match gravity_pair(&up, &down, self.options, self.correction) {
                Ok(m) => return Ok(Some(m)),
                Err(PassFault::UnsteadyUp | PassFault::UnsteadyDown) => *repeated += 1,
                Err(fault) => bail!("{}", fault.reason()),
            }
        }
        Ok(None)
    }
}

/// Trains the gravity net (angles → torques) on the averaged pairs, its inputs encoded by
/// `encoding`.
pub fn train_gravity_net(
    pairs: &[GravityPair],
    encoding: InputEncoding,
    settings: &Settings,
    on_epoch: &mut dyn FnMut(&EpochInfo<'_>),
) -> Result<WeightsFile> {
    let n = pairs[0].0.len();
    let x = encoding.encode_all(&DMatrix::from_fn(n, pairs.len(), |r, c| pairs[c].0[r]));
    let t = DMatrix::from_fn(n, pairs.len(), |r, c| pairs[c].1[r]);
    let train_settings = TrainSettings {
        hidden: settings.gravity_hidden,
        epochs: settings.gravity_epochs,
        max_fail: 20,
        restarts: 3,
        seed: settings.seed + 1,
        ..TrainSettings::default()
    };
    let trained = train(&x, &t, &train_settings, on_epoch).context("gravity net")?;
    // Named as the compensator's ports the net feeds.
    let signals = |family: &str, unit: &str| (1..=n).map(|j| Signal { name: names::joint(family, j), unit: unit.into() }).collect();
    Ok(WeightsFile::new(&trained.net, signals(names::ANGLE, "rad"), signals(names::GRAVITY_TORQUE, "N.m"), train_settings, trained.report)
        .with_encoding(encoding)
        .gravity())
}

/// A gravity net's error over random poses of one region, per joint.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct RegionErrors {
    /// RMS of net − truth [N·m].
    pub rms_nm: Vec<f64>,
    /// Largest |net − truth| [N·m].
    pub max_nm: Vec<f64>,
    /// Largest |true gravity torque| of the joint [N·m].
    pub largest_torque_nm: Vec<f64>,
    /// `rms_nm` as a share of the joint's own largest torque.
    pub rms_share: Vec<f64>,
    /// `max_nm` as a share of the joint's own largest torque.
    pub max_share: Vec<f64>,
}

impl RegionErrors {
    fn new(joints: usize) -> Self {
        Self { rms_nm: vec![0.0; joints], max_nm: vec![0.0; joints], largest_torque_nm: vec![0.0; joints], ..Self::default() }
    }

    fn add(&mut self, truth: &[f64], guess: &[f64]) {
        for i in 0..truth.len() {
            let e = guess[i] - truth[i];
            self.rms_nm[i] += e * e;
            self.max_nm[i] = self.max_nm[i].max(e.abs());
            self.largest_torque_nm[i] = self.largest_torque_nm[i].max(truth[i].abs());
        }
    }

    fn finish(mut self, poses: usize) -> Self {
        for s in self.rms_nm.iter_mut() {
            *s = (*s / poses.max(1) as f64).sqrt();
        }
        self.rms_share = self.rms_nm.iter().zip(&self.largest_torque_nm).map(|(e, m)| e / m).collect();
        self.max_share = self.max_nm.iter().zip(&self.largest_torque_nm).map(|(e, m)| e / m).collect();
        self
    }
}

/// The gravity net's error against the true gravity of the arm (base turned 90°).
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct GravityNetErrors {
    /// How the net's inputs are encoded.
    pub encoding: InputEncoding,
    /// On poses within the trained span (the paper's reading): the grid's, or the whole turn
    /// for a sampled design; none for a periodic net, for which no span is special.
    pub span: Option<RegionErrors>,
    /// On poses over the whole turn [0, 2π)ⁿ, each angle wrapped into a raw net's trained
    /// turn as the `NnCompensator` FMU does: what a user of the compensator gets.
    pub whole_turn: RegionErrors,
    /// Random poses per region.
    pub poses: usize,
    /// Each whole-turn pose's (true torque, net − truth) per joint [N·m], for the figure.
    #[serde(skip)]
    pub samples: Vec<Vec<(f64, f64)>>,
}

/// The gravity net against the true gravity of `arm` (base turned 90°) on
/// `settings.gravity_test_points` random poses (not training poses) over the whole turn and,
/// for a raw net, as many within the trained span [0, `span`)ⁿ [rad].
pub fn gravity_net_errors(gravity_net: &WeightsFile, arm: &ArmParams, span: f64, settings: &Settings) -> Result<GravityNetErrors> {
    let vertical = arm.clone().with_base_angle(PI / 2.0);
    let n = arm.dof();
    let net = gravity_net.network()?;
    let periodic = net.encoding.is_periodic();
    let low = &gravity_net.input_scaling.min;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(settings.seed + 99);
    let (mut in_span, mut whole) = (RegionErrors::new(n), RegionErrors::new(n));
    let mut samples = vec![Vec::with_capacity(settings.gravity_test_points); n];
    for _ in 0..if periodic { 0 } else { settings.gravity_test_points } {
        let q: Vec<f64> = (0..n).map(|_| rng.gen::<f64>() * span).collect();
        in_span.add(gravity_torques(&vertical, &q).as_slice(), &net.evaluate(&q));
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(settings.seed + 101);
    for _ in 0..settings.gravity_test_points {
        let q: Vec<f64> = (0..n).map(|_| rng.gen::<f64>() * 2.0 * PI).collect();
        let wrapped: Vec<f64> = if periodic { q.clone() } else { (0..n).map(|i| low[i] + (q[i] - low[i]).rem_euclid(2.0 * PI)).collect() };
        let (truth, guess) = (gravity_torques(&vertical, &q), net.evaluate(&wrapped));
        whole.add(truth.as_slice(), &guess);
        for i in 0..n {
            samples[i].push((truth[i], guess[i] - truth[i]));
        }
    }
    let poses = settings.gravity_test_points;
    let span = (!periodic).then(|| in_span.finish(poses));
    Ok(GravityNetErrors { encoding: net.encoding, span, whole_turn: whole.finish(poses), poses, samples })
}

/// The largest |averaged torque − true gravity at the averaged angles| over `pairs` [N·m]:
/// the accuracy of the sweep itself (what remains of friction, Coriolis terms and lag).
pub fn gravity_pair_error(pairs: &[GravityPair], arm: &ArmParams) -> f64 {
    let vertical = arm.clone().with_base_angle(PI / 2.0);
    pairs
        .iter()
        .map(|(q, t)| gravity_torques(&vertical, q).iter().zip(t).map(|(g, t)| (g - t).abs()).fold(0.0, f64::max))
        .fold(0.0, f64::max)
}
