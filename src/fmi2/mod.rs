//! A generic FMI 2.0 Co-Simulation export layer. It knows nothing of robots: a model
//! implements [`model::Model`] over a table of variables ([`description`]); this layer does
//! the C ABI ([`abi`], [`export_fmi2!`](crate::export_fmi2)), the state machine and argument
//! checks ([`instance`]), FMU state serialisation, `modelDescription.xml` and packaging.

pub mod abi;
pub mod codec;
pub mod description;
pub mod instance;
pub mod model;
#[cfg(feature = "app")]
pub mod package;
