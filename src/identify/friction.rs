//! Friction pairs from constant-torque levels: which levels reached a steady speed, the
//! steady ones binned by speed, and the pair at rest from the levels that did not move the
//! joint. One implementation for logs of a real robot and for the paper's own runs.

use std::collections::BTreeMap;
use std::ops::Range;

use anyhow::bail;
use serde::Serialize;

use super::RobotLog;

/// How levels are judged and binned. [`FrictionOptions::default`] gives the documented values.
///
/// A level is steady when the line fitted to its speed over the last `window_s` drifts by at
/// most `drift_rad_s` plus three standard errors (capped at `drift_rad_s`), and the speed's
/// spread about it is at most `spread_rad_s` or 10 % of the mean speed; a level below
/// `rest_speed_rad_s` is a breakaway probe, not a pair (docs/concepts/identification.md).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrictionOptions {
    /// Width of the speed bins [rad/s] (the paper: 0.05).
    pub bin_width_rad_s: f64,
    /// Measuring window at the end of each level [s]; a level shorter than this is refused.
    pub window_s: f64,
    /// Largest drift of the speed over the window beyond noise [rad/s].
    pub drift_rad_s: f64,
    /// Largest spread of the speed about its fitted line [rad/s] (or 10 % of the speed).
    pub spread_rad_s: f64,
    /// Below this |mean speed| the joint is at rest [rad/s].
    pub rest_speed_rad_s: f64,
    /// Torques that differ by at most this belong to one level of a log [N·m].
    pub torque_tolerance_nm: f64,
    /// The driven joint's inertia with the other joints held [kg·m²]: with it, friction is
    /// τ − H·s (what is left of the approach to the steady state is taken out); without it, τ.
    pub inertia_kgm2: Option<f64>,
}

impl Default for FrictionOptions {
    fn default() -> Self {
        Self {
            bin_width_rad_s: 0.05,
            window_s: 0.5,
            drift_rad_s: 0.01,
            spread_rad_s: 0.1,
            rest_speed_rad_s: 0.01,
            torque_tolerance_nm: 1e-6,
            inertia_kgm2: None,
        }
    }
}

impl FrictionOptions {
    /// Refuses options that make no sense, naming them.
    pub fn check(&self) -> anyhow::Result<()> {
        let positive = [
            ("bin width", self.bin_width_rad_s),
            ("window", self.window_s),
            ("drift", self.drift_rad_s),
            ("spread", self.spread_rad_s),
            ("rest speed", self.rest_speed_rad_s),
        ];
        for (name, v) in positive {
            if !(v > 0.0 && v.is_finite()) {
                bail!("the {name} must be a positive number (got {v})");
            }
        }
        if !(self.torque_tolerance_nm >= 0.0 && self.torque_tolerance_nm.is_finite()) {
            bail!("the torque tolerance must be >= 0 (got {})", self.torque_tolerance_nm);
        }
        if let Some(h) = self.inertia_kgm2.filter(|h| !(*h >= 0.0 && h.is_finite())) {
            bail!("the inertia must be >= 0 kg·m² (got {h})");
        }
        Ok(())
    }
}

/// A training pair of a friction net: (speed [rad/s], mean friction torque [N·m], samples).
pub type FrictionPair = (f64, f64, usize);

/// One level: the driven joint's samples while one torque command (or one speed target) held.
#[derive(Clone, Copy, Debug)]
pub struct Level<'a> {
    /// Sample times [s], increasing.
    pub time: &'a [f64],
    /// The driven joint's measured speed [rad/s].
    pub speed: &'a [f64],
    /// The driven joint's torque [N·m] (constant on a constant-torque level).
    pub torque: &'a [f64],
    /// File line of the level's first sample (0 when not from a file).
    pub line: u64,
}

/// What became of a level.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Steady: its window is a pair's data.
    Kept,
    /// The joint did not move: a breakaway probe.
    AtRest,
    /// No torque on the joint (a pause between runs).
    NoTorque,
    /// Shorter than the measuring window.
    TooShort,
    /// The joint moved against its torque (pushed by something else).
    AgainstTorque,
    /// The speed still drifted in the window.
    Drifting,
    /// The speed spread too much about its trend (stick–slip, oscillation).
    Spread,
}

