//! Packaging the built library as the test FMUs.

use neurarm_fmi_export::ModelDescription;
use std::path::{Path, PathBuf};

use crate::{TestModel, MODEL_FILE};

/// The library's file name as cargo builds it.
pub const LIBRARY: &str = "libneurarm_test_fmus.so";

/// The built library: `$FMI2_TEST_FMUS_BINARY`, else beside the running program (or one
/// folder up, for test programs in `target/<profile>/deps`), else the newest in the
/// workspace's `target/<profile>/` folders.
pub fn built_library() -> Result<PathBuf, String> {
    if let Some(p) = std::env::var_os("FMI2_TEST_FMUS_BINARY") {
        return Ok(PathBuf::from(p));
    }
    let exe = std::env::current_exe().map_err(|e| e.to_string())?;
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
    newest.map(|(_, p)| p).ok_or_else(|| format!("{LIBRARY} is not built: run `cargo build -p neurarm-test-fmus` (scripts/test does)"))
}

/// `<Identifier>.fmu` of `model` in `dir`, packaged from the built library.
pub fn fmu_in(dir: &Path, model: TestModel) -> Result<PathBuf, String> {
    package(&dir.join(format!("{}.fmu", model.identifier())), model, neurarm_fmi_export::fmi2::write_fmu)
}

/// `<Identifier>.fmi3.fmu` of `model` in `dir`: its FMI 3.0 twin, from the same library.
pub fn fmu3_in(dir: &Path, model: TestModel) -> Result<PathBuf, String> {
    package(&dir.join(format!("{}.fmi3.fmu", model.identifier())), model, neurarm_fmi_export::fmi3::write_fmu)
}

/// The signature both versions' `write_fmu` share.
type WriteFmu = fn(&Path, &ModelDescription, &[(&str, &Path)], &[(&str, Vec<u8>)], &str) -> std::io::Result<()>;

fn package(out: &Path, model: TestModel, write_fmu: WriteFmu) -> Result<PathBuf, String> {
    let built = model.build().map_err(|e| e.to_string())?;
    let resources = [(MODEL_FILE, model.identifier().as_bytes().to_vec())];
    write_fmu(
        out,
        built.description(),
        &[(neurarm_fmi_export::package::PLATFORM.0, &built_library()?)],
        &resources,
        model.equations_html(),
    )
    .map_err(|e| format!("writing {}: {e}", out.display()))?;
    Ok(out.to_path_buf())
}
