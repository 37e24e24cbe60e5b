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

use std::collections::HashMap;
use std::ffi::CString;
use std::path::{Path, PathBuf};

use fmi::fmi2::import::Fmi2Import;
use fmi::fmi2::instance::{CoSimulation as _, Common as _, InstanceCS as Fmi2Instance};
use fmi::fmi2::Fmi2Error;
use fmi::fmi3::import::Fmi3Import;
use fmi::fmi3::instance::InstanceCS as Fmi3Instance;
use fmi::fmi3::{CoSimulation as _, Common as _, Fmi3Error, Fmi3Model as _, GetSet as _};
use fmi::traits::FmiImport;
use quick_xml::escape::escape;

use crate::capture;
use crate::error::{DiscardedStep, FmuFileError, FmuProblem, MasterError};
use crate::interface::{BaseType, FmiVersion};
use crate::system::UnitPlan;

/// The largest unpacked FMU accepted [bytes]: a damaged or hostile archive must not fill the
/// disk.
const MAX_UNPACKED_BYTES: u64 = 16 << 30;

/// A failed call into a unit: the function called and the status it returned (or why the
/// master did not pass a value on).
#[derive(Debug)]
pub(crate) struct CallError {
    pub call: String,
    pub status: String,
}

impl CallError {
    fn new(call: impl Into<String>, status: impl std::fmt::Debug) -> Self {
        Self { call: call.into(), status: format!("{status:?}") }
    }
}

/// How a step ended that did not fail.
pub(crate) enum Stepped {
    Completed,
    /// The step completed (its outputs are valid at its end) and the unit asks to end the
    /// simulation (FMI 3.0 `terminateSimulation` with `fmi3OK`).
    CompletedEnding,
    /// The unit discarded the step or asked to end the simulation.
    Discarded(DiscardedStep),
}

/// The instance behind a unit, of either version. The master passes values in four access
/// classes ([`BaseType::access`]): f64, i64, Boolean as 0/1 and strings; FMI 3.0 units
/// dispatch each value reference to its own type's function.
// Both boxed: the fmi crate's instances are large and of different sizes.
enum Instance {
    V2(Box<Fmi2Instance>),
    V3 {
        instance: Box<Fmi3Instance>,
        /// Value reference → type.
        types: HashMap<u32, BaseType>,
    },
}

/// An instantiated unit.
pub(crate) struct Unit {
    pub name: String,
    instance: Instance,
    /// Scratch for FMI 2.0 integer and Boolean calls.
    scratch: Vec<i32>,
    /// Scratch for FMI 3.0 Boolean calls (C `bool`s), kept so a step allocates nothing.
    booleans: Vec<bool>,
    /// The import (its unpacked folder and library), kept while the instance lives.
    _import: Box<dyn std::any::Any>,
}

