//! Friction identification: constant torques on one joint, the others held; the steady
//! velocities binned into training pairs; one net per joint.

use std::path::Path;

use anyhow::{bail, Context, Result};
use nalgebra::DMatrix;

use super::{identification_internal_step, joint_loop, lightest_inertias, real_handles, Settings, ARM_UNIT, CONTROLLER_UNIT};
pub use crate::identify::FrictionCurve;
use crate::identify::{identify_levels, judge_level, FrictionIdentification, FrictionOptions, Level, Verdict};
use neurarm_cosim::{Algorithm, Handle, Simulation, Value};
use neurarm_models::names;
use neurarm_nn::encoding::LOG_SPEED_SCALE_RAD_S;
use neurarm_nn::{train, EncodedNet, InputEncoding, Signal, TrainSettings, WeightsFile};
use neurarm_physics::arm::{coriolis_of_one_joint_into, mass_matrix_into, ArmData, ArmParams, JointFriction};
use neurarm_physics::control::holds::{friction_hold_accelerations_into, friction_hold_torques_into};

/// How the friction runs hold the joints that are not driven.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum FrictionHold {
    /// The joint controller's PD, inertia-scaled ([`hold_gains`]): the coupling torques of
    /// the driven joint bend the held ones at speed, and the pairs with them.
    Pd,
    /// Computed torque from the nominal rigid-body model without gravity
    /// ([`friction_hold_torques_into`], critically damped at
    /// [`FRICTION_HOLD_RAD_S`](neurarm_physics::control::holds::FRICTION_HOLD_RAD_S)), with the
    /// held joints' inertia taken while the driven one moves freely: they settle exactly once
    /// it runs at constant speed, in every pose (docs/decisions/0006-friction-hold.md).
    Rigid,
}

pub use crate::identify::FrictionPair;

/// One joint's run in one direction: the levels it played, each as the samples of its last
/// measuring window (what [`identify_levels`] judges).
#[derive(Clone, Debug, Default)]
pub struct FrictionRun {
    /// Joint index (0-based).
    pub joint: usize,
    /// Each level's last samples: times [s], speeds [rad/s], torques [N·m].
    pub levels: Vec<LevelRecord>,
    /// Speed-controlled levels below the first moving one (rigid hold only).
    pub speed_levels: usize,
    /// Simulated time [s].
    pub simulated_s: f64,
}

/// The end of one level: at least a measuring window of samples.
#[derive(Clone, Debug, Default)]
pub struct LevelRecord {
    /// Times [s].
    pub time: Vec<f64>,
    /// The driven joint's measured speed [rad/s].
    pub speed: Vec<f64>,
    /// The driven joint's torque [N·m].
    pub torque: Vec<f64>,
}

impl LevelRecord {
    /// The record as a level to judge.
    pub fn level(&self) -> Level<'_> {
        Level { time: &self.time, speed: &self.speed, torque: &self.torque, line: 0 }
    }

    /// The samples from time `from` [s] on.
    fn since(&self, from: f64) -> LevelRecord {
        let k = self.time.partition_point(|&t| t < from);
        LevelRecord { time: self.time[k..].to_vec(), speed: self.speed[k..].to_vec(), torque: self.torque[k..].to_vec() }
    }

    fn clear(&mut self) {
        self.time.clear();
        self.speed.clear();
        self.torque.clear();
    }

    /// Adds a sample, dropping those older than `keep_s` before it.
    fn push(&mut self, time: f64, speed: f64, torque: f64, keep_s: f64) {
        self.time.push(time);
        self.speed.push(speed);
        self.torque.push(torque);
        let old = self.time.partition_point(|&t| t < time - keep_s);
        // Drop in blocks, not sample by sample.
        if old > 4096 {
            self.time.drain(..old);
            self.speed.drain(..old);
            self.torque.drain(..old);
        }
    }
}

/// The options the paper's friction runs judge their levels with: the documented defaults,
/// the settings' bin width, and the driven joint's inertia when the hold is rigid.
pub fn run_options(settings: &Settings, inertia: Option<f64>) -> FrictionOptions {
    FrictionOptions { bin_width_rad_s: settings.bin_width, inertia_kgm2: inertia, ..FrictionOptions::default() }
}

/// The pairs of one joint from its runs (both directions): every level judged and binned by
/// [`identify_levels`], the same code `neurarm identify friction` runs on a robot's log.
pub fn pairs_of_runs(runs: &[&FrictionRun], options: &FrictionOptions) -> FrictionIdentification {
    let levels: Vec<Level<'_>> = runs.iter().flat_map(|r| r.levels.iter().map(LevelRecord::level)).collect();
    identify_levels(&levels, options)
}

/// Joint `joint`'s (0-based) inertia with the other joints held rigidly at 0 [kg·m²]: H_ff of
/// the straight arm, which the driven joint's own angle does not change.
pub fn held_inertia(model: &ArmParams, joint: usize) -> f64 {
    let rigid_body = model.clone().with_base_angle(0.0).frictionless();
    neurarm_physics::arm::mass_matrix(&rigid_body, &vec![0.0; model.dof()])[(joint, joint)]
}

