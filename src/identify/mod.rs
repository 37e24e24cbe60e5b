//! Identification from logs: friction pairs from constant-torque runs and gravity pairs from
//! slow up and down passes, as `neurarm identify` runs them on a robot's logs and the paper's
//! experiments run them on the logs their own simulations record.
//!
//! A log is a CSV with a time column and, per joint i (from 1), the measured angle, speed and
//! torque, by default `time`, `q_i` [rad], `qd_i` [rad/s], `tau_i` [N·m] (what `neurarm
//! simulate` writes; [`LogColumns`] renames them). Other columns are ignored. A header cell may
//! carry its unit in brackets, `qd_1 [rad/s]`.

pub mod friction;
pub mod gravity;

use std::path::{Path, PathBuf};

use crate::table::{NumericTable, TableError};

pub use friction::{
    identify_friction_log, identify_levels, judge_level, torque_levels, FrictionCurve, FrictionIdentification, FrictionOptions,
    FrictionPair, Level, LevelReport, RestPair, Verdict,
};
pub use gravity::{
    gravity_pair, identify_gravity_log, GravityCorrection, GravityIdentification, GravityMeasurement, GravityOptions, PassFault,
    PassWindow, PoseReport,
};

/// The column names of a log: patterns in which `{i}` stands for the joint number (from 1).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LogColumns {
    /// Time [s], strictly increasing.
    pub time: String,
    /// Joint angle [rad].
    pub q: String,
    /// Joint speed [rad/s].
    pub qd: String,
    /// Joint torque [N·m].
    pub tau: String,
}

impl Default for LogColumns {
    fn default() -> Self {
        Self { time: "time".into(), q: "q_{i}".into(), qd: "qd_{i}".into(), tau: "tau_{i}".into() }
    }
}

impl LogColumns {
    /// Refuses a per-joint pattern without `{i}`.
    pub fn check(&self) -> anyhow::Result<()> {
        for (what, p) in [("angle", &self.q), ("speed", &self.qd), ("torque", &self.tau)] {
            if !p.contains("{i}") {
                anyhow::bail!("the {what} column pattern '{p}' has no {{i}} for the joint number");
            }
        }
        Ok(())
    }

    fn name(pattern: &str, joint: usize) -> String {
        pattern.replace("{i}", &joint.to_string())
    }
}

/// A robot's log: time and, per joint read, angle, speed and torque.
#[derive(Clone, Debug)]
pub struct RobotLog {
    /// The file.
    pub path: PathBuf,
    /// Times [s], strictly increasing.
    pub time: Vec<f64>,
    /// Joint numbers read (from 1), in the order of the columns below.
    pub joints: Vec<usize>,
    /// Angles [rad] per joint read (empty for a joint whose angle was not needed).
    pub q: Vec<Vec<f64>>,
    /// Speeds [rad/s] per joint read.
    pub qd: Vec<Vec<f64>>,
    /// Torques [N·m] per joint read.
    pub tau: Vec<Vec<f64>>,
    /// File line of each row.
    pub lines: Vec<u64>,
}

impl RobotLog {
    /// Reads the speed and torque of joint `joint` (from 1): what friction identification needs.
    pub fn read_joint(path: &Path, columns: &LogColumns, joint: usize) -> Result<Self, TableError> {
        let header = header_names(path)?;
        let present = joints_in(&header, columns);
        let (qd, tau) = (LogColumns::name(&columns.qd, joint), LogColumns::name(&columns.tau, joint));
        for name in [&qd, &tau] {
            if !header.contains(name) {
                let has = if present.is_empty() { "no joint's columns".to_owned() } else { format!("joints {}", list(&present)) };
                return Err(table_error(
                    path,
                    Some(1),
                    format!(
                        "joint {joint}: no column '{name}' (the log has {has}; columns {}, {}, {}, time '{}')",
                        columns.q, columns.qd, columns.tau, columns.time
                    ),
                ));
            }
        }
        let table = NumericTable::read_only(path, &[&columns.time, &qd, &tau])?;
        table.require_increasing(&columns.time)?;
        let take = |n: &str| table.column(n).expect("read").to_vec();
        Ok(Self {
            path: path.to_path_buf(),
            time: take(&columns.time),
            joints: vec![joint],
            q: vec![Vec::new()],
            qd: vec![take(&qd)],
            tau: vec![take(&tau)],
            lines: table.lines.clone(),
        })
    }

