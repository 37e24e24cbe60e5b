//! The app's integration tests: the CLI, the master over neurarm's FMUs, SSP, logs, the committed
//! modelDescription files. The slow tier (whole paper runs, the arm family) is `tests/slow`.

mod cli;
mod cli_inputs;
mod cli_logs;
mod cli_output;
mod cli_system;
mod cli_train;
mod export_loops;
mod friction_levels;
mod intent;
mod logs;
mod master;
mod model_description;
mod ssp;