/// Gains of the joint PD loops of the identification experiments: critically damped at
/// 40 rad/s for the smallest inertia each joint can present ([`lightest_inertias`]), so the
/// sampled loop stays stable in every pose.
pub fn hold_gains(arm: &ArmParams) -> Vec<(f64, f64)> {
    // Stiffer or more damped settings (150 rad/s, or damping ratio 3) made the coupled sampled
    // loop unstable in some poses of the gravity sweep.
    let (w, zeta) = (40.0, 1.0);
    lightest_inertias(arm).iter().map(|m| (m * w * w, 2.0 * zeta * m * w)).collect()
}

/// What drives the driven joint for a step.
#[derive(Clone, Copy)]
enum Drive {
    /// A constant torque [N·m].
    Torque(f64),
    /// Computed torque tracking speed `wanted` [rad/s] with `bandwidth` [rad/s], plus
    /// `feedforward` [N·m].
    Speed { wanted: f64, feedforward: f64, bandwidth: f64 },
}

/// Bandwidths of the speed loop of the low-speed levels, tried in turn until the level holds
/// its speed [rad/s] (see [`friction_run`]); at 1 ms steps the last is K h / H_ff = 0.64.
const SPEED_LOOP_RAD_S: [f64; 3] = [40.0, 160.0, 640.0];
/// Time a low-speed level settles before it is averaged [s].
const SPEED_LEVEL_SETTLE_S: f64 = 0.5;
/// Time a low-speed level is averaged over [s].
const SPEED_LEVEL_AVERAGE_S: f64 = 1.0;

/// Smallest torque step between constant-torque levels [N·m]: spaces the levels by 0.1 rad/s
/// down to a viscous slope of 0.01 N·m·s/rad.
const MIN_TORQUE_STEP_NM: f64 = 1e-3;

/// A second moving level this many velocity spacings above the first has left a gap: the
/// levels are climbed again from the first with a finer step.
const OVERSHOOT_SPACINGS: f64 = 3.0;

/// Drives joint `joint` of the arm in `arm_fmu` with constant torques in `direction` (±1),
/// the others held at 0 (see [`FrictionHold`]), raising the torque level by level until the
/// steady speed passes `settings.max_velocity`. Each level lasts until the measured
/// level's last window passes the steadiness test of [`FrictionOptions`] (at most 20 s). The step
/// between levels aims at `velocity_spacing` from the local slope of the levels so far. With
/// the rigid hold, speed-held levels then fill the speeds the constant torques jumped over.
pub fn friction_run(
    arm_fmu: &Path,
    controller: &Path,
    model: &ArmParams,
    joint: usize,
    direction: f64,
    settings: &Settings,
) -> Result<FrictionRun> {
    let mut rig = FrictionRig::new(arm_fmu, controller, model, joint, settings)?;
    let rigid = settings.friction_hold == FrictionHold::Rigid;
    // The driven joint's inertia with the others held rigidly: H_ff, which the held joints'
    // angles (all 0) fix and the driven joint's own angle does not change.
    let inertia = held_inertia(model, joint);
    let options = run_options(settings, rigid.then_some(inertia));
    let mut run = FrictionRun { joint, ..Default::default() };
    let moving_levels = climb_torque_levels(&mut rig, model, direction, settings, &options, &mut run)?;
    if rigid {
        speed_held_levels(&mut rig, &moving_levels, direction, settings, &mut run)?;
    }
    run.simulated_s = rig.sim.time();
    Ok(run)
}

/// One friction run's loop: the arm and the joint controller through the master, joint
/// `joint` driven and the others held (see [`FrictionHold`]), with the buffers a step needs.
struct FrictionRig {
    sim: Simulation,
    /// The controller's `tau_comp_i`: the torques the run commands.
    torque_inputs: Vec<Handle>,
    /// The measured angles, then speeds.
    state: Vec<Handle>,
    joint: usize,
    rigid: bool,
    /// The nominal arm horizontal and without friction: the rigid hold's model.
    rigid_body: ArmParams,
    data: ArmData,
    /// Mass matrix [kg·m²], Coriolis torques [N·m], accelerations [rad/s²], measured state,
    /// commanded torques [N·m].
    h: DMatrix<f64>,
    c: Vec<f64>,
    u: Vec<f64>,
    x: Vec<f64>,
    commanded: Vec<f64>,
}

