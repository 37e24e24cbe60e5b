//! The physics' integration tests: dynamics against Pinocchio's values and a second formulation,
//! friction, control, limits, allocation-free steps.

mod control;
mod dynamics;
mod friction;
mod limits;
mod step_allocations;
