//! Gravity pairs from slow up and down passes: every joint moves at the same constant speed up
//! through a pose and back down; at the middle of each pass the angles and torques are
//! averaged over a short window, and the two passes averaged. One implementation for logs and
//! for the paper's own sweeps.

use anyhow::bail;
use serde::Serialize;

use super::{FrictionCurve, RobotLog};
use neurarm_physics::arm::{inverse_dynamics_rnea_into, ArmData, ArmParams};

/// How passes are found and judged. [`GravityOptions::default`] gives the documented values.
///
/// A pass is steady when every joint's speed, averaged over `smoothing_s`, stays within `share`
/// of ±`speed_rad_s` throughout its window. An up and a down pass through common angles make a
/// pair, each measured where it comes closest to the overlap's middle (within
/// `pose_tolerance_rad`); a pose passed one way only is refused (docs/concepts/identification.md).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GravityOptions {
    /// Speed of every joint in a pass [rad/s] (the plan's: 0.25).
    pub speed_rad_s: f64,
    /// Largest deviation of a smoothed speed from the pass speed, as a share of it.
    pub share: f64,
    /// Measuring window at the middle of a pass [s]: 0.5 s for logs (a quarter of the plan's
    /// 2 s passes), whose torques carry the controller's response to sensor noise; the paper's
    /// noise-free sweeps take 40 ms.
    pub window_s: f64,
    /// Moving average of the speeds for the steadiness test [s].
    pub smoothing_s: f64,
    /// Largest distance of a pass's closest sample from its pair's pose [rad].
    pub pose_tolerance_rad: f64,
    /// Shortest stretch of a log taken as a pass [s].
    pub min_pass_s: f64,
}

impl Default for GravityOptions {
    fn default() -> Self {
        Self { speed_rad_s: 0.25, share: 0.2, window_s: 0.5, smoothing_s: 0.05, pose_tolerance_rad: 0.05, min_pass_s: 0.1 }
    }
}

impl GravityOptions {
    /// Refuses options that make no sense, naming them.
    pub fn check(&self) -> anyhow::Result<()> {
        for (name, v) in [
            ("pass speed", self.speed_rad_s),
            ("window", self.window_s),
            ("pose tolerance", self.pose_tolerance_rad),
            ("shortest pass", self.min_pass_s),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                bail!("the {name} must be a positive number (got {v})");
            }
        }
        if !(self.share > 0.0 && self.share < 1.0) {
            bail!("the speed share must lie between 0 and 1 (got {})", self.share);
        }
        if !(self.smoothing_s >= 0.0 && self.smoothing_s.is_finite()) {
            bail!("the smoothing must be >= 0 s (got {})", self.smoothing_s);
        }
        Ok(())
    }
}

/// What is taken out of each pass's torques before the two are averaged.
///
/// Averaging cancels what is odd in the speed. Friction that differs with the direction, and
/// the Coriolis and centrifugal torques (even in the speed), do not cancel: the identified
/// friction (each joint's curve at the measured speed) and the velocity terms of a rigid-body
/// model at the measured angles and speeds are subtracted from every sample.
#[derive(Clone, Copy, Debug, Default)]
pub struct GravityCorrection<'a> {
    /// Each joint's identified friction; empty for none.
    pub friction: &'a [FrictionCurve],
    /// A rigid-body model of the arm without gravity or friction, for the velocity terms.
    pub model: Option<&'a ArmParams>,
}

impl GravityCorrection<'_> {
    /// Whether anything is taken out.
    pub fn is_empty(&self) -> bool {
        self.friction.is_empty() && self.model.is_none()
    }
}

/// The samples of one pass's measuring window, row by row (each row one value per joint).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PassWindow {
    /// Joints.
    pub joints: usize,
    /// Sample times [s].
    pub time: Vec<f64>,
    /// Angles [rad], `joints` per sample.
    pub q: Vec<f64>,
    /// Speeds [rad/s], `joints` per sample.
    pub qd: Vec<f64>,
    /// Torques [N·m], `joints` per sample.
    pub tau: Vec<f64>,
}

impl PassWindow {
    /// An empty window for `joints` joints.
    pub fn new(joints: usize) -> Self {
        Self { joints, ..Self::default() }
    }

    /// Adds one sample.
    pub fn push(&mut self, time: f64, q: &[f64], qd: &[f64], tau: &[f64]) {
        self.time.push(time);
        self.q.extend_from_slice(q);
        self.qd.extend_from_slice(qd);
        self.tau.extend_from_slice(tau);
    }

