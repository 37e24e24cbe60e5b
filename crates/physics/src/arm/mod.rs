//! The planar n-R arm: parameters, kinematics, rigid-body dynamics, friction, a fixed-step
//! integrator with stick–slip, and hardware-like measurement effects.
//!
//! Plain functions over plain data: nothing here knows about FMI, files or the command line.

pub mod drift;
pub mod dynamics;
pub mod friction;
pub mod hardware;
pub mod integrator;
pub mod kinematics;
pub mod params;

pub use drift::{OperatingChange, MAX_FRICTION_SCALE};
pub use dynamics::{
    coriolis_centrifugal, coriolis_centrifugal_into, coriolis_matrix, coriolis_matrix_into, coriolis_of_one_joint_into, gravity_torques,
    gravity_torques_into, inverse_dynamics, inverse_dynamics_into, inverse_dynamics_rnea, inverse_dynamics_rnea_into, kinetic_energy,
    kinetic_energy_with, largest_viscous_rate, mass_matrix, mass_matrix_into, potential_energy, ArmData,
};
pub use friction::{FrictionBranch, JointFriction};
pub use hardware::{HardwareEffects, Sensors};
pub use integrator::{max_substeps, ArmSimulator, ArmState, IntegratorSettings, StepError, MAX_STEP_WORK};
pub use kinematics::{end_effector_position, end_effector_state, end_effector_velocity, jacobian, jacobian_dot_qd, jacobian_into};
pub use params::{check_joint_count, limits, show_number, ArmParams, LinkParams, ParamError, MAX_JOINTS};