    /// Reads every joint 1…n that has all three columns (n ≥ 1): what gravity identification
    /// needs. `joints`, when given, must be that count.
    pub fn read_all(path: &Path, columns: &LogColumns, joints: Option<usize>) -> Result<Self, TableError> {
        let header = header_names(path)?;
        let present = joints_in(&header, columns);
        let n = present.iter().enumerate().take_while(|(k, &j)| j == k + 1).count();
        if n == 0 {
            return Err(table_error(
                path,
                Some(1),
                format!(
                    "no joint has all of its columns {}, {}, {} (with {{i}} = 1, 2, …); the header has: {}",
                    columns.q,
                    columns.qd,
                    columns.tau,
                    header.join(", ")
                ),
            ));
        }
        if let Some(want) = joints.filter(|&w| w != n) {
            return Err(table_error(path, Some(1), format!("the log has {n} joints' columns, the arm has {want}")));
        }
        let names: Vec<[String; 3]> = (1..=n)
            .map(|i| [LogColumns::name(&columns.q, i), LogColumns::name(&columns.qd, i), LogColumns::name(&columns.tau, i)])
            .collect();
        let mut wanted: Vec<&str> = vec![&columns.time];
        wanted.extend(names.iter().flat_map(|c| c.iter().map(String::as_str)));
        let table = NumericTable::read_only(path, &wanted)?;
        table.require_increasing(&columns.time)?;
        let take = |n: &str| table.column(n).expect("read").to_vec();
        Ok(Self {
            path: path.to_path_buf(),
            time: take(&columns.time),
            joints: (1..=n).collect(),
            q: names.iter().map(|c| take(&c[0])).collect(),
            qd: names.iter().map(|c| take(&c[1])).collect(),
            tau: names.iter().map(|c| take(&c[2])).collect(),
            lines: table.lines.clone(),
        })
    }

    /// Where joint `joint` (from 1) is in the columns read, or an error naming the joints read.
    pub fn joint_index(&self, joint: usize) -> Result<usize, TableError> {
        self.joints
            .iter()
            .position(|&j| j == joint)
            .ok_or_else(|| table_error(&self.path, None, format!("joint {joint} is not in the log (joints read: {})", list(&self.joints))))
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.time.len()
    }
}

/// The joint numbers whose three columns all appear in `header`, increasing.
fn joints_in(header: &[String], columns: &LogColumns) -> Vec<usize> {
    (1..=header.len())
        .filter(|&i| [&columns.q, &columns.qd, &columns.tau].iter().all(|p| header.contains(&LogColumns::name(p, i))))
        .collect()
}

fn list(joints: &[usize]) -> String {
    joints.iter().map(|j| j.to_string()).collect::<Vec<_>>().join(", ")
}

fn table_error(path: &Path, line: Option<u64>, message: String) -> TableError {
    TableError { path: path.to_path_buf(), line, column: None, message }
}