impl FrictionRig {
    /// The loop of `joint`'s run: the PD hold of [`hold_gains`] on the other joints, or (rigid
    /// hold) the controller's gains at 0 and the hold computed here.
    fn new(arm_fmu: &Path, controller: &Path, model: &ArmParams, joint: usize, settings: &Settings) -> Result<Self> {
        let n = model.dof();
        let rigid = settings.friction_hold == FrictionHold::Rigid;
        let mut gains = if rigid { vec![(0.0, 0.0); n] } else { hold_gains(model) };
        gains[joint] = (0.0, 0.0);
        // Friction is identified with the arm horizontal, whatever its configured base angle.
        let parameters = [(names::INTERNAL_STEP, Value::Real(identification_internal_step(model))), (names::BASE_ANGLE, Value::Real(0.0))];
        let mut s = joint_loop(arm_fmu, controller, &parameters, &gains, None)?;
        s.set(CONTROLLER_UNIT, names::USE_SEQUENCE, Value::Boolean(false))?;
        let sim = s.initialize(0.0, settings.step, Algorithm::GaussSeidel, &[])?;
        let torque_inputs = real_handles(&sim, n, CONTROLLER_UNIT, names::COMPENSATION_TORQUE)?;
        let state =
            [real_handles(&sim, n, ARM_UNIT, names::MEASURED_ANGLE)?, real_handles(&sim, n, ARM_UNIT, names::MEASURED_VELOCITY)?].concat();
        let rigid_body = model.clone().with_base_angle(0.0).frictionless();
        let data = ArmData::new(&rigid_body);
        Ok(Self {
            sim,
            torque_inputs,
            state,
            joint,
            rigid,
            rigid_body,
            data,
            h: DMatrix::zeros(n, n),
            c: vec![0.0; n],
            u: vec![0.0; n],
            x: vec![0.0; 2 * n],
            commanded: vec![0.0; n],
        })
    }

    /// One step with the driven joint under `drive`: its measured speed after the step
    /// [rad/s] and the torque it got [N·m].
    fn step(&mut self, drive: Drive) -> Result<(f64, f64)> {
        let (n, joint) = (self.u.len(), self.joint);
        self.sim.get_reals(&self.state, &mut self.x)?;
        if self.rigid {
            self.rigid_hold(drive);
        } else {
            self.commanded.fill(0.0);
        }
        if let Drive::Torque(tau) = drive {
            self.commanded[joint] = tau;
        }
        let torque = self.commanded[joint];
        self.sim.set_reals(&self.torque_inputs, &self.commanded)?;
        self.sim.step()?;
        self.sim.get_reals(&self.state, &mut self.x)?;
        Ok((self.x[n + joint], torque))
    }

    /// The rigid hold's torques (see [`FrictionHold::Rigid`]) from the measured state, into
    /// `commanded`: under a constant torque the held joints' hold, under a speed drive
    /// computed torque on every joint, the driven one tracking its speed.
    fn rigid_hold(&mut self, drive: Drive) {
        let (n, joint) = (self.u.len(), self.joint);
        let (q, qd) = self.x.split_at(n);
        mass_matrix_into(&self.rigid_body, &mut self.data, q, &mut self.h);
        // The held joints are at rest but for noise: their measured speeds would only put
        // that noise into the Coriolis terms (× the driven joint's speed).
        coriolis_of_one_joint_into(&self.rigid_body, &mut self.data, q, joint, qd[joint], &mut self.c);
        friction_hold_accelerations_into(q, qd, &mut self.u);
        match drive {
            Drive::Torque(_) => friction_hold_torques_into(&self.h, &self.c, &mut self.u, joint, &mut self.commanded),
            Drive::Speed { wanted, feedforward, bandwidth } => {
                self.u[joint] = bandwidth * (wanted - qd[joint]);
                for i in 0..n {
                    self.commanded[i] = (0..n).map(|k| self.h[(i, k)] * self.u[k]).sum::<f64>() + self.c[i];
                }
                self.commanded[joint] += feedforward;
            }
        }
    }
}

/// Plays the constant torque `tau` [N·m] on the driven joint, `window` steps at a time, until
/// the last window of `record` (samples of the last `keep_s` seconds) passes the
/// identification's steadiness test, or for 20 s: the test the levels are judged by
/// afterwards. Returns the level's mean speed [rad/s].
fn play_torque_level(
    rig: &mut FrictionRig,
    tau: f64,
    window: usize,
    keep_s: f64,
    options: &FrictionOptions,
    record: &mut LevelRecord,
) -> Result<f64> {
    let started = rig.sim.time();
    record.clear();
    let verdict = loop {
        for _ in 0..window {
            let (speed, torque) = rig.step(Drive::Torque(tau))?;
            record.push(rig.sim.time(), speed, torque, keep_s);
        }
        let report = judge_level(&record.level(), options);
        if matches!(report.verdict, Verdict::Kept | Verdict::AtRest) || rig.sim.time() - started > 20.0 {
            break report;
        }
    };
    Ok(verdict.speed_rad_s)
}

/// Where the constant-torque climb of a friction run stands.
struct Climb {
    /// The torque of the level [N·m].
    tau: f64,
    /// The step to the next level [N·m].
    increment: f64,
    /// (torque [N·m], mean speed [rad/s]) of the levels that moved the joint.
    moving: Vec<(f64, f64)>,
}

