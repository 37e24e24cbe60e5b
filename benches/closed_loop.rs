//! The NN-compensated tracking loop of Table 1 (arm, NN friction compensator, task-space
//! controller; 1 ms communication step), one step at a time:
//! - `master`: the three FMUs through our master (Gauss–Seidel, nothing recorded);
//! - `in_process`: the same computation as plain Rust calls, no FMI: arm step and sensors,
//!   the four friction nets, the task-space law and computed torque, all in preallocated data,
//!   through the functions the models call (`EncodedNet::friction_torque`,
//!   `task_space_torque_into`), at the times the FMUs see.
//!
//! `cargo bench --bench closed_loop -- --test` (run by `scripts/test`) is the smoke mode: the
//! plain loop is checked against the master over 5 s, and each loop steps once.
//!
//! After criterion, both loops are also timed in alternating batches (see
//! [`alternating_batches`]), into `alternating.json`; `LOOP_BENCH_BATCHES` sets how many
//! (`scripts/bench-loop --smoke`: a few).
//!
//! `scripts/bench-loop --instructions` counts instructions per step instead (callgrind), which
//! a shared machine does not disturb; see [`PROFILE_STEPS`].
//!
//! The FMUs and nets go to `<target>/closed-loop-bench/` (its `system.toml` is the loop, and
//! `system.ssp` the same loop as SSP), where `benches/python/loop_ratio.py` has fmpy drive the
//! same FMUs and libcosim run the SSP, and checks their runs against the master's end-effector
//! trajectory over the checked steps (`master_xy.csv`). `scripts/bench-loop` runs both and
//! prints the ratios and real-time factors.

#![allow(missing_docs)] // criterion_group! makes an undocumented public function

use std::path::PathBuf;

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use nalgebra::DMatrix;
use neurarm::experiments::{build_fmus, tracking_start, tracking_system, Arms, Settings};
use neurarm::export::export_fmu;
use neurarm_cosim::System;
use neurarm_models::{FmuSpec, ModelSpec, NnCompensatorSpec};
use neurarm_nn::{train, EncodedNet, Signal, TrainSettings, WeightsFile};
use neurarm_physics::arm::{end_effector_position, end_effector_state, ArmParams, ArmSimulator, ArmState, JointFriction, Sensors};
use neurarm_physics::config::ArmConfig;
use neurarm_physics::control::{
    scaled_reference, task_space_torque_into, ReferencePlacement, TaskReference, TaskSpaceData, TaskSpaceGains,
};

const STEP: f64 = 1e-3;

fn bench_dir() -> PathBuf {
    let target =
        std::env::var_os("CARGO_TARGET_DIR").map(PathBuf::from).unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target"));
    target.join("closed-loop-bench")
}

/// Friction nets of the nominal arm (10 hidden neurons, as `neurarm paper` trains them), trained
/// briefly on its friction law: their cost per evaluation is what matters here.
fn friction_nets() -> Vec<WeightsFile> {
    (0..4)
        .map(|j| {
            let law = JointFriction::default_for_joint(j);
            let v: Vec<f64> = (0..201).map(|k| -5.0 + 0.05 * k as f64).collect();
            let x = DMatrix::from_row_slice(1, v.len(), &v);
            let t = DMatrix::from_fn(1, v.len(), |_, c| law.torque(v[c]));
            let settings = TrainSettings { hidden: 10, epochs: 30, restarts: 1, seed: j as u64, ..TrainSettings::default() };
            let trained = train(&x, &t, &settings, &mut |_| {}).expect("training");
            let signal = |name: String, unit: &str| Signal { name, unit: unit.into() };
            WeightsFile::new(
                &trained.net,
                vec![signal(format!("qd_{}", j + 1), "rad/s")],
                vec![signal(format!("tau_friction_{}", j + 1), "N.m")],
                settings,
                trained.report,
            )
        })
        .collect()
}

