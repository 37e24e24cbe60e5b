//! Helpers the workspace's tests share, so that no test reaches into another crate's files:
//!
//! - [`allocations`]: a global allocator that counts a thread's allocations, installed in every
//!   test binary that uses it, for the tests that a step allocates nothing;
//! - [`nets`]: small nets with fixed weights for the compensator's tests.

pub mod allocations;
pub mod nets;
