//! The models' integration tests.

mod adaptive;
mod drift;
mod step_allocations;
mod task_space;
