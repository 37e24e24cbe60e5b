//! The export layer's integration tests: both C APIs, the instance's checks, packaging, resource URIs.

mod fmi3_abi;
mod fmi_panics;
mod header_signatures;
mod instance_checks;
mod platforms;
mod resource_uri;