    /// Samples.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// Whether it holds no sample.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// Whether every joint's smoothed speed stays within the share of `direction` × speed.
    pub fn steady(&self, direction: f64, options: &GravityOptions) -> bool {
        let (n, want) = (self.joints, direction * options.speed_rad_s);
        let half = 0.5 * options.smoothing_s;
        (0..self.len()).all(|k| {
            let lo = self.time.partition_point(|&t| t < self.time[k] - half);
            let hi = self.time.partition_point(|&t| t <= self.time[k] + half);
            (0..n).all(|i| {
                let mean = (lo..hi).map(|s| self.qd[s * n + i]).sum::<f64>() / (hi - lo) as f64;
                (mean - want).abs() <= options.share * options.speed_rad_s
            })
        })
    }

    /// Mean angles, mean torques and mean torques less the correction.
    fn means(&self, correction: &GravityCorrection<'_>, scratch: &mut Scratch) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let n = self.joints;
        let (mut q, mut tau, mut corrected) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
        for k in 0..self.len() {
            let (qk, qdk, tk) = (&self.q[k * n..(k + 1) * n], &self.qd[k * n..(k + 1) * n], &self.tau[k * n..(k + 1) * n]);
            if let (Some(model), Some(data)) = (correction.model, scratch.data.as_mut()) {
                inverse_dynamics_rnea_into(model, data, qk, qdk, &scratch.zero, &mut scratch.velocity_torque);
            }
            for i in 0..n {
                q[i] += qk[i];
                tau[i] += tk[i];
                let friction = correction.friction.get(i).map_or(0.0, |c| c.torque(qdk[i]));
                corrected[i] += tk[i] - friction - scratch.velocity_torque[i];
            }
        }
        let count = self.len().max(1) as f64;
        for v in q.iter_mut().chain(tau.iter_mut()).chain(corrected.iter_mut()) {
            *v /= count;
        }
        (q, tau, corrected)
    }
}

struct Scratch {
    data: Option<ArmData>,
    zero: Vec<f64>,
    velocity_torque: Vec<f64>,
}

/// An averaged pose: the mean of the up and the down pass.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GravityMeasurement {
    /// Mean angles [rad].
    pub q: Vec<f64>,
    /// Mean torques less the correction [N·m]: the training targets.
    pub torque: Vec<f64>,
    /// Mean torques as measured (the paper's plain average) [N·m].
    pub torque_uncorrected: Vec<f64>,
}

/// Why a pair of passes gave no pair.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PassFault {
    /// The up pass was not steady.
    UnsteadyUp,
    /// The down pass was not steady.
    UnsteadyDown,
    /// A window held no sample.
    Empty,
    /// The correction has friction curves for another number of joints.
    CorrectionJoints,
}

impl PassFault {
    /// In words.
    pub fn reason(&self) -> &'static str {
        match self {
            PassFault::UnsteadyUp => "the up pass was not steady",
            PassFault::UnsteadyDown => "the down pass was not steady",
            PassFault::Empty => "a pass window held no sample",
            PassFault::CorrectionJoints => "the friction curves are for another number of joints",
        }
    }
}

/// One pose's pair from its up and down pass windows (see [`GravityOptions`] and
/// [`GravityCorrection`]).
pub fn gravity_pair(
    up: &PassWindow,
    down: &PassWindow,
    options: &GravityOptions,
    correction: &GravityCorrection<'_>,
) -> Result<GravityMeasurement, PassFault> {
    let n = up.joints;
    if up.is_empty() || down.is_empty() {
        return Err(PassFault::Empty);
    }
    if !correction.friction.is_empty() && correction.friction.len() != n {
        return Err(PassFault::CorrectionJoints);
    }
    if !up.steady(1.0, options) {
        return Err(PassFault::UnsteadyUp);
    }
    if !down.steady(-1.0, options) {
        return Err(PassFault::UnsteadyDown);
    }
    let mut scratch = Scratch { data: correction.model.map(ArmData::new), zero: vec![0.0; n], velocity_torque: vec![0.0; n] };
    let (qa, ta, ca) = up.means(correction, &mut scratch);
    let (qb, tb, cb) = down.means(correction, &mut scratch);
    let mean = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| 0.5 * (x + y)).collect::<Vec<f64>>();
    let corrected = if correction.is_empty() { mean(&ta, &tb) } else { mean(&ca, &cb) };
    Ok(GravityMeasurement { q: mean(&qa, &qb), torque: corrected, torque_uncorrected: mean(&ta, &tb) })
}