impl Verdict {
    /// Why a level was not kept, in words.
    pub fn reason(&self) -> &'static str {
        match self {
            Verdict::Kept => "steady",
            Verdict::AtRest => "at rest (breakaway probe)",
            Verdict::NoTorque => "no torque",
            Verdict::TooShort => "shorter than the measuring window",
            Verdict::AgainstTorque => "moved against its torque",
            Verdict::Drifting => "speed still drifting",
            Verdict::Spread => "speed spread too wide (stick-slip or oscillation)",
        }
    }
}

/// One level's measurement and verdict.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LevelReport {
    /// Start and end time of the level [s].
    pub start_s: f64,
    /// End time [s].
    pub end_s: f64,
    /// File line of its first sample.
    pub line: u64,
    /// Mean torque over the window [N·m].
    pub torque_nm: f64,
    /// Mean speed over the window [rad/s].
    pub speed_rad_s: f64,
    /// Drift of the speed over the window, |s|·window [rad/s].
    pub drift_rad_s: f64,
    /// Tolerated drift (the option plus three standard errors) [rad/s].
    pub drift_limit_rad_s: f64,
    /// RMS of the speed about its fitted line [rad/s].
    pub spread_rad_s: f64,
    /// The friction torque of the level: the mean torque less H·s when the inertia is known [N·m].
    pub friction_nm: f64,
    /// Samples in the window.
    pub samples: usize,
    /// What became of it.
    pub verdict: Verdict,
}

/// The pair at rest and where it came from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct RestPair {
    /// Midpoint of the two breakaway torques [N·m].
    pub torque_nm: f64,
    /// Largest positive torque that did not move the joint [N·m].
    pub positive_nm: f64,
    /// Largest negative torque that did not move the joint [N·m].
    pub negative_nm: f64,
    /// Levels at rest behind it.
    pub levels: usize,
}

/// The result of identifying one joint's friction.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrictionIdentification {
    /// Pairs by increasing speed, the pair at rest among them when there is one.
    pub pairs: Vec<FrictionPair>,
    /// Every level, in order.
    pub levels: Vec<LevelReport>,
    /// The pair at rest, if both directions had levels that did not move the joint.
    pub rest: Option<RestPair>,
    /// Rows of a log in runs of fewer than [`MIN_LEVEL_ROWS`] equal torques: the joint under
    /// closed-loop control (held while another joint is driven), not a level.
    pub ignored_rows: usize,
}

/// Fewest rows of equal torque that make a level of a log.
pub const MIN_LEVEL_ROWS: usize = 3;

impl FrictionIdentification {
    /// Levels kept.
    pub fn kept(&self) -> usize {
        self.levels.iter().filter(|l| l.verdict == Verdict::Kept).count()
    }

    /// The noise of the measured speed [rad/s], a standard deviation: the median spread of the
    /// speed about its trend over the levels at rest, where the true speed is zero and all
    /// spread is the sensor's; without such levels, over the kept ones (an upper bound: their
    /// spread holds the motion's ripple too); 0 without either.
    pub fn speed_noise_rad_s(&self) -> f64 {
        let median_spread = |verdict: Verdict| {
            let mut spreads: Vec<f64> = self.levels.iter().filter(|l| l.verdict == verdict).map(|l| l.spread_rad_s).collect();
            spreads.sort_by(f64::total_cmp);
            (!spreads.is_empty()).then(|| spreads[spreads.len() / 2])
        };
        median_spread(Verdict::AtRest).or_else(|| median_spread(Verdict::Kept)).unwrap_or(0.0)
    }
}

/// The steadiness test of one window (see [`FrictionOptions`]): (mean, drift, drift limit,
/// spread, slope [rad/s²]).
pub fn window_trend(time: &[f64], speed: &[f64], drift_allowed: f64) -> (f64, f64, f64, f64, f64) {
    let n = speed.len() as f64;
    let t_mean = time.iter().sum::<f64>() / n;
    let v_mean = speed.iter().sum::<f64>() / n;
    let (mut stt, mut stv) = (0.0, 0.0);
    for (t, v) in time.iter().zip(speed) {
        stt += (t - t_mean).powi(2);
        stv += (t - t_mean) * (v - v_mean);
    }
    let slope = if stt > 0.0 { stv / stt } else { 0.0 };
    let residual: f64 = time.iter().zip(speed).map(|(t, v)| (v - v_mean - slope * (t - t_mean)).powi(2)).sum();
    let spread = (residual / n).sqrt();
    let span = time.last().copied().unwrap_or(0.0) - time.first().copied().unwrap_or(0.0);
    let slope_error = if stt > 0.0 && n > 2.0 { (residual / (n - 2.0) / stt).sqrt() } else { f64::INFINITY };
    // Noise widens the limit by at most the allowed drift itself: a sparse or noisy log cannot
    // let a level that is still slowing down pass as steady.
    (v_mean, slope.abs() * span, drift_allowed + (3.0 * slope_error * span).min(drift_allowed), spread, slope)
}

