//! Packaging the built library as the test FMUs.

use neurarm_fmi_export::{ModelDescription, ModelError};
use std::path::{Path, PathBuf};

use crate::{TestModel, MODEL_FILE};

/// The library's file name as cargo builds it.
pub const LIBRARY: &str = "libneurarm_test_fmus.so";

/// Why a test FMU could not be packaged.
#[derive(Debug, thiserror::Error)]
pub enum PackageError {
    /// The running program's path, where the library is looked for, is unknown.
    #[error(transparent)]
    CurrentExe(std::io::Error),
    /// No built library was found.
    #[error("{LIBRARY} is not built: run `cargo build -p neurarm-test-fmus` (scripts/test does)")]
    NotBuilt,
    /// The model could not be built.
    #[error("{0}")]
    Model(ModelError),
    /// The `.fmu` could not be written.
    #[error("writing {}: {source}", path.display())]
    Write {
        /// The `.fmu`.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// The built library: `$FMI2_TEST_FMUS_BINARY`, else beside the running program (or one
/// folder up, for test programs in `target/<profile>/deps`), else the newest in the
/// workspace's `target/<profile>/` folders.
pub fn built_library() -> Result<PathBuf, PackageError> {
    if let Some(p) = std::env::var_os("FMI2_TEST_FMUS_BINARY") {
        return Ok(PathBuf::from(p));
    }
    let exe = std::env::current_exe().map_err(PackageError::CurrentExe)?;
    let beside = exe.parent().into_iter().flat_map(|d| [d.join(LIBRARY), d.join("..").join(LIBRARY)]);
    if let Some(p) = beside.into_iter().find(|p| p.is_file()) {
        return Ok(p);
    }
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target"));
    let newest = ["release", "debug"]
        .iter()
        .map(|profile| target.join(profile).join(LIBRARY))
        .filter_map(|p| Some((std::fs::metadata(&p).ok()?.modified().ok()?, p)))
        .max();
    newest.map(|(_, p)| p).ok_or(PackageError::NotBuilt)
}

/// `<Identifier>.fmu` of `model` in `dir`, packaged from the built library.
pub fn fmu_in(dir: &Path, model: TestModel) -> Result<PathBuf, PackageError> {
    package(&dir.join(format!("{}.fmu", model.identifier())), model, neurarm_fmi_export::fmi2::write_fmu)
}

/// `<Identifier>.fmi3.fmu` of `model` in `dir`: its FMI 3.0 twin, from the same library.
pub fn fmu3_in(dir: &Path, model: TestModel) -> Result<PathBuf, PackageError> {
    package(&dir.join(format!("{}.fmi3.fmu", model.identifier())), model, neurarm_fmi_export::fmi3::write_fmu)
}

/// The signature both versions' `write_fmu` share.
type WriteFmu = fn(&Path, &ModelDescription, &[(&str, &Path)], &[(&str, Vec<u8>)], &str) -> std::io::Result<()>;

fn package(out: &Path, model: TestModel, write_fmu: WriteFmu) -> Result<PathBuf, PackageError> {
    let built = model.build().map_err(PackageError::Model)?;
    let resources = [(MODEL_FILE, model.identifier().as_bytes().to_vec())];
    write_fmu(
        out,
        built.description(),
        &[(neurarm_fmi_export::package::PLATFORM.0, &built_library()?)],
        &resources,
        model.equations_html(),
    )
    .map_err(|source| PackageError::Write { path: out.to_path_buf(), source })?;
    Ok(out.to_path_buf())
}