impl Unit {
    /// Unpacks and instantiates the FMU of `plan` under the unit's name; its binary is shared
    /// with an identical one in `shared` where it may be.
    pub fn load(plan: &UnitPlan, shared: &mut SharedBinaries) -> Result<Self, MasterError> {
        capture::install();
        let err = |m: String| MasterError::new(m).unit(&plan.name);
        let path = &plan.path;
        let dir = unpack(path).map_err(|e| err(e.to_string()))?;
        let interface = &plan.interface;
        let version = interface.fmi_version;
        if !interface.only_once_per_process {
            shared.share(&dir.path().join(binary_path(version, &interface.model_identifier)));
        }
        let (id, token) = (escape(interface.model_identifier.as_str()), escape(interface.guid.as_str()));
        let loading = |e: fmi::Error| err(format!("cannot load {}: {e}", path.display()));
        let before = capture::mark();
        let instantiation = |e: fmi::Error, call: &str| {
            let mut x = err(format!("{call} of {} failed: {e}", path.display()));
            x.log = capture::since(before, &plan.name);
            x
        };
        let (instance, import) = match version {
            FmiVersion::V2 => {
                let description = format!(
                    r#"<?xml version="1.0" encoding="UTF-8"?><fmiModelDescription fmiVersion="2.0" modelName="{id}" guid="{token}"><CoSimulation modelIdentifier="{id}"/><ModelVariables/><ModelStructure/></fmiModelDescription>"#
                );
                let import = Fmi2Import::new(dir, &description).map_err(loading)?;
                let instance = import.instantiate_cs(&plan.name, false, false).map_err(|e| instantiation(e, "fmi2Instantiate"))?;
                (Instance::V2(Box::new(instance)), Box::new(import) as Box<dyn std::any::Any>)
            }
            FmiVersion::V3 => {
                let description = format!(
                    r#"<?xml version="1.0" encoding="UTF-8"?><fmiModelDescription fmiVersion="3.0" modelName="{id}" instantiationToken="{token}"><CoSimulation modelIdentifier="{id}"/><ModelVariables/><ModelStructure/></fmiModelDescription>"#
                );
                let import = Fmi3Import::new(dir, &description).map_err(loading)?;
                // No event mode, no early return, no intermediate update: plain Co-Simulation.
                let instance = import
                    .instantiate_cs(&plan.name, false, false, false, false, &[])
                    .map_err(|e| instantiation(e, "fmi3InstantiateCoSimulation"))?;
                let types = interface.variables.iter().map(|v| (v.value_reference, v.base)).collect();
                (Instance::V3 { instance: Box::new(instance), types }, Box::new(import) as Box<dyn std::any::Any>)
            }
        };
        Ok(Self { name: plan.name.clone(), instance, scratch: Vec::new(), booleans: Vec::new(), _import: import })
    }

    /// The FMI version of the unit's API.
    pub fn version(&self) -> FmiVersion {
        match self.instance {
            Instance::V2(_) => FmiVersion::V2,
            Instance::V3 { .. } => FmiVersion::V3,
        }
    }

    /// The error of a failed call, with what the FMU logged since `since`.
    pub fn fail(&self, e: CallError, since: usize, time: Option<f64>) -> MasterError {
        let mut x = MasterError::new(format!("{} returned {}", e.call, e.status)).unit(&self.name);
        x.time = time;
        x.log = capture::since(since, &self.name);
        x
    }

    /// FMI 2.0: `fmi2SetupExperiment` from `start` [s]; FMI 3.0 gives the start time on
    /// entering initialization instead.
    pub fn setup(&mut self, start: f64) -> Result<(), CallError> {
        match &mut self.instance {
            Instance::V2(i) => i.setup_experiment(None, start, None).map(drop).map_err(|e| CallError::new("fmi2SetupExperiment", e)),
            Instance::V3 { .. } => Ok(()),
        }
    }

    /// Enters initialization mode (FMI 3.0: with start time `start` [s], no stop time).
    pub fn enter_initialization(&mut self, start: f64) -> Result<(), CallError> {
        match &mut self.instance {
            Instance::V2(i) => i.enter_initialization_mode().map(drop).map_err(|e| CallError::new("fmi2EnterInitializationMode", e)),
            Instance::V3 { instance, .. } => instance
                .enter_initialization_mode(None, start, None)
                .map(drop)
                .map_err(|e| CallError::new("fmi3EnterInitializationMode", e)),
        }
    }

    /// Leaves initialization mode (FMI 3.0: into step mode, as event mode is not used).
    pub fn exit_initialization(&mut self) -> Result<(), CallError> {
        match &mut self.instance {
            Instance::V2(i) => i.exit_initialization_mode().map(drop).map_err(|e| CallError::new("fmi2ExitInitializationMode", e)),
            Instance::V3 { instance, .. } => {
                instance.exit_initialization_mode().map(drop).map_err(|e| CallError::new("fmi3ExitInitializationMode", e))
            }
        }
    }

