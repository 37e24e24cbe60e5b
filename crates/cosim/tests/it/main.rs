//! The master's integration tests over the test FMUs. The tests over the van der Pol example
//! are a binary of their own (`tests/van_der_pol`): both FMU libraries export the `fmi2*`
//! symbols, and one binary cannot link both. `tests/shared_binaries` counts the libraries
//! mapped into its process, so no other test may run beside it.

mod fmi3;
mod standard;
mod step_allocations;
