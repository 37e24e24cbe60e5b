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
    pub fn check(&self) -> Result<(), String> {
        for (what, p) in [("angle", &self.q), ("speed", &self.qd), ("torque", &self.tau)] {
            if !p.contains("{i}") {
                return Err(format!("the {what} column pattern '{p}' has no {{i}} for the joint number"));
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
    pub fn joint_index(&self, joint: usize) -> Result<usize, String> {
        self.joints
            .iter()
            .position(|&j| j == joint)
            .ok_or_else(|| format!("{}: joint {joint} is not in the log (joints read: {})", self.path.display(), list(&self.joints)))
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
