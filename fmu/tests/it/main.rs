//! The FMU binary's integration tests through its C ABI (FMI 2.0 and 3.0), a C host under
//! valgrind, hostile hosts, robustness and the soak.

mod adaptive_abi;
mod c_host;
mod common;
mod fmu_abi;
mod hostile_host;
mod robustness;
mod soak;
