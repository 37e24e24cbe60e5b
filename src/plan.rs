//! Experiment plans a robot can run: the paper's friction and gravity experiments as tables of
//! segments that a user's own controller plays (and `neurarm simulate --plan` emulates), from
//! which `neurarm identify` makes training pairs.
//!
//! **Friction plan.** One row per segment, held until the next row's time: `time [s]`, `segment`,
//! `joint` (the driven joint, 0 for a pause), `tau_i [N.m]` (the driven joint's constant torque,
//! 0 for the others) and `hold_i` (1: hold joint i with your position controller at the angle it
//! has when the hold begins; 0: torque control). Per joint and direction: breakaway probes (torques
//! below the expected breakaway, which should leave the joint at rest), then constant torques from
//! the highest speed down (the descending levels reach the low speeds where friction still rises
//! with speed; rising ones would jump over them where friction falls with speed, the Stribeck
//! dip), each long enough to settle from the last (ln(Δv / 1 mrad/s) time constants H/(df/dv) of
//! the expected friction) plus the measuring window; then a pause with no torque.
//!
//! **Gravity plan.** One row per segment: `time [s]`, `pose`, `pass` (0: a smooth rest-to-rest
//! move from this row's angles to the next row's; 1: up, −1: down, every joint at constant speed
//! `qd_i` from the angles `q_i`), `q_i [rad]`, `qd_i [rad/s]`.

use std::f64::consts::PI;
use std::path::Path;

use anyhow::{bail, Context, Result};

use crate::experiments::gravity::design_poses;
use crate::experiments::{held_inertia, GravityDesign};
use crate::table::{header_cell, number, write_text_atomic};
use neurarm_physics::arm::ArmParams;

/// Settings of a friction plan.
#[derive(Clone, Debug, PartialEq)]
pub struct FrictionPlanSettings {
    /// Joints to plan (1-based).
    pub joints: Vec<usize>,
    /// Highest speed of the levels [rad/s] (the paper: 5).
    pub max_speed_rad_s: f64,
    /// Spacing of the levels' expected speeds [rad/s].
    pub spacing_rad_s: f64,
    /// Measuring window at the end of each level [s] (what `identify friction` judges).
    pub window_s: f64,
    /// Longest level [s].
    pub longest_level_s: f64,
}

impl FrictionPlanSettings {
    /// The defaults for an arm of `joints` joints: every joint, up to 5 rad/s every 0.1 rad/s,
    /// a 0.5 s window, levels of at most 30 s.
    pub fn for_joints(joints: usize) -> Self {
        Self { joints: (1..=joints).collect(), max_speed_rad_s: 5.0, spacing_rad_s: 0.1, window_s: 0.5, longest_level_s: 30.0 }
    }

    fn check(&self, n: usize) -> Result<()> {
        if let Some(j) = self.joints.iter().find(|&&j| j == 0 || j > n) {
            bail!("joint {j}: the arm has joints 1 to {n}");
        }
        if !(self.max_speed_rad_s > 0.0 && self.spacing_rad_s > 0.0 && self.spacing_rad_s <= self.max_speed_rad_s) {
            bail!("need 0 < spacing <= max speed (got spacing {} rad/s, max speed {} rad/s)", self.spacing_rad_s, self.max_speed_rad_s);
        }
        if self.max_speed_rad_s / self.spacing_rad_s > 1000.0 {
            bail!("more than 1000 levels per direction: take a larger spacing");
        }
        if !(self.window_s > 0.0 && self.longest_level_s >= 2.0 * self.window_s && self.longest_level_s.is_finite()) {
            bail!("need a window > 0 and levels of at least two windows (got {} s, {} s)", self.window_s, self.longest_level_s);
        }
        Ok(())
    }
}

/// A planned segment of a friction plan.
#[derive(Clone, Debug, PartialEq)]
pub struct FrictionSegment {
    /// Start [s].
    pub time_s: f64,
    /// Driven joint (1-based), 0 for a pause of every joint.
    pub joint: usize,
    /// Its torque [N·m].
    pub torque_nm: f64,
    /// Expected steady speed [rad/s] (0 for probes and pauses).
    pub expected_speed_rad_s: f64,
}

/// A friction plan: its segments and the end time.
#[derive(Clone, Debug, PartialEq)]
pub struct FrictionPlan {
    /// Joints of the arm.
    pub joints: usize,
    /// Segments in time order.
    pub segments: Vec<FrictionSegment>,
    /// End of the last segment [s].
    pub end_s: f64,
    /// Per planned joint (1-based): how far it turns in each direction [rad].
    pub travel_rad: Vec<(usize, f64, f64)>,
}

