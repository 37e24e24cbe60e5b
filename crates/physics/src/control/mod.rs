//! Control laws of the paper as plain functions of the arm model: task-space computed torque
//! for the redundant arm (pseudo-inverse with null-space damping) and joint-space P control
//! with gravity compensation. Nothing here knows about FMI; the controller FMUs wrap these.
//!
//! The task-space law runs in [`TaskSpaceData`], made once per arm: [`task_space_torque_into`]
//! allocates nothing. [`task_space_acceleration`] and [`computed_torque`] are conveniences
//! over the same code for one call.
//!
//! Files: `reference` (the paper's curve and where it sits), `inverse` (pseudo-inverse, damped
//! inverse, inverse kinematics), `gains`, `task_space` (the task-space law and computed torque),
//! `learning_signal` (the adaptive compensator's signal), `joint` (joint-space P control).

mod gains;
pub mod holds;
mod inverse;
mod joint;
mod learning_signal;
mod reference;
mod task_space;

pub use gains::{TaskSpaceGains, DEFAULT_NULL_DAMPING};
pub use inverse::{damped_inverse_into, inverse_kinematics, pseudo_inverse, pseudo_inverse_into, SINGULAR_MARGIN_SHARE};
pub use joint::joint_p_torque;
pub use learning_signal::{task_learning_signal_into, LearningSignalData};
pub use reference::{paper_reference, scaled_reference, workspace_hole, PlacementError, ReferencePlacement, TaskReference};
pub use task_space::{
    computed_torque, computed_torque_into, task_space_acceleration, task_space_acceleration_into, task_space_torque_into, wrapped_angle,
    TaskSpaceData,
};