fn loop_step(c: &mut Criterion) {
    let dir = bench_dir();
    let arms = Arms::builtin();
    let settings = Settings::quick();
    let fmus = build_fmus(&dir, &arms, &settings).expect("FMUs");
    let nets = friction_nets();
    let mut sources = Vec::new();
    for (j, net) in nets.iter().enumerate() {
        let path = dir.join(format!("friction_{}.json", j + 1));
        std::fs::write(&path, net.to_json()).expect("net written");
        sources.push((format!("friction_{}.json", j + 1), path));
    }
    let comp = dir.join("NnFrictionCompensator.fmu");
    let model = ModelSpec::NnCompensator(NnCompensatorSpec {
        joints: 4,
        friction: sources.iter().map(|s| s.0.clone()).collect(),
        gravity: None,
        enable_friction: true,
        enable_gravity: false,
    });
    export_fmu(&FmuSpec { identifier: "NnFrictionCompensator".into(), model }, &sources, &comp).expect("compensator FMU");
    let start = tracking_start(&arms.nominal.arm, &arms.placement).expect("start");
    let mut spec = tracking_system(&fmus.arm, &fmus.task_controller, Some(&comp), &start, &settings);
    spec.simulation.record.clear();
    std::fs::write(dir.join("system.toml"), spec.to_toml().expect("toml")).expect("system written");
    neurarm_cosim::ssp::write_ssp(&spec, &dir, &dir.join("system.ssp")).expect("SSP written");

    let system = System::from_spec(&spec, &dir).expect("system");
    let mut sim = system.initialize(0.0, STEP, spec.simulation.algorithm, &[]).expect("initialised");
    let profile_steps: Option<u64> = std::env::var(PROFILE_STEPS).ok().map(|s| s.parse().expect("a step count"));
    if let Some(n) = profile_steps {
        for _ in 0..n {
            master_step(&mut sim);
        }
    }
    c.bench_function("closed_loop_1ms/master", |b| b.iter(|| master_step(&mut sim)));

    // The same loop without FMI; first checked to compute what the master does.
    let mut plain = PlainLoop::new(nets.iter().map(|w| w.network().expect("net")).collect());
    let mut check = System::from_spec(&spec, &dir)
        .expect("system")
        .initialize(0.0, STEP, spec.simulation.algorithm, &["arm.x".into(), "arm.y".into()])
        .expect("initialised");
    for k in 0..CHECKED_STEPS {
        check.step().expect("step");
        let [x, y, ..] = plain.step();
        let row = &check.rows()[k + 1];
        assert!(
            row[1] == x && row[2] == y,
            "the plain loop left the master's at step {k} (they must agree bit for bit): {row:?} vs ({x}, {y})"
        );
    }
    let mut csv = String::from("time,arm.x,arm.y\n");
    for row in check.rows() {
        csv += &format!("{},{},{}\n", row[0], row[1], row[2]);
    }
    std::fs::write(dir.join("master_xy.csv"), csv).expect("master_xy.csv written");
    if let Some(n) = profile_steps {
        let mut plain = PlainLoop::new(nets.iter().map(|w| w.network().expect("net")).collect());
        for _ in 0..n {
            plain_step(&mut plain);
        }
    }
    c.bench_function("closed_loop_1ms/in_process", |b| b.iter(|| plain_step(&mut plain)));
    let smoke = std::env::args().any(|a| a == "--test");
    if profile_steps.is_none() && !smoke {
        let batches = std::env::var("LOOP_BENCH_BATCHES").map_or(BATCHES, |s| s.parse().expect("LOOP_BENCH_BATCHES: a count"));
        let (master, plain) = alternating_batches(&mut sim, &mut plain, batches);
        let json =
            format!("{{\"batch_steps\": {BATCH_STEPS}, \"batches\": {batches}, \"master_s\": {master:e}, \"plain_s\": {plain:e}}}\n");
        std::fs::write(dir.join("alternating.json"), json).expect("alternating.json written");
    }
}

/// Steps over which the plain loop must follow the master (5 s: the joints stick and slip in it).
const CHECKED_STEPS: usize = 5000;

/// Steps per batch and batches per loop of [`alternating_batches`] (unless `LOOP_BENCH_BATCHES`
/// gives another count).
const BATCH_STEPS: u32 = 100;
const BATCHES: u32 = 2000;

