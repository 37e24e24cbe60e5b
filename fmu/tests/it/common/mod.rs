//! A minimal FMI 2.0 host for tests: loads the FMU binary with `dlopen` (libloading), sets up
//! an unpacked FMU folder, and captures log messages.
#![allow(dead_code, non_snake_case)]

use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use neurarm_fmi_export::description::{BaseType, ModelDescription};
use neurarm_models::{FmuSpec, SPEC_FILE};
use neurarm_nn::NetKind;

pub use nets::{net, signal};
use neurarm_test_support::nets;

pub const OK: c_int = 0;
pub const ERROR: c_int = 3;
pub const FATAL: c_int = 4;

/// The FMU binary of this package in the profile folder of the test program
/// (`target/<profile>/deps/<test>` → `target/<profile>`). `cargo test` does not rebuild a
/// cdylib, so `cargo build` first (scripts/test does).
pub fn binary_path() -> PathBuf {
    let exe = std::env::current_exe().expect("the test program's path");
    let profile = exe.parent().and_then(Path::parent).expect("target/<profile>/deps");
    let p = profile.join("libneurarm_fmu.so");
    assert!(p.is_file(), "{} is missing: run `cargo build -p neurarm-fmu` in this profile first (scripts/test does)", p.display());
    p
}

type Logger = unsafe extern "C" fn(*mut c_void, *const c_char, c_int, *const c_char, *const c_char);

#[repr(C)]
pub struct Callbacks {
    pub logger: Option<Logger>,
    pub allocate: *const c_void,
    pub free: *const c_void,
    pub step_finished: *const c_void,
    pub environment: *mut c_void,
}

/// Log messages an instance sent: (status, category, message).
#[derive(Default)]
pub struct Log(pub Mutex<Vec<(c_int, String, String)>>);

impl Log {
    pub fn take(&self) -> Vec<(c_int, String, String)> {
        std::mem::take(&mut *self.0.lock().unwrap())
    }
    pub fn contains(&self, text: &str) -> bool {
        self.0.lock().unwrap().iter().any(|(_, _, m)| m.contains(text))
    }
    pub fn dump(&self) -> String {
        self.0.lock().unwrap().iter().map(|(s, c, m)| format!("[{s} {c}] {m}")).collect::<Vec<_>>().join("\n")
    }
}

/// A non-variadic logger: the host receives the message as the format string (the FMU
/// escapes '%'), as fmpy's ctypes logger does.
unsafe extern "C" fn capture(env: *mut c_void, _name: *const c_char, status: c_int, category: *const c_char, message: *const c_char) {
    // SAFETY: `env` is the component environment `instantiate_with` gave: a `Log` in a box
    // kept beside the instance, which outlives every call on it that can log.
    let log = unsafe { &*(env as *const Log) };
    // SAFETY: the FMU logs with category and message NULL or NUL-terminated strings that live
    // until this callback returns.
    let s = |p: *const c_char| if p.is_null() { String::new() } else { unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned() };
    log.0.lock().unwrap().push((status, s(category), s(message).replace("%%", "%")));
}

macro_rules! api {
    ($($name:ident: $ty:ty;)*) => {
        #[allow(non_snake_case)]
        pub struct Api { $(pub $name: $ty,)* _lib: libloading::Library }
        impl Api {
            pub fn load(path: &Path) -> Api {
                // SAFETY: the library is this package's FMU binary, whose initialisers are Rust's
                // own; each symbol is read as a function type of the ABI the FMI 2.0 header gives
                // it (`c_int` for its enums, `u8` for `fmi2Byte`; the export layer checks its
                // functions against the header), and the library stays loaded in `_lib` as long
                // as the pointers are kept.
                unsafe {
                    let lib = libloading::Library::new(path).expect("dlopen the FMU binary");
                    $(let $name: $ty = *lib.get::<$ty>(concat!(stringify!($name), "\0").as_bytes()).expect(stringify!($name));)*
                    Api { $($name,)* _lib: lib }
                }
            }
        }
    };
}

