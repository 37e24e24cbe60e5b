//! neurarm: learn robot-joint dynamics with neural networks and ship them as FMI 2.0
//! components.
//!
//! This is the application: the paper's experiments ([`experiments`]), the report and
//! plots ([`report`]), CSV tables ([`table`]), where outputs go ([`output`]), open-loop
//! simulation ([`simulate`]) and FMU export ([`export`]), over the workspace's crates: `neurarm-physics` (arm, networks,
//! control), `neurarm-models` (the models behind the FMUs), `fmi2-export` (the FMI 2.0
//! export layer) and `neurarm-cosim` (the co-simulation master).

#![forbid(unsafe_code)]

pub mod experiments;
pub mod export;
pub mod identify;
pub mod logs;
pub mod output;
pub mod plan;
pub mod report;
pub mod simulate;
pub mod system_run;
pub mod table;
