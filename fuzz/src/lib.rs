//! What the fuzz targets share: the FMU binary's exported `fmi2*` functions, called in
//! process through the C ABI; a host logger that keeps what the FMU says; and one unpacked
//! FMU (a `resources/` folder) per model kind, written once per process with the project's
//! own spec and weights code.
//!
//! Every target checks the same promises beside "no crash, no hang, no leak": an FMU call
//! never returns `fmi2Fatal` (the layer's sign of a caught panic) or `fmi2Pending`; a call
//! that returns `fmi2Error` has logged why; and `fmi2GetReal` never returns `fmi2OK` with a
//! number that is not finite.

#![feature(c_variadic)]

use std::cell::RefCell;
use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::path::Path;
use std::sync::OnceLock;

use neurarm_fmi_export::fmi2::abi::{CallbackFunctions, Component, FmuState};
use neurarm_fmi_export::description::{BaseType, ModelDescription};
use neurarm_fmi_export::Causality;
use nalgebra::{DMatrix, DVector};
use neurarm_models::*;
use neurarm_physics::arm::{ArmParams, FrictionBranch, JointFriction};
use neurarm_physics::config::ArmConfig;
use neurarm_physics::control::TaskSpaceGains;
use neurarm_nn::{InputEncoding, MinMaxScaling, Mlp, NetKind, Signal, StopReason, TrainReport, TrainSettings, WeightsFile};

// The FMU crate is linked for its exported symbols, declared here as a host sees them.
use neurarm_fmu as _;

/// `fmi2OK`.
pub const OK: c_int = 0;
/// `fmi2Error`.
pub const ERROR: c_int = 3;
/// `fmi2Fatal`.
pub const FATAL: c_int = 4;

#[allow(missing_docs, non_snake_case)]
extern "C" {
    pub fn fmi2GetTypesPlatform() -> *const c_char;
    pub fn fmi2GetVersion() -> *const c_char;
    pub fn fmi2SetDebugLogging(c: Component, on: c_int, n: usize, categories: *const *const c_char) -> c_int;
    pub fn fmi2Instantiate(
        name: *const c_char,
        fmu_type: c_int,
        guid: *const c_char,
        resources: *const c_char,
        functions: *const CallbackFunctions,
        visible: c_int,
        logging_on: c_int,
    ) -> Component;
    pub fn fmi2FreeInstance(c: Component);
    pub fn fmi2SetupExperiment(c: Component, tol_defined: c_int, tol: f64, start: f64, stop_defined: c_int, stop: f64) -> c_int;
    pub fn fmi2EnterInitializationMode(c: Component) -> c_int;
    pub fn fmi2ExitInitializationMode(c: Component) -> c_int;
    pub fn fmi2Terminate(c: Component) -> c_int;
    pub fn fmi2Reset(c: Component) -> c_int;
    pub fn fmi2GetReal(c: Component, vr: *const u32, n: usize, v: *mut f64) -> c_int;
    pub fn fmi2GetInteger(c: Component, vr: *const u32, n: usize, v: *mut c_int) -> c_int;
    pub fn fmi2GetBoolean(c: Component, vr: *const u32, n: usize, v: *mut c_int) -> c_int;
    pub fn fmi2GetString(c: Component, vr: *const u32, n: usize, v: *mut *const c_char) -> c_int;
    pub fn fmi2SetReal(c: Component, vr: *const u32, n: usize, v: *const f64) -> c_int;
    pub fn fmi2SetInteger(c: Component, vr: *const u32, n: usize, v: *const c_int) -> c_int;
    pub fn fmi2SetBoolean(c: Component, vr: *const u32, n: usize, v: *const c_int) -> c_int;
    pub fn fmi2SetString(c: Component, vr: *const u32, n: usize, v: *const *const c_char) -> c_int;
    pub fn fmi2GetFMUstate(c: Component, s: *mut FmuState) -> c_int;
    pub fn fmi2SetFMUstate(c: Component, s: FmuState) -> c_int;
    pub fn fmi2FreeFMUstate(c: Component, s: *mut FmuState) -> c_int;
    pub fn fmi2SerializedFMUstateSize(c: Component, s: FmuState, size: *mut usize) -> c_int;
    pub fn fmi2SerializeFMUstate(c: Component, s: FmuState, out: *mut u8, size: usize) -> c_int;
    pub fn fmi2DeSerializeFMUstate(c: Component, bytes: *const u8, size: usize, s: *mut FmuState) -> c_int;
    pub fn fmi2GetDirectionalDerivative(
        c: Component,
        unknown: *const u32,
        n_unknown: usize,
        known: *const u32,
        n_known: usize,
        dv_known: *const f64,
        dv_unknown: *mut f64,
    ) -> c_int;
    pub fn fmi2SetRealInputDerivatives(c: Component, vr: *const u32, n: usize, order: *const c_int, v: *const f64) -> c_int;
    pub fn fmi2GetRealOutputDerivatives(c: Component, vr: *const u32, n: usize, order: *const c_int, v: *mut f64) -> c_int;
    pub fn fmi2DoStep(c: Component, t: f64, h: f64, no_prior: c_int) -> c_int;
    pub fn fmi2CancelStep(c: Component) -> c_int;
    pub fn fmi2GetStatus(c: Component, kind: c_int, v: *mut c_int) -> c_int;
    pub fn fmi2GetRealStatus(c: Component, kind: c_int, v: *mut f64) -> c_int;
    pub fn fmi2GetIntegerStatus(c: Component, kind: c_int, v: *mut c_int) -> c_int;
    pub fn fmi2GetBooleanStatus(c: Component, kind: c_int, v: *mut c_int) -> c_int;
    pub fn fmi2GetStringStatus(c: Component, kind: c_int, v: *mut *const c_char) -> c_int;
}

