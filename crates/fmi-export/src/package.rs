//! Packaging an FMU: `modelDescription.xml`, the model's shared library for each platform under
//! `binaries/<platform>/`, `resources/` and `documentation/index.html` in a zip, written
//! atomically. The caller says which files go in; finding a build's output is its business.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::description::ModelDescription;

/// The FMI 2.0 platform folder and shared-library extension of the platform this crate is
/// built for, e.g. `("linux64", "so")`.
pub const PLATFORM: (&str, &str) = if cfg!(all(target_os = "linux", target_pointer_width = "64")) {
    ("linux64", "so")
} else if cfg!(all(target_os = "linux", target_pointer_width = "32")) {
    ("linux32", "so")
} else if cfg!(all(target_os = "windows", target_pointer_width = "64")) {
    ("win64", "dll")
} else if cfg!(all(target_os = "windows", target_pointer_width = "32")) {
    ("win32", "dll")
} else if cfg!(target_os = "macos") {
    ("darwin64", "dylib")
} else {
    ("unknown", "so")
};

/// The platform folders under `binaries/` this crate packs, and the extension of each one's
/// shared library: FMI 2.0's names, and the FMI 3.0 tuple `aarch64-linux` (FMI 2.0.4 lets an
/// FMU use FMI 3.0's names for platforms FMI 2.0 has none for). `linux64` may hold an x86_64
/// or an aarch64 library: importers built for ARM Linux (fmpy among them) look there.
pub const PLATFORMS: [(&str, &str); 7] = [
    ("linux64", "so"),
    ("linux32", "so"),
    ("win64", "dll"),
    ("win32", "dll"),
    ("darwin64", "dylib"),
    ("darwin32", "dylib"),
    ("aarch64-linux", "so"),
];

/// The shared-library extension of platform folder `platform` (`"so"`, `"dll"`, `"dylib"`),
/// `None` for a folder this crate does not know.
pub fn library_extension(platform: &str) -> Option<&'static str> {
    PLATFORMS.iter().find(|(p, _)| *p == platform).map(|(_, e)| *e)
}

/// The file format and architecture of each library in `bytes`: one, or several for a
/// universal Mach-O.
fn slices(bytes: &[u8]) -> Result<Vec<(object::BinaryFormat, object::Architecture)>, NotALibrary> {
    use object::read::macho::FatArch;
    use object::{BinaryFormat as F, Object};
    let kind = object::FileKind::parse(bytes).map_err(NotALibrary::Unknown)?;
    Ok(match kind {
        object::FileKind::MachOFat32 => {
            let fat = object::read::macho::MachOFatFile32::parse(bytes).map_err(NotALibrary::BrokenUniversal)?;
            fat.arches().iter().map(|a| (F::MachO, a.architecture())).collect()
        }
        object::FileKind::MachOFat64 => {
            let fat = object::read::macho::MachOFatFile64::parse(bytes).map_err(NotALibrary::BrokenUniversal)?;
            fat.arches().iter().map(|a| (F::MachO, a.architecture())).collect()
        }
        _ => vec![object::File::parse(bytes).map(|file| (file.format(), file.architecture())).map_err(NotALibrary::Unknown)?],
    })
}

/// Why bytes given as a shared library are none.
#[derive(Debug, thiserror::Error)]
pub enum NotALibrary {
    /// Not a file format a platform loads libraries from.
    #[error("not a shared library ({0})")]
    Unknown(object::read::Error),
    /// A universal Mach-O whose header does not hold together.
    #[error("a broken universal Mach-O ({0})")]
    BrokenUniversal(object::read::Error),
    /// A library, but not a Mach-O one.
    #[error("not a Mach-O library")]
    NotMachO,
}

