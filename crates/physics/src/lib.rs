//! The physics of neurarm, with no FMI, files of the FMU layer or command line in it: the
//! planar n-R arm ([`arm`]: parameters, kinematics, dynamics, friction, integrator, sensors)
//! and the paper's control laws ([`control`]), after Petrič & Žlajpah, *Application of neural
//! networks for dynamic modeling of robotic mechanisms*. The networks and their trainer are
//! the crate `neurarm-nn`.
//!
//! Parameters are immutable plain data; algorithms are functions of the parameters, a data
//! struct with the scratch space (made once) and the state, writing into outputs the caller
//! owns, so nothing allocates inside a step. The functions that return a new vector or
//! matrix are thin conveniences over those.

#![forbid(unsafe_code)]

pub mod arm;
pub mod config;
pub mod control;
pub mod family;
pub mod linalg;
pub mod text_file;