thread_local! {
    /// What the FMU logged on this thread: (status, message).
    static LOG: RefCell<Vec<(c_int, String)>> = const { RefCell::new(Vec::new()) };
}

/// The host's logger: printf-style and variadic, as the standard declares it. The FMU passes
/// its message as the format (with '%' escaped), so the message is taken as it is.
unsafe extern "C" fn logger(
    _env: *mut c_void,
    _name: *const c_char,
    status: c_int,
    _category: *const c_char,
    message: *const c_char,
    _args: ...
) {
    assert!(!message.is_null(), "the FMU logged a NULL message");
    let text = unsafe { CStr::from_ptr(message) }.to_string_lossy().replace("%%", "%");
    LOG.with(|log| log.borrow_mut().push((status, text)));
}

/// The callbacks every instance gets.
pub fn callbacks() -> &'static CallbackFunctions {
    struct Shared(CallbackFunctions);
    // SAFETY: the environment pointer is null and nothing in it is ever written.
    unsafe impl Sync for Shared {}
    unsafe impl Send for Shared {}
    static CALLBACKS: OnceLock<Shared> = OnceLock::new();
    &CALLBACKS
        .get_or_init(|| {
            Shared(CallbackFunctions {
                logger: Some(logger),
                allocate_memory: None,
                free_memory: None,
                step_finished: None,
                component_environment: std::ptr::null_mut(),
            })
        })
        .0
}

/// Number of messages logged so far on this thread.
pub fn log_len() -> usize {
    LOG.with(|log| log.borrow().len())
}

/// Forgets the log (each fuzz input starts with an empty one).
pub fn clear_log() {
    LOG.with(|log| log.borrow_mut().clear());
}

/// The messages logged since position `from`.
pub fn log_since(from: usize) -> Vec<(c_int, String)> {
    LOG.with(|log| log.borrow()[from.min(log.borrow().len())..].to_vec())
}

/// Checks the promises every FMU call keeps: no `fmi2Fatal` (a caught panic) and no
/// `fmi2Pending` (steps are never asynchronous); `fmi2Error` only with a logged reason.
/// `log_from` is [`log_len`] before the call.
pub fn check_status(call: &str, status: c_int, log_from: usize) {
    assert!((OK..=ERROR).contains(&status), "{call} returned status {status}: {:?}", log_since(log_from));
    if status == ERROR {
        let logged = log_since(log_from);
        assert!(logged.iter().any(|(s, m)| *s == ERROR && !m.is_empty()), "{call} returned fmi2Error without logging why");
    }
}

