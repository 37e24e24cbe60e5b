//! The one FMI 2.0 Co-Simulation binary behind every neurarm FMU. Each `.fmu` ships a copy
//! named after its model identifier; `resources/neurarm.toml` says which model it holds.

fmi2_export::export_fmi2!(neurarm_models::instantiate);
