//! Soak of the FMU binary through its C ABI: many instances of every model kind stepped for a
//! long time, each saving its state along the way (`fmi2GetFMUstate`, into a reused slot),
//! serialising and deserialising it, stepping on, restoring and stepping again. Checked: a
//! restored state gives back the outputs it was saved with and the same trajectory after it
//! (bit for bit); an instance that saved and restored ends bit-identical to a fresh one that
//! never did; restoring the first state saved, at the end, replays its steps exactly. Measured:
//! step rates with and without the state work, resident memory sampled along the run (start,
//! end, peak) and the C heap in use.
//!
//! `cargo test` runs a short version (a few instances, 10⁴ steps); `scripts/soak` runs the full
//! one (the ignored test: 100 PlanarArm instances × 10⁶ steps and two of every other kind) and
//! prints the figures. Needs the FMU binary built (`cargo build --release -p neurarm-fmu`).

use crate::common;

use std::ffi::c_void;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use common::*;
use neurarm_fmi_export::description::BaseType;
use neurarm_fmi_export::Causality;
use neurarm_models::*;
use neurarm_physics::arm::ArmParams;
use neurarm_physics::config::ArmConfig;
use neurarm_physics::control::TaskSpaceGains;

/// Communication step [s].
const STEP: f64 = 1e-3;

/// How long and how often.
#[derive(Clone, Copy, Debug)]
struct Plan {
    /// PlanarArm instances (spread over four arm configurations).
    arms: usize,
    /// Instances of each other model kind.
    others: usize,
    /// Steps of each instance.
    steps: usize,
    /// Steps between two saved states.
    every: usize,
    /// Steps replayed after each restore.
    replay: usize,
    /// Worker threads.
    threads: usize,
}

/// A model to soak: its FMU folder, which profile of its kind, and its real inputs and outputs.
struct Model {
    name: String,
    fmu: Fmu,
    inputs: Vec<u32>,
    outputs: Vec<u32>,
    /// Scale of the inputs (torques for the arm, angles and speeds for the others).
    amplitude: f64,
}

/// Every model to soak: four PlanarArm configurations (plain; noise, encoders and torque limits;
/// gravity in the plane; three joints), then one of each other kind.
#[allow(clippy::too_many_lines, reason = "a table of the models soaked, one entry per kind, read top to bottom")]
fn models() -> Vec<Model> {
    let arm = ArmParams::default_four_link();
    let mut noisy = ArmConfig::default();
    noisy.hardware.q_noise_std_rad = 1e-3;
    noisy.hardware.qd_noise_std_rad_s = 1e-2;
    noisy.hardware.seed = 5;
    noisy.hardware.encoder_counts_per_rev = Some(vec![65536.0; 4]);
    noisy.hardware.torque_limit_nm = Some(vec![4.0, 3.0, 2.0, 1.0]);
    let mut vertical = ArmConfig::default();
    vertical.arm.base_angle_rad = std::f64::consts::FRAC_PI_2;
    let mut three = ArmConfig::default();
    three.arm.links.truncate(3);
    three.arm.friction.truncate(3);
    let mut specs: Vec<(String, ModelSpec, f64)> =
        [("plain", ArmConfig::default()), ("noisy", noisy), ("vertical", vertical), ("3-joint", three)]
            .into_iter()
            .map(|(name, config)| {
                let n = config.arm.dof();
                (format!("PlanarArm {name}"), ModelSpec::PlanarArm(PlanarArmSpec { config, q0: vec![0.2; n], qd0: vec![0.0; n] }), 2.5)
            })
            .collect();
    specs.extend([
        (
            "NnCompensator".to_owned(),
            ModelSpec::NnCompensator(NnCompensatorSpec {
                joints: 4,
                friction: (1..=4).map(|j| format!("friction_{j}.json")).collect(),
                gravity: Some("gravity.json".into()),
                enable_friction: true,
                enable_gravity: true,
            }),
            1.0,
        ),
        (
            "AdaptiveCompensator".to_owned(),
            ModelSpec::AdaptiveCompensator(AdaptiveCompensatorSpec {
                joints: 4,
                friction: (1..=4).map(|j| format!("friction_{j}.json")).collect(),
                gravity: Some("gravity.json".into()),
                enable_friction: true,
                enable_gravity: true,
                law: AdaptationLaw::default(),
            }),
            1.0,
        ),
        (
            "IdealCompensator".to_owned(),
            ModelSpec::IdealCompensator(IdealCompensatorSpec {
                arm: arm.clone().with_base_angle(1.0),
                enable_friction: true,
                enable_gravity: true,
            }),
            1.0,
        ),
        (
            "TaskSpaceController".to_owned(),
            ModelSpec::TaskSpaceController(TaskSpaceControllerSpec {
                model: arm.clone().frictionless(),
                gains: TaskSpaceGains::default(),
                centre: [0.45, 0.1],
                scale: 1.0,
                q_start: vec![-0.4, 0.9, 0.7, 0.5],
            }),
            0.3,
        ),
        (
            "JointController".to_owned(),
            ModelSpec::JointController(JointControllerSpec { joints: 4, kp: 50.0, kd: 2.0, use_sequence: true }),
            1.0,
        ),
        ("Integrator".to_owned(), ModelSpec::Integrator(IntegratorSpec { y0: 1.0 }), 1.0),
        ("Gain".to_owned(), ModelSpec::Gain(GainSpec { k: 2.0 }), 1.0),
    ]);
    specs
        .into_iter()
        .enumerate()
        .map(|(i, (name, model, amplitude))| {
            // Every model gets the nets in its resources; the compensators read them.
            let fmu = fmu_with_nets(&format!("Soak{i}"), model);
            let reals = |causality: Causality| -> Vec<u32> {
                fmu.description
                    .variables
                    .iter()
                    .filter(|v| v.causality == causality && v.base_type() == BaseType::Real)
                    .map(|v| v.value_reference)
                    .collect()
            };
            let (inputs, outputs) = (reals(Causality::Input), reals(Causality::Output));
            assert!(!inputs.is_empty() && !outputs.is_empty(), "{name}");
            Model { name, fmu, inputs, outputs, amplitude }
        })
        .collect()
}

