//! The one binary behind every neurarm FMU, FMI 2.0 and FMI 3.0 Co-Simulation alike: it
//! carries both versions' functions (`fmi2*` and `fmi3*`, which do not clash) over the same
//! models. Each `.fmu` ships a copy named after its model identifier; `resources/neurarm.toml`
//! says which model it holds.

neurarm_fmi_export::export_fmi2!(neurarm_models::instantiate);
neurarm_fmi_export::export_fmi3!(neurarm_models::instantiate);

/// The marker of the sources this binary was built from (see `build.rs`): a NUL-terminated
/// `neurarm-fmu-sources:<16 hex digits>`.
static SOURCES: &str = concat!("neurarm-fmu-sources:", env!("NEURARM_FMU_SOURCES"), "\0");

/// The marker of this build's sources, a NUL-terminated string (not part of FMI): exported so
/// that the linker keeps it, and so that a tool can ask a loaded binary for it.
#[no_mangle]
pub extern "C" fn neurarm_fmu_sources() -> *const std::ffi::c_char {
    SOURCES.as_ptr().cast()
}