/// Why a library does not belong in a platform folder.
#[derive(Debug, thiserror::Error)]
pub enum BinaryError {
    /// The bytes are no shared library.
    #[error(transparent)]
    NotALibrary(#[from] NotALibrary),
    /// A platform folder FMI 2.0 does not name.
    #[error("unknown platform folder {platform:?} (known: {known})")]
    UnknownPlatform {
        /// The folder given.
        platform: String,
        /// The folders known, listed.
        known: String,
    },
    /// A library for another platform.
    #[error("a {is} library, not one for {platform} ({wanted})")]
    OtherPlatform {
        /// What the library is: its formats and architectures.
        is: String,
        /// The folder given.
        platform: String,
        /// What that folder takes.
        wanted: String,
    },
    /// FMI 3.0 has no platform folder for this FMI 2.0 one.
    #[error("no FMI 3.0 platform folder known for {0:?}")]
    NoFmi3Folder(String),
}

/// Why the binaries to pack could not be selected ([`select_binaries`]).
#[derive(Debug, thiserror::Error)]
pub enum SelectError {
    /// No library was built for the host platform.
    #[error("no {name} library built for {platform}")]
    NoHostLibrary {
        /// The library crate's name.
        name: String,
        /// The host's platform folder.
        platform: &'static str,
    },
    /// An empty list of platforms.
    #[error("no platform asked for")]
    NoPlatformAsked,
    /// A platform folder this crate does not know.
    #[error("unknown platform {platform:?} (known: {known})")]
    UnknownPlatform {
        /// The folder asked for.
        platform: String,
        /// The folders known, listed.
        known: String,
    },
    /// Platforms asked for with no library built.
    #[error("no {name} library built for {} ({})", missing.join(", "), looked_in.as_ref().map_or("no folder of cross builds".to_owned(), |d| format!("looked in {}", d.display())))]
    NotBuilt {
        /// The library crate's name.
        name: String,
        /// The platforms without a library.
        missing: Vec<String>,
        /// The folder of cross builds searched, if any.
        looked_in: Option<PathBuf>,
    },
}

/// The architectures of a macOS library, thin or universal: `"x86_64"`, `"arm64"`.
pub fn macho_architectures(bytes: &[u8]) -> Result<Vec<&'static str>, NotALibrary> {
    use object::{Architecture as A, BinaryFormat as F};
    let slices = slices(bytes)?;
    if slices.iter().any(|(f, _)| *f != F::MachO) {
        return Err(NotALibrary::NotMachO);
    }
    Ok(slices
        .iter()
        .filter_map(|(_, a)| match a {
            A::X86_64 => Some("x86_64"),
            A::Aarch64 => Some("arm64"),
            _ => None,
        })
        .collect())
}

/// Checks that `bytes` is a shared library a host of platform folder `platform` can load: its
/// file format (ELF, PE, Mach-O or a universal Mach-O), word size and architecture. The error
/// says what the file is instead, so a binary in the wrong folder is caught when the FMU is
/// written, not when a user's tool fails to load it.
pub fn check_binary(platform: &str, bytes: &[u8]) -> Result<(), BinaryError> {
    use object::{Architecture as A, BinaryFormat as F};
    let slices = slices(bytes)?;
    let accepted: &[(F, A)] = match platform {
        "linux64" => &[(F::Elf, A::X86_64), (F::Elf, A::Aarch64)],
        "linux32" => &[(F::Elf, A::I386), (F::Elf, A::Arm)],
        "win64" => &[(F::Pe, A::X86_64), (F::Pe, A::Aarch64)],
        "win32" => &[(F::Pe, A::I386)],
        "darwin64" => &[(F::MachO, A::X86_64), (F::MachO, A::Aarch64)],
        "darwin32" => &[(F::MachO, A::I386)],
        "aarch64-linux" => &[(F::Elf, A::Aarch64)],
        _ => return Err(BinaryError::UnknownPlatform { platform: platform.to_owned(), known: platform_names() }),
    };
    let wrong: Vec<String> = slices.iter().filter(|s| !accepted.contains(s)).map(|(f, a)| format!("{f:?} {a:?}")).collect();
    if slices.is_empty() || !wrong.is_empty() {
        let is: Vec<String> = slices.iter().map(|(f, a)| format!("{f:?} {a:?}")).collect();
        let want: Vec<String> = accepted.iter().map(|(f, a)| format!("{f:?} {a:?}")).collect();
        return Err(BinaryError::OtherPlatform { is: is.join(" + "), platform: platform.to_owned(), wanted: want.join(" or ") });
    }
    Ok(())
}