/// A state pointer of an instance, sent with it to its worker.
struct State(*mut c_void);
// SAFETY: the pointer is a handle of the instance it is sent with, only ever passed back to
// that instance's functions (which take it as a number), never read through.
unsafe impl Send for State {}

/// One instance on its run: either soaked (states saved, restored, replayed) or plain.
struct Run {
    model: Arc<Model>,
    /// Index in the list of models (the plain run of the same model is the reference).
    model_index: usize,
    soaked: bool,
    instance: Instance,
    /// Steps taken on the trajectory (a replay goes back and forth; it does not count).
    k: usize,
    /// Persistent state slot, overwritten at each save.
    slot: State,
    /// The step the first state was saved at and the hash of the replay window after it; its
    /// serialised bytes are in `first_bytes`.
    first: Option<(usize, u64)>,
    /// Buffers the run keeps, allocated before the measurement starts, so that the heap in use
    /// shows the FMU's memory and not the soak's own records.
    first_bytes: Vec<u8>,
    serialized: Vec<u8>,
    input_values: Vec<f64>,
    output_values: Vec<f64>,
    restores: usize,
    replays: usize,
    rewinds: usize,
    do_steps: usize,
    /// CPU time of the worker thread spent on this run [s].
    busy: f64,
    initial_outputs: Vec<f64>,
    final_outputs: Vec<f64>,
}

impl Run {
    fn new(model: Arc<Model>, model_index: usize, soaked: bool) -> Run {
        let instance = model.fmu.instance();
        instance.initialize();
        let initial_outputs = instance.get_real(&model.outputs).unwrap();
        // The slot is taken now (and overwritten at each save); its size sizes the buffers.
        let mut slot = State(std::ptr::null_mut());
        let mut size = 0;
        if soaked {
            assert_eq!(instance.get_fmu_state(&mut slot.0), OK);
            assert_eq!(instance.serialized_fmu_state_size(slot.0, &mut size), OK);
        }
        let (n_in, n_out) = (model.inputs.len(), model.outputs.len());
        Run {
            model,
            model_index,
            soaked,
            instance,
            k: 0,
            slot,
            first: None,
            first_bytes: Vec::with_capacity(size),
            serialized: Vec::with_capacity(size),
            input_values: vec![0.0; n_in],
            output_values: vec![0.0; n_out],
            restores: 0,
            replays: 0,
            rewinds: 0,
            do_steps: 0,
            busy: 0.0,
            initial_outputs,
            final_outputs: Vec::with_capacity(n_out),
        }
    }

    fn outputs(&self) -> Vec<f64> {
        self.instance.get_real(&self.model.outputs).unwrap()
    }

