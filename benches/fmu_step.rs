//! One 1 ms step of the default arm: in process (`ArmSimulator::step`, then the outputs the
//! FMU computes) and through the PlanarArm FMU's C ABI loaded with dlopen (fmi2SetReal of the
//! 4 torques, fmi2DoStep, fmi2GetReal of the 12 kinematic outputs). `scripts/bench-fmu` runs
//! this and fmpy driving the same FMU, and prints the ratios.
//!
//! Both sides are checked to compute the same: after the timing, the FMU takes [`CHECKED_STEPS`]
//! steps from the start through its C ABI and its 12 outputs must be the in-process arm's, bit
//! for bit; those go to `<target>/fmu-bench/in_process.json`, against which
//! `benches/python/fmu_ratio.py` checks fmpy's run.

#![allow(missing_docs)] // criterion_group! makes an undocumented public function

use std::ffi::{c_char, c_int, c_void, CString};
use std::path::PathBuf;

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use neurarm_models::{FmuSpec, SPEC_FILE};
use neurarm_physics::arm::{end_effector_state, ArmState};
use neurarm_physics::config::ArmConfig;

type C = *mut c_void;
type Logger = unsafe extern "C" fn(*mut c_void, *const c_char, c_int, *const c_char, *const c_char);

#[repr(C)]
struct Callbacks {
    logger: Option<Logger>,
    rest: [*const c_void; 3],
    env: *mut c_void,
}

unsafe extern "C" fn quiet(_: *mut c_void, _: *const c_char, _: c_int, _: *const c_char, _: *const c_char) {}

const TAU: [f64; 4] = [2.0, -1.0, 0.5, 0.2];
const Q0: [f64; 4] = [0.3, -0.5, 0.7, -0.2];
const QD0: [f64; 4] = [1.0, -2.0, 1.5, 3.0];
/// The outputs compared, in this order.
const OUTPUTS: [&str; 12] = ["q_1", "q_2", "q_3", "q_4", "qd_1", "qd_2", "qd_3", "qd_4", "x", "y", "xd", "yd"];
/// Steps from the start after which the FMU's outputs are checked against the in-process arm's
/// (the timed loops restart after as many).
const CHECKED_STEPS: u32 = 1000;

fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target"))
}

/// The default arm's [`OUTPUTS`] after [`CHECKED_STEPS`] steps of 1 ms from the bench's start
/// under its torques, in process; written to `<target>/fmu-bench/in_process.json` for fmpy's
/// check.
fn in_process_reference() -> [f64; 12] {
    let config = ArmConfig::default();
    let (mut sim, _) = config.build().unwrap();
    let mut state = ArmState { q: Q0.to_vec(), qd: QD0.to_vec() };
    for _ in 0..CHECKED_STEPS {
        sim.step(&mut state, &TAU, 1e-3).unwrap();
    }
    let mut out = [0.0; 12];
    out[..4].copy_from_slice(&state.q);
    out[4..8].copy_from_slice(&state.qd);
    out[8..].copy_from_slice(&end_effector_state(&config.arm, &state.q, &state.qd));
    let dir = target_dir().join("fmu-bench");
    std::fs::create_dir_all(&dir).unwrap();
    let outputs: serde_json::Map<String, serde_json::Value> = OUTPUTS.iter().zip(out).map(|(n, v)| (n.to_string(), v.into())).collect();
    let json = serde_json::json!({ "steps": CHECKED_STEPS, "step_s": 1e-3, "outputs": outputs });
    std::fs::write(dir.join("in_process.json"), json.to_string()).unwrap();
    out
}

fn in_process(c: &mut Criterion) {
    let config = ArmConfig::default();
    let (mut sim, mut sensors) = config.build().unwrap();
    let start = ArmState { q: Q0.to_vec(), qd: QD0.to_vec() };
    let mut state = start.clone();
    let (mut qm, mut qdm) = ([0.0; 4], [0.0; 4]);
    let mut k = 0u32;
    c.bench_function("arm_1ms/in_process_step", |b| {
        b.iter(|| {
            k += 1;
            if k % CHECKED_STEPS == 0 {
                state.clone_from(&start);
            }
            sim.step(black_box(&mut state), &TAU, 1e-3).unwrap();
        })
    });
    let mut k = 0u32;
    state.clone_from(&start);
    c.bench_function("arm_1ms/in_process_step_and_outputs", |b| {
        b.iter(|| {
            k += 1;
            if k % CHECKED_STEPS == 0 {
                state.clone_from(&start);
            }
            sim.step(black_box(&mut state), &TAU, 1e-3).unwrap();
            black_box(end_effector_state(&config.arm, &state.q, &state.qd));
            sensors.measure(&state, &mut qm, &mut qdm);
        })
    });
}

