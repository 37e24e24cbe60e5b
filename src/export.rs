//! Exporting neurarm's models as `.fmu` files: the spec of a model, its resource files, and
//! the one FMU binary (`fmu/`) per platform, which this module finds among cargo's output:
//! the host's beside the running program, cross-built ones (`scripts/build-platforms`) in
//! `fmu-binaries/<platform>/` beside it.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, ensure, Context, Result};
use neurarm_fmi_export::package::{select_binaries, SelectError, PLATFORM};
use neurarm_models::{FmuSpec, SPEC_FILE};

/// File name of the FMU binary that `cargo build --release` makes.
pub const BINARY_NAME: &str = "libneurarm_fmu.so";

/// Folder of the cross-built FMU binaries, beside the running program (or one folder up):
/// `fmu-binaries/<platform>/` holds each platform's library under cargo's name for it.
pub const CROSS_DIR: &str = "fmu-binaries";

/// Finds the FMU binary: `$NEURARM_FMU_BINARY` if set, else beside the running program (or
/// one folder up, for test binaries in `target/*/deps` and examples in `target/*/examples`).
pub fn find_binary() -> Result<PathBuf> {
    if let Some(p) = std::env::var_os("NEURARM_FMU_BINARY") {
        let p = PathBuf::from(p);
        ensure!(p.is_file(), "NEURARM_FMU_BINARY={} is not a file", p.display());
        return Ok(p);
    }
    let exe = std::env::current_exe().context("cannot locate the running program")?;
    let dir = exe.parent().context("the running program has no folder")?;
    for candidate in [dir.join(BINARY_NAME), dir.join("..").join(BINARY_NAME)] {
        if candidate.is_file() {
            return Ok(candidate);
        }
    }
    bail!(
        "the FMU binary {BINARY_NAME} is not beside {}; build it with `cargo build --release -p neurarm-fmu` \
         (scripts/run does), or point NEURARM_FMU_BINARY at it",
        exe.display()
    )
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
pub fn fmu_binaries(platforms: Option<&[String]>) -> Result<Vec<(String, PathBuf)>> {
    let host = if platforms.is_none_or(|w| w.iter().any(|p| p == PLATFORM.0)) { Some(find_binary()?) } else { None };
    let found = select_binaries(host, cross_dir().as_deref(), "neurarm_fmu", platforms).map_err(|e| match e {
        SelectError::UnknownPlatform { .. } => anyhow::Error::new(e),
        // How to build what is missing is added here.
        _ => anyhow::Error::new(e)
            .context("an FMU binary is missing (build it with scripts/build-platforms, or point NEURARM_FMU_PLATFORMS at a folder of <platform>/<library> builds)"),
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
pub fn same_sources(binaries: &[(String, PathBuf)]) -> Result<()> {
    let mut hashes = Vec::with_capacity(binaries.len());
    for (platform, path) in binaries {
        let bytes = std::fs::read(path).with_context(|| path.display().to_string())?;
        hashes.push((platform.as_str(), sources_of(&bytes).map(str::to_owned)));
    }
    let Some(reference) = hashes.iter().find(|(p, _)| *p == PLATFORM.0).or(hashes.first()).cloned() else { return Ok(()) };
    let differ: Vec<&str> = hashes.iter().filter(|(_, h)| *h != reference.1).map(|(p, _)| *p).collect();
    if differ.is_empty() {
        return Ok(());
    }
    bail!(
        "the FMU binaries for {} were built from other sources than the {} one: rebuild them with scripts/build-platforms",
        differ.join(", "),
        reference.0
    )
}

/// The FMI version of an FMU to write.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum FmiVersion {
    /// FMI 2.0 Co-Simulation.
    Fmi2,
    /// FMI 3.0 Co-Simulation.
    Fmi3,
}

impl FmiVersion {
    /// "2.0" or "3.0".
    pub fn number(self) -> &'static str {
        match self {
            FmiVersion::Fmi2 => "2.0",
            FmiVersion::Fmi3 => "3.0",
        }
    }
}

/// An FMI version neurarm does not write, as given.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("FMI version {0:?}: 2 (FMI 2.0) or 3 (FMI 3.0)")]
pub struct UnknownFmiVersion(pub String);

impl std::str::FromStr for FmiVersion {
    type Err = UnknownFmiVersion;
    fn from_str(s: &str) -> Result<Self, UnknownFmiVersion> {
        match s.trim() {
            "2" | "2.0" => Ok(FmiVersion::Fmi2),
            "3" | "3.0" => Ok(FmiVersion::Fmi3),
            other => Err(UnknownFmiVersion(other.to_owned())),
        }
    }
}

/// Writes the FMU for `spec` to `path` with the binaries of every platform found: see
/// [`export_fmu_for`].
pub fn export_fmu(spec: &FmuSpec, sources: &[(String, PathBuf)], path: &Path) -> Result<()> {
    export_fmu_for(spec, sources, path, None)
}

/// Writes the FMU for `spec` to `path`, with the files it names taken from `sources` and the
/// binaries of `platforms` (see [`fmu_binaries`]: `None` packs every one found). The
/// files are checked by building the model from them exactly as the FMU will at
/// instantiation. The FMU is packed in a temporary folder, then written to `path` as
/// [`crate::output`] says: a file is replaced whole (nothing is left at `path` on failure), a
/// device or FIFO gets the archive's bytes. `-` is refused: an FMU is a binary archive, not
/// something for a terminal (`/dev/stdout` streams it to a pipe).
pub fn export_fmu_for(spec: &FmuSpec, sources: &[(String, PathBuf)], path: &Path, platforms: Option<&[String]>) -> Result<()> {
    export_fmu_as(spec, sources, path, platforms, FmiVersion::Fmi2)
}

/// As [`export_fmu_for`], as an FMU of FMI version `version`: the same binary (it carries both
/// versions' functions), resources and checks; the FMI 3.0 twin has FMI 3.0's model
/// description and platform folders.
pub fn export_fmu_as(
    spec: &FmuSpec,
    sources: &[(String, PathBuf)],
    path: &Path,
    platforms: Option<&[String]>,
    version: FmiVersion,
) -> Result<()> {
    refuse_stdout(path)?;
    let binaries = fmu_binaries(platforms)?;
    let staging = tempfile::tempdir().context("temporary folder")?;
    let mut resources = vec![(SPEC_FILE.to_owned(), spec.to_toml().into_bytes())];
    for name in spec.resource_files() {
        let source =
            sources.iter().find(|(n, _)| *n == name).map(|(_, p)| p).with_context(|| format!("no source file given for {name}"))?;
        let bytes = std::fs::read(source).with_context(|| source.display().to_string())?;
        std::fs::write(staging.path().join(&name), &bytes).with_context(|| format!("staging {name}"))?;
        resources.push((name, bytes));
    }
    let model = spec.build_from(Some(staging.path())).map_err(|e| {
        // Name the user's file, not the staging copy: the paths are in the error's words.
        let e = e.to_string();
        anyhow::Error::msg(
            sources.iter().fold(e, |e, (name, p)| e.replace(&staging.path().join(name).display().to_string(), &p.display().to_string())),
        )
    })?;
    let packed = staging.path().join(format!("{}.fmu", spec.identifier));
    let binaries: Vec<(&str, &Path)> = binaries.iter().map(|(p, b)| (p.as_str(), b.as_path())).collect();
    let files: Vec<(&str, Vec<u8>)> = resources.iter().map(|(n, b)| (n.as_str(), b.clone())).collect();
    match version {
        FmiVersion::Fmi2 => neurarm_fmi_export::fmi2::write_fmu(&packed, model.description(), &binaries, &files, spec.equations_html()),
        FmiVersion::Fmi3 => neurarm_fmi_export::fmi3::write_fmu(&packed, model.description(), &binaries, &files, spec.equations_html()),
    }
    .with_context(|| format!("packing {}", path.display()))?;
    deliver(&packed, path)
}

/// Copies the FMU packed at `packed` to `path` as [`crate::output`] writes.
fn deliver(packed: &Path, path: &Path) -> Result<()> {
    let bytes = std::fs::read(packed).with_context(|| format!("reading the packed {}", path.display()))?;
    crate::output::write_bytes(path, &bytes).with_context(|| format!("writing {}", path.display()))
}

/// An FMI 2.0 FMU's files unpacked for its FMI 3.0 twin: `resources/` (also written to the
/// staging folder's `resources/`, to build the model from) and the binaries (written to its
/// `binaries/<platform>/`).
struct Unpacked {
    resources: Vec<(String, Vec<u8>)>,
    binaries: Vec<(String, PathBuf)>,
}

/// Unpacks the neurarm FMI 2.0 FMU `fmi2_fmu` into `staging` (see [`Unpacked`]); refuses an
/// entry that escapes the archive and a binary without the `fmi3*` functions.
fn unpack_for_twin(fmi2_fmu: &Path, staging: &Path) -> Result<Unpacked> {
    use std::io::Read;
    let at = || fmi2_fmu.display().to_string();
    let file = std::fs::File::open(fmi2_fmu).with_context(at)?;
    let mut zip = zip::ZipArchive::new(file).with_context(|| format!("{}: not an FMU archive", at()))?;
    let resources_dir = staging.join("resources");
    std::fs::create_dir_all(&resources_dir).context("staging")?;
    let mut unpacked = Unpacked { resources: Vec::new(), binaries: Vec::new() };
    for i in 0..zip.len() {
        let mut entry = zip.by_index(i).with_context(at)?;
        if entry.is_dir() {
            continue;
        }
        let Some(name) = entry.enclosed_name() else { bail!("{}: entry {:?} escapes the archive", at(), entry.name()) };
        let parts: Vec<String> = name.iter().map(|p| p.to_string_lossy().into_owned()).collect();
        let mut bytes = Vec::new();
        entry.read_to_end(&mut bytes).with_context(at)?;
        match parts.iter().map(String::as_str).collect::<Vec<_>>().as_slice() {
            ["resources", file] => {
                std::fs::write(resources_dir.join(file), &bytes).with_context(|| format!("staging {file}"))?;
                unpacked.resources.push((file.to_string(), bytes));
            }
            ["binaries", platform, file] => {
                ensure!(
                    bytes.windows(10).any(|w| w == b"fmi3DoStep"),
                    "{}: its {platform} binary has no FMI 3.0 functions (made by a neurarm without FMI 3.0 export): export the FMU again, or with --fmi 3",
                    at()
                );
                let folder = staging.join("binaries").join(platform);
                std::fs::create_dir_all(&folder).context("staging")?;
                std::fs::write(folder.join(file), &bytes).with_context(|| format!("staging {file}"))?;
                unpacked.binaries.push((platform.to_string(), folder.join(file)));
            }
            _ => {}
        }
    }
    Ok(unpacked)
}

/// Writes the FMI 3.0 twin of the neurarm FMI 2.0 FMU `fmi2_fmu` to `path`: the same model
/// (its `resources/`, checked by building the model from them), the same binaries (moved into
/// FMI 3.0's platform folders), an FMI 3.0 model description. Refused, saying why, for an
/// archive that is not a neurarm FMU or whose binaries lack the `fmi3*` functions (made before
/// neurarm exported FMI 3.0). Written as [`export_fmu_for`] writes: nothing is left at `path` on
/// failure.
pub fn export_fmi3_twin(fmi2_fmu: &Path, path: &Path) -> Result<()> {
    refuse_stdout(path)?;
    let at = || fmi2_fmu.display().to_string();
    let staging = tempfile::tempdir().context("temporary folder")?;
    let Unpacked { resources, binaries } = unpack_for_twin(fmi2_fmu, staging.path())?;
    let spec_text = resources
        .iter()
        .find(|(n, _)| n == SPEC_FILE)
        .map(|(_, b)| String::from_utf8_lossy(b).into_owned())
        .with_context(|| format!("{}: not a neurarm FMU (no resources/{SPEC_FILE})", at()))?;
    // `FmuSpec::from_toml` says what is wrong in words.
    let spec = FmuSpec::from_toml(&spec_text).map_err(|e| anyhow!("{}: resources/{SPEC_FILE}: {e}", at()))?;
    ensure!(!binaries.is_empty(), "{}: it carries no binaries", at());
    let model = spec.build_from(Some(&staging.path().join("resources"))).with_context(at)?;
    let binaries: Vec<(&str, &Path)> = binaries.iter().map(|(p, b)| (p.as_str(), b.as_path())).collect();
    let files: Vec<(&str, Vec<u8>)> = resources.iter().map(|(n, b)| (n.as_str(), b.clone())).collect();
    let packed = staging.path().join(format!("{}.fmu", spec.identifier));
    neurarm_fmi_export::fmi3::write_fmu(&packed, model.description(), &binaries, &files, spec.equations_html())
        .with_context(|| format!("packing {}", path.display()))?;
    deliver(&packed, path)
}

/// Refuses `-` as the path of an FMU, saying why.
pub fn refuse_stdout(path: &Path) -> Result<()> {
    ensure!(
        !crate::output::is_stdout(path),
        "an FMU is a binary archive: give a .fmu file name with -o, not '-' (to pipe it, -o /dev/stdout)"
    );
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
        let e = same_sources(&[host.clone(), same, other, unmarked]).unwrap_err().to_string();
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