    /// One communication step from `t` by `h` [s].
    pub fn do_step(&mut self, t: f64, h: f64) -> Result<Stepped, CallError> {
        match &mut self.instance {
            Instance::V2(i) => match i.do_step(t, h, true) {
                Ok(_) => Ok(Stepped::Completed),
                Err(Fmi2Error::Discard) => Ok(Stepped::Discarded(DiscardedStep {
                    last_successful_time: i.last_successful_time().ok(),
                    terminated: i.terminated().ok(),
                })),
                Err(e) => Err(CallError::new("fmi2DoStep", e)),
            },
            Instance::V3 { instance, .. } => {
                let (mut event, mut terminate, mut early, mut last) = (false, false, false, t);
                match instance.do_step(t, h, true, &mut event, &mut terminate, &mut early, &mut last) {
                    Ok(_) if terminate => Ok(Stepped::CompletedEnding),
                    Ok(_) => Ok(Stepped::Completed),
                    Err(Fmi3Error::Discard) => {
                        Ok(Stepped::Discarded(DiscardedStep { last_successful_time: Some(last), terminated: Some(terminate) }))
                    }
                    Err(e) => Err(CallError::new("fmi3DoStep", e)),
                }
            }
        }
    }

    /// Reads Real-class variables (FMI 2.0 Real; FMI 3.0 Float64, Float32).
    pub fn get_real(&mut self, vrs: &[u32], out: &mut [f64]) -> Result<(), CallError> {
        match &mut self.instance {
            Instance::V2(i) => i.get_real(vrs, out).map(drop).map_err(|e| CallError::new("fmi2GetReal", e)),
            Instance::V3 { instance, types } => {
                if vrs.iter().all(|vr| types.get(vr) == Some(&BaseType::Float64)) {
                    return instance.get_float64(vrs, out).map(drop).map_err(|e| CallError::new("fmi3GetFloat64", e));
                }
                for (vr, o) in vrs.iter().zip(out.iter_mut()) {
                    *o = match types.get(vr) {
                        Some(BaseType::Float32) => {
                            let mut x = [0f32];
                            instance.get_float32(&[*vr], &mut x).map_err(|e| CallError::new("fmi3GetFloat32", e))?;
                            f64::from(x[0])
                        }
                        _ => {
                            let mut x = [0f64];
                            instance.get_float64(&[*vr], &mut x).map_err(|e| CallError::new("fmi3GetFloat64", e))?;
                            x[0]
                        }
                    };
                }
                Ok(())
            }
        }
    }

    /// Sets Real-class variables (a Float32 gets the nearest f32).
    pub fn set_real(&mut self, vrs: &[u32], values: &[f64]) -> Result<(), CallError> {
        match &mut self.instance {
            Instance::V2(i) => i.set_real(vrs, values).map(drop).map_err(|e| CallError::new("fmi2SetReal", e)),
            Instance::V3 { instance, types } => {
                if vrs.iter().all(|vr| types.get(vr) == Some(&BaseType::Float64)) {
                    return instance.set_float64(vrs, values).map(drop).map_err(|e| CallError::new("fmi3SetFloat64", e));
                }
                for (vr, &x) in vrs.iter().zip(values) {
                    match types.get(vr) {
                        Some(BaseType::Float32) => {
                            instance.set_float32(&[*vr], &[x as f32]).map(drop).map_err(|e| CallError::new("fmi3SetFloat32", e))?
                        }
                        _ => instance.set_float64(&[*vr], &[x]).map(drop).map_err(|e| CallError::new("fmi3SetFloat64", e))?,
                    }
                }
                Ok(())
            }
        }
    }

    /// Reads Integer-class variables (integers of every width, enumerations).
    pub fn get_integer(&mut self, vrs: &[u32], out: &mut [i64]) -> Result<(), CallError> {
        match &mut self.instance {
            Instance::V2(i) => {
                self.scratch.resize(vrs.len(), 0);
                i.get_integer(vrs, &mut self.scratch).map_err(|e| CallError::new("fmi2GetInteger", e))?;
                for (o, &x) in out.iter_mut().zip(&self.scratch) {
                    *o = x.into();
                }
                Ok(())
            }
            Instance::V3 { instance, types } => {
                for (vr, o) in vrs.iter().zip(out.iter_mut()) {
                    let base = types.get(vr).copied().unwrap_or(BaseType::Int64);
                    *o = get_fmi3_integer(instance, *vr, base)?;
                }
                Ok(())
            }
        }
    }