/// One pose found in a log, paired or refused.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PoseReport {
    /// Mean angles of the pass windows [rad].
    pub q: Vec<f64>,
    /// Time of the up pass's middle [s], if there was one.
    pub up_s: Option<f64>,
    /// Time of the down pass's middle [s], if there was one.
    pub down_s: Option<f64>,
    /// File line of the first pass's middle.
    pub line: u64,
    /// None when kept, else why not.
    pub refused: Option<String>,
}

/// The pairs of a gravity log and every pose found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GravityIdentification {
    /// One pair per kept pose, in the order of the log.
    pub pairs: Vec<GravityMeasurement>,
    /// Every pose found, kept or refused, in the order of the log.
    pub poses: Vec<PoseReport>,
    /// Passes found.
    pub passes: usize,
}

/// A pass found in a log: direction and its rows.
struct Pass {
    direction: f64,
    rows: std::ops::Range<usize>,
    middle_s: f64,
    line: u64,
    /// Angles at the middle of the stretch [rad].
    pose: Vec<f64>,
    /// Each joint's smallest and largest angle over the stretch [rad].
    range: Vec<(f64, f64)>,
}

/// The window of `pass` centred on the row closest to `pose`, and that row's time.
fn window_at(log: &RobotLog, pass: &Pass, pose: &[f64], window_s: f64) -> (PassWindow, f64, f64) {
    let n = pose.len();
    let distance = |k: usize| (0..n).map(|i| (log.q[i][k] - pose[i]).abs()).fold(0.0, f64::max);
    let centre = pass.rows.clone().min_by(|&a, &b| distance(a).total_cmp(&distance(b))).unwrap_or(pass.rows.start);
    let miss = distance(centre);
    let (t0, mut window) = (log.time[centre], PassWindow::new(n));
    let (mut qk, mut qdk, mut tk) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    for k in pass.rows.clone() {
        if (log.time[k] - t0).abs() <= 0.5 * window_s {
            for i in 0..n {
                (qk[i], qdk[i], tk[i]) = (log.q[i][k], log.qd[i][k], log.tau[i][k]);
            }
            window.push(log.time[k], &qk, &qdk, &tk);
        }
    }
    (window, t0, miss)
}

/// Finds the passes of `log` and pairs them (see [`GravityOptions`]).
pub fn identify_gravity_log(
    log: &RobotLog,
    options: &GravityOptions,
    correction: &GravityCorrection<'_>,
) -> anyhow::Result<GravityIdentification> {
    options.check()?;
    let n = log.joints.len();
    if !correction.friction.is_empty() && correction.friction.len() != n {
        bail!("friction pairs of {} joints for a log of {n} joints", correction.friction.len());
    }
    let passes = find_passes(log, options);
    let partner = pair_passes(&passes);
    let mut found = GravityIdentification { pairs: Vec::new(), poses: Vec::new(), passes: passes.len() };
    for (a, pass) in passes.iter().enumerate() {
        match partner[a] {
            Some(b) if b < a => continue,
            Some(b) => {
                let (report, pair) = measure_pose(log, pass, &passes[b], options, correction);
                found.poses.push(report);
                found.pairs.extend(pair);
            }
            None => found.poses.push(one_way_pose(pass)),
        }
    }
    if found.pairs.is_empty() {
        bail!(
            "{}: no pose passed both up and down at {} rad/s (±{:.0} %) by every joint ({} passes found): see `neurarm plan gravity`",
            log.path.display(),
            options.speed_rad_s,
            100.0 * options.share,
            passes.len()
        );
    }
    Ok(found)
}

/// Each row's direction: 1 (or −1) when every joint's speed, averaged over the smoothing time,
/// is within the share of +speed (−speed), else 0.
fn pass_directions(log: &RobotLog, options: &GravityOptions) -> Vec<i8> {
    let (n, rows) = (log.joints.len(), log.rows());
    // Moving averages of the speeds over the smoothing time, by prefix sums.
    let mut prefix = vec![vec![0.0; rows + 1]; n];
    for i in 0..n {
        for r in 0..rows {
            prefix[i][r + 1] = prefix[i][r] + log.qd[i][r];
        }
    }
    let half = 0.5 * options.smoothing_s;
    (0..rows)
        .map(|r| {
            let lo = log.time.partition_point(|&t| t < log.time[r] - half);
            let hi = log.time.partition_point(|&t| t <= log.time[r] + half);
            let near = |sign: f64| {
                (0..n).all(|i| {
                    let mean = (prefix[i][hi] - prefix[i][lo]) / (hi - lo) as f64;
                    (mean - sign * options.speed_rad_s).abs() <= options.share * options.speed_rad_s
                })
            };
            if near(1.0) {
                1
            } else if near(-1.0) {
                -1
            } else {
                0
            }
        })
        .collect()
}