/// One unpacked FMU of one model kind.
pub struct Fixture {
    /// The model kind, for messages.
    pub name: &'static str,
    /// `file://` URI of its resources folder.
    pub uri: CString,
    /// Its GUID.
    pub guid: CString,
    /// Its model description.
    pub description: ModelDescription,
    /// Value references by base type (Real, Integer, Boolean, String).
    pub vrs: [Vec<u32>; 4],
    /// Value references of the Real parameters and inputs (what a host sets).
    pub settable_reals: Vec<u32>,
    /// Serialized FMU states of this FMU: after instantiation, initialization and some steps.
    pub states: Vec<Vec<u8>>,
}

/// A small net with fixed, varied weights.
fn net(n_in: usize, hidden: usize, n_out: usize, salt: usize, input_range: f64) -> Mlp {
    let f = |a: usize, b: usize| ((a * 7 + b * 3 + salt) % 11) as f64 / 8.0 - 0.6;
    Mlp {
        iw: DMatrix::from_fn(hidden, n_in, f),
        b1: DVector::from_fn(hidden, |j, _| f(j, 1)),
        lw: DMatrix::from_fn(n_out, hidden, f),
        b2: DVector::from_fn(n_out, |k, _| f(k, 2)),
        input_scaling: MinMaxScaling { min: vec![-input_range; n_in], max: vec![input_range; n_in] },
        output_scaling: MinMaxScaling { min: vec![-2.0; n_out], max: vec![2.0; n_out] },
    }
}

/// A weights file of `net` with inputs `x` [unit] and outputs `tau` [N·m].
pub fn weights_file(net: &Mlp, inputs: &[(&str, &str)], outputs: usize) -> WeightsFile {
    let report = TrainReport {
        epochs: 3,
        best_epoch: 2,
        stop_reason: StopReason::Epochs,
        restart: 0,
        train_mse: 1e-3,
        validation_mse: Some(2e-3),
        test_mse: None,
        counts: [10, 3, 0],
    };
    let signals = |list: &[(&str, &str)]| list.iter().map(|(n, u)| Signal { name: n.to_string(), unit: u.to_string() }).collect();
    let outs: Vec<(String, &str)> = (1..=outputs).map(|i| (format!("tau_{i}"), "N.m")).collect();
    let outs: Vec<(&str, &str)> = outs.iter().map(|(n, u)| (n.as_str(), *u)).collect();
    WeightsFile::new(net, signals(inputs), signals(&outs), TrainSettings::default(), report)
}

/// The friction nets (one per joint) and the link-angle gravity net of a 4-joint compensator.
pub fn compensator_nets() -> Vec<(String, WeightsFile)> {
    let mut files: Vec<(String, WeightsFile)> = (1..=4)
        .map(|j| {
            let input = format!("qd_{j}");
            let file = weights_file(&net(1, 5, 1, j, 3.0), &[(input.as_str(), "rad/s")], 1).friction_of_joint(j);
            (format!("friction_{j}.json"), file)
        })
        .collect();
    let q: Vec<String> = (1..=4).map(|i| format!("q_{i}")).collect();
    let inputs: Vec<(&str, &str)> = q.iter().map(|n| (n.as_str(), "rad")).collect();
    let gravity = weights_file(&net(8, 6, 4, 0, 1.0), &inputs, 4).with_encoding(InputEncoding::LinkAngles).gravity();
    debug_assert_eq!(gravity.kind, NetKind::Gravity);
    files.push(("gravity.json".into(), gravity));
    files
}

