//! Two-layer networks (tansig hidden layer, linear output), their Levenberg–Marquardt
//! trainer, and the versioned weights file that carries a trained net with its names, units,
//! scaling and training record.

pub mod encoding;
pub mod lm;
pub mod mlp;
pub mod weights;

pub use encoding::{EncodedNet, InputEncoding};
pub use lm::{train, EpochInfo, StopReason, TrainReport, TrainSettings, Trained};
pub use mlp::{MinMaxScaling, Mlp};
pub use weights::{read_limits, NetKind, Signal, WeightsError, WeightsFile};
