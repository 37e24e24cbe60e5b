//! Write FMI 3.0 Co-Simulation FMUs in Rust, from the same model as an FMI 2.0 one.
//!
//! A model implements fmi2-export's [`Model`](fmi2_export::Model) over one variable table
//! ([`TableBuilder`](fmi2_export::TableBuilder)); this crate adds what FMI 3.0 needs beside
//! it, and nothing of the rules:
//!
//! - the FMI 3.0 `modelDescription.xml` ([`description::to_xml`]): `Float64`, `Int32`,
//!   `Boolean`, `String` and `Enumeration` variables with their units, `EnumerationType`s,
//!   `ModelStructure` by value reference, the `instantiationToken` (the model's GUID);
//! - every `fmi3*` function as an `extern "C"` symbol ([`export_fmi3!`]), behind
//!   `catch_unwind`, over fmi2-export's [`Instance`](fmi2_export::Instance): one state
//!   machine, one set of argument checks (wrong state, unknown or mistyped value reference,
//!   NaN, a bad step), one FMU-state format, for both versions; messages name the `fmi3*`
//!   functions;
//! - packaging with FMI 3.0's platform folders ([`package::write_fmu`], feature `package`).
//!
//! Why a sibling crate and not a module of fmi2-export: the model trait, the table and the
//! instance are version-neutral and stay where FMI 2.0 users already have them; FMI 3.0 is an
//! addition a model opts into (its cdylib calls both `export_fmi2!` and `export_fmi3!`, whose
//! symbols do not clash), so nothing on the FMI 2.0 side changes for a user who does not.
//!
//! What FMI 3.0 offers and these FMUs do not: event mode (`hasEventMode="false"`), clocks,
//! intermediate update, early return, directional and adjoint derivatives, arrays (every
//! variable is a scalar, as in the FMI 2.0 twin), Model Exchange and Scheduled Execution.
//! Their functions exist, log why and return `fmi3Error` (instantiation: NULL).
//!
//! Value references: FMI 3.0 wants them unique over all variables; a variable's FMI 3.0 value
//! reference is its position in `ModelVariables` ([`description::Fmi3Variables`]).

#![warn(missing_docs)]

pub mod abi;
pub mod description;
#[cfg(feature = "package")]
pub mod package;

/// The layer this one builds on, for [`export_fmi3!`]'s expansion.
pub use fmi2_export;