    /// One step from step `k`: inputs that depend on `k` only, then the step; returns a hash of
    /// the outputs after it.
    fn step(&mut self, inputs: &mut [f64], outputs: &mut [f64]) -> u64 {
        let t = self.k as f64 * STEP;
        for (i, v) in inputs.iter_mut().enumerate() {
            *v = self.model.amplitude * ((0.7 + 0.13 * i as f64) * t + 0.5 * i as f64).sin();
        }
        let i = &self.instance;
        assert_eq!(i.set_real(&self.model.inputs, inputs), OK, "{}", i.log.dump());
        assert_eq!(i.step(t, STEP), OK, "{} at step {}: {}", self.model.name, self.k, i.log.dump());
        assert_eq!(i.get_real_into(&self.model.outputs, outputs), OK);
        self.k += 1;
        self.do_steps += 1;
        outputs.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, v| (h ^ v.to_bits()).wrapping_mul(0x0100_0000_01b3))
    }

    /// `steps` steps; the hashes of their outputs, combined.
    fn steps(&mut self, steps: usize) -> u64 {
        let (mut inputs, mut outputs) = (std::mem::take(&mut self.input_values), std::mem::take(&mut self.output_values));
        let hash = (0..steps).fold(0u64, |h, _| h.rotate_left(5) ^ self.step(&mut inputs, &mut outputs));
        (self.input_values, self.output_values) = (inputs, outputs);
        hash
    }

    /// Saves the state (into the reused slot), serialises and deserialises it, steps `replay`
    /// steps, restores (from the copy or the slot, in turn) and steps them again: the outputs at
    /// the restore and the whole replay must be the same.
    fn checkpoint(&mut self, replay: usize) {
        assert_eq!(self.instance.get_fmu_state(&mut self.slot.0), OK);
        let (saved_at, at_save) = (self.k, self.outputs());
        let mut size = 0;
        assert_eq!(self.instance.serialized_fmu_state_size(self.slot.0, &mut size), OK);
        self.serialized.resize(size, 0);
        assert_eq!(self.instance.serialize_fmu_state(self.slot.0, &mut self.serialized), OK);
        let mut copy = std::ptr::null_mut();
        assert_eq!(self.instance.deserialize_fmu_state(&self.serialized, &mut copy), OK);
        let first_pass = self.steps(replay);
        let after = self.outputs();
        let from_copy = self.restores % 2 == 0;
        assert_eq!(self.instance.set_fmu_state(if from_copy { copy } else { self.slot.0 }), OK);
        self.restores += 1;
        self.k = saved_at;
        assert_eq!(bits(&self.outputs()), bits(&at_save), "{}: outputs at the restore of step {saved_at}", self.model.name);
        let second_pass = self.steps(replay);
        assert_eq!(second_pass, first_pass, "{}: replay of steps {saved_at}..{}", self.model.name, saved_at + replay);
        assert_eq!(bits(&self.outputs()), bits(&after));
        self.replays += 1;
        assert_eq!(self.instance.free_fmu_state(&mut copy), OK);
        if self.first.is_none() {
            self.first = Some((saved_at, first_pass));
            self.first_bytes.extend_from_slice(&self.serialized);
        }
    }

    /// Advances by one chunk of `plan.every` steps (and a checkpoint after it, when soaked);
    /// returns whether the run is over.
    fn advance(&mut self, plan: &Plan) -> bool {
        let started = thread_cpu_seconds();
        let chunk = plan.every.min(plan.steps - self.k);
        self.steps(chunk);
        if self.soaked && self.k + plan.replay <= plan.steps {
            self.checkpoint(plan.replay);
        }
        if self.k == plan.steps {
            let outputs = self.outputs();
            self.final_outputs.extend_from_slice(&outputs);
        }
        self.busy += thread_cpu_seconds() - started;
        self.k == plan.steps
    }

    /// After the run: restores the first state saved (deserialised into this instance) and
    /// replays the steps after it.
    fn rewind_to_first(&mut self, replay: usize) {
        let Some((saved_at, hash)) = self.first.take() else { return };
        let mut state = std::ptr::null_mut();
        assert_eq!(self.instance.deserialize_fmu_state(&self.first_bytes, &mut state), OK);
        assert_eq!(self.instance.set_fmu_state(state), OK);
        self.k = saved_at;
        assert_eq!(self.steps(replay), hash, "{}: replay after the first state, at the end", self.model.name);
        assert_eq!(self.instance.free_fmu_state(&mut state), OK);
        self.rewinds += 1;
    }
}

