//! The weights file: JSON, versioned, with everything needed to use and to judge a net.

use std::path::Path;

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::encoding::{EncodedNet, InputEncoding};
use crate::lm::{TrainReport, TrainSettings};
use crate::mlp::{MinMaxScaling, Mlp};
use crate::text::{read_text, show_number};

/// Value of `format` in every weights file.
pub const FORMAT: &str = "neurarm-weights";
/// The version this build writes. Version 3 added `kind` and `joint`, version 2 `encoding`;
/// files of versions 1 and 2 are still read (their kind is [`NetKind::Unspecified`]).
pub const VERSION: u32 = 3;

/// Limits a weights file must keep to be read, so that a file that parses but holds no
/// usable net (a billion inputs, a weight of 1e308) is refused by name instead of exhausting
/// memory or turning every output into infinity. This trainer makes nets of at most
/// [`MAX_HIDDEN`](crate::lm::MAX_HIDDEN) neurons and [`MAX_WEIGHTS`](crate::lm::MAX_WEIGHTS)
/// weights; the limits leave room for nets trained elsewhere.
pub mod read_limits {
    /// Inputs and outputs of a net, each.
    pub const SIGNALS: usize = 1024;
    /// Hidden neurons.
    pub const HIDDEN: usize = 10_000;
    /// Weights and biases in all (one evaluation is about this many multiply-adds).
    pub const WEIGHTS: usize = 1_000_000;
    /// Magnitude of a weight or bias. The hidden layer sees inputs scaled to [-1, 1] and
    /// saturates (tanh) beyond a few units, so a trained net's weights stay many orders below.
    pub const WEIGHT: f64 = 1e8;
    /// Magnitude of a scaling bound (the range of a signal in its own unit).
    pub const SCALING: f64 = 1e15;
    /// Size of the file [bytes]: a net of [`WEIGHTS`] weights written as pretty JSON is about
    /// 30 MB.
    pub const FILE_BYTES: u64 = 64 << 20;
}

/// What a net computes, so that a compensator can check it is given the right nets in the
/// right places.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum NetKind {
    /// Not recorded (files before version 3, or trained on other data).
    #[default]
    Unspecified,
    /// One joint's friction torque [N·m] from that joint's velocity [rad/s].
    Friction,
    /// The gravity torques of all joints [N·m] from all joint angles [rad].
    Gravity,
}

impl NetKind {
    /// The name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            NetKind::Unspecified => "unspecified",
            NetKind::Friction => "friction",
            NetKind::Gravity => "gravity",
        }
    }

    /// Parses [`NetKind::name`].
    pub fn parse(text: &str) -> Result<Self, String> {
        match text.trim() {
            "unspecified" => Ok(NetKind::Unspecified),
            "friction" => Ok(NetKind::Friction),
            "gravity" => Ok(NetKind::Gravity),
            other => Err(format!("unknown net kind '{other}': use friction, gravity or unspecified")),
        }
    }
}

/// A named input or output with its unit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Signal {
    /// Name, e.g. `qd_1`.
    pub name: String,
    /// Unit, e.g. `rad/s`.
    pub unit: String,
}

/// A trained net as stored on disk.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WeightsFile {
    /// Always `neurarm-weights`.
    pub format: String,
    /// Format version.
    pub version: u32,
    /// The inputs, in order.
    pub inputs: Vec<Signal>,
    /// How the inputs are encoded before the first layer (absent in version 1: raw).
    #[serde(default)]
    pub encoding: InputEncoding,
    /// The outputs, in order.
    pub outputs: Vec<Signal>,
    /// What the net computes (absent before version 3: unspecified).
    #[serde(default)]
    pub kind: NetKind,
    /// The joint (1-based) of a friction net; none for other kinds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub joint: Option<usize>,
    /// Input weights, one row per hidden neuron and one value per encoded input.
    pub iw: Vec<Vec<f64>>,
    /// Hidden biases.
    pub b1: Vec<f64>,
    /// Layer weights, one row per output.
    pub lw: Vec<Vec<f64>>,
    /// Output biases.
    pub b2: Vec<f64>,
    /// Input scaling (mapminmax) of the encoded inputs.
    pub input_scaling: MinMaxScaling,
    /// Output scaling (mapminmax).
    pub output_scaling: MinMaxScaling,
    /// How it was trained.
    pub training: TrainSettings,
    /// How training went (errors in the outputs' units squared).
    pub report: TrainReport,
}