    /// Sets Integer-class variables; a value outside the variable's type is refused.
    pub fn set_integer(&mut self, vrs: &[u32], values: &[i64]) -> Result<(), CallError> {
        match &mut self.instance {
            Instance::V2(i) => {
                self.scratch.clear();
                for &x in values {
                    let x = i32::try_from(x)
                        .map_err(|_| CallError::new("fmi2SetInteger", format_args!("not called: {x} does not fit an fmi2Integer")))?;
                    self.scratch.push(x);
                }
                i.set_integer(vrs, &self.scratch).map(drop).map_err(|e| CallError::new("fmi2SetInteger", e))
            }
            Instance::V3 { instance, types } => {
                for (vr, &x) in vrs.iter().zip(values) {
                    let base = types.get(vr).copied().unwrap_or(BaseType::Int64);
                    set_fmi3_integer(instance, *vr, base, x)?;
                }
                Ok(())
            }
        }
    }

    /// Reads Booleans as 0 or 1.
    pub fn get_boolean(&mut self, vrs: &[u32], out: &mut [i32]) -> Result<(), CallError> {
        match &mut self.instance {
            Instance::V2(i) => i.get_boolean(vrs, out).map(drop).map_err(|e| CallError::new("fmi2GetBoolean", e)),
            Instance::V3 { instance, .. } => {
                self.booleans.clear();
                self.booleans.resize(vrs.len(), false);
                instance.get_boolean(vrs, &mut self.booleans).map_err(|e| CallError::new("fmi3GetBoolean", e))?;
                for (o, &b) in out.iter_mut().zip(&self.booleans) {
                    *o = i32::from(b);
                }
                Ok(())
            }
        }
    }

    /// Sets Booleans given as 0 (false) or anything else (true).
    pub fn set_boolean(&mut self, vrs: &[u32], values: &[i32]) -> Result<(), CallError> {
        match &mut self.instance {
            Instance::V2(i) => i.set_boolean(vrs, values).map(drop).map_err(|e| CallError::new("fmi2SetBoolean", e)),
            Instance::V3 { instance, .. } => {
                self.booleans.clear();
                self.booleans.extend(values.iter().map(|&b| b != 0));
                instance.set_boolean(vrs, &self.booleans).map(drop).map_err(|e| CallError::new("fmi3SetBoolean", e))
            }
        }
    }

    /// Reads strings.
    pub fn get_string(&mut self, vrs: &[u32], out: &mut [CString]) -> Result<(), CallError> {
        match &mut self.instance {
            Instance::V2(i) => i.get_string(vrs, out).map_err(|e| CallError::new("fmi2GetString", e)),
            Instance::V3 { instance, .. } => instance.get_string(vrs, out).map_err(|e| CallError::new("fmi3GetString", e)),
        }
    }

    /// Sets strings.
    pub fn set_string(&mut self, vrs: &[u32], values: &[CString]) -> Result<(), CallError> {
        match &mut self.instance {
            Instance::V2(i) => i.set_string(vrs, values).map_err(|e| CallError::new("fmi2SetString", e)),
            Instance::V3 { instance, .. } => instance.set_string(vrs, values).map_err(|e| CallError::new("fmi3SetString", e)),
        }
    }
}