/// Judges one level (see [`FrictionOptions`]).
pub fn judge_level(level: &Level<'_>, options: &FrictionOptions) -> LevelReport {
    let (Some(&start), Some(&end)) = (level.time.first(), level.time.last()) else {
        return LevelReport {
            start_s: 0.0,
            end_s: 0.0,
            line: level.line,
            torque_nm: 0.0,
            speed_rad_s: 0.0,
            drift_rad_s: 0.0,
            drift_limit_rad_s: 0.0,
            spread_rad_s: 0.0,
            friction_nm: 0.0,
            samples: 0,
            verdict: Verdict::TooShort,
        };
    };
    let from = level.time.partition_point(|&t| t < end - options.window_s);
    let (time, speed, torque) = (&level.time[from..], &level.speed[from..], &level.torque[from..]);
    let (mean, drift, limit, spread, slope) = window_trend(time, speed, options.drift_rad_s);
    let torque_nm = torque.iter().sum::<f64>() / torque.len() as f64;
    let friction_nm = torque_nm - options.inertia_kgm2.unwrap_or(0.0) * slope;
    // A window of the full length needs a sample at or before its start.
    let long_enough = end - start >= options.window_s * (1.0 - 1e-9) && time.len() >= 3;
    let verdict = if torque_nm.abs() <= options.torque_tolerance_nm.max(1e-12) && mean.abs() < options.rest_speed_rad_s {
        Verdict::NoTorque
    } else if !long_enough {
        Verdict::TooShort
    } else if mean.abs() < options.rest_speed_rad_s {
        if torque_nm.abs() <= options.torque_tolerance_nm.max(1e-12) {
            Verdict::NoTorque
        } else {
            Verdict::AtRest
        }
    } else if mean * torque_nm <= 0.0 {
        Verdict::AgainstTorque
    } else if spread > options.spread_rad_s.max(0.1 * mean.abs()) {
        Verdict::Spread
    } else if drift > limit {
        Verdict::Drifting
    } else {
        Verdict::Kept
    };
    LevelReport {
        start_s: start,
        end_s: end,
        line: level.line,
        torque_nm,
        speed_rad_s: mean,
        drift_rad_s: drift,
        drift_limit_rad_s: limit,
        spread_rad_s: spread,
        friction_nm,
        samples: time.len(),
        verdict,
    }
}

