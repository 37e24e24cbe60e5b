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
    pub fn parse(text: &str) -> Result<Self, UnknownNetKind> {
        match text.trim() {
            "unspecified" => Ok(NetKind::Unspecified),
            "friction" => Ok(NetKind::Friction),
            "gravity" => Ok(NetKind::Gravity),
            other => Err(UnknownNetKind { text: other.into() }),
        }
    }
}

/// A name that is no [`NetKind::name`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown net kind '{text}': use friction, gravity or unspecified")]
pub struct UnknownNetKind {
    /// The name given (trimmed).
    pub text: String,
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

/// Why a weights file cannot be used. The message is the file's name and what is wrong; the
/// error inside is shown in it, so it is not also given as [`std::error::Error::source`] (a
/// report of the chain would say it twice).
#[derive(Debug, thiserror::Error)]
pub enum WeightsError {
    /// The file could not be read.
    #[error("{path}: {error}")]
    Io {
        /// The file.
        path: String,
        /// Why.
        error: std::io::Error,
    },
    /// The file is not the JSON of a weights file.
    #[error("{path}: {error}")]
    Parse {
        /// The file.
        path: String,
        /// Where and why the JSON does not parse.
        error: serde_json::Error,
    },
    /// The file parses but holds no usable net.
    #[error("{path}: {error}")]
    Invalid {
        /// The file.
        path: String,
        /// What is wrong.
        error: NetError,
    },
}

/// Why a weights file holds no usable net ([`WeightsFile::network`]).
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum NetError {
    /// `format` is not [`FORMAT`].
    #[error("format is '{format}', expected '{FORMAT}'")]
    Format {
        /// The format the file gives.
        format: String,
    },
    /// A version this build does not read.
    #[error("version {version} is not supported (this build reads versions 1 to {VERSION})")]
    Version {
        /// The version the file gives.
        version: u32,
    },
    /// A version 1 file with an encoding (they came with version 2).
    #[error("a version 1 file has raw inputs only, not the '{}' encoding", encoding.name())]
    EncodingBeforeVersion2 {
        /// The encoding the file gives.
        encoding: InputEncoding,
    },
    /// A kind or a joint in a file before version 3.
    #[error("a version {version} file records no kind or joint (they came with version 3)")]
    KindBeforeVersion3 {
        /// The version the file gives.
        version: u32,
    },
    /// No inputs.
    #[error("empty network: 0 inputs")]
    NoInputs,
    /// A friction net without its joint.
    #[error("a friction net must name its joint (\"joint\": 1, 2, …)")]
    FrictionWithoutJoint,
    /// Joint 0.
    #[error("joint 0: joints are numbered from 1")]
    JointZero,
    /// A friction net of other than one input and one output.
    #[error("a friction net has 1 input (velocity) and 1 output (torque), not {inputs} and {outputs}")]
    FrictionSignals {
        /// Its inputs.
        inputs: usize,
        /// Its outputs.
        outputs: usize,
    },
    /// A friction net's input encoded as angles.
    #[error("a friction net takes the velocity raw or as '{}', not encoded as '{}'", InputEncoding::LogSpeed.name(), encoding.name())]
    FrictionEncoding {
        /// The encoding the file gives.
        encoding: InputEncoding,
    },
    /// A gravity net's inputs encoded as speeds.
    #[error("a gravity net takes angles, not speeds encoded as '{}'", encoding.name())]
    GravityEncoding {
        /// The encoding the file gives.
        encoding: InputEncoding,
    },
    /// A gravity net of not one output per input.
    #[error("a gravity net has one output per angle input, not {inputs} inputs and {outputs} outputs")]
    GravitySignals {
        /// Its inputs.
        inputs: usize,
        /// Its outputs.
        outputs: usize,
    },
    /// A joint named by a net other than a friction net.
    #[error("only a friction net names a joint; this {} names joint {joint}", kind.name())]
    JointOfOtherKind {
        /// The net's kind.
        kind: NetKind,
        /// The joint it names.
        joint: usize,
    },
    /// No hidden neurons or no outputs.
    #[error("empty network: {hidden} hidden neurons, {outputs} outputs")]
    Empty {
        /// Hidden neurons.
        hidden: usize,
        /// Outputs.
        outputs: usize,
    },
    /// More inputs or outputs than [`read_limits::SIGNALS`].
    #[error("{inputs} inputs and {outputs} outputs: a net may have at most {} of each (read_limits::SIGNALS)", read_limits::SIGNALS)]
    TooManySignals {
        /// Inputs.
        inputs: usize,
        /// Outputs.
        outputs: usize,
    },
    /// More hidden neurons than [`read_limits::HIDDEN`].
    #[error("{hidden} hidden neurons: a net may have at most {} (read_limits::HIDDEN)", read_limits::HIDDEN)]
    TooManyHidden {
        /// Hidden neurons.
        hidden: usize,
    },
    /// More weights and biases than [`read_limits::WEIGHTS`].
    #[error("{weights} weights and biases: a net may have at most {} (read_limits::WEIGHTS)", read_limits::WEIGHTS)]
    TooManyWeights {
        /// Weights and biases.
        weights: usize,
    },
    /// A weight matrix (`iw`, `lw`) of the wrong number of rows.
    #[error("{layer} has {rows} rows, expected {expected}")]
    Rows {
        /// `iw` or `lw`.
        layer: &'static str,
        /// Rows in the file.
        rows: usize,
        /// Rows the sizes of the net need.
        expected: usize,
    },
    /// A row of a weight matrix of the wrong length.
    #[error("{layer} row {row} has {values} values, expected {expected}")]
    RowLength {
        /// `iw` or `lw`.
        layer: &'static str,
        /// The row (0-based).
        row: usize,
        /// Values in the row.
        values: usize,
        /// Values the sizes of the net need.
        expected: usize,
    },
    /// Output biases of the wrong number.
    #[error("b2 has {values} values, expected {expected}")]
    OutputBiases {
        /// Values in the file.
        values: usize,
        /// One per output.
        expected: usize,
    },
    /// A scaling of the wrong length.
    #[error("{scaling} has {min}/{max} min/max values, expected {expected}")]
    ScalingLength {
        /// `input_scaling` or `output_scaling`.
        scaling: &'static str,
        /// Values of `min`.
        min: usize,
        /// Values of `max`.
        max: usize,
        /// One per encoded input or per output.
        expected: usize,
    },
    /// A scaling row whose min is not at most its max.
    #[error("{scaling} row {row}: min {min} is not <= max {max}")]
    ScalingOrder {
        /// `input_scaling` or `output_scaling`.
        scaling: &'static str,
        /// The row (0-based).
        row: usize,
        /// Its min.
        min: f64,
        /// Its max.
        max: f64,
    },
    /// A weight, bias or scaling bound that is NaN or infinite.
    #[error("a weight or scaling value is {value}, not a finite number")]
    NotFinite {
        /// The value.
        value: f64,
    },
    /// A weight or bias beyond [`read_limits::WEIGHT`].
    #[error("a weight or bias is {}: beyond ±1e8 (read_limits::WEIGHT) no trained net has them", show_number(*value))]
    WeightTooLarge {
        /// The value.
        value: f64,
    },
    /// A scaling bound beyond [`read_limits::SCALING`].
    #[error("a scaling bound is {}: beyond ±1e15 (read_limits::SCALING)", show_number(*value))]
    ScalingTooLarge {
        /// The value.
        value: f64,
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
    pub fn network(&self) -> Result<EncodedNet, NetError> {
        self.check_version()?;
        self.check_kind()?;
        let (n, h, k) = self.check_sizes()?;
        self.check_values()?;
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

    /// The format, and the version with the fields it has.
    fn check_version(&self) -> Result<(), NetError> {
        if self.format != FORMAT {
            return Err(NetError::Format { format: self.format.clone() });
        }
        if !(1..=VERSION).contains(&self.version) {
            return Err(NetError::Version { version: self.version });
        }
        if self.version == 1 && self.encoding != InputEncoding::Raw {
            return Err(NetError::EncodingBeforeVersion2 { encoding: self.encoding });
        }
        if self.version < 3 && (self.kind != NetKind::Unspecified || self.joint.is_some()) {
            return Err(NetError::KindBeforeVersion3 { version: self.version });
        }
        Ok(())
    }

    /// Inputs there, and the signals, encoding and joint the kind asks for.
    fn check_kind(&self) -> Result<(), NetError> {
        if self.inputs.is_empty() {
            return Err(NetError::NoInputs);
        }
        let (inputs, outputs) = (self.inputs.len(), self.outputs.len());
        match (self.kind, self.joint) {
            (NetKind::Friction, None) => Err(NetError::FrictionWithoutJoint),
            (NetKind::Friction, Some(0)) => Err(NetError::JointZero),
            (NetKind::Friction, Some(_)) if inputs != 1 || outputs != 1 => Err(NetError::FrictionSignals { inputs, outputs }),
            (NetKind::Friction, Some(_)) if !matches!(self.encoding, InputEncoding::Raw | InputEncoding::LogSpeed) => {
                Err(NetError::FrictionEncoding { encoding: self.encoding })
            }
            (NetKind::Gravity, _) if !self.encoding.is_of_angles() => Err(NetError::GravityEncoding { encoding: self.encoding }),
            (NetKind::Gravity, _) if inputs != outputs => Err(NetError::GravitySignals { inputs, outputs }),
            (NetKind::Gravity | NetKind::Unspecified, Some(joint)) => Err(NetError::JointOfOtherKind { kind: self.kind, joint }),
            _ => Ok(()),
        }
    }

    /// The net's sizes (N encoded inputs, H hidden neurons, K outputs) within
    /// [`read_limits`], and every layer and scaling of them.
    fn check_sizes(&self) -> Result<(usize, usize, usize), NetError> {
        let (n, h, k) = (self.encoding.features(self.inputs.len()), self.b1.len(), self.outputs.len());
        if h == 0 || k == 0 {
            return Err(NetError::Empty { hidden: h, outputs: k });
        }
        if self.inputs.len() > read_limits::SIGNALS || k > read_limits::SIGNALS {
            return Err(NetError::TooManySignals { inputs: self.inputs.len(), outputs: k });
        }
        if h > read_limits::HIDDEN {
            return Err(NetError::TooManyHidden { hidden: h });
        }
        let weights = h * (n + 1) + k * (h + 1);
        if weights > read_limits::WEIGHTS {
            return Err(NetError::TooManyWeights { weights });
        }
        check_shape("iw", &self.iw, h, n)?;
        check_shape("lw", &self.lw, k, h)?;
        if self.b2.len() != k {
            return Err(NetError::OutputBiases { values: self.b2.len(), expected: k });
        }
        for (scaling, s, len) in [("input_scaling", &self.input_scaling, n), ("output_scaling", &self.output_scaling, k)] {
            if s.min.len() != len || s.max.len() != len {
                return Err(NetError::ScalingLength { scaling, min: s.min.len(), max: s.max.len(), expected: len });
            }
            if let Some(row) = (0..len).find(|&i| !(s.min[i] <= s.max[i])) {
                return Err(NetError::ScalingOrder { scaling, row, min: s.min[row], max: s.max[row] });
            }
        }
        Ok((n, h, k))
    }

    /// Every weight, bias and scaling bound finite and within [`read_limits`].
    fn check_values(&self) -> Result<(), NetError> {
        let all = self.iw.iter().flatten().chain(&self.b1).chain(self.lw.iter().flatten()).chain(&self.b2);
        let scalings = [&self.input_scaling, &self.output_scaling].into_iter().flat_map(|s| s.min.iter().chain(&s.max));
        if let Some(&value) = all.clone().chain(scalings.clone()).find(|v| !v.is_finite()) {
            return Err(NetError::NotFinite { value });
        }
        if let Some(value) = all.copied().find(|v| !(v.abs() <= read_limits::WEIGHT)) {
            return Err(NetError::WeightTooLarge { value });
        }
        if let Some(value) = scalings.copied().find(|v| !(v.abs() <= read_limits::SCALING)) {
            return Err(NetError::ScalingTooLarge { value });
        }
        Ok(())
    }

    /// Parses JSON text; `path` names the source in messages.
    pub fn from_json(text: &str, path: &str) -> Result<Self, WeightsError> {
        let file: Self = serde_json::from_str(text).map_err(|error| WeightsError::Parse { path: path.into(), error })?;
        file.network().map_err(|error| WeightsError::Invalid { path: path.into(), error })?;
        Ok(file)
    }

    /// Reads and checks a weights file.
    pub fn read(path: &Path) -> Result<Self, WeightsError> {
        let shown = path.display().to_string();
        let text = read_text(path, read_limits::FILE_BYTES).map_err(|error| WeightsError::Io { path: shown.clone(), error })?;
        Self::from_json(&text, &shown)
    }

    /// The file as pretty JSON; floats round-trip exactly.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).expect("weights serialise to JSON")
    }
}

/// Checks that the weight matrix `layer` (rows of values) has `rows` rows of `columns` values.
fn check_shape(layer: &'static str, matrix: &[Vec<f64>], rows: usize, columns: usize) -> Result<(), NetError> {
    if matrix.len() != rows {
        return Err(NetError::Rows { layer, rows: matrix.len(), expected: rows });
    }
    match matrix.iter().position(|row| row.len() != columns) {
        Some(row) => Err(NetError::RowLength { layer, row, values: matrix[row].len(), expected: columns }),
        None => Ok(()),
    }
}