/// Fractions of the expected breakaway torque probed before each direction's levels.
const PROBES: [f64; 8] = [0.3, 0.5, 0.7, 0.8, 0.9, 1.0, 1.1, 1.2];
/// The lowest speed a plan's levels aim at [rad/s]: about the paper's bin width.
const LOWEST_SPEED_RAD_S: f64 = 0.04;
/// Duration of a breakaway probe [s]: a joint at rest is steady at once; one that moves is data.
const PROBE_S: f64 = 1.0;

/// Plans the friction experiment of `arm` from its expected friction (see the module docs).
pub fn friction_plan(arm: &ArmParams, settings: &FrictionPlanSettings) -> Result<FrictionPlan> {
    let n = arm.dof();
    settings.check(n)?;
    let round = |t: f64| (t * 10.0).ceil() / 10.0;
    let mut segments = Vec::new();
    let mut t = 1.0; // A pause first: every joint held at rest.
    segments.push(FrictionSegment { time_s: 0.0, joint: 0, torque_nm: 0.0, expected_speed_rad_s: 0.0 });
    let mut travel = Vec::new();
    for &joint in &settings.joints {
        let law = arm.friction[joint - 1];
        let inertia = held_inertia(arm, joint - 1);
        let mut turns = [0.0, 0.0];
        for (side, direction) in [1.0f64, -1.0].into_iter().enumerate() {
            let breakaway = law.breakaway(direction).max(0.05);
            for fraction in PROBES {
                segments.push(FrictionSegment { time_s: t, joint, torque_nm: direction * fraction * breakaway, expected_speed_rad_s: 0.0 });
                t += PROBE_S;
            }
            // Levels from the top speed down while friction still rises with speed.
            let slope_at = |v: f64| {
                let d = 1e-3;
                (law.torque(direction * (v + d)) - law.torque(direction * (v - d))) * direction / (2.0 * d)
            };
            let mut previous_speed = 0.0;
            let count = (settings.max_speed_rad_s / settings.spacing_rad_s).floor() as usize;
            let mut speeds: Vec<f64> = (0..count).map(|k| settings.max_speed_rad_s - k as f64 * settings.spacing_rad_s).collect();
            // Below the grid, halving speeds down to LOWEST_SPEED_RAD_S: the pairs nearest the
            // jump at rest, which a net needs to place its jump.
            let mut low = speeds.last().copied().unwrap_or(settings.max_speed_rad_s);
            while low > 0.5 * settings.spacing_rad_s {
                low -= settings.spacing_rad_s;
            }
            low = if low < LOWEST_SPEED_RAD_S { speeds.last().copied().unwrap_or(0.0) } else { low };
            while low * 0.5 >= LOWEST_SPEED_RAD_S {
                low *= 0.5;
                speeds.push(low);
            }
            for v in speeds {
                let slope = slope_at(v);
                if slope <= 0.02 * law.torque(direction * v).abs() || v < LOWEST_SPEED_RAD_S {
                    break;
                }
                let time_constant = inertia / slope;
                let change: f64 = (v - previous_speed).abs().max(1e-3);
                let settle = time_constant * (change / 1e-3).ln().max(1.0);
                let duration = round((settle + settings.window_s).clamp(2.0 * settings.window_s, settings.longest_level_s));
                segments.push(FrictionSegment {
                    time_s: t,
                    joint,
                    torque_nm: law.torque(direction * v),
                    expected_speed_rad_s: direction * v,
                });
                turns[side] += v * duration;
                t += duration;
                previous_speed = v;
            }
            // Coast to rest: the slowest deceleration is by the smaller Coulomb level.
            let coulomb = law.torque(direction * 1e-6).abs().max(0.05);
            let pause = round(1.0 + 2.0 * inertia * previous_speed / coulomb);
            segments.push(FrictionSegment { time_s: t, joint, torque_nm: 0.0, expected_speed_rad_s: 0.0 });
            t += pause;
        }
        travel.push((joint, turns[0], turns[1]));
    }
    Ok(FrictionPlan { joints: n, segments, end_s: t, travel_rad: travel })
}

impl FrictionPlan {
    /// The plan as CSV (see the module docs); the last row marks the end, every joint held.
    pub fn to_csv(&self) -> String {
        let n = self.joints;
        let mut header = vec![header_cell("time", "s"), "segment".into(), "joint".into()];
        header.extend((1..=n).map(|i| header_cell(&format!("tau_{i}"), "N.m")));
        header.extend((1..=n).map(|i| format!("hold_{i}")));
        let mut out = header.join(",") + "\n";
        let end = FrictionSegment { time_s: self.end_s, joint: 0, torque_nm: 0.0, expected_speed_rad_s: 0.0 };
        for (k, s) in self.segments.iter().chain(std::iter::once(&end)).enumerate() {
            let mut row = vec![number(s.time_s), (k + 1).to_string(), s.joint.to_string()];
            row.extend((1..=n).map(|i| if i == s.joint { number(s.torque_nm) } else { "0".into() }));
            row.extend((1..=n).map(|i| if i == s.joint { "0" } else { "1" }.to_owned()));
            out += &(row.join(",") + "\n");
        }
        out
    }

