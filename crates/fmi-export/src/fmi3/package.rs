//! Packing an FMI 3.0 `.fmu`: `modelDescription.xml` for FMI 3.0, the binaries in FMI 3.0's
//! platform folders (`x86_64-linux`, `x86_64-windows`, `x86_64-darwin`, `aarch64-darwin`,
//! `aarch64-linux`, …), resources and documentation.
//!
//! The binaries are given under their FMI 2.0 platform names, as the FMI 2.0 packager builds and
//! checks them (`linux64`, `win64`, `darwin64`, `aarch64-linux`): one library that carries
//! both the `fmi2*` and the `fmi3*` functions serves both twins. A universal macOS library
//! (`darwin64`, x86_64 + arm64) goes into both `x86_64-darwin` and `aarch64-darwin`, each
//! architecture a folder holding it; a thin one only into its own architecture's folder.

use std::path::Path;

use crate::package::{documentation_page, macho_architectures, read_binaries, write_archive, BinaryError};
use crate::ModelDescription;

/// The FMI 3.0 platform folders (section 2.5.1.2) of a library built for the FMI 2.0 platform
/// `platform`, given its bytes (a macOS library holds one or two architectures).
pub fn platform_folders(platform: &str, bytes: &[u8]) -> Result<Vec<&'static str>, BinaryError> {
    Ok(match platform {
        "linux64" => vec!["x86_64-linux"],
        "linux32" => vec!["x86-linux"],
        "win64" => vec!["x86_64-windows"],
        "win32" => vec!["x86-windows"],
        "aarch64-linux" => vec!["aarch64-linux"],
        "darwin32" => vec!["x86-darwin"],
        "darwin64" => {
            let mut folders = Vec::new();
            for (architecture, folder) in [("x86_64", "x86_64-darwin"), ("arm64", "aarch64-darwin")] {
                if macho_architectures(bytes)?.contains(&architecture) {
                    folders.push(folder);
                }
            }
            folders
        }
        other => return Err(BinaryError::NoFmi3Folder(other.to_owned())),
    })
}

/// Writes the FMI 3.0 twin of a model to `path`: like
/// [`crate::fmi2::write_fmu`] (the same binaries, checked the same way, the same
/// resources), with the FMI 3.0 model description and platform folders, and the library named
/// `<modelIdentifier>.<ext>` (FMI 3.0 has no `lib` prefix). Nothing is left at `path` on
/// failure.
pub fn write_fmu(
    path: &Path,
    description: &ModelDescription,
    binaries: &[(&str, &Path)],
    resources: &[(&str, Vec<u8>)],
    equations_html: &str,
) -> std::io::Result<()> {
    let mut libraries = Vec::new();
    for ((platform, extension, bytes), (_, binary)) in read_binaries(binaries)?.into_iter().zip(binaries) {
        let folders = platform_folders(platform, &bytes)
            .map_err(|e| std::io::Error::new(std::io::ErrorKind::InvalidInput, format!("{}: {e}", binary.display())))?;
        for folder in folders {
            libraries.push((format!("binaries/{folder}/{}.{extension}", description.model_identifier), bytes.clone()));
        }
    }
    let html = documentation_page(description, equations_html, "FMI 3.0 Co-Simulation; instantiation token");
    write_archive(path, &super::description::to_xml(description), &libraries, resources, &html)
}