impl Drop for Run {
    fn drop(&mut self) {
        if !self.slot.0.is_null() {
            self.instance.free_fmu_state(&mut self.slot.0);
        }
    }
}

fn bits(values: &[f64]) -> Vec<u64> {
    values.iter().map(|v| v.to_bits()).collect()
}

#[repr(C)]
struct Timespec {
    seconds: i64,
    nanoseconds: i64,
}

extern "C" {
    fn clock_gettime(clock: i32, time: *mut Timespec) -> i32;
}

/// CPU time of the calling thread [s]: the rates are per CPU second, so that other processes
/// on the machine taking the cores do not count against a run.
fn thread_cpu_seconds() -> f64 {
    const CLOCK_THREAD_CPUTIME_ID: i32 = 3;
    let mut t = Timespec { seconds: 0, nanoseconds: 0 };
    // SAFETY: `clock_gettime` is libc's, declared as POSIX does; `t` is a writable `timespec`
    // (two 64-bit fields on the 64-bit Linux this test runs on) that outlives the call.
    assert_eq!(unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut t) }, 0);
    t.seconds as f64 + t.nanoseconds as f64 * 1e-9
}

/// Resident memory [KiB] and its high-water mark, from /proc.
fn resident_kib() -> (u64, u64) {
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let field = |name: &str| {
        status.lines().find_map(|l| l.strip_prefix(name)).and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok()).unwrap_or(0)
    };
    (field("VmRSS:"), field("VmHWM:"))
}

/// glibc's heap statistics (all arenas); the FMU binary allocates through the same malloc.
#[repr(C)]
struct MallInfo2 {
    arena: usize,
    ordblks: usize,
    smblks: usize,
    hblks: usize,
    hblkhd: usize,
    usmblks: usize,
    fsmblks: usize,
    uordblks: usize,
    fordblks: usize,
    keepcost: usize,
}

extern "C" {
    fn mallinfo2() -> MallInfo2;
}

/// Bytes allocated by malloc and not freed (small blocks and mapped ones).
fn heap_in_use() -> usize {
    // SAFETY: `mallinfo2` is glibc's (2.33 and later), declared as glibc does; it takes nothing
    // and returns its struct by value.
    let m = unsafe { mallinfo2() };
    m.uordblks + m.hblkhd
}

/// Memory samples in a buffer allocated once: when it is full, every second sample is dropped
/// and only every second one kept from then on, so a run of any length keeps an even record
/// without allocating while it is measured.
struct Samples {
    /// (resident KiB, heap bytes).
    kept: Vec<(u64, usize)>,
    stride: usize,
    taken: usize,
    peak_rss_kib: u64,
    peak_heap: usize,
}

impl Samples {
    const CAPACITY: usize = 4096;

    fn new() -> Self {
        Samples { kept: Vec::with_capacity(Self::CAPACITY), stride: 1, taken: 0, peak_rss_kib: 0, peak_heap: 0 }
    }

    fn add(&mut self, rss_kib: u64, heap: usize) {
        self.peak_rss_kib = self.peak_rss_kib.max(rss_kib);
        self.peak_heap = self.peak_heap.max(heap);
        if self.taken % self.stride == 0 {
            if self.kept.len() == Self::CAPACITY {
                let mut i = 0;
                self.kept.retain(|_| {
                    i += 1;
                    i % 2 == 1
                });
                self.stride *= 2;
            }
            if self.taken % self.stride == 0 {
                self.kept.push((rss_kib, heap));
            }
        }
        self.taken += 1;
    }
}

/// What a soak measured.
struct Figures {
    lines: Vec<String>,
}