/// Judges every level, bins the kept ones and adds the pair at rest.
///
/// A kept level enters its bin (width `bin_width_rad_s`, edges at its multiples) whole, at its
/// window's mean speed and friction weighted by its samples, so speed noise does not bias bins
/// towards their edges. The pair at rest is (0, the midpoint of each direction's largest torque
/// that left the joint at rest with no smaller one moving it), which pushes neither way; it
/// needs probes of both directions (docs/concepts/identification.md).
pub fn identify_levels(levels: &[Level<'_>], options: &FrictionOptions) -> FrictionIdentification {
    let reports: Vec<LevelReport> = levels.iter().map(|l| judge_level(l, options)).collect();
    let mut bins: BTreeMap<i64, (f64, f64, usize)> = BTreeMap::new();
    for r in reports.iter().filter(|r| r.verdict == Verdict::Kept) {
        let key = (r.speed_rad_s / options.bin_width_rad_s).floor() as i64;
        let bin = bins.entry(key).or_insert((0.0, 0.0, 0));
        bin.0 += r.speed_rad_s * r.samples as f64;
        bin.1 += r.friction_nm * r.samples as f64;
        bin.2 += r.samples;
    }
    let mut pairs: Vec<FrictionPair> = bins.into_values().map(|(v, f, n)| (v / n as f64, f / n as f64, n)).collect();
    let rest = rest_pair(&reports);
    if let Some(rest) = rest {
        let at = pairs.partition_point(|p| p.0 < 0.0);
        pairs.insert(at, (0.0, rest.torque_nm, rest.levels));
    }
    FrictionIdentification { pairs, levels: reports, rest, ignored_rows: 0 }
}

/// The pair at rest of [`identify_levels`], if both directions have probes at rest.
fn rest_pair(reports: &[LevelReport]) -> Option<RestPair> {
    let side = |sign: f64| -> Option<(f64, usize)> {
        // The smallest torque of this direction that moved the joint bounds the probes.
        let moved = reports
            .iter()
            .filter(|r| r.torque_nm * sign > 0.0 && !matches!(r.verdict, Verdict::AtRest | Verdict::NoTorque | Verdict::TooShort))
            .map(|r| r.torque_nm.abs())
            .fold(f64::INFINITY, f64::min);
        let probes: Vec<f64> = reports
            .iter()
            .filter(|r| r.verdict == Verdict::AtRest && r.torque_nm * sign > 0.0 && r.torque_nm.abs() < moved)
            .map(|r| r.torque_nm.abs())
            .collect();
        let largest = probes.iter().copied().fold(f64::NAN, f64::max);
        (!probes.is_empty()).then_some((sign * largest, probes.len()))
    };
    let (up, down) = (side(1.0)?, side(-1.0)?);
    Some(RestPair { torque_nm: 0.5 * (up.0 + down.0), positive_nm: up.0, negative_nm: down.0, levels: up.1 + down.1 })
}

/// The constant-torque levels of `torque`: maximal runs of rows whose torque stays within
/// `tolerance` of the run's first row [N·m].
pub fn torque_levels(torque: &[f64], tolerance: f64) -> Vec<Range<usize>> {
    let mut levels = Vec::new();
    let mut start = 0;
    for r in 1..=torque.len() {
        if r == torque.len() || (torque[r] - torque[start]).abs() > tolerance {
            levels.push(start..r);
            start = r;
        }
    }
    levels
}

/// Identifies joint `joint`'s (1-based) friction from a log of constant-torque runs: the
/// levels are the runs of constant `tau_joint` (see [`torque_levels`]), judged and binned by
/// [`identify_levels`].
pub fn identify_friction_log(log: &RobotLog, joint: usize, options: &FrictionOptions) -> anyhow::Result<FrictionIdentification> {
    options.check()?;
    let j = log.joint_index(joint)?;
    let (speed, torque) = (&log.qd[j], &log.tau[j]);
    let (ranges, short): (Vec<Range<usize>>, Vec<Range<usize>>) =
        torque_levels(torque, options.torque_tolerance_nm).into_iter().partition(|r| r.len() >= MIN_LEVEL_ROWS);
    let levels: Vec<Level<'_>> = ranges
        .iter()
        .map(|r| Level { time: &log.time[r.clone()], speed: &speed[r.clone()], torque: &torque[r.clone()], line: log.lines[r.start] })
        .collect();
    let mut found = identify_levels(&levels, options);
    found.ignored_rows = short.iter().map(|r| r.len()).sum();
    if found.kept() == 0 {
        let moving = found.levels.iter().filter(|l| !matches!(l.verdict, Verdict::AtRest | Verdict::NoTorque)).count();
        bail!(
            "{}: joint {joint}: no steady constant-torque level among the {} levels of the log ({moving} moved the joint; \
             a level needs at least {} s of constant torque and a steady speed at its end: see `neurarm plan friction`)",
            log.path.display(),
            found.levels.len(),
            options.window_s
        );
    }
    Ok(found)
}

/// A joint's identified friction as the piecewise-linear interpolant of its pairs: what the
/// friction experiment measured, without a net's fitting error.
#[derive(Clone, Debug, PartialEq)]
pub struct FrictionCurve {
    /// (velocity [rad/s], torque [N·m]) in increasing velocity.
    points: Vec<(f64, f64)>,
}

impl FrictionCurve {
    /// The curve through `pairs` (sorted by velocity, as the binned pairs are).
    pub fn new(pairs: &[FrictionPair]) -> Self {
        let mut points: Vec<(f64, f64)> = pairs.iter().map(|p| (p.0, p.1)).collect();
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        Self { points }
    }

    /// The friction torque at `velocity` [rad/s]: interpolated between the neighbouring
    /// pairs, the end pairs' values beyond them [N·m]; 0 without pairs.
    pub fn torque(&self, velocity: f64) -> f64 {
        let p = &self.points;
        match p.len() {
            0 => 0.0,
            1 => p[0].1,
            len => {
                let j = p.partition_point(|q| q.0 < velocity).clamp(1, len - 1);
                let (a, b) = (p[j - 1], p[j]);
                let w = if b.0 > a.0 { ((velocity - a.0) / (b.0 - a.0)).clamp(0.0, 1.0) } else { 0.0 };
                a.1 + w * (b.1 - a.1)
            }
        }
    }
}
