//! A co-simulation master for FMI 2.0 and FMI 3.0 Co-Simulation FMUs, mixed in one system,
//! over the `fmi` crate.
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
//! what the FMU itself logged; reading an FMU ([`FmuFileError`]) and a system file
//! ([`SystemFileError`]) have errors of their own ([`error`]).
//!
//! System files ([`SystemSpec`], TOML) describe the same: `[[fmu]]` entries, `[[connection]]`
//! entries and a `[simulation]` table; [`run`] runs one and keeps the rows recorded before a
//! failure.
//!
//! # Example
//!
//! Two oscillators `ẍ = μ (1 − x²) ẋ − x + u` (the Van der Pol FMU of this workspace's
//! examples), with μ = 0 and each forced by the other's position: ẍ_a = x_b − x_a,
//! ẍ_b = x_a − x_b. From x_a = 1, x_b = 0 at rest, x_a = (1 + cos √2 t)/2 exactly; the master
//! passes values at communication points only, so it is that to first order in the step.
//!
//! ```
//! use neurarm_cosim::{Algorithm, SimulationSpec, System, Value};
//!
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! # let dir = tempfile::tempdir()?;
//! # let fmu = van_der_pol::package::fmu_in(dir.path())?;
//! let mut system = System::new();
//! system.add_fmu("a", &fmu)?.add_fmu("b", &fmu)?;
//! for (unit, x0) in [("a", 1.0), ("b", 0.0)] {
//!     system.set(unit, "mu", Value::Real(0.0))?.set(unit, "x0", Value::Real(x0))?;
//! }
//! system.connect("a.x", "b.u")?.connect("b.x", "a.u")?;
//!
//! // Checked before anything is loaded: a mistake names the unit and the variable.
//! let e = system.connect("a.position", "b.u").unwrap_err();
//! assert_eq!((e.unit.as_deref(), e.variable.as_deref()), (Some("a"), Some("position")));
//! let e = system.set("a", "x", Value::Real(0.0)).unwrap_err();
//! assert!(e.to_string().contains("an output cannot be set"), "{e}");
//!
//! // The same system, simulated...
//! let record = vec!["a.x".to_owned(), "b.x".to_owned()];
//! let mut sim = system.clone().initialize(0.0, 1e-3, Algorithm::GaussSeidel, &record)?;
//! assert_eq!(sim.run_until(10.0)?, neurarm_cosim::RunEnd::Completed);
//! let last = sim.rows().last().unwrap();
//! let exact = (1.0 + (2f64.sqrt() * 10.0).cos()) / 2.0;
//! assert!((last[1] - exact).abs() < 5e-3, "x_a(10) = {} vs {exact}", last[1]);
//! assert!((last[1] + last[2] - 1.0).abs() < 5e-3, "x_a + x_b stays 1");
//!
//! // ...and written as an SSP 1.0 archive for other engines.
//! let simulation = SimulationSpec { start: 0.0, stop: 10.0, step: 1e-3, algorithm: Algorithm::GaussSeidel, record, record_every: 1, on_discard: neurarm_cosim::OnDiscard::Stop };
//! neurarm_cosim::ssp::write_system(&system, &simulation, &dir.path().join("pair.ssp"))?;
//! # Ok(())
//! # }
//! ```

#![forbid(unsafe_code)]

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

pub use error::{DescriptionError, DiscardedStep, FmuFileError, FmuProblem, MasterError, SpecError, SystemFileError};
pub use interface::{BaseType, Causality, EnumerationInfo, FmiVersion, Initial, Interface, Variability, VariableInfo};
pub use recording::{run, Rows, RunOutcome};
pub use simulation::{Handle, RunEnd, Simulation};
pub use spec::{Algorithm, ConnectionSpec, EventSpec, FmuEntry, OnDiscard, SimulationSpec, SystemSpec, Value};
pub use system::{expand_connection, Link, Setting, System, UnitPlan};
