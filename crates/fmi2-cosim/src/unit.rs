//! One loaded FMU: the unpacked archive (kept alive for its binary) and its instance, over
//! the `fmi` crate.
//!
//! The archive is unpacked here and the `fmi` crate is given a minimal model description
//! (GUID and model identifier, all it uses to load and instantiate): its own XML parser
//! refuses some documents the standard allows (`<Annotations>` in a variable,
//! `canHandleMultipleSetPerTimeInstant`, unknown vendor attributes), and everything else the
//! master needs it has already read itself ([`crate::interface`]).

use std::fmt;
use std::path::Path;

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
    /// Unpacks and instantiates the FMU of `plan` under the unit's name.
    pub fn load(plan: &UnitPlan) -> Result<Self, MasterError> {
        capture::install();
        let err = |m: String| MasterError::new(m).unit(&plan.name);
        let path = &plan.path;
        let dir = unpack(path).map_err(|e| err(format!("cannot load {}: {e}", path.display())))?;
        let interface = &plan.interface;
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