fn platform_names() -> String {
    PLATFORMS.iter().map(|(p, _)| *p).collect::<Vec<_>>().join(", ")
}

/// Cargo's file name of library crate `name` built for platform folder `platform`
/// (`libname.so`, `name.dll`, `libname.dylib`); `None` for an unknown folder.
pub fn library_file_name(platform: &str, name: &str) -> Option<String> {
    let extension = library_extension(platform)?;
    Some(if extension == "dll" { format!("{name}.{extension}") } else { format!("lib{name}.{extension}") })
}

/// The binaries of library crate `name` to pack, `(platform folder, library)`: `host` (the
/// library built for [`PLATFORM`]) and those under `cross_dir/<platform>/` with cargo's file
/// name for the platform ([`library_file_name`]). With `wanted` `None`, `host` (required)
/// and every cross build found; with `Some(list)`, exactly the platforms listed, and an error
/// naming each one not built (`host` may then be `None` if the list leaves the host out).
pub fn select_binaries(
    host: Option<PathBuf>,
    cross_dir: Option<&Path>,
    name: &str,
    wanted: Option<&[String]>,
) -> Result<Vec<(String, PathBuf)>, SelectError> {
    let cross = |platform: &str| -> Option<PathBuf> {
        let file = library_file_name(platform, name)?;
        cross_dir.map(|d| d.join(platform).join(file)).filter(|p| p.is_file())
    };
    let Some(wanted) = wanted else {
        let host = host.ok_or_else(|| SelectError::NoHostLibrary { name: name.to_owned(), platform: PLATFORM.0 })?;
        let mut found = vec![(PLATFORM.0.to_owned(), host)];
        found.extend(PLATFORMS.iter().filter(|(p, _)| *p != PLATFORM.0).filter_map(|(p, _)| Some((p.to_string(), cross(p)?))));
        return Ok(found);
    };
    if wanted.is_empty() {
        return Err(SelectError::NoPlatformAsked);
    }
    let mut found: Vec<(String, PathBuf)> = Vec::new();
    let mut missing = Vec::new();
    for platform in wanted {
        if library_extension(platform).is_none() {
            return Err(SelectError::UnknownPlatform { platform: platform.clone(), known: platform_names() });
        }
        if found.iter().any(|(p, _)| p == platform) || missing.contains(&platform.as_str()) {
            continue;
        }
        let binary = if platform == PLATFORM.0 { host.clone().filter(|p| p.is_file()) } else { cross(platform) };
        match binary {
            Some(p) => found.push((platform.clone(), p)),
            None => missing.push(platform.as_str()),
        }
    }
    if !missing.is_empty() {
        let missing = missing.into_iter().map(str::to_owned).collect();
        return Err(SelectError::NotBuilt { name: name.to_owned(), missing, looked_in: cross_dir.map(Path::to_path_buf) });
    }
    Ok(found)
}

/// Reads each `(platform, binary)` of `binaries` (FMI 2.0 platform names) and checks it with
/// [`check_binary`]: `(platform, library extension, bytes)` in order, or an
/// [`std::io::ErrorKind::InvalidInput`] error naming the file for an empty list, a platform
/// given twice or unknown, or a binary not built for its platform.
pub fn read_binaries<'a>(binaries: &[(&'a str, &Path)]) -> std::io::Result<Vec<(&'a str, &'static str, Vec<u8>)>> {
    let invalid = |m: String| std::io::Error::new(std::io::ErrorKind::InvalidInput, m);
    if binaries.is_empty() {
        return Err(invalid("no platform binary to pack".into()));
    }
    let mut read = Vec::with_capacity(binaries.len());
    for (i, &(platform, binary)) in binaries.iter().enumerate() {
        if binaries[..i].iter().any(|(p, _)| *p == platform) {
            return Err(invalid(format!("platform {platform} given twice")));
        }
        let extension = library_extension(platform)
            .ok_or_else(|| invalid(format!("unknown platform folder {platform:?} (known: {})", platform_names())))?;
        let bytes = std::fs::read(binary).map_err(|e| std::io::Error::new(e.kind(), format!("{}: {e}", binary.display())))?;
        check_binary(platform, &bytes).map_err(|e| invalid(format!("{}: {e}", binary.display())))?;
        read.push((platform, extension, bytes));
    }
    Ok(read)
}