impl Climb {
    /// Takes the mean speed `mean` [rad/s] of the level just played: a level that moved the
    /// joint sets the next step from the local slope. Returns whether the level overshot (then
    /// the climb goes back to the first moving level and the level is not counted as moving).
    fn after_level(&mut self, mean: f64, direction: f64, settings: &Settings) -> bool {
        let moving = mean * direction > 2.0 * settings.bin_width.min(0.05);
        if !moving {
            return false;
        }
        let mut overshot = false;
        if let Some(&(t0, v0)) = self.moving.last() {
            let slope = (self.tau - t0) / (mean - v0);
            if slope.is_finite() && slope > 0.0 {
                // At most doubling: one level whose speed barely moved (noise, the Stribeck
                // dip) would otherwise make the next step jump by a whole rad/s.
                let adapted = (slope * settings.velocity_spacing).clamp(MIN_TORQUE_STEP_NM, (2.0 * self.increment).min(0.5));
                // The step to the second moving level is made before any slope is known;
                // far too large for a joint with little viscous friction, it jumps past
                // speeds no level then covers: go back to the first moving level, once, and
                // climb again with the step the slope asks for. (Later jumps, where friction
                // falls with speed faster than the levels can follow, are the law's own: the
                // speed-controlled levels below fill them.)
                overshot = self.moving.len() == 1
                    && (mean - v0).abs() > OVERSHOOT_SPACINGS * settings.velocity_spacing
                    && adapted < 0.5 * self.increment;
                self.increment = adapted;
                if overshot {
                    self.tau = t0;
                }
            }
        }
        if !overshot {
            self.moving.push((self.tau, mean));
        }
        overshot
    }
}

/// The constant-torque levels of a friction run: from 0.02 N·m up in `direction` until the
/// steady speed passes `settings.max_velocity`, each level's last window kept in `run`.
/// Returns (torque [N·m], mean speed [rad/s]) of the levels that moved the joint. A joint that
/// never reaches the top speed stops the run: at most twice the torque its motor must give
/// to carry the stretched arm (at least 100 N·m), so heavy arms' joints are not cut off below
/// their own friction.
fn climb_torque_levels(
    rig: &mut FrictionRig,
    model: &ArmParams,
    direction: f64,
    settings: &Settings,
    options: &FrictionOptions,
    run: &mut FrictionRun,
) -> Result<Vec<(f64, f64)>> {
    let window = (0.1 / settings.step).round() as usize;
    let keep_s = options.window_s + 2.0 * settings.step;
    let torque_cap = (2.0 * model.gravity_load_nm(rig.joint)).max(100.0);
    let mut climb = Climb { tau: 0.0, increment: 0.02, moving: Vec::new() };
    let mut record = LevelRecord::default();
    loop {
        climb.tau += direction * climb.increment;
        let mean = play_torque_level(rig, climb.tau, window, keep_s, options, &mut record)?;
        let overshot = climb.after_level(mean, direction, settings);
        // Every level is kept for the identification, the probes at rest below the first
        // moving level among them (they give the pair at rest).
        run.levels.push(record.since(rig.sim.time() - keep_s));
        if !overshot && mean * direction >= settings.max_velocity {
            return Ok(climb.moving);
        }
        if climb.tau.abs() > torque_cap {
            bail!(
                "joint {}: no speed of {} rad/s below {torque_cap:.0} N·m (the larger of 100 N·m and twice the joint's \
                 gravity load); lower the runs' top speed (`neurarm paper --friction-max-speed`) if the joint cannot reach it",
                rig.joint + 1,
                settings.max_velocity
            );
        }
    }
}

/// The rigid hold's speed-held levels, kept in `run`: where constant torques cannot hold a
/// speed (a Stribeck dip), the driven joint runs a P loop on its speed around the planned
/// feedforward torque, and a steady state of it is a point of the friction curve. Each level
/// tries the bandwidths [`SPEED_LOOP_RAD_S`] in turn and keeps the first within half a bin
/// width of its target, else the closest within half its target, else none
/// (docs/decisions/0002-friction-speed-levels.md).
fn speed_held_levels(
    rig: &mut FrictionRig,
    moving_levels: &[(f64, f64)],
    direction: f64,
    settings: &Settings,
    run: &mut FrictionRun,
) -> Result<()> {
    let settle = (SPEED_LEVEL_SETTLE_S / settings.step).round() as usize;
    let average = (SPEED_LEVEL_AVERAGE_S / settings.step).round() as usize;
    let mut level = LevelRecord::default();
    for (target, feedforward) in speed_level_plan(moving_levels, settings) {
        let wanted = direction * target;
        // The first level within half a bin of its target, else the closest within half
        // its target: (how far off [rad/s], level).
        let mut chosen: Option<(f64, LevelRecord)> = None;
        for bandwidth in SPEED_LOOP_RAD_S {
            level.clear();
            for k in 0..settle + average {
                let (speed, torque) = rig.step(Drive::Speed { wanted, feedforward, bandwidth })?;
                if k >= settle {
                    level.push(rig.sim.time(), speed, torque, f64::INFINITY);
                }
            }
            let off = (level.speed.iter().sum::<f64>() / level.speed.len() as f64 - wanted).abs();
            if off < 0.5 * target.min(settings.bin_width) {
                chosen = Some((off, std::mem::take(&mut level)));
                break;
            }
            if off < 0.5 * target && chosen.as_ref().is_none_or(|(best, _)| off < *best) {
                chosen = Some((off, level.clone()));
            }
        }
        // Judged like every level: the mean torque of a P loop's steady state, less H_ff
        // times the fitted acceleration.
        if let Some((_, kept)) = chosen {
            run.levels.push(kept);
            run.speed_levels += 1;
        }
    }
    Ok(())
}