type C = *mut c_void;
api! {
    fmi2GetTypesPlatform: unsafe extern "C" fn() -> *const c_char;
    fmi2GetVersion: unsafe extern "C" fn() -> *const c_char;
    fmi2SetDebugLogging: unsafe extern "C" fn(C, c_int, usize, *const *const c_char) -> c_int;
    fmi2Instantiate: unsafe extern "C" fn(*const c_char, c_int, *const c_char, *const c_char, *const Callbacks, c_int, c_int) -> C;
    fmi2FreeInstance: unsafe extern "C" fn(C);
    fmi2SetupExperiment: unsafe extern "C" fn(C, c_int, f64, f64, c_int, f64) -> c_int;
    fmi2EnterInitializationMode: unsafe extern "C" fn(C) -> c_int;
    fmi2ExitInitializationMode: unsafe extern "C" fn(C) -> c_int;
    fmi2Terminate: unsafe extern "C" fn(C) -> c_int;
    fmi2Reset: unsafe extern "C" fn(C) -> c_int;
    fmi2GetReal: unsafe extern "C" fn(C, *const u32, usize, *mut f64) -> c_int;
    fmi2GetInteger: unsafe extern "C" fn(C, *const u32, usize, *mut c_int) -> c_int;
    fmi2GetBoolean: unsafe extern "C" fn(C, *const u32, usize, *mut c_int) -> c_int;
    fmi2GetString: unsafe extern "C" fn(C, *const u32, usize, *mut *const c_char) -> c_int;
    fmi2SetReal: unsafe extern "C" fn(C, *const u32, usize, *const f64) -> c_int;
    fmi2SetInteger: unsafe extern "C" fn(C, *const u32, usize, *const c_int) -> c_int;
    fmi2SetBoolean: unsafe extern "C" fn(C, *const u32, usize, *const c_int) -> c_int;
    fmi2SetString: unsafe extern "C" fn(C, *const u32, usize, *const *const c_char) -> c_int;
    fmi2GetFMUstate: unsafe extern "C" fn(C, *mut C) -> c_int;
    fmi2SetFMUstate: unsafe extern "C" fn(C, C) -> c_int;
    fmi2FreeFMUstate: unsafe extern "C" fn(C, *mut C) -> c_int;
    fmi2SerializedFMUstateSize: unsafe extern "C" fn(C, C, *mut usize) -> c_int;
    fmi2SerializeFMUstate: unsafe extern "C" fn(C, C, *mut u8, usize) -> c_int;
    fmi2DeSerializeFMUstate: unsafe extern "C" fn(C, *const u8, usize, *mut C) -> c_int;
    fmi2GetDirectionalDerivative: unsafe extern "C" fn(C, *const u32, usize, *const u32, usize, *const f64, *mut f64) -> c_int;
    fmi2SetRealInputDerivatives: unsafe extern "C" fn(C, *const u32, usize, *const c_int, *const f64) -> c_int;
    fmi2GetRealOutputDerivatives: unsafe extern "C" fn(C, *const u32, usize, *const c_int, *mut f64) -> c_int;
    fmi2DoStep: unsafe extern "C" fn(C, f64, f64, c_int) -> c_int;
    fmi2CancelStep: unsafe extern "C" fn(C) -> c_int;
    fmi2GetStatus: unsafe extern "C" fn(C, c_int, *mut c_int) -> c_int;
    fmi2GetRealStatus: unsafe extern "C" fn(C, c_int, *mut f64) -> c_int;
    fmi2GetIntegerStatus: unsafe extern "C" fn(C, c_int, *mut c_int) -> c_int;
    fmi2GetBooleanStatus: unsafe extern "C" fn(C, c_int, *mut c_int) -> c_int;
    fmi2GetStringStatus: unsafe extern "C" fn(C, c_int, *mut *const c_char) -> c_int;
}

/// An unpacked FMU: the binary's API, a resources folder and the model description.
pub struct Fmu {
    pub api: Arc<Api>,
    pub dir: tempfile::TempDir,
    pub description: ModelDescription,
}

