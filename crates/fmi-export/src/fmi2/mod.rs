//! FMI 2.0 Co-Simulation: the `fmi2*` C API ([`export_fmi2!`](crate::export_fmi2)) and
//! packaging ([`write_fmu`]). The model description's FMI 2.0 XML is
//! [`ModelDescription::to_xml`](crate::ModelDescription::to_xml).

pub mod abi;
pub(crate) mod description;
#[cfg(feature = "package")]
mod package;

#[cfg(feature = "package")]
pub use package::write_fmu;