/// The (speed [rad/s, magnitude], feedforward torque [N·m]) of the speed-held levels after
/// the climb's `moving_levels` (torque, speed): below the first moving level, then in every
/// gap the constant torques jumped (where friction falls with speed faster than the levels
/// can follow: a Stribeck dip past the first level, viscous friction falling with speed),
/// each level fed forward the torque of the moving level below it. None without a moving
/// level.
fn speed_level_plan(moving_levels: &[(f64, f64)], settings: &Settings) -> Vec<(f64, f64)> {
    let Some(&(tau_first, v_first)) = moving_levels.first() else { return Vec::new() };
    let mut targets: Vec<(f64, f64)> =
        speed_level_targets(v_first.abs(), settings.velocity_spacing, settings.bin_width).into_iter().map(|t| (t, tau_first)).collect();
    let mut climbed: Vec<(f64, f64)> = moving_levels.iter().map(|&(tau, v)| (v.abs(), tau)).collect();
    climbed.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (below, above) in climbed.iter().zip(climbed.iter().skip(1)) {
        targets.extend(gap_level_targets(below.0, above.0, settings.velocity_spacing).into_iter().map(|t| (t, below.1)));
    }
    targets
}

/// The speeds [rad/s, magnitudes] of the rigid hold's speed-controlled levels below the first
/// moving level at `first` [rad/s], for friction bins `bin_width` [rad/s] wide: down from it by
/// `spacing` [rad/s] while at least 3.5 bin widths, then 2.5, 1.5 and 0.5 widths, each unless
/// `first` lies in the same bin. The lowest three, mid-bin where a Stribeck dip bends, are taken
/// whatever the spaced ones left; no two levels share a bin
/// (docs/decisions/0002-friction-speed-levels.md).
pub fn speed_level_targets(first: f64, spacing: f64, bin_width: f64) -> Vec<f64> {
    let mut targets = Vec::new();
    let mut target = first - spacing;
    while target >= 3.5 * bin_width {
        targets.push(target);
        target -= spacing;
    }
    for low in [2.5 * bin_width, 1.5 * bin_width, 0.5 * bin_width] {
        if first - low > 0.5 * bin_width {
            targets.push(low);
        }
    }
    targets
}

/// The speeds [rad/s, magnitudes] of the rigid hold's speed-controlled levels between two
/// consecutive moving levels at `below` < `above` [rad/s] whose speeds lie more than two
/// `spacing`s apart: every `spacing` up from `below`, at least `spacing` short of `above`.
///
/// Constant torques leave such gaps where friction falls with speed faster than the torque
/// steps can follow (a Stribeck dip past the first moving level, viscous friction falling with
/// speed), and a net would bridge them blindly (docs/decisions/0002-friction-speed-levels.md).
pub fn gap_level_targets(below: f64, above: f64, spacing: f64) -> Vec<f64> {
    let mut targets = Vec::new();
    if above - below <= 2.0 * spacing {
        return targets;
    }
    let mut target = below + spacing;
    while target <= above - spacing + 1e-9 {
        targets.push(target);
        target += spacing;
    }
    targets
}

/// The narrowest step of a friction net at zero speed [rad/s]: half its width, the speed at
/// which a net trained on the Coulomb step ([`train_friction_net`]) is at the moving friction.
pub fn friction_step_width(speed_noise_rad_s: f64) -> f64 {
    // A joint at rest reads within ±2σ of zero 95 % of the time: a step narrower than that
    // would flip the compensation on measurement noise alone.
    LOG_SPEED_SCALE_RAD_S.max(2.0 * speed_noise_rad_s)
}

