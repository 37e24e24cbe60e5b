//! A minimal FMI 2.0 host for tests: loads the FMU binary with `dlopen` (libloading), sets up
//! an unpacked FMU folder, and captures log messages.
#![allow(dead_code, non_snake_case)]

use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};

use fmi2_export::description::{BaseType, ModelDescription};
use neurarm_models::{FmuSpec, SPEC_FILE};
use neurarm_nn::NetKind;

#[path = "../../../crates/models/tests/support/nets.rs"]
mod nets;
pub use nets::{net, signal};

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
    let log = unsafe { &*(env as *const Log) };
    let s = |p: *const c_char| if p.is_null() { String::new() } else { unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned() };
    log.0.lock().unwrap().push((status, s(category), s(message).replace("%%", "%")));
}

macro_rules! api {
    ($($name:ident: $ty:ty;)*) => {
        #[allow(non_snake_case)]
        pub struct Api { $(pub $name: $ty,)* _lib: libloading::Library }
        impl Api {
            pub fn load(path: &Path) -> Api {
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
        let c = unsafe { (self.api.fmi2Instantiate)(name.as_ptr(), 1, guid.as_ptr(), uri.as_ptr(), &*callbacks, 0, 0) };
        (c, log, callbacks)
    }

    pub fn instance(&self) -> Instance {
        let (c, log, callbacks) = self.instantiate_with("test", &self.guid(), &self.resource_uri());
        assert!(!c.is_null(), "instantiation failed: {}", log.dump());
        Instance { api: self.api.clone(), c, log, _callbacks: callbacks }
    }
}

/// A live instance; freed on drop.
pub struct Instance {
    pub api: Arc<Api>,
    pub c: C,
    pub log: Box<Log>,
    pub _callbacks: Box<Callbacks>,
}

unsafe impl Send for Instance {}

impl Instance {
    pub fn setup(&self) -> c_int {
        unsafe { (self.api.fmi2SetupExperiment)(self.c, 0, 0.0, 0.0, 0, 0.0) }
    }
    pub fn enter(&self) -> c_int {
        unsafe { (self.api.fmi2EnterInitializationMode)(self.c) }
    }
    pub fn exit(&self) -> c_int {
        unsafe { (self.api.fmi2ExitInitializationMode)(self.c) }
    }
    /// Setup, enter and exit initialization.
    pub fn initialize(&self) {
        assert_eq!(self.setup(), OK, "{}", self.log.dump());
        assert_eq!(self.enter(), OK, "{}", self.log.dump());
        assert_eq!(self.exit(), OK, "{}", self.log.dump());
    }
    pub fn set_real(&self, vrs: &[u32], values: &[f64]) -> c_int {
        unsafe { (self.api.fmi2SetReal)(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr()) }
    }
    pub fn get_real(&self, vrs: &[u32]) -> Result<Vec<f64>, c_int> {
        let mut out = vec![f64::NAN; vrs.len()];
        match unsafe { (self.api.fmi2GetReal)(self.c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) } {
            OK => Ok(out),
            s => Err(s),
        }
    }
    pub fn step(&self, t: f64, h: f64) -> c_int {
        unsafe { (self.api.fmi2DoStep)(self.c, t, h, 1) }
    }
    pub fn terminate(&self) -> c_int {
        unsafe { (self.api.fmi2Terminate)(self.c) }
    }
    pub fn reset(&self) -> c_int {
        unsafe { (self.api.fmi2Reset)(self.c) }
    }
}

impl Drop for Instance {
    fn drop(&mut self) {
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