impl Fmu {
    pub fn new(spec: &FmuSpec) -> Fmu {
        let dir = tempfile::tempdir().unwrap();
        std::fs::create_dir(dir.path().join("resources")).unwrap();
        std::fs::write(dir.path().join("resources").join(SPEC_FILE), spec.to_toml()).unwrap();
        Fmu { api: Arc::new(Api::load(&binary_path())), dir, description: spec.description().unwrap() }
    }

    pub fn resources(&self) -> PathBuf {
        self.dir.path().join("resources")
    }

    pub fn resource_uri(&self) -> String {
        format!("file://{}", self.resources().display())
    }

    pub fn guid(&self) -> String {
        self.description.guid()
    }

    /// Value reference of the variable called `name`.
    pub fn vr(&self, name: &str) -> u32 {
        self.description.variables.iter().find(|v| v.name == name).unwrap_or_else(|| panic!("no variable {name}")).value_reference
    }

    pub fn base_type(&self, name: &str) -> BaseType {
        self.description.variables.iter().find(|v| v.name == name).unwrap().base_type()
    }

    /// Instantiates with the given GUID and resource URI; the log is kept with the instance.
    pub fn instantiate_with(&self, name: &str, guid: &str, uri: &str) -> (C, Box<Log>, Box<Callbacks>) {
        let log = Box::<Log>::default();
        let callbacks = Box::new(Callbacks {
            logger: Some(capture),
            allocate: std::ptr::null(),
            free: std::ptr::null(),
            step_finished: std::ptr::null(),
            environment: &*log as *const Log as *mut c_void,
        });
        let (name, guid, uri) = (CString::new(name).unwrap(), CString::new(guid).unwrap(), CString::new(uri).unwrap());
        // SAFETY: name, GUID and URI are NUL-terminated strings and `callbacks` a valid
        // `fmi2CallbackFunctions` whose environment is `log`; the strings outlive the call, the
        // callbacks and the log are returned with the component, whose holder keeps them.
        let c = unsafe { (self.api.fmi2Instantiate)(name.as_ptr(), 1, guid.as_ptr(), uri.as_ptr(), &*callbacks, 0, 0) };
        (c, log, callbacks)
    }

    pub fn instance(&self) -> Instance {
        let (c, log, callbacks) = self.instantiate_with("test", &self.guid(), &self.resource_uri());
        assert!(!c.is_null(), "instantiation failed: {}", log.dump());
        Instance { api: self.api.clone(), c, log, _callbacks: callbacks }
    }
}

/// A live instance; freed on drop. Its methods call the FMU's functions with well-formed
/// arguments and are safe: `c` is a component `api` instantiated, freed only on drop; `api`
/// keeps the library loaded; `log` and `_callbacks`, which the component's logger uses, live
/// as long as it. (Calls with hostile arguments are written out in the tests.)
pub struct Instance {
    pub api: Arc<Api>,
    pub c: C,
    pub log: Box<Log>,
    pub _callbacks: Box<Callbacks>,
}

// SAFETY: an FMI 2.0 component may be used from any thread, one call at a time; `Instance`
// is not `Sync`, so calls on one never overlap; the log the FMU writes to from the calling
// thread is a `Mutex`, and the library (`Arc<Api>`) is shared read-only.
unsafe impl Send for Instance {}

