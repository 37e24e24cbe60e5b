//! Reading a text input with a bound on its size ([`read_text`], shared with `neurarm-nn`,
//! which reads weights files with it), and the bound of a configuration file.

pub use neurarm_nn::text::read_text;

/// Largest configuration or spec file read [bytes]: a 64-joint arm's configuration is under
/// 100 kB.
pub const MAX_CONFIG_BYTES: u64 = 4 << 20;