    /// How to run the plan, in words.
    pub fn instructions(&self, source: &str) -> String {
        let mut text = format!(
            "Friction plan for {source}: {} segments, {:.0} s ({:.1} min) in all.\n\n\
             Play each row from its time until the next row's: give the joint in column `joint` the constant torque\n\
             of its tau column as an open-loop command, and hold every joint whose hold column is 1 with your\n\
             position controller at the angle it has when its hold begins. Rows with joint 0 hold every joint.\n\
             Keep gravity off the driven joint (the arm horizontal, or the joint's axis vertical).\n\
             Log time [s] and, per joint i, q_i [rad], qd_i [rad/s] and tau_i [N.m] (the torque commanded or measured)\n\
             at 100 Hz or faster (1 kHz is best), from the start to the end of the plan.\n\
             Then: neurarm identify friction --log LOG.csv --joint J -o friction_J.csv (for each joint).\n\n\
             Each direction starts with breakaway probes (torques that should leave the joint at rest: they give the\n\
             pair at rest), then constant torques from the highest speed down. Each level lasts long enough to settle\n\
             and ends with the window the identification measures. The driven joint turns continuously:\n",
            self.segments.len(),
            self.end_s,
            self.end_s / 60.0
        );
        for (joint, up, down) in &self.travel_rad {
            text += &format!(
                "  joint {joint}: about {up:.0} rad ({:.0} turns) in the positive direction, {down:.0} rad ({:.0} turns) in the negative\n",
                up / (2.0 * PI),
                down / (2.0 * PI)
            );
        }
        text += "A joint that cannot turn that far needs a lower --max-speed (or its levels played in several runs).\n";
        text
    }
}

/// Settings of a gravity plan.
#[derive(Clone, Debug, PartialEq)]
pub struct GravityPlanSettings {
    /// The poses: a kⁿ grid or a sampled design.
    pub design: GravityDesign,
    /// Speed of every joint in a pass [rad/s].
    pub speed_rad_s: f64,
    /// Duration of each pass [s] (2 s: the controller settles on the pass speed in its first
    /// part, and the identification averages 0.5 s at its middle).
    pub pass_s: f64,
    /// Seed of a sampled design.
    pub seed: u64,
}

impl Default for GravityPlanSettings {
    fn default() -> Self {
        Self { design: GravityDesign::default(), speed_rad_s: 0.25, pass_s: 2.0, seed: 1 }
    }
}

/// A segment of a gravity plan.
#[derive(Clone, Debug, PartialEq)]
pub struct GravitySegment {
    /// Start [s].
    pub time_s: f64,
    /// Pose number (from 1).
    pub pose: usize,
    /// 0: a move to the next row's angles; 1 up; −1 down.
    pub pass: i8,
    /// Angles at the start [rad].
    pub q: Vec<f64>,
    /// Speeds [rad/s] (0 on a move).
    pub qd: Vec<f64>,
}

/// A gravity plan.
#[derive(Clone, Debug, PartialEq)]
pub struct GravityPlan {
    /// Joints.
    pub joints: usize,
    /// Poses.
    pub poses: usize,
    /// Segments in time order; the last one holds the final angles.
    pub segments: Vec<GravitySegment>,
    /// End [s].
    pub end_s: f64,
}

