//! Exporting neurarm's models as `.fmu` files: the spec of a model, its resource files, and
//! the one FMU binary (`fmu/`) per platform, which this module finds among cargo's output:
//! the host's beside the running program, cross-built ones (`scripts/build-platforms`) in
//! `fmu-binaries/<platform>/` beside it.

use std::path::{Path, PathBuf};

use fmi2_export::package::{select_binaries, PLATFORM};
use neurarm_models::{FmuSpec, SPEC_FILE};

/// File name of the FMU binary that `cargo build --release` makes.
pub const BINARY_NAME: &str = "libneurarm_fmu.so";

/// Folder of the cross-built FMU binaries, beside the running program (or one folder up):
/// `fmu-binaries/<platform>/` holds each platform's library under cargo's name for it.
pub const CROSS_DIR: &str = "fmu-binaries";

/// Finds the FMU binary: `$NEURARM_FMU_BINARY` if set, else beside the running program (or
/// one folder up, for test binaries in `target/*/deps` and examples in `target/*/examples`).
pub fn find_binary() -> Result<PathBuf, String> {
    if let Some(p) = std::env::var_os("NEURARM_FMU_BINARY") {
        let p = PathBuf::from(p);
        return if p.is_file() { Ok(p) } else { Err(format!("NEURARM_FMU_BINARY={} is not a file", p.display())) };
    }
    let exe = std::env::current_exe().map_err(|e| format!("cannot locate the running program: {e}"))?;
    let dir = exe.parent().ok_or("the running program has no folder")?;
    for candidate in [dir.join(BINARY_NAME), dir.join("..").join(BINARY_NAME)] {
        if candidate.is_file() {
            return Ok(candidate);
        }
    }
    Err(format!(
        "the FMU binary {BINARY_NAME} is not beside {}; build it with `cargo build --release -p neurarm-fmu` \
         (scripts/run does), or point NEURARM_FMU_BINARY at it",
        exe.display()
    ))
}

/// The folder of cross-built binaries: `$NEURARM_FMU_PLATFORMS` if set, else [`CROSS_DIR`]
/// beside the running program or one folder up; `None` if there is none.
pub fn cross_dir() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("NEURARM_FMU_PLATFORMS") {
        return Some(PathBuf::from(p));
    }
    let exe = std::env::current_exe().ok()?;
    let dir = exe.parent()?;
    [dir.join(CROSS_DIR), dir.join("..").join(CROSS_DIR)].into_iter().find(|p| p.is_dir())
}

/// The platform binaries an FMU carries, `(platform folder, library)`: the host's (see
/// [`find_binary`]) and, for `platforms` `None`, every cross-built one found in
/// [`cross_dir`]; for `Some(list)`, exactly the platforms listed, with an error naming each
/// one not built and how to build it.
pub fn fmu_binaries(platforms: Option<&[String]>) -> Result<Vec<(String, PathBuf)>, String> {
    let host = if platforms.is_none_or(|w| w.iter().any(|p| p == PLATFORM.0)) { Some(find_binary()?) } else { None };
    select_binaries(host, cross_dir().as_deref(), "neurarm_fmu", platforms).map_err(|e| {
        if e.starts_with("unknown platform") {
            e
        } else {
            format!(
                "{e}; build them with scripts/build-platforms, or point NEURARM_FMU_PLATFORMS at a folder of <platform>/<library> builds"
            )
        }
    })
}

/// Writes the FMU for `spec` to `path` with the binaries of every platform found: see
/// [`export_fmu_for`].
pub fn export_fmu(spec: &FmuSpec, sources: &[(String, PathBuf)], path: &Path) -> Result<(), String> {
    export_fmu_for(spec, sources, path, None)
}

/// Writes the FMU for `spec` to `path`, with the files it names taken from `sources` and the
/// binaries of `platforms` (see [`fmu_binaries`]: `None` packs every one found). The
/// files are checked by building the model from them exactly as the FMU will at
/// instantiation. The FMU is packed in a temporary folder, then written to `path` as
/// [`crate::output`] says: a file is replaced whole (nothing is left at `path` on failure), a
/// device or FIFO gets the archive's bytes. `-` is refused: an FMU is a binary archive, not
/// something for a terminal (`/dev/stdout` streams it to a pipe).
pub fn export_fmu_for(spec: &FmuSpec, sources: &[(String, PathBuf)], path: &Path, platforms: Option<&[String]>) -> Result<(), String> {
    refuse_stdout(path)?;
    let binaries = fmu_binaries(platforms)?;
    let staging = tempfile::tempdir().map_err(|e| format!("temporary folder: {e}"))?;
    let mut resources = vec![(SPEC_FILE.to_owned(), spec.to_toml().into_bytes())];
    for name in spec.resource_files() {
        let source = sources.iter().find(|(n, _)| *n == name).map(|(_, p)| p).ok_or_else(|| format!("no source file given for {name}"))?;
        let bytes = std::fs::read(source).map_err(|e| format!("{}: {e}", source.display()))?;
        std::fs::write(staging.path().join(&name), &bytes).map_err(|e| format!("staging {name}: {e}"))?;
        resources.push((name, bytes));
    }
    let model = spec.build_from(Some(staging.path())).map_err(|e| {
        // Name the user's file, not the staging copy.
        let e = e.to_string();
        sources.iter().fold(e, |e, (name, p)| e.replace(&staging.path().join(name).display().to_string(), &p.display().to_string()))
    })?;
    let binaries: Vec<(&str, &Path)> = binaries.iter().map(|(p, b)| (p.as_str(), b.as_path())).collect();
    let files: Vec<(&str, Vec<u8>)> = resources.iter().map(|(n, b)| (n.as_str(), b.clone())).collect();
    let packed = staging.path().join(format!("{}.fmu", spec.identifier));
    fmi2_export::package::write_fmu(&packed, model.description(), &binaries, &files, spec.equations_html())
        .map_err(|e| format!("packing {}: {e}", path.display()))?;
    let bytes = std::fs::read(&packed).map_err(|e| format!("reading the packed {}: {e}", path.display()))?;
    crate::output::write_bytes(path, &bytes).map_err(|e| format!("writing {}: {e}", path.display()))
}

/// Refuses `-` as the path of an FMU, saying why.
pub fn refuse_stdout(path: &Path) -> Result<(), String> {
    if crate::output::is_stdout(path) {
        return Err("an FMU is a binary archive: give a .fmu file name with -o, not '-' (to pipe it, -o /dev/stdout)".into());
    }
    Ok(())
}
