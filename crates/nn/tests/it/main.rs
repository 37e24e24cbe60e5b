//! The nets' integration tests.

mod limits;
mod nn;
mod step_allocations;