/// Trains the friction net (velocity [rad/s] → torque [N·m]) of joint `joint` (from 0) on
/// binned pairs, the pair at rest among them, for a measured speed with noise
/// `speed_noise_rad_s` (standard deviation, [`FrictionIdentification::speed_noise_rad_s`]).
/// Where both directions' lowest pairs lie above twice [`friction_step_width`], the data get
/// the Coulomb step at that width and the net reads the speed on a log scale
/// ([`InputEncoding::LogSpeed`]), so friction jumps at zero speed instead of ramping up;
/// otherwise it is the paper's net on the raw speed (docs/decisions/0007-friction-step.md).
pub fn train_friction_net(joint: usize, pairs: &[FrictionPair], speed_noise_rad_s: f64, seed: u64) -> Result<WeightsFile> {
    let width = friction_step_width(speed_noise_rad_s);
    let lowest = |direction: f64| pairs.iter().filter(|p| p.0 * direction > 0.0).map(|p| p.0.abs()).fold(f64::INFINITY, f64::min);
    // Both directions need room for the step's points below their lowest pair.
    let stepped = lowest(1.0).min(lowest(-1.0)) > 2.0 * width && lowest(1.0).max(lowest(-1.0)).is_finite();
    let mut training: Vec<FrictionPair> = pairs.to_vec();
    let encoding = if stepped {
        training.extend(step_pairs(pairs, width));
        training.sort_by(|a, b| a.0.total_cmp(&b.0));
        InputEncoding::LogSpeed
    } else {
        InputEncoding::Raw
    };
    let pairs = &training[..];
    let raw = DMatrix::from_fn(1, pairs.len(), |_, c| pairs[c].0);
    let x = encoding.encode_all(&raw);
    let t = DMatrix::from_fn(1, pairs.len(), |_, c| pairs[c].1);
    // A few hundred pairs with a jump at zero: 6 validation failures in a row stop most
    // starts in the first epochs, so this allows 20. Of 10 starts, each stopped early on its own
    // validation part, the one closest to the pairs' piecewise-linear interpolant on a dense
    // grid is kept ([`interpolant_rms`]): scoring on the validation part alone picks nets whose
    // jump is anywhere, as it rarely holds a pair near q̇ = 0, and scoring at the pairs alone
    // let a net overshoot between the pair at rest and the first moving one.
    const STARTS: u64 = 10;
    let mut best: Option<(f64, TrainSettings, neurarm_nn::Trained)> = None;
    for start in 0..STARTS {
        let mut settings =
            TrainSettings { hidden: 15, restarts: 1, max_fail: 20, seed: seed + joint as u64 + 7919 * start, ..TrainSettings::default() };
        // The pair at rest is the only one in the stick band: keep it in the training part
        // (the first split seed from there that does), or the jump lands anywhere in the band.
        if let Some(rest) = pairs.iter().position(|p| p.0 == 0.0) {
            for _ in 0..1000 {
                if neurarm_nn::lm::split(pairs.len(), settings.split, settings.seed)[0].contains(&rest) {
                    break;
                }
                settings.seed += 1000;
            }
        }
        let trained = train(&x, &t, &settings, &mut |_| {}).with_context(|| format!("friction net of joint {}", joint + 1))?;
        let net = EncodedNet { encoding, mlp: trained.net.clone() };
        let at_pairs = (pairs.iter().map(|p| (net.evaluate(&[p.0])[0] - p.1).powi(2)).sum::<f64>() / pairs.len() as f64).sqrt();
        let score = at_pairs + interpolant_rms(&net, pairs);
        if best.as_ref().is_none_or(|b| score < b.0) {
            best = Some((score, settings, trained));
        }
    }
    let (_, settings, trained) = best.expect("at least one start");
    // Named as the compensator's ports the net feeds.
    Ok(WeightsFile::new(
        &trained.net,
        vec![Signal { name: names::joint(names::VELOCITY, joint + 1), unit: "rad/s".into() }],
        vec![Signal { name: names::joint(names::FRICTION_TORQUE, joint + 1), unit: "N.m".into() }],
        settings,
        trained.report,
    )
    .with_encoding(encoding)
    .friction_of_joint(joint + 1))
}

/// The Coulomb step's training points of [`train_friction_net`]: in each direction a pair at
/// ±`width` [rad/s] carrying the lowest moving pair's friction extrapolated linearly from the
/// two lowest (the lowest pair's own torque where that would change its sign or more than
/// double it), and points on the straight line from there to the lowest pair, four a decade.
fn step_pairs(pairs: &[FrictionPair], width: f64) -> Vec<FrictionPair> {
    let mut out = Vec::new();
    for direction in [1.0, -1.0] {
        let mut side: Vec<&FrictionPair> = pairs.iter().filter(|p| p.0 * direction > 0.0).collect();
        side.sort_by(|a, b| a.0.abs().total_cmp(&b.0.abs()));
        let Some(low) = side.first() else { continue };
        if low.0.abs() <= width {
            continue;
        }
        let mut torque = low.1;
        if let Some(next) = side.get(1) {
            let slope = (next.1 - low.1) / (next.0 - low.0);
            let extrapolated = low.1 + slope * (direction * width - low.0);
            if extrapolated * low.1 > 0.0 && extrapolated.abs() <= 2.0 * low.1.abs() {
                torque = extrapolated;
            }
        }
        // The gap up to the lowest pair, four points a decade on the straight line there.
        let (v_low, mut v) = (low.0.abs(), width);
        while v < 0.8 * v_low {
            let share = (v - width) / (v_low - width);
            out.push((direction * v, torque + share * (low.1 - torque), low.2));
            v *= 10f64.powf(0.25);
        }
    }
    out
}

/// RMS over a 1 mrad/s grid spanning the pairs of net(q̇) − the pairs' piecewise-linear
/// interpolant [N·m]: how a net behaves between the pairs, the stick band included.
pub fn interpolant_rms(net: &EncodedNet, pairs: &[FrictionPair]) -> f64 {
    let (Some(first), Some(last)) = (pairs.first(), pairs.last()) else { return f64::INFINITY };
    let curve = FrictionCurve::new(pairs);
    let steps = ((last.0 - first.0) / 1e-3).floor() as usize;
    let mut sq = 0.0;
    for i in 0..=steps {
        let v = first.0 + i as f64 * 1e-3;
        sq += (net.evaluate(&[v])[0] - curve.torque(v)).powi(2);
    }
    (sq / (steps + 1) as f64).sqrt()
}

