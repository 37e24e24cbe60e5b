//! neurarm: learn robot-joint dynamics with neural networks and ship them as FMI 2.0 components.
//!
//! The crate implements Petrič & Žlajpah, *Application of neural networks for dynamic modeling
//! of robotic mechanisms*: a planar n-R arm ([`arm`]), and (in later modules) the networks that
//! learn its friction and gravity, the FMUs that carry both, and the closed loops that use them.

#![warn(missing_docs)]

pub mod arm;
pub mod config;
pub mod control;
pub mod fmi2;
pub mod linalg;
pub mod models;
pub mod nn;
#[cfg(feature = "app")]
pub mod simulate;
#[cfg(feature = "app")]
pub mod table;
#[cfg(feature = "app")]
pub mod master;
#[cfg(feature = "app")]
pub mod report;
#[cfg(feature = "app")]
pub mod experiments;