// In the methods below, "`self.c` is live" stands for `Instance`'s invariant: a component of
// `self.api`, not freed, with its logger's log and callbacks alive.
impl Instance {
    pub fn setup(&self) -> c_int {
        self.setup_experiment(None, 0.0, None)
    }
    /// `fmi2SetupExperiment` with the tolerance and stop time given or not.
    pub fn setup_experiment(&self, tolerance: Option<f64>, start: f64, stop: Option<f64>) -> c_int {
        let (tol, stop_time) = (tolerance.unwrap_or(0.0), stop.unwrap_or(0.0));
        // SAFETY: `self.c` is live; the rest are values.
        unsafe { (self.api.fmi2SetupExperiment)(self.c, tolerance.is_some() as _, tol, start, stop.is_some() as _, stop_time) }
    }
    pub fn enter(&self) -> c_int {
        // SAFETY: `self.c` is live.
        unsafe { (self.api.fmi2EnterInitializationMode)(self.c) }
    }
    pub fn exit(&self) -> c_int {
        // SAFETY: `self.c` is live.
        unsafe { (self.api.fmi2ExitInitializationMode)(self.c) }
    }
    /// Setup, enter and exit initialization.
    pub fn initialize(&self) {
        assert_eq!(self.setup(), OK, "{}", self.log.dump());
        assert_eq!(self.enter(), OK, "{}", self.log.dump());
        assert_eq!(self.exit(), OK, "{}", self.log.dump());
    }
    pub fn set_real(&self, vrs: &[u32], values: &[f64]) -> c_int {
        assert_eq!(vrs.len(), values.len(), "one value per reference");
        // SAFETY: `self.c` is live; `vrs` and `values` hold `vrs.len()` elements each and
        // outlive the call.
        unsafe { (self.api.fmi2SetReal)(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr()) }
    }
    pub fn get_real(&self, vrs: &[u32]) -> Result<Vec<f64>, c_int> {
        let mut out = vec![f64::NAN; vrs.len()];
        match self.get_real_into(vrs, &mut out) {
            OK => Ok(out),
            s => Err(s),
        }
    }
    /// `fmi2GetReal` of `vrs` into `out` (no allocation).
    pub fn get_real_into(&self, vrs: &[u32], out: &mut [f64]) -> c_int {
        assert_eq!(vrs.len(), out.len(), "one value per reference");
        // SAFETY: `self.c` is live; `vrs` and `out` hold `out.len()` elements each and outlive
        // the call; `out` is borrowed mutably, so the FMU's writes alias nothing.
        unsafe { (self.api.fmi2GetReal)(self.c, vrs.as_ptr(), out.len(), out.as_mut_ptr()) }
    }
    /// `fmi2GetInteger` of `vrs` into `out`.
    pub fn get_integer(&self, vrs: &[u32], out: &mut [c_int]) -> c_int {
        assert_eq!(vrs.len(), out.len(), "one value per reference");
        // SAFETY: as in `get_real_into`.
        unsafe { (self.api.fmi2GetInteger)(self.c, vrs.as_ptr(), out.len(), out.as_mut_ptr()) }
    }
    pub fn step(&self, t: f64, h: f64) -> c_int {
        // SAFETY: `self.c` is live; the rest are values.
        unsafe { (self.api.fmi2DoStep)(self.c, t, h, 1) }
    }
    pub fn terminate(&self) -> c_int {
        // SAFETY: `self.c` is live.
        unsafe { (self.api.fmi2Terminate)(self.c) }
    }
    pub fn reset(&self) -> c_int {
        // SAFETY: `self.c` is live.
        unsafe { (self.api.fmi2Reset)(self.c) }
    }
    /// `fmi2SetDebugLogging`; no categories are passed as NULL with n = 0.
    pub fn set_debug_logging(&self, on: bool, categories: &[&CStr]) -> c_int {
        let pointers: Vec<*const c_char> = categories.iter().map(|c| c.as_ptr()).collect();
        let array = if pointers.is_empty() { std::ptr::null() } else { pointers.as_ptr() };
        // SAFETY: `self.c` is live; `array` is NULL with n = 0 or `pointers`, n NUL-terminated
        // strings borrowed from `categories`, all outliving the call.
        unsafe { (self.api.fmi2SetDebugLogging)(self.c, on as c_int, pointers.len(), array) }
    }
    /// `fmi2GetRealStatus` of `kind` into `value`.
    pub fn get_real_status(&self, kind: c_int, value: &mut f64) -> c_int {
        // SAFETY: `self.c` is live; `value` is a writable real that outlives the call.
        unsafe { (self.api.fmi2GetRealStatus)(self.c, kind, value) }
    }
    /// `fmi2GetBooleanStatus` of `kind` into `value`.
    pub fn get_boolean_status(&self, kind: c_int, value: &mut c_int) -> c_int {
        // SAFETY: `self.c` is live; `value` is a writable `fmi2Boolean` that outlives the call.
        unsafe { (self.api.fmi2GetBooleanStatus)(self.c, kind, value) }
    }
    /// `fmi2GetFMUstate`: a new state into `state` if it is NULL, else the state it holds
    /// overwritten.
    pub fn get_fmu_state(&self, state: &mut C) -> c_int {
        // SAFETY: `self.c` is live; `state` is a writable handle that outlives the call.
        unsafe { (self.api.fmi2GetFMUstate)(self.c, state) }
    }
    /// `fmi2SetFMUstate`. Any handle is sound to pass: the layer looks its handles up as
    /// numbers and never reads through one (a foreign one is refused).
    pub fn set_fmu_state(&self, state: C) -> c_int {
        // SAFETY: `self.c` is live; `state` is only compared with the instance's handles.
        unsafe { (self.api.fmi2SetFMUstate)(self.c, state) }
    }
    /// `fmi2FreeFMUstate`: frees `*state` and sets it to NULL.
    pub fn free_fmu_state(&self, state: &mut C) -> c_int {
        // SAFETY: `self.c` is live; `state` is a writable handle that outlives the call, its
        // value only compared with the instance's handles.
        unsafe { (self.api.fmi2FreeFMUstate)(self.c, state) }
    }
    /// `fmi2SerializedFMUstateSize` of `state` into `size`.
    pub fn serialized_fmu_state_size(&self, state: C, size: &mut usize) -> c_int {
        // SAFETY: `self.c` is live; `state` is only compared with the instance's handles;
        // `size` is writable and outlives the call.
        unsafe { (self.api.fmi2SerializedFMUstateSize)(self.c, state, size) }
    }
    /// `fmi2SerializeFMUstate` of `state` into `bytes` (its length is the size passed).
    pub fn serialize_fmu_state(&self, state: C, bytes: &mut [u8]) -> c_int {
        // SAFETY: `self.c` is live; `state` is only compared with the instance's handles;
        // `bytes` holds the `bytes.len()` writable bytes passed and outlives the call.
        unsafe { (self.api.fmi2SerializeFMUstate)(self.c, state, bytes.as_mut_ptr(), bytes.len()) }
    }
    /// `fmi2DeSerializeFMUstate` of `bytes` into `state` (a new state if it is NULL).
    pub fn deserialize_fmu_state(&self, bytes: &[u8], state: &mut C) -> c_int {
        // SAFETY: `self.c` is live; `bytes` holds the `bytes.len()` bytes passed and `state`
        // is a writable handle, both outliving the call.
        unsafe { (self.api.fmi2DeSerializeFMUstate)(self.c, bytes.as_ptr(), bytes.len(), state) }
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
        // SAFETY: `self.c` is live, and no call is made on it after this one.
        unsafe { (self.api.fmi2FreeInstance)(self.c) }
    }
}