/// Why a weights file cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum WeightsError {
    /// The file could not be read or written.
    #[error("{path}: {message}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        message: String,
    },
    /// The file is not valid.
    #[error("{path}: {message}")]
    Invalid {
        /// The file.
        path: String,
        /// What is wrong.
        message: String,
    },
}

impl WeightsFile {
    /// Wraps a trained net with its signal names and training record; the inputs are raw
    /// (see [`WeightsFile::with_encoding`]).
    pub fn new(net: &Mlp, inputs: Vec<Signal>, outputs: Vec<Signal>, training: TrainSettings, report: TrainReport) -> Self {
        let rows = |m: &DMatrix<f64>| m.row_iter().map(|r| r.iter().copied().collect()).collect();
        Self {
            format: FORMAT.into(),
            version: VERSION,
            inputs,
            encoding: InputEncoding::Raw,
            outputs,
            kind: NetKind::Unspecified,
            joint: None,
            iw: rows(&net.iw),
            b1: net.b1.iter().copied().collect(),
            lw: rows(&net.lw),
            b2: net.b2.iter().copied().collect(),
            input_scaling: net.input_scaling.clone(),
            output_scaling: net.output_scaling.clone(),
            training,
            report,
        }
    }

    /// The same file for a net trained on inputs encoded by `encoding` (the net's first
    /// layer then has [`InputEncoding::features`] inputs).
    pub fn with_encoding(mut self, encoding: InputEncoding) -> Self {
        self.encoding = encoding;
        self
    }

    /// The same file marked as the friction net of `joint` (1-based).
    pub fn friction_of_joint(mut self, joint: usize) -> Self {
        self.kind = NetKind::Friction;
        self.joint = Some(joint);
        self
    }

    /// The same file marked as a gravity net.
    pub fn gravity(mut self) -> Self {
        self.kind = NetKind::Gravity;
        self.joint = None;
        self
    }

    /// What the file says it is, for messages: "friction net of joint 2", "gravity net", "net".
    pub fn describe(&self) -> String {
        match (self.kind, self.joint) {
            (NetKind::Friction, Some(j)) => format!("friction net of joint {j}"),
            (NetKind::Friction, None) => "friction net".into(),
            (NetKind::Gravity, _) => "gravity net".into(),
            (NetKind::Unspecified, _) => format!("net of unspecified kind ({} inputs, {} outputs)", self.inputs.len(), self.outputs.len()),
        }
    }

