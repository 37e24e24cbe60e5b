//! What a hostile host found (issue 42), through the C ABI of the FMU binary in both FMI
//! versions, as a host calls it: FMU states of other instances and models, made-up state
//! handles, steps that would leave the time where it can no longer advance, steps past the stop
//! time by more than rounding, blank instance names, the independent variable `time`, and a
//! compensator switched on for a part it has no nets for. Each case failed before its fix.

use crate::common;

use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::sync::{Arc, Mutex};

use common::{fmu_with_nets, Fmu, ERROR, OK};
use neurarm_models::{
    AdaptationLaw, AdaptiveCompensatorSpec, FmuSpec, GainSpec, IdealCompensatorSpec, IntegratorSpec, JointControllerSpec, ModelSpec,
    NnCompensatorSpec, TaskSpaceControllerSpec,
};
use neurarm_physics::arm::ArmParams;
use neurarm_physics::config::ArmConfig;
use neurarm_physics::control::TaskSpaceGains;

/// The compensator of `fmu_with_nets`' four friction nets and gravity net.
fn all_nets() -> NnCompensatorSpec {
    NnCompensatorSpec::of_nets(4, (1..=4).map(|j| format!("friction_{j}.json")).collect(), Some("gravity.json".into()))
}

/// One FMU of every model kind the binary serves.
fn every_kind() -> Vec<(&'static str, Fmu)> {
    let arm = ArmParams::default_four_link();
    let nets = |identifier: &str, model| fmu_with_nets(identifier, model);
    let plain = |spec: FmuSpec| Fmu::new(&spec);
    let spec = |identifier: &str, model| FmuSpec { identifier: identifier.into(), model };
    vec![
        ("PlanarArm", plain(FmuSpec::planar_arm("PlanarArm", ArmConfig::default()))),
        ("NnCompensator", nets("NnCompensator", ModelSpec::NnCompensator(all_nets()))),
        ("AdaptiveCompensator", nets("AdaptiveCompensator", ModelSpec::AdaptiveCompensator(all_nets().adaptive(AdaptationLaw::default())))),
        (
            "IdealCompensator",
            plain(spec(
                "IdealCompensator",
                ModelSpec::IdealCompensator(IdealCompensatorSpec { arm: arm.clone(), enable_friction: true, enable_gravity: true }),
            )),
        ),
        (
            "TaskSpaceController",
            plain(spec(
                "TaskSpaceController",
                ModelSpec::TaskSpaceController(TaskSpaceControllerSpec {
                    model: arm.clone().frictionless(),
                    gains: TaskSpaceGains::default(),
                    centre: [0.45, 0.1],
                    scale: 1.0,
                    q_start: vec![-0.4, 0.9, 0.7, 0.5],
                }),
            )),
        ),
        (
            "JointController",
            plain(spec(
                "JointController",
                ModelSpec::JointController(JointControllerSpec { joints: 4, kp: 50.0, kd: 2.0, use_sequence: false }),
            )),
        ),
        ("Integrator", plain(spec("Integrator", ModelSpec::Integrator(IntegratorSpec { y0: 0.5 })))),
        ("Gain", plain(spec("Gain", ModelSpec::Gain(GainSpec { k: 2.0 })))),
    ]
}

/// The FMI 3.0 functions these checks call, from the same binary.
#[allow(non_snake_case)]
struct Api3 {
    fmi3InstantiateCoSimulation: unsafe extern "C" fn(
        *const c_char,
        *const c_char,
        *const c_char,
        bool,
        bool,
        bool,
        bool,
        *const u32,
        usize,
        *mut c_void,
        Option<unsafe extern "C" fn(*mut c_void, c_int, *const c_char, *const c_char)>,
    ) -> *mut c_void,
    fmi3FreeInstance: unsafe extern "C" fn(*mut c_void),
    fmi3EnterInitializationMode: unsafe extern "C" fn(*mut c_void, bool, f64, f64, bool, f64) -> c_int,
    fmi3ExitInitializationMode: unsafe extern "C" fn(*mut c_void) -> c_int,
    fmi3Reset: unsafe extern "C" fn(*mut c_void) -> c_int,
    fmi3DoStep: unsafe extern "C" fn(*mut c_void, f64, f64, bool, *mut bool, *mut bool, *mut bool, *mut f64) -> c_int,
    fmi3GetFloat64: unsafe extern "C" fn(*mut c_void, *const u32, usize, *mut f64, usize) -> c_int,
    fmi3GetFMUState: unsafe extern "C" fn(*mut c_void, *mut *mut c_void) -> c_int,
    fmi3SetFMUState: unsafe extern "C" fn(*mut c_void, *mut c_void) -> c_int,
    fmi3FreeFMUState: unsafe extern "C" fn(*mut c_void, *mut *mut c_void) -> c_int,
    fmi3SerializedFMUStateSize: unsafe extern "C" fn(*mut c_void, *mut c_void, *mut usize) -> c_int,
    fmi3SerializeFMUState: unsafe extern "C" fn(*mut c_void, *mut c_void, *mut u8, usize) -> c_int,
    fmi3DeserializeFMUState: unsafe extern "C" fn(*mut c_void, *const u8, usize, *mut *mut c_void) -> c_int,
    _lib: libloading::Library,
}

