//! One loaded FMU: the unpacked archive (kept alive for its binary) and its instance, over
//! the `fmi` crate.
//!
//! The archive is unpacked here and the `fmi` crate is given a minimal model description
//! (GUID and model identifier, all it uses to load and instantiate): its own XML parser
//! refuses some documents the standard allows (`<Annotations>` in a variable,
//! `canHandleMultipleSetPerTimeInstant`, unknown vendor attributes), and everything else the
//! master needs it has already read itself ([`crate::interface`]).
//!
//! FMUs that carry the very same binary (byte for byte, as every FMU of one exporter's runtime
//! may) share one loaded copy: the unpacked file is a hard link to the first, so the dynamic
//! loader maps it once. Their instances are then instances of one library, which an FMU that
//! allows several instances per process must support anyway; one that declares
//! `canBeInstantiatedOnlyOncePerProcess` is never shared. One copy of the code keeps a loop of
//! such units in the processor's caches.

use std::fmt;
use std::path::{Path, PathBuf};

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::InstanceCS;
use fmi::traits::FmiImport;
use quick_xml::escape::escape;

use crate::capture;
use crate::error::MasterError;
use crate::system::UnitPlan;

/// The largest unpacked FMU accepted [bytes]: a damaged or hostile archive must not fill the
/// disk.
const MAX_UNPACKED_BYTES: u64 = 16 << 30;

/// An instantiated unit.
pub(crate) struct Unit {
    pub name: String,
    pub instance: InstanceCS,
    _import: Fmi2Import,
}

impl Unit {
    /// Unpacks and instantiates the FMU of `plan` under the unit's name; its binary is shared
    /// with an identical one in `shared` where it may be.
    pub fn load(plan: &UnitPlan, shared: &mut SharedBinaries) -> Result<Self, MasterError> {
        capture::install();
        let err = |m: String| MasterError::new(m).unit(&plan.name);
        let path = &plan.path;
        let dir = unpack(path).map_err(|e| err(format!("cannot load {}: {e}", path.display())))?;
        let interface = &plan.interface;
        if !interface.only_once_per_process {
            shared.share(&dir.path().join(binary_path(&interface.model_identifier)));
        }
        let description = format!(
            r#"<?xml version="1.0" encoding="UTF-8"?><fmiModelDescription fmiVersion="2.0" modelName="{id}" guid="{guid}"><CoSimulation modelIdentifier="{id}"/><ModelVariables/><ModelStructure/></fmiModelDescription>"#,
            id = escape(interface.model_identifier.as_str()),
            guid = escape(interface.guid.as_str()),
        );
        let import = Fmi2Import::new(dir, &description).map_err(|e| err(format!("cannot load {}: {e}", path.display())))?;
        let before = capture::mark();
        let instance = import.instantiate_cs(&plan.name, false, false).map_err(|e| {
            let mut x = err(format!("fmi2Instantiate of {} failed: {e}", path.display()));
            x.log = capture::since(before, &plan.name);
            x
        })?;
        Ok(Self { name: plan.name.clone(), instance, _import: import })
    }

    /// The error of a failed call `call`, with what the FMU logged since `since`.
    pub fn fail(&self, call: &str, status: impl fmt::Debug, since: usize, time: Option<f64>) -> MasterError {
        let mut e = MasterError::new(format!("{call} returned {status:?}")).unit(&self.name);
        e.time = time;
        e.log = capture::since(since, &self.name);
        e
    }
}

/// The binaries already unpacked, to share an identical one (see the module documentation).
#[derive(Default)]
pub(crate) struct SharedBinaries {
    /// (size, CRC-32, path) of each distinct binary so far.
    seen: Vec<(u64, u32, PathBuf)>,
}

impl SharedBinaries {
    /// Replaces the binary at `path` by a hard link to an identical one unpacked before, or
    /// remembers it. Anything that fails leaves the file as it was (then it is loaded on its
    /// own, as without sharing).
    fn share(&mut self, path: &Path) {
        let Ok(bytes) = std::fs::read(path) else { return };
        let (size, crc) = (bytes.len() as u64, crc32fast::hash(&bytes));
        let same = self
            .seen
            .iter()
            .filter(|(s, c, _)| (*s, *c) == (size, crc))
            .find(|(_, _, p)| std::fs::read(p).is_ok_and(|other| other == bytes))
            .map(|(_, _, p)| p.clone());
        match same {
            Some(first) => {
                let link = path.with_extension("shared");
                if std::fs::hard_link(&first, &link).is_ok() && std::fs::rename(&link, path).is_err() {
                    let _ = std::fs::remove_file(&link);
                }
            }
            None => self.seen.push((size, crc, path.to_owned())),
        }
    }
}

/// The path of an FMU's binary for this platform in its unpacked archive (FMI 2.0 names the
/// folders linux64, darwin64, win64; aarch64 Linux exporters use linux64 too).
fn binary_path(model_identifier: &str) -> PathBuf {
    let folder = match std::env::consts::OS {
        "windows" => "win64",
        "macos" => "darwin64",
        _ => "linux64",
    };
    Path::new("binaries").join(folder).join(format!("{model_identifier}{}", std::env::consts::DLL_SUFFIX))
}

/// The archive at `path` unpacked into a new temporary folder.
fn unpack(path: &Path) -> Result<tempfile::TempDir, String> {
    let file = std::fs::File::open(path).map_err(|e| e.to_string())?;
    let mut archive = zip::ZipArchive::new(file).map_err(|e| format!("it is not an FMU (not a zip archive: {e})"))?;
    let mut total: u64 = 0;
    for i in 0..archive.len() {
        let entry = archive.by_index_raw(i).map_err(|e| e.to_string())?;
        total = total.saturating_add(entry.size());
    }
    if total > MAX_UNPACKED_BYTES {
        return Err(format!("it would unpack to {total} bytes, more than the {} GiB allowed", MAX_UNPACKED_BYTES >> 30));
    }
    let dir = tempfile::Builder::new().prefix("fmi2-cosim-").tempdir().map_err(|e| format!("temporary folder: {e}"))?;
    archive.extract(dir.path()).map_err(|e| format!("unpacking: {e}"))?;
    Ok(dir)
}