/// An unpacked FMU of `model` whose `resources/` also hold four friction nets
/// (`friction_j.json`) and a gravity net (`gravity.json`) of [`net`], for the compensators.
pub fn fmu_with_nets(identifier: &str, model: neurarm_models::ModelSpec) -> Fmu {
    let dir = tempfile::tempdir().unwrap();
    let resources = dir.path().join("resources");
    std::fs::create_dir(&resources).unwrap();
    for j in 1..=4 {
        let file =
            net(NetKind::Friction, Some(j), vec![signal(format!("qd_{j}"), "rad/s")], vec![signal(format!("tau_friction_{j}"), "N.m")], 5);
        std::fs::write(resources.join(format!("friction_{j}.json")), file.to_json()).unwrap();
    }
    let gravity = net(
        NetKind::Gravity,
        None,
        (1..=4).map(|j| signal(format!("q_{j}"), "rad")).collect(),
        (1..=4).map(|j| signal(format!("tau_gravity_{j}"), "N.m")).collect(),
        6,
    );
    std::fs::write(resources.join("gravity.json"), gravity.to_json()).unwrap();
    let spec = FmuSpec { identifier: identifier.into(), model };
    std::fs::write(resources.join(SPEC_FILE), spec.to_toml()).unwrap();
    let description = spec.build_from(Some(&resources)).unwrap().description().clone();
    Fmu { api: Arc::new(Api::load(&binary_path())), dir, description }
}