/// How well a friction net matches a known friction law over |q̇| from `min_speed` to
/// `max_speed` [rad/s], both directions, on a 1 mrad/s grid.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct FrictionNetError {
    /// RMS of net − law [N·m].
    pub rms_nm: f64,
    /// Largest |net − law| [N·m].
    pub max_nm: f64,
    /// Largest |law| over the range: the joint's largest friction torque [N·m].
    pub largest_friction_nm: f64,
}

impl FrictionNetError {
    /// RMS error as a share of the largest friction torque.
    pub fn share(&self) -> f64 {
        self.rms_nm / self.largest_friction_nm
    }
}

/// The error of `net` (velocity → torque) against the friction law `law` (see
/// [`FrictionNetError`]).
pub fn friction_net_error(net: &WeightsFile, law: &JointFriction, min_speed: f64, max_speed: f64) -> Result<FrictionNetError> {
    let mlp = net.network()?;
    let steps = ((max_speed - min_speed) / 1e-3).round() as usize;
    let (mut sq, mut worst, mut largest, mut count) = (0.0, 0.0f64, 0.0f64, 0usize);
    for k in 0..=steps {
        for sign in [1.0, -1.0] {
            let v = sign * (min_speed + k as f64 * 1e-3);
            let truth = law.torque(v);
            let e = mlp.evaluate(&[v])[0] - truth;
            sq += e * e;
            worst = worst.max(e.abs());
            largest = largest.max(truth.abs());
            count += 1;
        }
    }
    Ok(FrictionNetError { rms_nm: (sq / count as f64).sqrt(), max_nm: worst, largest_friction_nm: largest })
}

/// The largest |pair torque − law at the pair's velocity| over the moving pairs (the pair at
/// rest excluded) [N·m], and the velocity where it is [rad/s]: the accuracy of the
/// identification itself, before any fitting.
pub fn pair_error(pairs: &[FrictionPair], law: &JointFriction) -> (f64, f64) {
    pairs.iter().filter(|p| p.0 != 0.0).map(|p| ((p.1 - law.torque(p.0)).abs(), p.0)).fold((0.0, 0.0), |a, b| if b.0 > a.0 { b } else { a })
}

#[cfg(test)]
mod tests {
    use super::*;
    use neurarm_physics::arm::FrictionBranch;

    /// A Stribeck joint, asymmetric, and its pairs as a constant-torque identification gives
    /// them: the law at 30 mrad/s to 5 rad/s and the pair at rest (the breakaway midpoint).
    fn stribeck_joint() -> (JointFriction, Vec<FrictionPair>) {
        let branch = |coulomb_nm, static_nm, viscous_nms_rad| FrictionBranch {
            coulomb_nm,
            static_nm,
            stribeck_velocity_rad_s: 0.15,
            viscous_nms_rad,
            viscous_falloff_rad_s: None,
        };
        let law = JointFriction { positive: branch(1.0, 1.5, 0.7), negative: branch(0.8, 1.2, 0.9) };
        let mut pairs: Vec<FrictionPair> = vec![(0.0, 0.5 * (law.breakaway(1.0) - law.breakaway(-1.0)), 10)];
        for k in 0..=50 {
            let v = 0.03 * (5.0f64 / 0.03).powf(k as f64 / 50.0);
            pairs.push((v, law.torque(v), 500));
            pairs.push((-v, law.torque(-v), 500));
        }
        pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
        (law, pairs)
    }

    #[test]
    fn a_quiet_joints_net_crosses_the_coulomb_step_within_a_few_milliradians_per_second() {
        let (law, pairs) = stribeck_joint();
        let net = train_friction_net(0, &pairs, 0.0, 1).unwrap();
        assert_eq!(net.encoding, InputEncoding::LogSpeed);
        let mlp = net.network().unwrap();
        // Against the law itself, from twice the step width (2 mrad/s) up: the lowest pair is
        // at 30 mrad/s, so all below it is the step's training points.
        for v in [0.002, 0.005, 0.01, 0.02] {
            for sign in [1.0, -1.0] {
                let (got, want) = (mlp.evaluate(&[sign * v])[0], law.torque(sign * v));
                assert!((got - want).abs() < 0.1 * want.abs(), "at {:+} rad/s: net {got:.4}, law {want:.4}", sign * v);
            }
        }
        let error = friction_net_error(&net, &law, 0.005, 5.0).unwrap();
        assert!(error.share() < 0.01, "{error:?}");
    }

    #[test]
    fn a_noisy_joints_net_keeps_the_raw_speed_and_the_pairs_alone() {
        let (law, pairs) = stribeck_joint();
        // 20 mrad/s of noise: a 40 mrad/s step, wider than the gap below the lowest pair.
        let net = train_friction_net(0, &pairs, 0.02, 1).unwrap();
        assert_eq!(net.encoding, InputEncoding::Raw);
        let error = friction_net_error(&net, &law, 0.2, 5.0).unwrap();
        assert!(error.share() < 0.01, "{error:?}");
        assert_eq!(friction_step_width(0.02), 0.04);
        assert_eq!(friction_step_width(0.0), LOG_SPEED_SCALE_RAD_S);
    }

