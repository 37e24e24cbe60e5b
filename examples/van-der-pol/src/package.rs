//! Packaging the built library as `VanDerPol.fmu`, for the program `van-der-pol-fmu` and for
//! the tests and examples of this workspace that need an FMU with no robot in it.

use std::path::{Path, PathBuf};

use neurarm_fmi_export::package::SelectError;
use neurarm_fmi_export::{Model, ModelError};

/// Why the FMU could not be written.
#[derive(Debug, thiserror::Error)]
pub enum PackageError {
    /// The model could not be built.
    #[error("the model: {0}")]
    Model(ModelError),
    /// The built library was not found.
    #[error("{LIBRARY} is not built: run `cargo build -p neurarm-van-der-pol` (scripts/test does)")]
    NotBuilt,
    /// The running program's path is unknown.
    #[error("cannot locate the running program")]
    NoProgram(#[source] std::io::Error),
    /// The binaries to pack could not be selected.
    #[error(transparent)]
    Select(#[from] SelectError),
    /// Writing the archive failed.
    #[error("writing {}: {source}", path.display())]
    Write {
        /// The FMU's path.
        path: PathBuf,
        /// What failed.
        source: std::io::Error,
    },
}

/// The library's file name as cargo builds it.
pub const LIBRARY: &str = "libvan_der_pol.so";

/// The equations, for the FMU's documentation page.
pub const EQUATIONS_HTML: &str = "<p><code>ẍ = μ (1 − x²) ẋ − x + u</code>, <code>x(t0) = x0</code>, \
<code>ẋ(t0) = v0</code>; classic RK4 in sub-steps of at most 1 ms, with u held over each step.</p>";

/// Writes the FMU of the libraries `binaries`, `(platform folder, library)`, to `out`.
pub fn write_fmu(binaries: &[(String, PathBuf)], out: &Path) -> Result<(), PackageError> {
    let model = crate::VanDerPol::new().map_err(PackageError::Model)?;
    let binaries: Vec<(&str, &Path)> = binaries.iter().map(|(p, b)| (p.as_str(), b.as_path())).collect();
    neurarm_fmi_export::fmi2::write_fmu(out, model.description(), &binaries, &[], EQUATIONS_HTML)
        .map_err(|source| PackageError::Write { path: out.to_path_buf(), source })
}

/// The libraries to pack: the built one ([`built_library`]) and every cross build found in
/// `$VAN_DER_POL_PLATFORMS`, else in `fmu-binaries/<platform>/` beside the built one
/// (`scripts/build-platforms` puts them there).
pub fn built_binaries() -> Result<Vec<(String, PathBuf)>, PackageError> {
    let host = built_library()?;
    let cross = std::env::var_os("VAN_DER_POL_PLATFORMS").map(PathBuf::from).or_else(|| host.parent().map(|d| d.join("fmu-binaries")));
    Ok(neurarm_fmi_export::package::select_binaries(Some(host), cross.as_deref(), "van_der_pol", None)?)
}

/// The built library: `$VAN_DER_POL_BINARY`, else beside the running program (or one folder
/// up, for test programs in `target/<profile>/deps`), else the newest in the workspace's
/// `target/<profile>/` folders (for doctests, which run from a temporary folder).
pub fn built_library() -> Result<PathBuf, PackageError> {
    if let Some(p) = std::env::var_os("VAN_DER_POL_BINARY") {
        return Ok(PathBuf::from(p));
    }
    let exe = std::env::current_exe().map_err(PackageError::NoProgram)?;
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

/// `VanDerPol.fmu` in `dir`, packaged from the built library.
pub fn fmu_in(dir: &Path) -> Result<PathBuf, PackageError> {
    let out = dir.join("VanDerPol.fmu");
    write_fmu(&built_binaries()?, &out)?;
    Ok(out)
}