impl Api3 {
    fn load() -> Arc<Api3> {
        // SAFETY: the library is this package's FMU binary, whose initialisers are Rust's own;
        // each symbol is read as a function type of the ABI the FMI 3.0 header gives it (`c_int`
        // for `fmi3Status`; the export layer checks its functions against the header), and the
        // library stays loaded in `_lib` as long as the pointers are kept.
        unsafe {
            let lib = libloading::Library::new(common::binary_path()).expect("dlopen the FMU binary");
            macro_rules! get {
                ($name:ident) => {
                    *lib.get(concat!(stringify!($name), "\0").as_bytes()).expect(stringify!($name))
                };
            }
            Arc::new(Api3 {
                fmi3InstantiateCoSimulation: get!(fmi3InstantiateCoSimulation),
                fmi3FreeInstance: get!(fmi3FreeInstance),
                fmi3EnterInitializationMode: get!(fmi3EnterInitializationMode),
                fmi3ExitInitializationMode: get!(fmi3ExitInitializationMode),
                fmi3Reset: get!(fmi3Reset),
                fmi3DoStep: get!(fmi3DoStep),
                fmi3GetFloat64: get!(fmi3GetFloat64),
                fmi3GetFMUState: get!(fmi3GetFMUState),
                fmi3SetFMUState: get!(fmi3SetFMUState),
                fmi3FreeFMUState: get!(fmi3FreeFMUState),
                fmi3SerializedFMUStateSize: get!(fmi3SerializedFMUStateSize),
                fmi3SerializeFMUState: get!(fmi3SerializeFMUState),
                fmi3DeserializeFMUState: get!(fmi3DeserializeFMUState),
                _lib: lib,
            })
        }
    }
}

/// The messages an FMI 3.0 instance logged.
type Log3 = Mutex<Vec<(c_int, String)>>;