/// The spec of every model kind the targets drive, with the files beside it.
pub fn specs() -> Vec<(&'static str, FmuSpec, Vec<(String, String)>)> {
    let mut vertical = ArmConfig::default();
    vertical.arm.base_angle_rad = std::f64::consts::FRAC_PI_2;
    let mut small = ArmConfig::default();
    small.arm.links.truncate(2);
    small.arm.friction = vec![
        JointFriction {
            positive: FrictionBranch {
                coulomb_nm: 1.0,
                static_nm: 1.4,
                stribeck_velocity_rad_s: 0.1,
                viscous_nms_rad: 0.5,
                viscous_falloff_rad_s: Some(2.0),
            },
            negative: FrictionBranch::coulomb_viscous(0.8, 0.4),
        },
        JointFriction::symmetric(FrictionBranch::coulomb_viscous(0.3, 0.1)),
    ];
    small.arm.base_angle_rad = 1.0;
    small.hardware.encoder_counts_per_rev = Some(vec![4096.0, 0.0]);
    small.hardware.q_noise_std_rad = 1e-3;
    small.hardware.qd_noise_std_rad_s = 1e-2;
    small.hardware.torque_limit_nm = Some(vec![5.0, 0.0]);
    small.hardware.seed = 7;
    let arm = ArmParams::default_four_link().with_base_angle(std::f64::consts::FRAC_PI_2);
    let nets = compensator_nets();
    let net_texts: Vec<(String, String)> = nets.iter().map(|(n, f)| (n.clone(), f.to_json())).collect();
    let spec = |identifier: &str, model: ModelSpec| FmuSpec { identifier: identifier.into(), model };
    vec![
        ("PlanarArm", FmuSpec::planar_arm("PlanarArm", vertical), vec![]),
        ("PlanarArm2", FmuSpec::planar_arm("PlanarArm2", small), vec![]),
        (
            "NnCompensator",
            spec(
                "NnCompensator",
                ModelSpec::NnCompensator(NnCompensatorSpec {
                    joints: 4,
                    friction: (1..=4).map(|j| format!("friction_{j}.json")).collect(),
                    gravity: Some("gravity.json".into()),
                    enable_friction: true,
                    enable_gravity: true,
                }),
            ),
            net_texts.clone(),
        ),
        (
            "AdaptiveCompensator",
            spec(
                "AdaptiveCompensator",
                ModelSpec::AdaptiveCompensator(AdaptiveCompensatorSpec {
                    joints: 4,
                    friction: (1..=4).map(|j| format!("friction_{j}.json")).collect(),
                    gravity: Some("gravity.json".into()),
                    enable_friction: true,
                    enable_gravity: true,
                    law: AdaptationLaw::default(),
                }),
            ),
            net_texts,
        ),
        (
            "TaskSpaceController",
            spec(
                "TaskSpaceController",
                ModelSpec::TaskSpaceController(TaskSpaceControllerSpec {
                    model: arm.clone().frictionless(),
                    gains: TaskSpaceGains::default(),
                    centre: [0.45, 0.1],
                    scale: 1.0,
                    q_start: vec![-0.4, 0.9, 0.7, 0.5],
                }),
            ),
            vec![],
        ),
        (
            "JointController",
            spec("JointController", ModelSpec::JointController(JointControllerSpec { joints: 4, kp: 50.0, kd: 2.0, use_sequence: true })),
            vec![],
        ),
        (
            "IdealCompensator",
            spec(
                "IdealCompensator",
                ModelSpec::IdealCompensator(IdealCompensatorSpec { arm, enable_friction: true, enable_gravity: true }),
            ),
            vec![],
        ),
        ("Integrator", spec("Integrator", ModelSpec::Integrator(IntegratorSpec { y0: 1.0 })), vec![]),
        ("Gain", spec("Gain", ModelSpec::Gain(GainSpec { k: 2.0 })), vec![]),
    ]
}

/// Writes `spec` and `files` into `resources` (made if missing).
pub fn write_resources(resources: &Path, spec_text: &str, files: &[(String, String)]) {
    std::fs::create_dir_all(resources).expect("make resources/");
    std::fs::write(resources.join(SPEC_FILE), spec_text).expect("write the spec");
    for (name, text) in files {
        std::fs::write(resources.join(name), text).expect("write a resource file");
    }
}

/// Every model kind, unpacked once per process into a temporary folder.
pub fn fixtures() -> &'static [Fixture] {
    static FIXTURES: OnceLock<(tempfile::TempDir, Vec<Fixture>)> = OnceLock::new();
    &FIXTURES
        .get_or_init(|| {
            let dir = tempfile::tempdir().expect("a temporary folder");
            let fixtures = specs()
                .into_iter()
                .map(|(name, spec, files)| {
                    let resources = dir.path().join(name).join("resources");
                    write_resources(&resources, &spec.to_toml(), &files);
                    let description = spec.build_from(Some(&resources)).expect("the fixture's model builds").description().clone();
                    let of = |base: BaseType| {
                        description.variables.iter().filter(|v| v.base_type() == base).map(|v| v.value_reference).collect::<Vec<_>>()
                    };
                    let vrs = [of(BaseType::Real), of(BaseType::Integer), of(BaseType::Boolean), of(BaseType::String)];
                    let settable_reals = description
                        .variables
                        .iter()
                        .filter(|v| v.base_type() == BaseType::Real && matches!(v.causality, Causality::Parameter | Causality::Input))
                        .map(|v| v.value_reference)
                        .collect();
                    let mut fixture = Fixture {
                        name,
                        uri: CString::new(format!("file://{}", resources.display())).expect("no NUL in a temp path"),
                        guid: CString::new(description.guid()).expect("no NUL in a GUID"),
                        description,
                        vrs,
                        settable_reals,
                        states: Vec::new(),
                    };
                    fixture.states = sample_states(&fixture);
                    fixture
                })
                .collect();
            (dir, fixtures)
        })
        .1
}

