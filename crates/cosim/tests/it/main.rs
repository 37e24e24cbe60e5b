//! The master's integration tests, over the test FMUs and the van der Pol example.

mod fmi3;
mod shared_binaries;
mod standard;
mod step_allocations;
mod system;
