//! A co-simulation master for FMI 2.0 Co-Simulation FMUs, over the `fmi` crate.
//!
//! It loads `.fmu` files, sets parameters by name, connects outputs to inputs by name (with
//! `*` patterns), steps at a fixed communication step (Gauss–Seidel in dependency order, or
//! Jacobi) and records chosen variables. It knows nothing of what the FMUs model.
//!
//! A [`System`] is checked as it is built and before anything is instantiated: each FMU's
//! interface is read from its `modelDescription.xml` ([`interface`]), every value set is
//! checked against the variable's type and causality, every connection against the
//! outputs and inputs it joins. The same `System` is then simulated
//! ([`System::initialize`], [`Simulation`]) or written as an SSP 1.0 archive that other
//! engines read ([`ssp`]). Errors ([`MasterError`]) name the unit, the variable, the time and
//! what the FMU itself logged.
//!
//! System files ([`SystemSpec`], TOML) describe the same: `[[fmu]]` entries, `[[connection]]`
//! entries and a `[simulation]` table; [`run`] runs one and keeps the rows recorded before a
//! failure.

mod capture;
pub mod error;
pub mod interface;
mod recording;
mod schedule;
mod simulation;
pub mod spec;
pub mod ssp;
pub mod system;
mod unit;

pub use error::MasterError;
pub use interface::{BaseType, Causality, Interface, VariableInfo};
pub use recording::{run, RunOutcome};
pub use simulation::{Handle, Simulation};
pub use spec::{Algorithm, ConnectionSpec, FmuEntry, SimulationSpec, SystemSpec, Value};
pub use system::{expand_connection, Link, Setting, System, UnitPlan};
