//! FMI 3.0 Co-Simulation from the same model and variable table as FMI 2.0:
//!
//! - the FMI 3.0 `modelDescription.xml` ([`description::to_xml`]): `Float64`, `Int32`,
//!   `Boolean`, `String` and `Enumeration` variables with their units, `EnumerationType`s,
//!   `ModelStructure` by value reference, and the model's GUID as `instantiationToken`;
//! - every `fmi3*` function as an `extern "C"` symbol ([`export_fmi3!`](crate::export_fmi3)),
//!   behind `catch_unwind`, over the same [`Instance`](crate::Instance) as FMI 2.0: one state
//!   machine, one set of argument checks, one FMU-state format; messages name the `fmi3*`
//!   functions;
//! - packaging with FMI 3.0's platform folders ([`write_fmu`], feature `package`).
//!
//! One library can carry both `export_fmi2!` and `export_fmi3!`: their symbols do not clash.
//!
//! Not offered: event mode (`hasEventMode="false"`), clocks, intermediate update, early
//! return, directional and adjoint derivatives, arrays, Model Exchange and Scheduled
//! Execution. Their functions exist, log why and return `fmi3Error` (instantiation: NULL).
//!
//! Value references: FMI 3.0 wants them unique over all variables; a variable's FMI 3.0 value
//! reference is its position in `ModelVariables` ([`description::Fmi3Variables`]).

pub mod abi;
pub mod description;
#[cfg(feature = "package")]
mod package;

#[cfg(feature = "package")]
pub use package::{platform_folders, write_fmu};