    /// Checks sizes, finiteness, version and kind; returns the network behind its encoding.
    pub fn network(&self) -> Result<EncodedNet, String> {
        if self.format != FORMAT {
            return Err(format!("format is '{}', expected '{FORMAT}'", self.format));
        }
        if !(1..=VERSION).contains(&self.version) {
            return Err(format!("version {} is not supported (this build reads versions 1 to {VERSION})", self.version));
        }
        if self.version == 1 && self.encoding != InputEncoding::Raw {
            return Err(format!("a version 1 file has raw inputs only, not the '{}' encoding", self.encoding.name()));
        }
        if self.version < 3 && (self.kind != NetKind::Unspecified || self.joint.is_some()) {
            return Err(format!("a version {} file records no kind or joint (they came with version 3)", self.version));
        }
        if self.inputs.is_empty() {
            return Err("empty network: 0 inputs".into());
        }
        match (self.kind, self.joint) {
            (NetKind::Friction, None) => return Err("a friction net must name its joint (\"joint\": 1, 2, …)".into()),
            (NetKind::Friction, Some(0)) => return Err("joint 0: joints are numbered from 1".into()),
            (NetKind::Friction, Some(_)) if self.inputs.len() != 1 || self.outputs.len() != 1 => {
                return Err(format!(
                    "a friction net has 1 input (velocity) and 1 output (torque), not {} and {}",
                    self.inputs.len(),
                    self.outputs.len()
                ))
            }
            (NetKind::Friction, Some(_)) if !matches!(self.encoding, InputEncoding::Raw | InputEncoding::LogSpeed) => {
                return Err(format!(
                    "a friction net takes the velocity raw or as '{}', not encoded as '{}'",
                    InputEncoding::LogSpeed.name(),
                    self.encoding.name()
                ))
            }
            (NetKind::Gravity, _) if !self.encoding.is_of_angles() => {
                return Err(format!("a gravity net takes angles, not speeds encoded as '{}'", self.encoding.name()))
            }
            (NetKind::Gravity, _) if self.inputs.len() != self.outputs.len() => {
                return Err(format!(
                    "a gravity net has one output per angle input, not {} inputs and {} outputs",
                    self.inputs.len(),
                    self.outputs.len()
                ))
            }
            (NetKind::Gravity | NetKind::Unspecified, Some(j)) => {
                return Err(format!("only a friction net names a joint; this {} names joint {j}", self.kind.name()))
            }
            _ => {}
        }
        let (n, h, k) = (self.encoding.features(self.inputs.len()), self.b1.len(), self.outputs.len());
        if h == 0 || k == 0 {
            return Err(format!("empty network: {h} hidden neurons, {k} outputs"));
        }
        if self.inputs.len() > read_limits::SIGNALS || k > read_limits::SIGNALS {
            return Err(format!(
                "{} inputs and {k} outputs: a net may have at most {} of each (read_limits::SIGNALS)",
                self.inputs.len(),
                read_limits::SIGNALS
            ));
        }
        if h > read_limits::HIDDEN {
            return Err(format!("{h} hidden neurons: a net may have at most {} (read_limits::HIDDEN)", read_limits::HIDDEN));
        }
        let weights = h * (n + 1) + k * (h + 1);
        if weights > read_limits::WEIGHTS {
            return Err(format!("{weights} weights and biases: a net may have at most {} (read_limits::WEIGHTS)", read_limits::WEIGHTS));
        }
        let shape = |name: &str, rows: &Vec<Vec<f64>>, r: usize, c: usize| -> Result<(), String> {
            if rows.len() != r {
                return Err(format!("{name} has {} rows, expected {r}", rows.len()));
            }
            match rows.iter().position(|row| row.len() != c) {
                Some(i) => Err(format!("{name} row {i} has {} values, expected {c}", rows[i].len())),
                None => Ok(()),
            }
        };
        shape("iw", &self.iw, h, n)?;
        shape("lw", &self.lw, k, h)?;
        if self.b2.len() != k {
            return Err(format!("b2 has {} values, expected {k}", self.b2.len()));
        }
        for (name, s, len) in [("input_scaling", &self.input_scaling, n), ("output_scaling", &self.output_scaling, k)] {
            if s.min.len() != len || s.max.len() != len {
                return Err(format!("{name} has {}/{} min/max values, expected {len}", s.min.len(), s.max.len()));
            }
            if let Some(i) = (0..len).find(|&i| !(s.min[i] <= s.max[i])) {
                return Err(format!("{name} row {i}: min {} is not <= max {}", s.min[i], s.max[i]));
            }
        }
        let all = self.iw.iter().flatten().chain(&self.b1).chain(self.lw.iter().flatten()).chain(&self.b2);
        let scalings = [&self.input_scaling, &self.output_scaling].into_iter().flat_map(|s| s.min.iter().chain(&s.max));
        if let Some(v) = all.clone().chain(scalings.clone()).find(|v| !v.is_finite()) {
            return Err(format!("a weight or scaling value is {v}, not a finite number"));
        }
        if let Some(v) = all.copied().find(|v| !(v.abs() <= read_limits::WEIGHT)) {
            return Err(format!("a weight or bias is {}: beyond ±1e8 (read_limits::WEIGHT) no trained net has them", show_number(v)));
        }
        if let Some(v) = scalings.copied().find(|v| !(v.abs() <= read_limits::SCALING)) {
            return Err(format!("a scaling bound is {}: beyond ±1e15 (read_limits::SCALING)", show_number(v)));
        }
        let mlp = Mlp {
            iw: DMatrix::from_fn(h, n, |j, i| self.iw[j][i]),
            b1: DVector::from_column_slice(&self.b1),
            lw: DMatrix::from_fn(k, h, |o, j| self.lw[o][j]),
            b2: DVector::from_column_slice(&self.b2),
            input_scaling: self.input_scaling.clone(),
            output_scaling: self.output_scaling.clone(),
        };
        Ok(EncodedNet { encoding: self.encoding, mlp })
    }

    /// Parses JSON text; `path` names the source in messages.
    pub fn from_json(text: &str, path: &str) -> Result<Self, WeightsError> {
        let file: Self = serde_json::from_str(text).map_err(|e| WeightsError::Invalid { path: path.into(), message: e.to_string() })?;
        file.network().map_err(|message| WeightsError::Invalid { path: path.into(), message })?;
        Ok(file)
    }

    /// Reads and checks a weights file.
    pub fn read(path: &Path) -> Result<Self, WeightsError> {
        let shown = path.display().to_string();
        let text =
            read_text(path, read_limits::FILE_BYTES).map_err(|e| WeightsError::Io { path: shown.clone(), message: e.to_string() })?;
        Self::from_json(&text, &shown)
    }

    /// The file as pretty JSON; floats round-trip exactly.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("weights serialise to JSON")
    }
}