/// The passes of `log`: stretches of one direction (see [`pass_directions`]) lasting at least
/// the shortest pass.
fn find_passes(log: &RobotLog, options: &GravityOptions) -> Vec<Pass> {
    let (n, rows) = (log.joints.len(), log.rows());
    let state = pass_directions(log, options);
    let mut passes = Vec::new();
    let mut start = 0;
    for r in 1..=rows {
        if r == rows || state[r] != state[start] {
            let (a, b) = (start, r - 1);
            if state[a] != 0 && log.time[b] - log.time[a] >= options.min_pass_s {
                let middle = 0.5 * (log.time[a] + log.time[b]);
                let m = log.time.partition_point(|&t| t < middle).min(b);
                let pose = (0..n).map(|i| log.q[i][m]).collect();
                let range = (0..n)
                    .map(|i| log.q[i][a..=b].iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &q| (lo.min(q), hi.max(q))))
                    .collect();
                passes.push(Pass { direction: f64::from(state[a]), rows: a..b + 1, middle_s: middle, line: log.lines[m], pose, range });
            }
            start = r;
        }
    }
    passes
}

/// Each pass's partner: the nearest (in time) unpaired later pass of the other direction
/// through common angles, taken in the order of the log.
fn pair_passes(passes: &[Pass]) -> Vec<Option<usize>> {
    let mut partner: Vec<Option<usize>> = vec![None; passes.len()];
    for a in 0..passes.len() {
        if partner[a].is_some() {
            continue;
        }
        let overlap = |b: usize| passes[a].range.iter().zip(&passes[b].range).all(|(x, y)| x.0.max(y.0) <= x.1.min(y.1));
        let best = (a + 1..passes.len())
            .filter(|&b| partner[b].is_none() && passes[b].direction != passes[a].direction && overlap(b))
            .min_by(|&x, &y| (passes[x].middle_s - passes[a].middle_s).abs().total_cmp(&(passes[y].middle_s - passes[a].middle_s).abs()));
        if let Some(b) = best {
            partner[a] = Some(b);
            partner[b] = Some(a);
        }
    }
    partner
}

/// The pose of the paired passes `first` (the earlier) and `second`, measured in both passes'
/// windows at the middle of their common angles: its report, and its pair unless refused.
fn measure_pose(
    log: &RobotLog,
    first: &Pass,
    second: &Pass,
    options: &GravityOptions,
    correction: &GravityCorrection<'_>,
) -> (PoseReport, Option<GravityMeasurement>) {
    let (up, down) = if first.direction > 0.0 { (first, second) } else { (second, first) };
    let pose: Vec<f64> = up.range.iter().zip(&down.range).map(|(x, y)| 0.5 * (x.0.max(y.0) + x.1.min(y.1))).collect();
    let (up_window, up_s, up_miss) = window_at(log, up, &pose, options.window_s);
    let (down_window, down_s, down_miss) = window_at(log, down, &pose, options.window_s);
    let result = if up_miss.max(down_miss) > options.pose_tolerance_rad {
        Err(None)
    } else {
        gravity_pair(&up_window, &down_window, options, correction).map_err(Some)
    };
    let q = match &result {
        Ok(m) => m.q.clone(),
        Err(_) => first.pose.clone(),
    };
    let refused = result.as_ref().err().map(|f| match f {
        Some(fault) => fault.reason().to_owned(),
        None => format!("the passes come no closer than {:.4} rad to a common pose", up_miss.max(down_miss)),
    });
    (PoseReport { q, up_s: Some(up_s), down_s: Some(down_s), line: first.line, refused }, result.ok())
}

/// The report of a pose passed in one direction only: refused.
fn one_way_pose(p: &Pass) -> PoseReport {
    let (word, other) = if p.direction > 0.0 { ("up", "down") } else { ("down", "up") };
    PoseReport {
        q: p.pose.clone(),
        up_s: (p.direction > 0.0).then_some(p.middle_s),
        down_s: (p.direction < 0.0).then_some(p.middle_s),
        line: p.line,
        refused: Some(format!("passed {word} only: no {other} pass through these angles")),
    }
}
