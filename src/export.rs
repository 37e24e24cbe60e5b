//! Exporting neurarm's models as `.fmu` files: the spec of a model, its resource files, and
//! the one FMU binary (`fmu/`), which this module finds among cargo's output.

use std::path::{Path, PathBuf};

use neurarm_models::{FmuSpec, SPEC_FILE};

/// File name of the FMU binary that `cargo build --release` makes.
pub const BINARY_NAME: &str = "libneurarm_fmu.so";

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

/// Writes the FMU for `spec` to `path`, with the files it names taken from `sources`. The
/// files are checked by building the model from them exactly as the FMU will at
/// instantiation. The FMU is packed in a temporary folder, then written to `path` as
/// [`crate::output`] says: a file is replaced whole (nothing is left at `path` on failure), a
/// device or FIFO gets the archive's bytes. `-` is refused: an FMU is a binary archive, not
/// something for a terminal (`/dev/stdout` streams it to a pipe).
pub fn export_fmu(spec: &FmuSpec, sources: &[(String, PathBuf)], path: &Path) -> Result<(), String> {
    refuse_stdout(path)?;
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
    let binary = find_binary()?;
    let files: Vec<(&str, Vec<u8>)> = resources.iter().map(|(n, b)| (n.as_str(), b.clone())).collect();
    let packed = staging.path().join(format!("{}.fmu", spec.identifier));
    fmi2_export::package::write_fmu(&packed, model.description(), &binary, &files, spec.equations_html())
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
