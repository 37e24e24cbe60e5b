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
    let found = select_binaries(host, cross_dir().as_deref(), "neurarm_fmu", platforms).map_err(|e| {
        if e.starts_with("unknown platform") {
            e
        } else {
            format!(
                "{e}; build them with scripts/build-platforms, or point NEURARM_FMU_PLATFORMS at a folder of <platform>/<library> builds"
            )
        }
    })?;
    same_sources(&found)?;
    Ok(found)
}

/// The start of the marker every FMU binary carries (`fmu/build.rs`), followed by 16 hex
/// digits: a hash of the sources it was built from.
pub const SOURCES_MARKER: &[u8] = b"neurarm-fmu-sources:";

/// The source hash in the FMU binary `bytes`, if it carries one.
pub fn sources_of(bytes: &[u8]) -> Option<&str> {
    let at = bytes.windows(SOURCES_MARKER.len()).position(|w| w == SOURCES_MARKER)? + SOURCES_MARKER.len();
    let hash = bytes.get(at..at + 16)?;
    hash.iter().all(u8::is_ascii_hexdigit).then(|| std::str::from_utf8(hash).ok()).flatten()
}

/// Checks that the binaries `(platform, library)` were all built from the same sources: a
/// cross build left over from before a change would ship another model under this one's
/// description. The error names the platforms to rebuild.
pub fn same_sources(binaries: &[(String, PathBuf)]) -> Result<(), String> {
    let mut hashes = Vec::with_capacity(binaries.len());
    for (platform, path) in binaries {
        let bytes = std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))?;
        hashes.push((platform.as_str(), sources_of(&bytes).map(str::to_owned)));
    }
    let Some(reference) = hashes.iter().find(|(p, _)| *p == PLATFORM.0).or(hashes.first()).cloned() else { return Ok(()) };
    let differ: Vec<&str> = hashes.iter().filter(|(_, h)| *h != reference.1).map(|(p, _)| *p).collect();
    if differ.is_empty() {
        return Ok(());
    }
    Err(format!(
        "the FMU binaries for {} were built from other sources than the {} one: rebuild them with scripts/build-platforms",
        differ.join(", "),
        reference.0
    ))
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

#[cfg(test)]
mod tests {
    use super::*;

    fn library(dir: &Path, name: &str, hash: Option<&str>) -> PathBuf {
        let path = dir.join(name);
        let mut bytes = b"\x7fELF other bytes".to_vec();
        if let Some(h) = hash {
            bytes.extend_from_slice(SOURCES_MARKER);
            bytes.extend_from_slice(h.as_bytes());
            bytes.push(0);
        }
        std::fs::write(&path, bytes).unwrap();
        path
    }

    #[test]
    fn binaries_of_different_sources_are_not_packed_together() {
        let d = tempfile::tempdir().unwrap();
        let host = ("linux64".to_owned(), library(d.path(), "a", Some("0123456789abcdef")));
        let same = ("win64".to_owned(), library(d.path(), "b", Some("0123456789abcdef")));
        let other = ("darwin64".to_owned(), library(d.path(), "c", Some("fedcba9876543210")));
        let unmarked = ("aarch64-linux".to_owned(), library(d.path(), "d", None));
        same_sources(&[host.clone(), same.clone()]).unwrap();
        let e = same_sources(&[host.clone(), same, other, unmarked]).unwrap_err();
        assert!(e.contains("darwin64, aarch64-linux") && e.contains("than the linux64 one"), "{e}");
        assert_eq!(sources_of(&std::fs::read(&host.1).unwrap()), Some("0123456789abcdef"));
    }

    #[test]
    fn the_built_fmu_binary_carries_its_sources_hash() {
        let binary = find_binary().expect("the FMU binary is built (cargo build --release -p neurarm-fmu)");
        let bytes = std::fs::read(binary).unwrap();
        let hash = sources_of(&bytes).expect("a marker");
        assert_eq!(hash.len(), 16);
    }
}