unsafe extern "C" fn capture3(env: *mut c_void, status: c_int, _category: *const c_char, message: *const c_char) {
    // SAFETY: `env` is the instance environment `Probe::named` gave: its boxed `Log3`, which
    // the probe keeps until after it frees the instance.
    let log = unsafe { &*(env as *const Log3) };
    // SAFETY: the FMU logs with `message` a NUL-terminated string that lives until this
    // callback returns.
    log.lock().unwrap().push((status, unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned()));
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Version {
    Fmi2,
    Fmi3,
}

/// An instance of an FMU in one FMI version, as a host drives it; freed on drop. In FMI 3.0,
/// `c3` is an instance of `api3` (not NULL), its logger's environment `log3`, freed only on
/// drop; in FMI 2.0, `fmi2` holds the instance and `c3` is NULL.
struct Probe {
    version: Version,
    fmi2: Option<common::Instance>,
    api3: Arc<Api3>,
    c3: *mut c_void,
    log3: Box<Log3>,
    /// FMI 2.0 value reference of `time` and its FMI 3.0 one.
    time_vr: (u32, u32),
}

impl Probe {
    fn new(fmu: &Fmu, api3: &Arc<Api3>, version: Version) -> Probe {
        Probe::named(fmu, api3, version, "probe").expect("instantiated")
    }

    /// An instance called `name`, or the messages of a refusal.
    fn named(fmu: &Fmu, api3: &Arc<Api3>, version: Version, name: &str) -> Result<Probe, String> {
        let time_vr = (fmu.vr("time"), fmu.description.variables.iter().position(|v| v.name == "time").unwrap() as u32);
        let log3 = Box::<Log3>::default();
        let (mut fmi2, mut c3) = (None, std::ptr::null_mut());
        match version {
            Version::Fmi2 => {
                let (c, log, callbacks) = fmu.instantiate_with(name, &fmu.guid(), &fmu.resource_uri());
                if c.is_null() {
                    return Err(log.dump());
                }
                fmi2 = Some(common::Instance { api: fmu.api.clone(), c, log, _callbacks: callbacks });
            }
            Version::Fmi3 => {
                let (n, token) = (CString::new(name).unwrap(), CString::new(fmu.guid()).unwrap());
                let path = CString::new(format!("{}/", fmu.resources().display())).unwrap();
                let env = &*log3 as *const Log3 as *mut c_void;
                // SAFETY: name, token and path are NUL-terminated strings that outlive the call;
                // no required variables (NULL, 0); `env` is `log3`, which the probe keeps, and
                // `capture3` the logger that reads it.
                c3 = unsafe {
                    (api3.fmi3InstantiateCoSimulation)(
                        n.as_ptr(),
                        token.as_ptr(),
                        path.as_ptr(),
                        false,
                        false,
                        false,
                        false,
                        std::ptr::null(),
                        0,
                        env,
                        Some(capture3),
                    )
                };
                if c3.is_null() {
                    return Err(log3.lock().unwrap().iter().map(|(_, m)| m.clone()).collect::<Vec<_>>().join("\n"));
                }
            }
        }
        Ok(Probe { version, fmi2, api3: api3.clone(), c3, log3, time_vr })
    }

    fn log(&self) -> String {
        match &self.fmi2 {
            Some(i) => i.log.dump(),
            None => self.log3.lock().unwrap().iter().map(|(s, m)| format!("[{s}] {m}")).collect::<Vec<_>>().join("\n"),
        }
    }

    fn clear_log(&self) {
        match &self.fmi2 {
            Some(i) => drop(i.log.take()),
            None => self.log3.lock().unwrap().clear(),
        }
    }

    /// Initializes at `start` with an optional stop time.
    fn initialize(&self, start: f64, stop: Option<f64>) {
        let status = match &self.fmi2 {
            Some(i) => {
                assert_eq!(i.setup_experiment(None, start, stop), OK, "{}", self.log());
                assert_eq!(i.enter(), OK);
                i.exit()
            }
            // SAFETY: `self.c3` is a live FMI 3.0 instance (the probe's invariant); the rest
            // are values.
            None => unsafe {
                let s = (self.api3.fmi3EnterInitializationMode)(self.c3, false, 0.0, start, stop.is_some(), stop.unwrap_or(0.0));
                assert_eq!(s, OK, "{}", self.log());
                (self.api3.fmi3ExitInitializationMode)(self.c3)
            },
        };
        assert_eq!(status, OK, "{}", self.log());
    }

    fn reset(&self) -> c_int {
        match &self.fmi2 {
            Some(i) => i.reset(),
            // SAFETY: `self.c3` is a live FMI 3.0 instance (the probe's invariant).
            None => unsafe { (self.api3.fmi3Reset)(self.c3) },
        }
    }

    fn step(&self, t: f64, h: f64) -> c_int {
        match &self.fmi2 {
            Some(i) => i.step(t, h),
            None => {
                let (mut event, mut terminate, mut early, mut last) = (false, false, false, f64::NAN);
                // SAFETY: `self.c3` is a live FMI 3.0 instance (the probe's invariant); the four
                // outputs are writable locals that outlive the call.
                unsafe { (self.api3.fmi3DoStep)(self.c3, t, h, true, &mut event, &mut terminate, &mut early, &mut last) }
            }
        }
    }

    /// The instance's time, as `time` reads.
    fn time(&self) -> f64 {
        let mut t = f64::NAN;
        let status = match &self.fmi2 {
            Some(i) => i.get_real_into(&[self.time_vr.0], std::slice::from_mut(&mut t)),
            // SAFETY: `self.c3` is a live FMI 3.0 instance (the probe's invariant); one value
            // reference and room for one value, both outliving the call.
            None => unsafe { (self.api3.fmi3GetFloat64)(self.c3, &self.time_vr.1, 1, &mut t, 1) },
        };
        assert_eq!(status, OK, "{}", self.log());
        t
    }

    fn get_state(&self, state: &mut *mut c_void) -> c_int {
        match &self.fmi2 {
            Some(i) => i.get_fmu_state(state),
            // SAFETY: `self.c3` is a live FMI 3.0 instance (the probe's invariant); `state` is a
            // writable handle that outlives the call.
            None => unsafe { (self.api3.fmi3GetFMUState)(self.c3, state) },
        }
    }

    fn set_state(&self, state: *mut c_void) -> c_int {
        match &self.fmi2 {
            Some(i) => i.set_fmu_state(state),
            // SAFETY: `self.c3` is a live FMI 3.0 instance (the probe's invariant); `state`, of
            // whatever origin, is only compared with the instance's handles (which is what the
            // tests of foreign states check), never read through.
            None => unsafe { (self.api3.fmi3SetFMUState)(self.c3, state) },
        }
    }

    fn free_state(&self, state: &mut *mut c_void) -> c_int {
        match &self.fmi2 {
            Some(i) => i.free_fmu_state(state),
            // SAFETY: `self.c3` is a live FMI 3.0 instance (the probe's invariant); `state` is a
            // writable handle that outlives the call, its value only compared with the
            // instance's handles.
            None => unsafe { (self.api3.fmi3FreeFMUState)(self.c3, state) },
        }
    }

    fn serialize(&self, state: *mut c_void) -> Result<Vec<u8>, c_int> {
        let mut size = 0;
        let status = match &self.fmi2 {
            Some(i) => i.serialized_fmu_state_size(state, &mut size),
            // SAFETY: `self.c3` is a live FMI 3.0 instance (the probe's invariant); `state` is
            // only compared with its handles; `size` is a writable local.
            None => unsafe { (self.api3.fmi3SerializedFMUStateSize)(self.c3, state, &mut size) },
        };
        if status != OK {
            return Err(status);
        }
        let mut bytes = vec![0u8; size];
        let status = match &self.fmi2 {
            Some(i) => i.serialize_fmu_state(state, &mut bytes),
            // SAFETY: `self.c3` is a live FMI 3.0 instance (the probe's invariant); `state` is
            // only compared with its handles; `bytes` holds the `size` writable bytes passed.
            None => unsafe { (self.api3.fmi3SerializeFMUState)(self.c3, state, bytes.as_mut_ptr(), size) },
        };
        if status == OK {
            Ok(bytes)
        } else {
            Err(status)
        }
    }

    fn deserialize(&self, bytes: &[u8], state: &mut *mut c_void) -> c_int {
        match &self.fmi2 {
            Some(i) => i.deserialize_fmu_state(bytes, state),
            // SAFETY: `self.c3` is a live FMI 3.0 instance (the probe's invariant); `bytes` holds
            // the `bytes.len()` bytes passed and `state` is a writable handle, both outliving
            // the call.
            None => unsafe { (self.api3.fmi3DeserializeFMUState)(self.c3, bytes.as_ptr(), bytes.len(), state) },
        }
    }

    /// Asserts that the last call was refused with `fmi*Error` and a log entry holding `text`.
    fn refused(&self, status: c_int, text: &str, what: &str) {
        assert_eq!(status, ERROR, "{what}: {}", self.log());
        assert!(self.log().contains(text), "{what}: expected {text:?} in\n{}", self.log());
        self.clear_log();
    }
}

impl Drop for Probe {
    fn drop(&mut self) {
        if self.version == Version::Fmi3 && !self.c3.is_null() {
            // SAFETY: `self.c3` is a live FMI 3.0 instance, freed here once and used no more;
            // `log3` is dropped after this.
            unsafe { (self.api3.fmi3FreeInstance)(self.c3) };
        }
    }
}

const VERSIONS: [Version; 2] = [Version::Fmi2, Version::Fmi3];

#[test]
fn states_of_other_instances_and_models_are_refused_without_being_read() {
    let fmus = every_kind();
    let api3 = Api3::load();
    for version in VERSIONS {
        let probes: Vec<Probe> = fmus.iter().map(|(_, f)| Probe::new(f, &api3, version)).collect();
        for p in &probes {
            p.initialize(0.0, None);
            assert_eq!(p.step(0.0, 1e-3), OK, "{}", p.log());
        }
        let mut states: Vec<*mut c_void> = vec![std::ptr::null_mut(); probes.len()];
        let mut bytes = Vec::new();
        for (p, s) in probes.iter().zip(&mut states) {
            assert_eq!(p.get_state(s), OK, "{}", p.log());
            bytes.push(p.serialize(*s).expect("own state serializes"));
        }
        for (a, (name_a, _)) in fmus.iter().enumerate() {
            for (b, (name_b, _)) in fmus.iter().enumerate() {
                if a == b {
                    continue;
                }
                let what = format!("{version:?}: a state of {name_a} given to {name_b}");
                let target = &probes[b];
                target.refused(target.set_state(states[a]), "is not an FMU state of this instance", &what);
                target.refused(target.serialize(states[a]).unwrap_err(), "is not an FMU state of this instance", &what);
                let mut foreign = states[a];
                target.refused(target.free_state(&mut foreign), "is not an FMU state of this instance", &what);
                assert_eq!(foreign, states[a], "{what}: the handle is left to its owner");
                let mut into = std::ptr::null_mut();
                target.refused(target.deserialize(&bytes[a], &mut into), "belongs to another model", &what);
                assert!(into.is_null());
                // Overwriting a foreign handle with one's own state is refused too.
                let mut reuse = states[a];
                target.refused(target.get_state(&mut reuse), "is not an FMU state of this instance", &what);
            }
        }
        // Each instance still restores its own state, and goes on stepping.
        for (p, s) in probes.iter().zip(&mut states) {
            assert_eq!(p.set_state(*s), OK, "{}", p.log());
            assert_eq!(p.time(), 1e-3);
            assert_eq!(p.step(1e-3, 1e-3), OK, "{}", p.log());
            assert_eq!(p.free_state(s), OK);
            assert!(s.is_null());
        }
    }
}

#[test]
fn a_state_moves_between_instances_of_one_model_only_serialized() {
    let fmu = Fmu::new(&FmuSpec::planar_arm("PlanarArm", ArmConfig::default()));
    let api3 = Api3::load();
    for version in VERSIONS {
        let (a, b) = (Probe::new(&fmu, &api3, version), Probe::new(&fmu, &api3, version));
        a.initialize(0.0, None);
        b.initialize(0.0, None);
        assert_eq!(a.step(0.0, 0.25), OK);
        let mut state = std::ptr::null_mut();
        assert_eq!(a.get_state(&mut state), OK);
        b.refused(b.set_state(state), "serialize it to move it to another instance", &format!("{version:?}"));
        let bytes = a.serialize(state).unwrap();
        let mut copy = std::ptr::null_mut();
        assert_eq!(b.deserialize(&bytes, &mut copy), OK, "{}", b.log());
        assert_eq!(b.set_state(copy), OK, "{}", b.log());
        assert_eq!(b.time(), 0.25);
        // Freed handles, NULL's neighbours and addresses stay unknown.
        let mut freed = copy;
        assert_eq!(b.free_state(&mut freed), OK);
        for handle in [copy, 0x1usize as *mut c_void, usize::MAX as *mut c_void, &bytes as *const _ as *mut c_void] {
            b.refused(b.set_state(handle), "is not an FMU state of this instance", &format!("{version:?}: {handle:?}"));
        }
        assert_eq!(a.free_state(&mut state), OK);
    }
}

#[test]
fn a_step_the_time_could_not_go_on_from_is_refused_by_every_model() {
    let fmus = every_kind();
    let api3 = Api3::load();
    for version in VERSIONS {
        for (name, fmu) in &fmus {
            let p = Probe::new(fmu, &api3, version);
            p.initialize(0.0, None);
            for h in [1e300, f64::MAX, 1e12] {
                p.refused(p.step(0.0, h), "no longer resolves this FMU's step of 0.001 s", &format!("{version:?} {name} h = {h:e}"));
                assert_eq!(p.time(), 0.0, "{name}: the time stays");
            }
            assert_eq!(p.step(0.0, 1e-3), OK, "{version:?} {name}: the instance goes on: {}", p.log());
            assert_eq!(p.time(), 1e-3);
            assert_eq!(p.reset(), OK);
            // A start time at the horizon is refused when it is set, not at the first step.
            let refused = match &p.fmi2 {
                Some(i) => i.setup_experiment(None, 1e20, None),
                // SAFETY: `p.c3` is a live FMI 3.0 instance (the probe's invariant); the rest are
                // values.
                None => unsafe { (p.api3.fmi3EnterInitializationMode)(p.c3, false, 0.0, 1e20, false, 0.0) },
            };
            p.refused(refused, "start time 1e20 s is beyond", &format!("{version:?} {name}"));
        }
    }
}

#[test]
fn a_step_past_the_stop_time_by_more_than_rounding_is_refused() {
    let fmu = Fmu::new(&FmuSpec { identifier: "Gain".into(), model: ModelSpec::Gain(GainSpec { k: 2.0 }) });
    let api3 = Api3::load();
    for version in VERSIONS {
        // The fuzzer's case: start = stop = 1e9 s, a whole 0.5 s step from the stop time.
        let p = Probe::new(&fmu, &api3, version);
        p.initialize(1e9, Some(1e9));
        p.refused(p.step(1e9, 0.5), "past the stop time 1000000000 s", &format!("{version:?}"));
        assert_eq!(p.time(), 1e9);
        // 1 µs past a stop time of 10 s is refused; points computed as t0 + k·h end on it.
        let p = Probe::new(&fmu, &api3, version);
        p.initialize(0.0, Some(10.0));
        for k in 0..999 {
            assert_eq!(p.step(k as f64 * 0.01, 0.01), OK, "{}", p.log());
        }
        p.refused(p.step(9.99, 0.01 + 1e-6), "past the stop time 10 s", &format!("{version:?}"));
        assert_eq!(p.step(9.99, 10.0 - 9.99), OK, "{}", p.log());
        assert!((p.time() - 10.0).abs() < 1e-14, "{}", p.time());
        p.refused(p.step(10.0, 1e-9), "past the stop time", &format!("{version:?}"));
        // A current time off by more than rounding is refused too (at 1e9 s it was up to 1 s).
        let p = Probe::new(&fmu, &api3, version);
        p.initialize(1e9, None);
        p.refused(p.step(1e9 + 0.5, 1e-3), "differs from the FMU's time", &format!("{version:?}"));
        assert_eq!(p.step(1e9, 1e-3), OK);
    }
}

#[test]
fn a_blank_instance_name_is_refused() {
    let fmu = Fmu::new(&FmuSpec { identifier: "Gain".into(), model: ModelSpec::Gain(GainSpec { k: 2.0 }) });
    let api3 = Api3::load();
    for version in VERSIONS {
        for name in ["", " ", "\t\n "] {
            let refusal = Probe::named(&fmu, &api3, version, name).err().unwrap_or_else(|| panic!("{version:?}: {name:?} accepted"));
            assert!(refusal.contains("white space only"), "{version:?} {name:?}: {refusal}");
        }
        assert!(Probe::named(&fmu, &api3, version, " a ").is_ok());
    }
}

#[test]
fn time_reads_the_instance_time() {
    let fmus = every_kind();
    let api3 = Api3::load();
    for version in VERSIONS {
        for (name, fmu) in &fmus {
            let p = Probe::new(fmu, &api3, version);
            p.initialize(2.0, None);
            assert_eq!(p.time(), 2.0, "{version:?} {name}");
            let mut t = 2.0;
            for _ in 0..3 {
                assert_eq!(p.step(t, 0.01), OK, "{}", p.log());
                t += 0.01;
            }
            assert_eq!(p.time(), t, "{version:?} {name}: after three 10 ms steps");
            let mut state = std::ptr::null_mut();
            assert_eq!(p.get_state(&mut state), OK);
            assert_eq!(p.step(t, 0.5), OK, "{}", p.log());
            assert_eq!(p.time(), t + 0.5);
            assert_eq!(p.set_state(state), OK);
            assert_eq!(p.time(), t, "{version:?} {name}: restored with its state");
            assert_eq!(p.free_state(&mut state), OK);
        }
    }
}

#[test]
fn a_compensator_switched_on_for_a_part_without_nets_is_refused_by_its_spec_file() {
    let api3 = Api3::load();
    let gravity_only = |enable_friction, enable_gravity, adaptive: bool| {
        let (friction, gravity) = (Vec::new(), Some("gravity.json".to_owned()));
        let model = if adaptive {
            ModelSpec::AdaptiveCompensator(AdaptiveCompensatorSpec {
                joints: 4,
                friction,
                gravity,
                enable_friction,
                enable_gravity,
                law: AdaptationLaw::default(),
            })
        } else {
            ModelSpec::NnCompensator(NnCompensatorSpec { joints: 4, friction, gravity, enable_friction, enable_gravity })
        };
        FmuSpec { identifier: "Comp".into(), model }
    };
    for adaptive in [false, true] {
        // The fixture's own description is made from a spec that builds; the instance then
        // reads the broken one the host's FMU carries.
        let fmu = fmu_with_nets("Comp", gravity_only(false, true, adaptive).model);
        std::fs::write(fmu.resources().join(neurarm_models::SPEC_FILE), gravity_only(true, true, adaptive).to_toml()).unwrap();
        for version in VERSIONS {
            let refusal = Probe::named(&fmu, &api3, version, "c").err().expect("refused");
            assert!(refusal.contains("neurarm.toml") && refusal.contains("enable_friction = true, but friction = []"), "{refusal}");
        }
    }
}