/// Runs the soak of `plan`; asserts every equality; returns the figures as lines to print.
#[allow(clippy::too_many_lines, reason = "one soak scenario whose phases share the instances' state; a test read top to bottom")]
fn soak(plan: Plan) -> Figures {
    let heap_before = heap_in_use();
    let models: Vec<Arc<Model>> = models().into_iter().map(Arc::new).collect();
    let arm_kinds = 4;
    let mut runs = Vec::new();
    for (index, model) in models.iter().enumerate() {
        // The plain run of each model first: the reference.
        runs.push(Run::new(model.clone(), index, false));
    }
    for a in 0..plan.arms {
        runs.push(Run::new(models[a % arm_kinds].clone(), a % arm_kinds, true));
    }
    for (index, model) in models.iter().enumerate().skip(arm_kinds) {
        for _ in 0..plan.others {
            runs.push(Run::new(model.clone(), index, true));
        }
    }
    let instances = runs.len();
    let mut shares: Vec<Vec<Run>> = (0..plan.threads).map(|_| Vec::with_capacity(instances)).collect();
    for (i, run) in runs.into_iter().enumerate() {
        shares[i % plan.threads].push(run);
    }

    // Sample the resident memory and the heap while the workers step.
    let stop = Arc::new(AtomicBool::new(false));
    let samples = Arc::new(Mutex::new(Samples::new()));
    let sampler = {
        let (stop, samples) = (stop.clone(), samples.clone());
        std::thread::spawn(move || {
            while !stop.load(Ordering::Relaxed) {
                let heap = heap_in_use();
                samples.lock().unwrap().add(resident_kib().0, heap);
                std::thread::sleep(Duration::from_millis(50));
            }
        })
    };
    let (rss_start, _) = resident_kib();
    let heap_start = heap_in_use();
    let started = Instant::now();
    let workers: Vec<_> = shares
        .into_iter()
        .map(|mut share| {
            std::thread::spawn(move || {
                // Round robin over the share, one chunk each, so every instance stays alive and
                // advances through the whole run.
                let mut done = vec![false; share.len()];
                while done.iter().any(|d| !d) {
                    for (run, done) in share.iter_mut().zip(done.iter_mut()) {
                        if !*done {
                            *done = run.advance(&plan);
                        }
                    }
                }
                for run in &mut share {
                    run.rewind_to_first(plan.replay);
                }
                share
            })
        })
        .collect();
    let mut runs: Vec<Run> = workers.into_iter().flat_map(|w| w.join().unwrap()).collect();
    let wall = started.elapsed().as_secs_f64();
    let all_steps: usize = runs.iter().map(|r| r.do_steps).sum();
    stop.store(true, Ordering::Relaxed);
    sampler.join().unwrap();
    let (rss_end, rss_high_water) = resident_kib();
    let heap_end = heap_in_use();

    // Equalities: every soaked instance ends as the fresh run of its model.
    runs.sort_by_key(|r| (r.soaked, r.model_index));
    let references: Vec<(usize, Vec<u64>)> = runs.iter().filter(|r| !r.soaked).map(|r| (r.model_index, bits(&r.final_outputs))).collect();
    for r in runs.iter().filter(|r| !r.soaked) {
        assert!(r.final_outputs.iter().all(|v| v.is_finite()), "{}: {:?}", r.model.name, r.final_outputs);
        assert_ne!(bits(&r.final_outputs), bits(&r.initial_outputs), "{} did not move", r.model.name);
    }
    let mut equal_to_fresh = 0;
    for r in runs.iter().filter(|r| r.soaked) {
        let reference = &references.iter().find(|(i, _)| *i == r.model_index).unwrap().1;
        assert_eq!(&bits(&r.final_outputs), reference, "{}: soaked instance differs from the fresh run", r.model.name);
        equal_to_fresh += 1;
    }
    let soaked: Vec<&Run> = runs.iter().filter(|r| r.soaked).collect();
    let soaked_steps: usize = soaked.iter().map(|r| r.do_steps).sum();
    let restores: usize = soaked.iter().map(|r| r.restores).sum();
    let replays: usize = soaked.iter().map(|r| r.replays).sum();
    let rewinds: usize = soaked.iter().map(|r| r.rewinds).sum();
    assert!(restores > 0 && replays == restores && rewinds == soaked.len(), "{restores} {replays} {rewinds}");

    let mut lines = vec![
        format!(
            "{instances} instances ({} soaked: {} PlanarArm in 4 configurations, {} of each of 6 other kinds; {} fresh references), \
             {} steps each, a saved state every {} steps, {} steps replayed after each restore, {} threads, {wall:.1} s",
            soaked.len(),
            plan.arms,
            plan.others,
            instances - soaked.len(),
            plan.steps,
            plan.every,
            plan.replay,
            plan.threads
        ),
        format!(
            "{all_steps} doSteps in all ({soaked_steps} by the soaked instances, with the replays): {:.0} k steps/s over the wall clock",
            all_steps as f64 / wall / 1e3
        ),
        format!(
            "equal to a fresh run (final outputs, bit for bit): {equal_to_fresh} of {}; restores checked (outputs at the restore and the \
             replayed trajectory): {restores}; replays equal: {replays}, and {rewinds} more after restoring each instance's first \
             state at the end",
            soaked.len(),
        ),
    ];
    // Step rates per kind: soaked (with the state work and the replays) against the plain run.
    let mut names: Vec<&str> = models.iter().map(|m| m.name.split(' ').next().unwrap()).collect();
    names.dedup();
    for name in names {
        let rate = |soaked: bool| {
            let chosen: Vec<&Run> = runs.iter().filter(|r| r.soaked == soaked && r.model.name.starts_with(name)).collect();
            let steps: usize = chosen.iter().map(|r| r.do_steps).sum();
            let busy: f64 = chosen.iter().map(|r| r.busy).sum();
            (steps, steps as f64 / busy.max(1e-9))
        };
        let ((soaked_steps, soaked_rate), (_, plain_rate)) = (rate(true), rate(false));
        lines.push(format!(
            "{name:>20}: {soaked_steps:>11} doSteps soaked, {:>8.1} k steps per CPU second soaked, {:>8.1} k plain, ratio {:.3}",
            soaked_rate / 1e3,
            plain_rate / 1e3,
            soaked_rate / plain_rate
        ));
    }
    let samples = samples.lock().unwrap();
    let at = |f: f64, heap: bool| {
        let kept = &samples.kept;
        kept.get(((kept.len().max(1) - 1) as f64 * f).round() as usize).map_or(0, |s| if heap { s.1 / 1024 } else { s.0 as usize })
    };
    lines.push(format!(
        "resident memory [KiB]: start {rss_start} (instances ready), end {rss_end}, peak sampled {} ({} samples), high-water mark \
         {rss_high_water}; at 10/25/50/75/100 % of the run: {} / {} / {} / {} / {}",
        samples.peak_rss_kib.max(rss_end),
        samples.taken,
        at(0.1, false),
        at(0.25, false),
        at(0.5, false),
        at(0.75, false),
        at(1.0, false)
    ));
    lines.push(format!(
        "heap in use (malloc, every arena) [KiB]: before the instances {}, start {}, end {}, change {:+}, peak sampled {}; at \
         10/25/50/75/100 % of the run: {} / {} / {} / {} / {}",
        heap_before / 1024,
        heap_start / 1024,
        heap_end / 1024,
        (heap_end as i64 - heap_start as i64) / 1024,
        samples.peak_heap / 1024,
        at(0.1, true),
        at(0.25, true),
        at(0.5, true),
        at(0.75, true),
        at(1.0, true)
    ));
    drop(samples);
    drop(runs);
    let heap_freed = heap_in_use();
    drop(models);
    lines.push(format!(
        "after freeing every instance: heap in use {} KiB; and the models (FMU folders, descriptions): {} KiB; resident {} KiB",
        heap_freed / 1024,
        heap_in_use() / 1024,
        resident_kib().0
    ));
    Figures { lines }
}