/// Writes an FMU archive to `path`: `model_description` as `modelDescription.xml`, each
/// `(entry name, bytes)` of `libraries` (executable), each resource under `resources/` and
/// `documentation` as `documentation/index.html`. Nothing is checked here (that is
/// [`crate::fmi2::write_fmu`]'s or [`crate::fmi3::write_fmu`]'s part). The archive is written to a
/// temporary file beside `path` and renamed, so a failure leaves nothing behind.
pub fn write_archive(
    path: &Path,
    model_description: &str,
    libraries: &[(String, Vec<u8>)],
    resources: &[(&str, Vec<u8>)],
    documentation: &str,
) -> std::io::Result<()> {
    let dir = match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let mut builder = tempfile::Builder::new();
    // Readable by all (0644 less the umask), as a plain file would be, not a temporary 0600.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o644));
    let tmp = builder.prefix(".fmi-export-").suffix(".fmu.tmp").tempfile_in(dir)?;
    let mut zip = zip::ZipWriter::new(tmp.reopen()?);
    let options = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
    let exe_options = options.unix_permissions(0o755);
    let mut add = |name: String, bytes: &[u8], opts: zip::write::SimpleFileOptions| -> std::io::Result<()> {
        zip.start_file(name, opts).map_err(std::io::Error::other)?;
        zip.write_all(bytes)
    };
    add("modelDescription.xml".into(), model_description.as_bytes(), options)?;
    for (name, bytes) in libraries {
        add(name.clone(), bytes, exe_options)?;
    }
    for (name, bytes) in resources {
        add(format!("resources/{name}"), bytes, options)?;
    }
    add("documentation/index.html".into(), documentation.as_bytes(), options)?;
    zip.finish().map_err(std::io::Error::other)?.sync_all()?;
    tmp.persist(path).map_err(|e| e.error)?;
    Ok(())
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// `documentation/index.html`: the model's equations and a table of its variables.
pub fn documentation_html(d: &ModelDescription, equations_html: &str) -> String {
    documentation_page(d, equations_html, "FMI 2.0 Co-Simulation; GUID")
}

/// `documentation/index.html` for the interface `interface` (e.g. "FMI 3.0 Co-Simulation;
/// instantiation token", followed by the model's GUID).
pub fn documentation_page(d: &ModelDescription, equations_html: &str, interface: &str) -> String {
    let mut rows = String::new();
    for v in &d.variables {
        let unit = v.kind.unit().map_or("", |u| u.name);
        let start = v.kind.start_text().unwrap_or_default();
        let causality = v.causality.name();
        rows += &format!(
            "<tr><td><code>{}</code></td><td>{causality}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n",
            escape(&v.name),
            escape(unit),
            escape(&start),
            escape(&v.description)
        );
    }
    format!(
        "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{name}</title>\
         <style>body{{font-family:sans-serif;max-width:60em;margin:auto}}td,th{{padding:2px 8px;text-align:left}}</style>\
         </head><body>\n<h1>{name}</h1>\n<p>{desc}</p>\n<h2>Equations</h2>\n{equations_html}\n\
         <h2>Variables</h2>\n<table>\n<tr><th>name</th><th>causality</th><th>unit</th><th>start</th><th>description</th></tr>\n{rows}</table>\n\
         <p>Generated by {tool}. {interface} <code>{guid}</code>.</p>\n</body></html>\n",
        name = escape(&d.model_name),
        desc = escape(&d.description),
        tool = escape(&d.generation_tool),
        guid = escape(&d.guid()),
    )
}