/// Reads one FMI 3.0 integer or enumeration of type `base` as an i64.
fn get_fmi3_integer(instance: &mut Fmi3Instance, vr: u32, base: BaseType) -> Result<i64, CallError> {
    macro_rules! read {
        ($get:ident, $t:ty, $name:literal) => {{
            let mut x: [$t; 1] = [0];
            instance.$get(&[vr], &mut x).map_err(|e| CallError::new($name, e))?;
            i64::try_from(x[0]).map_err(|_| CallError::new($name, format_args!("read {}, more than the master passes on (i64)", x[0])))
        }};
    }
    match base {
        BaseType::Int8 => read!(get_int8, i8, "fmi3GetInt8"),
        BaseType::UInt8 => read!(get_uint8, u8, "fmi3GetUInt8"),
        BaseType::Int16 => read!(get_int16, i16, "fmi3GetInt16"),
        BaseType::UInt16 => read!(get_uint16, u16, "fmi3GetUInt16"),
        BaseType::Int32 => read!(get_int32, i32, "fmi3GetInt32"),
        BaseType::UInt32 => read!(get_uint32, u32, "fmi3GetUInt32"),
        BaseType::UInt64 => read!(get_uint64, u64, "fmi3GetUInt64"),
        // Int64, and enumerations, which FMI 3.0 reads as Int64.
        _ => read!(get_int64, i64, "fmi3GetInt64"),
    }
}

/// Sets one FMI 3.0 integer or enumeration of type `base`; a value outside it is refused.
fn set_fmi3_integer(instance: &mut Fmi3Instance, vr: u32, base: BaseType, x: i64) -> Result<(), CallError> {
    macro_rules! write {
        ($set:ident, $t:ty, $name:literal) => {{
            let v = <$t>::try_from(x).map_err(|_| CallError::new($name, format_args!("not called: {x} does not fit a {}", base.name())))?;
            instance.$set(&[vr], &[v]).map(drop).map_err(|e| CallError::new($name, e))
        }};
    }
    match base {
        BaseType::Int8 => write!(set_int8, i8, "fmi3SetInt8"),
        BaseType::UInt8 => write!(set_uint8, u8, "fmi3SetUInt8"),
        BaseType::Int16 => write!(set_int16, i16, "fmi3SetInt16"),
        BaseType::UInt16 => write!(set_uint16, u16, "fmi3SetUInt16"),
        BaseType::Int32 => write!(set_int32, i32, "fmi3SetInt32"),
        BaseType::UInt32 => write!(set_uint32, u32, "fmi3SetUInt32"),
        BaseType::UInt64 => write!(set_uint64, u64, "fmi3SetUInt64"),
        _ => write!(set_int64, i64, "fmi3SetInt64"),
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
/// folders linux64, darwin64, win64, and aarch64 Linux exporters use linux64 too; FMI 3.0
/// names them by architecture and system, x86_64-linux).
fn binary_path(version: FmiVersion, model_identifier: &str) -> PathBuf {
    let fmi3 = format!("{}-{}", std::env::consts::ARCH, if std::env::consts::OS == "macos" { "darwin" } else { std::env::consts::OS });
    let folder = match (version, std::env::consts::OS) {
        (FmiVersion::V3, _) => fmi3.as_str(),
        (_, "windows") => "win64",
        (_, "macos") => "darwin64",
        _ => "linux64",
    };
    Path::new("binaries").join(folder).join(format!("{model_identifier}{}", std::env::consts::DLL_SUFFIX))
}

/// The archive at `path` unpacked into a new temporary folder.
fn unpack(path: &Path) -> Result<tempfile::TempDir, FmuFileError> {
    let fail = |problem| FmuFileError { path: path.to_owned(), problem };
    let file = std::fs::File::open(path).map_err(|e| fail(FmuProblem::Open(e)))?;
    let mut archive = zip::ZipArchive::new(file).map_err(|e| fail(FmuProblem::NotZip(e)))?;
    let mut total: u64 = 0;
    for i in 0..archive.len() {
        let entry = archive.by_index_raw(i).map_err(|e| fail(FmuProblem::Entry(e)))?;
        total = total.saturating_add(entry.size());
    }
    if total > MAX_UNPACKED_BYTES {
        return Err(fail(FmuProblem::TooLarge { total, limit_gib: MAX_UNPACKED_BYTES >> 30 }));
    }
    let dir = tempfile::Builder::new().prefix("neurarm-cosim-").tempdir().map_err(|e| fail(FmuProblem::TempDir(e)))?;
    archive.extract(dir.path()).map_err(|e| fail(FmuProblem::Unpack(e)))?;
    Ok(dir)
}