fn env_or(name: &str, default: usize) -> usize {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

#[test]
fn short_soak_saves_restores_and_ends_as_a_fresh_run() {
    let plan = Plan { arms: 4, others: 1, steps: 10_000, every: 1_000, replay: 100, threads: 2 };
    let figures = soak(plan);
    for line in figures.lines {
        eprintln!("{line}");
    }
}

/// The full soak of `scripts/soak`; sizes from NEURARM_SOAK_ARMS (100), NEURARM_SOAK_OTHERS (2),
/// NEURARM_SOAK_STEPS (10⁶), NEURARM_SOAK_EVERY (10⁴), NEURARM_SOAK_REPLAY (100) and
/// NEURARM_SOAK_THREADS (the cores).
#[test]
#[ignore = "minutes: run by scripts/soak"]
fn full_soak() {
    let cores = std::thread::available_parallelism().map_or(2, |n| n.get());
    let plan = Plan {
        arms: env_or("NEURARM_SOAK_ARMS", 100),
        others: env_or("NEURARM_SOAK_OTHERS", 2),
        steps: env_or("NEURARM_SOAK_STEPS", 1_000_000),
        every: env_or("NEURARM_SOAK_EVERY", 10_000),
        replay: env_or("NEURARM_SOAK_REPLAY", 100),
        threads: env_or("NEURARM_SOAK_THREADS", cores).max(1),
    };
    assert!(plan.every >= 1 && plan.replay >= 1 && plan.steps >= plan.every, "{plan:?}");
    for line in soak(plan).lines {
        println!("{line}");
    }
}