fn through_abi(c: &mut Criterion) {
    // SAFETY: the library is this workspace's FMU binary, whose initialisers are Rust's own.
    let lib = unsafe { libloading::Library::new(target_dir().join("release/libneurarm_fmu.so")) }
        .expect("build the FMU binary first: cargo build --release -p neurarm-fmu");
    let spec = FmuSpec::planar_arm("PlanarArm", ArmConfig::default());
    let description = spec.description().unwrap();
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join(SPEC_FILE), spec.to_toml()).unwrap();
    let vr = |n: &str| description.variables.iter().find(|v| v.name == n).unwrap().value_reference;
    let inputs: Vec<u32> = (1..=4).map(|i| vr(&format!("tau_{i}"))).collect();
    let outputs: Vec<u32> = OUTPUTS.iter().map(|n| vr(n)).collect();
    // SAFETY: each symbol is read as a function type of the ABI the FMI 2.0 header gives it,
    // and `lib` stays loaded until the function returns, after the last call. `callbacks`
    // (a logger that reads nothing, a NULL environment) and the NUL-terminated strings outlive
    // fmi2Instantiate; `inst` is used from there until fmi2FreeInstance only, one call at a
    // time; every array passed holds the count passed with it (8 start values, 4 inputs, 12
    // outputs) and outlives its call; `start` is a handle of `inst`.
    unsafe {
        let instantiate = *lib
            .get::<unsafe extern "C" fn(*const c_char, c_int, *const c_char, *const c_char, *const Callbacks, c_int, c_int) -> C>(
                b"fmi2Instantiate\0",
            )
            .unwrap();
        let setup = *lib.get::<unsafe extern "C" fn(C, c_int, f64, f64, c_int, f64) -> c_int>(b"fmi2SetupExperiment\0").unwrap();
        let enter = *lib.get::<unsafe extern "C" fn(C) -> c_int>(b"fmi2EnterInitializationMode\0").unwrap();
        let exit = *lib.get::<unsafe extern "C" fn(C) -> c_int>(b"fmi2ExitInitializationMode\0").unwrap();
        let set_real = *lib.get::<unsafe extern "C" fn(C, *const u32, usize, *const f64) -> c_int>(b"fmi2SetReal\0").unwrap();
        let get_real = *lib.get::<unsafe extern "C" fn(C, *const u32, usize, *mut f64) -> c_int>(b"fmi2GetReal\0").unwrap();
        let do_step = *lib.get::<unsafe extern "C" fn(C, f64, f64, c_int) -> c_int>(b"fmi2DoStep\0").unwrap();
        let get_state = *lib.get::<unsafe extern "C" fn(C, *mut C) -> c_int>(b"fmi2GetFMUstate\0").unwrap();
        let set_state = *lib.get::<unsafe extern "C" fn(C, C) -> c_int>(b"fmi2SetFMUstate\0").unwrap();
        let free = *lib.get::<unsafe extern "C" fn(C)>(b"fmi2FreeInstance\0").unwrap();
        let callbacks = Callbacks { logger: Some(quiet), rest: [std::ptr::null(); 3], env: std::ptr::null_mut() };
        let name = CString::new("bench").unwrap();
        let guid = CString::new(description.guid()).unwrap();
        let uri = CString::new(format!("file://{}", dir.path().display())).unwrap();
        let inst = instantiate(name.as_ptr(), 1, guid.as_ptr(), uri.as_ptr(), &callbacks, 0, 0);
        assert!(!inst.is_null());
        let start_vrs: Vec<u32> = (1..=4).flat_map(|i| [vr(&format!("q0_{i}")), vr(&format!("qd0_{i}"))]).collect();
        let start_vals: Vec<f64> = Q0.iter().zip(QD0).flat_map(|(&q, qd)| [q, qd]).collect();
        assert_eq!(setup(inst, 0, 0.0, 0.0, 0, 0.0), 0);
        assert_eq!(set_real(inst, start_vrs.as_ptr(), 8, start_vals.as_ptr()), 0);
        assert_eq!(enter(inst), 0);
        assert_eq!(exit(inst), 0);
        let mut start = std::ptr::null_mut();
        assert_eq!(get_state(inst, &mut start), 0);
        let mut out = [0.0; 12];
        let mut k = 0u32;
        c.bench_function("arm_1ms/fmu_abi_set_step_get", |b| {
            b.iter(|| {
                if k % CHECKED_STEPS == 0 {
                    // Same regime as in process: restart every 1000 steps (not timed apart,
                    // but once per 1000 steps it is negligible).
                    assert_eq!(set_state(inst, start), 0);
                    k = 0;
                }
                set_real(inst, inputs.as_ptr(), 4, TAU.as_ptr());
                do_step(inst, k as f64 * 1e-3, 1e-3, 1);
                get_real(inst, outputs.as_ptr(), 12, out.as_mut_ptr());
                k += 1;
                black_box(&out);
            })
        });
        // The same steps from the start compute what the arm computes in process.
        assert_eq!(set_state(inst, start), 0);
        for k in 0..CHECKED_STEPS {
            assert_eq!(set_real(inst, inputs.as_ptr(), 4, TAU.as_ptr()), 0);
            assert_eq!(do_step(inst, f64::from(k) * 1e-3, 1e-3, 1), 0);
        }
        assert_eq!(get_real(inst, outputs.as_ptr(), 12, out.as_mut_ptr()), 0);
        let reference = in_process_reference();
        assert!(
            out.iter().zip(&reference).all(|(a, b)| a.to_bits() == b.to_bits()),
            "the FMU's outputs after {CHECKED_STEPS} steps are not the in-process arm's: {out:?} vs {reference:?}"
        );
        free(inst);
    }
}

criterion_group!(benches, in_process, through_abi);
criterion_main!(benches);