/// Plans the gravity sweep: for each pose of the design a smooth move to just below it, then
/// every joint up through it and back down at constant speed (the paper's sweep).
pub fn gravity_plan(joints: usize, settings: &GravityPlanSettings) -> Result<GravityPlan> {
    settings.design.check(joints)?;
    if !(settings.speed_rad_s > 0.0 && settings.speed_rad_s.is_finite() && settings.pass_s >= 0.1 && settings.pass_s.is_finite()) {
        bail!("need a pass speed > 0 and passes of at least 0.1 s (got {} rad/s, {} s)", settings.speed_rad_s, settings.pass_s);
    }
    let (poses, _) = design_poses(settings.design, joints, settings.seed);
    let offset = 0.5 * settings.speed_rad_s * settings.pass_s;
    let mut segments = Vec::new();
    let mut t = 0.0;
    let mut current: Option<Vec<f64>> = None;
    for (k, pose) in poses.iter().enumerate() {
        let below: Vec<f64> = pose.iter().map(|q| q - offset).collect();
        let above: Vec<f64> = pose.iter().map(|q| q + offset).collect();
        if let Some(from) = &current {
            let distance = from.iter().zip(&below).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
            let duration = ((distance / 1.5).max(0.3) * 10.0).ceil() / 10.0;
            segments.push(GravitySegment { time_s: t, pose: k + 1, pass: 0, q: from.clone(), qd: vec![0.0; joints] });
            t += duration;
        }
        segments.push(GravitySegment { time_s: t, pose: k + 1, pass: 1, q: below.clone(), qd: vec![settings.speed_rad_s; joints] });
        t += settings.pass_s;
        segments.push(GravitySegment { time_s: t, pose: k + 1, pass: -1, q: above, qd: vec![-settings.speed_rad_s; joints] });
        t += settings.pass_s;
        current = Some(below);
    }
    let last = current.unwrap_or_else(|| vec![0.0; joints]);
    segments.push(GravitySegment { time_s: t, pose: poses.len(), pass: 0, q: last, qd: vec![0.0; joints] });
    Ok(GravityPlan { joints, poses: poses.len(), segments, end_s: t })
}

impl GravityPlan {
    /// The plan as CSV (see the module docs).
    pub fn to_csv(&self) -> String {
        let n = self.joints;
        let mut header = vec![header_cell("time", "s"), "pose".into(), "pass".into()];
        header.extend((1..=n).map(|i| header_cell(&format!("q_{i}"), "rad")));
        header.extend((1..=n).map(|i| header_cell(&format!("qd_{i}"), "rad/s")));
        let mut out = header.join(",") + "\n";
        for s in &self.segments {
            let mut row = vec![number(s.time_s), s.pose.to_string(), s.pass.to_string()];
            row.extend(s.q.iter().map(|&v| number(v)));
            row.extend(s.qd.iter().map(|&v| number(v)));
            out += &(row.join(",") + "\n");
        }
        out
    }

    /// How to run the plan, in words.
    pub fn instructions(&self, source: &str, settings: &GravityPlanSettings) -> String {
        format!(
            "Gravity plan for {source}: {} poses, {} segments, {:.0} s ({:.1} min) in all.\n\n\
             Start at rest at the first row's angles, gravity acting as it will in use. Play each row from its time until\n\
             the next row's with your position controller:\n\
             - pass 1 (up) or -1 (down): every joint moves at the constant speed of its qd column from the row's angles,\n\
               q_i(t) = q_i + qd_i (t - time): the pass goes up through the pose and comes back down;\n\
             - pass 0 (move): a smooth rest-to-rest move from the row's angles to the next row's, ending at its time,\n\
               e.g. q(s) = q_a + (q_b - q_a)(1 - cos(pi s))/2 with s the fraction of the move's time.\n\
             Angles may leave [0, 2pi): the path between poses takes whole turns off where that is shorter.\n\
             Log time [s] and, per joint i, q_i [rad], qd_i [rad/s] and tau_i [N.m] at 1 kHz if you can (at least 100 Hz).\n\
             Then: neurarm identify gravity --log LOG.csv -o gravity.csv (--friction the friction pairs to take\n\
             friction that differs with the direction out of the pairs; -c the arm to take the velocity terms out).\n\n\
             Passes: {} rad/s for {} s each; the identification averages the angles and torques at the middle of each pass\n\
             and pairs the up and the down pass of each pose.\n",
            self.poses,
            self.segments.len(),
            self.end_s,
            self.end_s / 60.0,
            settings.speed_rad_s,
            settings.pass_s
        )
    }
}

/// Writes `csv` to `path` (see [`crate::output`]) and, when `path` is a file, `text` beside it
/// (same name, `.txt`), each atomically; returns the text file's path, or `None` when `path` is
/// standard output, a device or a FIFO: then there is no "beside", and the caller shows the text.
pub fn write_plan(path: &Path, csv: &str, text: &str) -> Result<Option<std::path::PathBuf>> {
    let beside = crate::output::Destination::of(path).with_context(|| path.display().to_string())?.is_file();
    let notes = path.with_extension("txt");
    if beside && notes == path {
        bail!("{}: give the plan a .csv name (its instructions go to a .txt beside it)", path.display());
    }
    write_text_atomic(path, csv).with_context(|| format!("writing {}", crate::output::describe(path)))?;
    if !beside {
        return Ok(None);
    }
    write_text_atomic(&notes, text).with_context(|| format!("writing {}", notes.display()))?;
    Ok(Some(notes))
}