/// An instance of `fixture`, or null after logging why.
pub fn instantiate(fixture: &Fixture) -> Component {
    unsafe { fmi2Instantiate(c"fuzz".as_ptr(), 1, fixture.guid.as_ptr(), fixture.uri.as_ptr(), callbacks(), 0, 0) }
}

/// The serialized state of `c`, if it can be saved.
pub fn serialized_state(c: Component) -> Option<Vec<u8>> {
    unsafe {
        let mut state: FmuState = std::ptr::null_mut();
        if fmi2GetFMUstate(c, &mut state) != OK {
            return None;
        }
        let mut size = 0;
        let mut bytes = None;
        if fmi2SerializedFMUstateSize(c, state, &mut size) == OK {
            let mut b = vec![0u8; size];
            if fmi2SerializeFMUstate(c, state, b.as_mut_ptr(), size) == OK {
                bytes = Some(b);
            }
        }
        fmi2FreeFMUstate(c, &mut state);
        bytes
    }
}

/// States of `fixture` in its ordinary life: instantiated, initialized, after 20 steps of
/// 1 ms with its Real inputs set.
fn sample_states(fixture: &Fixture) -> Vec<Vec<u8>> {
    let c = instantiate(fixture);
    assert!(!c.is_null(), "{}: {:?}", fixture.name, log_since(0));
    let mut states = Vec::new();
    states.extend(serialized_state(c));
    unsafe {
        assert_eq!(fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0), OK);
        assert_eq!(fmi2EnterInitializationMode(c), OK);
        assert_eq!(fmi2ExitInitializationMode(c), OK, "{}: {:?}", fixture.name, log_since(0));
        states.extend(serialized_state(c));
        let inputs: Vec<u32> = fixture
            .description
            .variables
            .iter()
            .filter(|v| v.base_type() == BaseType::Real && v.causality == Causality::Input)
            .map(|v| v.value_reference)
            .collect();
        for k in 0..20 {
            let values: Vec<f64> = (0..inputs.len()).map(|i| 0.3 * ((k + i) as f64).sin()).collect();
            assert_eq!(fmi2SetReal(c, inputs.as_ptr(), inputs.len(), values.as_ptr()), OK);
            assert_eq!(fmi2DoStep(c, k as f64 * 1e-3, 1e-3, 1), OK, "{}: {:?}", fixture.name, log_since(0));
        }
        states.extend(serialized_state(c));
        fmi2FreeInstance(c);
    }
    clear_log();
    states
}

/// Recomputes the CRC-32 at the end of a serialized state (the layer's format: the checksum
/// of everything before it, little-endian), so that an edit reaches the decoder's checks
/// beyond the checksum.
pub fn fix_checksum(bytes: &mut [u8]) {
    if bytes.len() >= 4 {
        let (body, crc) = bytes.split_at_mut(bytes.len() - 4);
        crc.copy_from_slice(&crc32fast::hash(body).to_le_bytes());
    }
}

/// Reads the Real variables `vrs` of `c` and checks the promise that an `fmi2OK` read holds
/// only finite numbers.
pub fn get_reals_checked(c: Component, vrs: &[u32]) -> c_int {
    let mut out = vec![0.0; vrs.len()];
    let from = log_len();
    let status = unsafe { fmi2GetReal(c, vrs.as_ptr(), vrs.len(), out.as_mut_ptr()) };
    check_status("fmi2GetReal", status, from);
    if status == OK {
        if let Some(i) = out.iter().position(|v| !v.is_finite()) {
            panic!("fmi2GetReal returned fmi2OK with value reference {} = {}", vrs[i], out[i]);
        }
    }
    status
}
