//! neurarm: learn robot-joint dynamics with neural networks and ship them as FMI 2.0 and FMI 3.0
//! Co-Simulation components.
//!
//! This is the application: the paper's experiments ([`experiments`]), the report and plots
//! ([`report`]), identification from a robot's logs ([`identify`], [`logs`]) and the plans that
//! record them ([`plan`]), CSV tables ([`table`]), where outputs go ([`output`]), open-loop
//! simulation ([`simulate`]), system files run through the master ([`system_run`]) and FMU
//! export ([`export`]). It stands on the workspace's crates: `neurarm-physics` (arm,
//! networks, control), `neurarm-models` (the models behind the FMUs), `neurarm-fmi-export`
//! (the FMI 2.0 and 3.0 export layer), `neurarm-fmu` (the one binary every
//! FMU carries, for both versions) and `neurarm-cosim` (the co-simulation master).

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