    #[test]
    fn the_steps_points_carry_the_lowest_pairs_friction_down_to_the_width() {
        let pairs: Vec<FrictionPair> = vec![(-0.05, -1.0, 5), (-0.03, -1.2, 5), (0.0, 0.0, 3), (0.04, 2.0, 5), (0.08, 2.2, 5)];
        let points = step_pairs(&pairs, 0.002);
        // Positive side: slope 5 N·m·s/rad extrapolated to 2 mrad/s: 1.81 N·m; negative side:
        // falling toward speed, −1.2 − 10 × 0.028 = −1.48, kept (same sign, under twice the lowest).
        let at = |v: f64| points.iter().find(|p| (p.0 - v).abs() < 1e-12).map(|p| p.1);
        assert!((at(0.002).unwrap() - 1.81).abs() < 1e-12);
        assert!((at(-0.002).unwrap() + 1.48).abs() < 1e-12);
        // Four points a decade, all below 80 % of the lowest pair, on the line to it.
        assert!(points.iter().all(|p| p.0.abs() >= 0.002 && p.0.abs() < 0.8 * 0.04));
        for p in points.iter().filter(|p| p.0 > 0.0) {
            let line = 1.81 + (p.0 - 0.002) / (0.04 - 0.002) * (2.0 - 1.81);
            assert!((p.1 - line).abs() < 1e-12, "{p:?}");
        }
        assert_eq!(points.iter().filter(|p| p.0 > 0.0).count(), 5);
        // Just below 80 % of the lowest pairs: the pair at ±width alone; above them: nothing.
        let narrow: Vec<f64> = step_pairs(&pairs, 0.02).iter().map(|p| p.0).collect();
        assert_eq!(narrow, [0.02, -0.02]);
        assert!(step_pairs(&pairs, 0.045).is_empty());
    }

    #[test]
    fn the_speed_held_levels_reach_the_lowest_speeds_each_in_a_bin_of_its_own() {
        let close = |got: Vec<f64>, want: &[f64]| {
            assert_eq!(got.len(), want.len(), "{got:?}");
            assert!(got.iter().zip(want).all(|(g, w)| (g - w).abs() < 1e-12), "{got:?}");
        };
        // Seed 4's joint 3: the spaced speeds end at 0.175; the three lowest follow (the old
        // rule dropped 0.05 after 0.075, leaving no pair under the Stribeck velocity, 0.049).
        close(speed_level_targets(0.375, 0.1, 0.05), &[0.275, 0.175, 0.125, 0.075, 0.025]);
        // No spaced speed fits under a first level of 0.128 rad/s (seed 4's joint 5): the two
        // lowest (0.125 shares the first level's bin).
        close(speed_level_targets(0.128, 0.1, 0.05), &[0.075, 0.025]);
        // Spaced speeds stop a bin above the lowest three: 0.14 would share 0.125's bin.
        close(speed_level_targets(0.44, 0.1, 0.05), &[0.34, 0.24, 0.125, 0.075, 0.025]);
        close(speed_level_targets(0.151, 0.1, 0.05), &[0.125, 0.075, 0.025]);
        close(speed_level_targets(0.04, 0.1, 0.05), &[]);
        // Every target mid-bin, none sharing a bin with another or with the first level.
        for first in (1..200).map(|k| k as f64 * 0.0037) {
            let targets = speed_level_targets(first, 0.1, 0.05);
            let mut bins: Vec<i64> = targets.iter().map(|t| (t / 0.05).floor() as i64).collect();
            bins.push((first / 0.05).floor() as i64);
            let count = bins.len();
            bins.sort();
            bins.dedup();
            assert_eq!(bins.len(), count, "first {first}: {targets:?}");
        }
    }

    #[test]
    fn the_gaps_between_moving_levels_get_speed_held_levels_a_spacing_apart() {
        // Seed 6's real joint 2: moving levels at 0.118 and 2.2 rad/s, nothing between.
        let filled = gap_level_targets(0.118, 2.198, 0.1);
        assert_eq!(filled.len(), 19, "{filled:?}");
        assert!((filled[0] - 0.218).abs() < 1e-12 && (filled[18] - 2.018).abs() < 1e-9, "{filled:?}");
        // Levels two spacings apart or closer are the climb's own step: nothing added.
        assert!(gap_level_targets(1.0, 1.2, 0.1).is_empty());
        assert!(gap_level_targets(1.0, 1.15, 0.1).is_empty());
        assert_eq!(gap_level_targets(1.0, 1.25, 0.1).len(), 1);
        // Wherever a gap is filled, no two neighbours (the moving levels included) lie more
        // than two spacings or less than one spacing apart.
        for k in 1..400 {
            let (below, above) = (0.05 + 0.001 * k as f64, 0.05 + 0.013 * k as f64);
            let mut speeds = vec![below];
            speeds.extend(gap_level_targets(below, above, 0.1));
            speeds.push(above);
            for pair in speeds.windows(2) {
                let step = pair[1] - pair[0];
                assert!(step <= 0.2 + 1e-9 && (step >= 0.1 - 1e-9 || speeds.len() == 2), "{below}–{above}: {speeds:?}");
            }
        }
    }
}