/// The header's column names (units stripped).
fn header_names(path: &Path) -> Result<Vec<String>, TableError> {
    let mut reader = crate::table::csv_reader(path).map_err(|e| table_error(path, None, format!("cannot open: {e}")))?;
    let header = reader.headers().map_err(|e| table_error(path, Some(1), format!("cannot read the header: {e}")))?;
    Ok(header.iter().map(|c| crate::table::split_unit(c).0).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn level(time: &[f64], speed: &[f64], torque: &[f64]) -> FrictionIdentification {
        identify_levels(&[Level { time, speed, torque, line: 2 }], &FrictionOptions::default())
    }

    #[test]
    fn a_level_is_steady_only_once_its_approach_has_died_out() {
        // v(t) = 1 − e^(−t/T), T = 0.5 s: after 1 s the window still drifts, after 5 s it does not.
        let (dt, tc) = (1e-3, 0.5);
        for (duration, verdict) in [(1.0, Verdict::Drifting), (5.0, Verdict::Kept)] {
            let time: Vec<f64> = (0..=(duration / dt) as usize).map(|k| k as f64 * dt).collect();
            let speed: Vec<f64> = time.iter().map(|t| 1.0 - (-t / tc).exp()).collect();
            let found = level(&time, &speed, &vec![1.5; time.len()]);
            assert_eq!(found.levels[0].verdict, verdict, "{:?}", found.levels[0]);
        }
        // Noise alone (±0.02 rad/s, deterministic) does not reject a steady level; too short is.
        let time: Vec<f64> = (0..2000).map(|k| k as f64 * 1e-3).collect();
        let speed: Vec<f64> = (0..2000).map(|k| 0.8 + 0.02 * ((k * 7919 % 1000) as f64 / 500.0 - 1.0)).collect();
        assert_eq!(level(&time, &speed, &vec![1.0; 2000]).levels[0].verdict, Verdict::Kept);
        assert_eq!(level(&time[..100], &speed[..100], &[1.0; 100]).levels[0].verdict, Verdict::TooShort);
        assert_eq!(level(&time, &vec![-0.5; 2000], &vec![1.0; 2000]).levels[0].verdict, Verdict::AgainstTorque);
        // Stick-slip: a speed that jumps between 0.2 and 1.4 rad/s.
        let jumpy: Vec<f64> = (0..2000).map(|k| if (k / 50) % 2 == 0 { 0.2 } else { 1.4 }).collect();
        assert_eq!(level(&time, &jumpy, &vec![1.0; 2000]).levels[0].verdict, Verdict::Spread);
    }

    #[test]
    fn pairs_are_binned_levels_and_the_pair_at_rest_is_the_breakaway_midpoint() {
        let time: Vec<f64> = (0..1000).map(|k| k as f64 * 1e-3).collect();
        let make = |v: f64| vec![v; 1000];
        // Probes at rest: +0.5, +0.9, −0.4, −0.7 N·m; +1.0 moves; levels at 0.51 and 0.52 rad/s
        // share a bin; −0.3 rad/s at −1.1 N·m.
        let data = [(0.0, 0.5), (0.0, 0.9), (0.6, 1.0), (0.51, 1.2), (0.52, 1.3), (0.0, -0.4), (0.0, -0.7), (-0.3, -1.1)];
        let (speeds, torques): (Vec<Vec<f64>>, Vec<Vec<f64>>) = data.iter().map(|&(v, t)| (make(v), make(t))).unzip();
        let levels: Vec<Level<'_>> =
            speeds.iter().zip(&torques).map(|(s, t)| Level { time: &time, speed: s, torque: t, line: 0 }).collect();
        let found = identify_levels(&levels, &FrictionOptions::default());
        let rest = found.rest.unwrap();
        assert!((rest.positive_nm - 0.9).abs() < 1e-12 && (rest.negative_nm + 0.7).abs() < 1e-12 && rest.levels == 4, "{rest:?}");
        assert!((rest.torque_nm - 0.1).abs() < 1e-12);
        let pairs: Vec<(f64, f64)> = found.pairs.iter().map(|p| (p.0, p.1)).collect();
        assert_eq!(pairs.len(), 4, "{pairs:?}");
        assert!((pairs[0].0 + 0.3).abs() < 1e-12 && (pairs[0].1 + 1.1).abs() < 1e-12);
        assert_eq!(pairs[1], (0.0, rest.torque_nm));
        assert!((pairs[2].0 - 0.515).abs() < 1e-12 && (pairs[2].1 - 1.25).abs() < 1e-12, "{pairs:?}");
        assert!((pairs[3].0 - 0.6).abs() < 1e-12);
    }

    #[test]
    fn torque_levels_split_where_the_torque_changes() {
        assert_eq!(torque_levels(&[1.0, 1.0, 2.0, 2.0, 2.0, 0.0], 1e-9), vec![0..2, 2..5, 5..6]);
        assert_eq!(torque_levels(&[], 0.0), Vec::<std::ops::Range<usize>>::new());
    }

    /// A synthetic gravity log of one joint: up through `pose` and down again at 0.25 rad/s,
    /// torque = 3 cos q + 0.5 sign(q̇) + 0.1 (a friction that differs with the direction: the
    /// plain average keeps 0.1).
    fn passes(pose: f64, up: bool, down: bool, start: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        let (mut t, mut q, mut qd, mut tau) = (vec![], vec![], vec![], vec![]);
        let dt = 1e-3;
        let mut now = start;
        for (go, sign) in [(up, 1.0), (down, -1.0)] {
            for k in 0..2000 {
                // Rest for 0.3 s (the controller catching up), then the pass.
                let moving = go && k >= 300;
                let angle = pose - sign * 0.25 + if moving { sign * 0.25 * (k - 300) as f64 * dt / 0.85 * 0.85 } else { 0.0 };
                t.push(now);
                q.push(angle);
                qd.push(if moving { sign * 0.25 } else { 0.0 });
                tau.push(3.0 * angle.cos() + if moving { 0.5 * sign + 0.1 } else { 0.0 });
                now += dt;
            }
        }
        (t, q, qd, tau)
    }

    fn log_of(parts: &[(f64, bool, bool)]) -> RobotLog {
        let mut log = RobotLog {
            path: "synthetic.csv".into(),
            time: vec![],
            joints: vec![1],
            q: vec![vec![]],
            qd: vec![vec![]],
            tau: vec![vec![]],
            lines: vec![],
        };
        for &(pose, up, down) in parts {
            let start = log.time.last().map_or(0.0, |t| t + 1e-3);
            let (t, q, qd, tau) = passes(pose, up, down, start);
            log.time.extend(t);
            log.q[0].extend(q);
            log.qd[0].extend(qd);
            log.tau[0].extend(tau);
        }
        log.lines = (2..2 + log.time.len() as u64).collect();
        log
    }

    #[test]
    fn gravity_passes_are_paired_through_common_angles_and_one_way_poses_refused() {
        let log = log_of(&[(0.3, true, true), (1.2, true, false), (2.0, true, true)]);
        let curve = [FrictionCurve::new(&[(-0.3, -0.4, 1), (0.0, 0.0, 1), (0.3, 0.6, 1)])];
        let found = identify_gravity_log(&log, &GravityOptions::default(), &GravityCorrection { friction: &curve, model: None }).unwrap();
        assert_eq!(found.pairs.len(), 2, "{:?}", found.poses);
        assert_eq!(found.poses.iter().filter(|p| p.refused.as_deref().is_some_and(|r| r.contains("passed up only"))).count(), 1);
        for (pair, pose) in found.pairs.iter().zip([0.3, 2.0]) {
            // The windows are centred on the pose. The plain average keeps the even part of the
            // friction, 0.1 N·m (to 2e-3: the mean of cos over the ±0.0625 rad window is not cos
            // of the mean). The corrected one has the curve's mean at ±0.25 rad/s taken out:
            // (0.5 − 1/3)/2.
            assert!((pair.q[0] - pose).abs() < 5e-3, "{pair:?}");
            let truth = 3.0 * pair.q[0].cos();
            assert!((pair.torque_uncorrected[0] - truth - 0.1).abs() < 5e-3, "{pair:?} vs {truth}");
            let taken_out = 0.5 * (curve[0].torque(0.25) + curve[0].torque(-0.25));
            assert!((pair.torque_uncorrected[0] - pair.torque[0] - taken_out).abs() < 1e-9, "{pair:?}");
        }
    }
}
