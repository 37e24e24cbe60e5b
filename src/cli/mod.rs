//! The commands of the `neurarm` binary, one module each; `main.rs` parses the command line
//! and hands each command's arguments to its module's `run`. What several commands share
//! (argument groups, configuration loading, progress bars) is in [`common`].

pub mod common;
pub mod compensator;
pub mod default_config;
pub mod eval;
pub mod export;
pub mod identify;
pub mod paper;
pub mod plan;
pub mod random_arm;
pub mod simulate;
pub mod train;