/// Seconds per step of the master and the plain loop, measured in alternation (a batch of one,
/// then a batch of the other), the fastest batch of each kept: on a machine that others load,
/// criterion's runs one after the other can see different loads, while the fastest of many
/// alternating batches sees each loop at its least disturbed.
fn alternating_batches(sim: &mut neurarm_cosim::Simulation, plain: &mut PlainLoop, batches: u32) -> (f64, f64) {
    let (mut master_best, mut plain_best) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..batches {
        let start = std::time::Instant::now();
        for _ in 0..BATCH_STEPS {
            master_step(sim);
        }
        master_best = master_best.min(start.elapsed().as_secs_f64() / f64::from(BATCH_STEPS));
        let start = std::time::Instant::now();
        for _ in 0..BATCH_STEPS {
            plain_step(plain);
        }
        plain_best = plain_best.min(start.elapsed().as_secs_f64() / f64::from(BATCH_STEPS));
    }
    (master_best, plain_best)
}

/// With this environment variable set to N, both loops take N steps from the start before
/// criterion runs (which `--bench no-such-benchmark` skips): what `scripts/bench-loop
/// --instructions` counts under callgrind, in [`master_step`] and [`plain_step`].
const PROFILE_STEPS: &str = "NEURARM_LOOP_PROFILE_STEPS";

/// One step of the timed master (nothing recorded); a call of its own, for the profiler.
#[inline(never)]
fn master_step(sim: &mut neurarm_cosim::Simulation) {
    sim.step().expect("step");
}

/// One step of the plain loop; a call of its own, for the profiler.
#[inline(never)]
fn plain_step(plain: &mut PlainLoop) {
    black_box(plain.step());
}

/// The loop as plain Rust calls: what the three FMUs compute, in the master's order.
struct PlainLoop {
    config: ArmConfig,
    arm: ArmSimulator,
    sensors: Sensors,
    model: ArmParams,
    placement: ReferencePlacement,
    control: TaskSpaceData,
    nets: Vec<EncodedNet>,
    state: ArmState,
    /// Communication steps taken (the master's points are `k · STEP`).
    steps: u32,
    q: [f64; 4],
    qd: [f64; 4],
    comp: [f64; 4],
    hidden: [f64; 10],
    tau: Vec<f64>,
}

impl PlainLoop {
    fn new(nets: Vec<EncodedNet>) -> Self {
        let config = ArmConfig::default();
        let (arm, sensors) = config.build().expect("arm");
        let model = config.arm.clone().frictionless();
        let placement = ReferencePlacement::for_arm(&config.arm);
        let ArmState { q: q0, qd: qd0 } = tracking_start(&config.arm, &placement).expect("start");
        let mut me = Self {
            config,
            arm,
            sensors,
            control: TaskSpaceData::new(&model),
            placement,
            model,
            nets,
            state: ArmState { q: q0, qd: qd0 },
            steps: 0,
            q: [0.0; 4],
            qd: [0.0; 4],
            comp: [0.0; 4],
            hidden: [0.0; 10],
            tau: vec![0.0; 4],
        };
        me.measure_and_control();
        me
    }

    fn measure_and_control(&mut self) {
        self.sensors.measure(&self.state, &mut self.q, &mut self.qd);
        for (j, net) in self.nets.iter().enumerate() {
            self.comp[j] = net.friction_torque(self.qd[j], &mut self.hidden);
        }
        // The controller FMU evaluates at the end of its step, the master's point `k · h` plus
        // `h` (not `(k + 1) · h`, which may differ in the last bit).
        let time = match self.steps {
            0 => 0.0,
            k => f64::from(k - 1) * STEP + STEP,
        };
        let (position, velocity, acceleration) = scaled_reference(time, self.placement.centre, self.placement.scale);
        black_box(position - end_effector_position(&self.model, &self.q));
        let reference = TaskReference { position, velocity, acceleration };
        let gains = TaskSpaceGains::default();
        let ok = task_space_torque_into(&self.model, &mut self.control, &self.q, &self.qd, &reference, &gains, &self.comp, &mut self.tau);
        assert!(ok, "control law");
    }

    /// One communication step; the arm's end-effector outputs (x, y, ẋ, ẏ) after it.
    fn step(&mut self) -> [f64; 4] {
        self.arm.step(&mut self.state, &self.tau, STEP).expect("arm step");
        self.steps += 1;
        let outputs = end_effector_state(&self.config.arm, &self.state.q, &self.state.qd);
        self.measure_and_control();
        outputs
    }
}

criterion_group!(benches, loop_step);
criterion_main!(benches);
