//! Two-layer networks (tansig hidden layer, linear output), their Levenberg–Marquardt
//! trainer, and the versioned weights file that carries a trained net with its names, units,
//! scaling and training record; after Petrič & Žlajpah, *Application of neural networks for
//! dynamic modeling of robotic mechanisms*. Nothing here knows about robot arms: the nets map
//! columns of numbers to columns of numbers.
//!
//! Beside the nets: the thread pool the trainer runs on ([`parallel`]), its dense linear
//! algebra ([`linalg`]), and two text helpers that `neurarm-physics` shares ([`text`]).
//!
//! Unsafe code is confined to [`parallel`] (a slice written by several threads in disjoint
//! parts, the pool's task pointer) and the GEMM calls of [`linalg`] and the trainer; every
//! `unsafe` block says why it is sound in a `// SAFETY:` comment.

#![deny(clippy::undocumented_unsafe_blocks)]

pub mod encoding;
pub mod linalg;
pub mod lm;
pub mod mlp;
pub mod parallel;
pub mod text;
pub mod weights;

pub use encoding::{EncodedNet, InputEncoding, UnknownEncoding};
pub use lm::{train, EpochInfo, StopReason, TrainReport, TrainSettings, Trained};
pub use mlp::{MinMaxScaling, Mlp};
pub use weights::{read_limits, NetError, NetKind, Signal, UnknownNetKind, WeightsError, WeightsFile};
