//! The whole pipeline of `neurarm paper` (quick runs, 200 sampled gravity poses) on arms of the
//! seeded random family (`neurarm_physics::family`, `neurarm random-arm`): two seeds for every
//! joint count from 2 to 8, arms nobody tuned the pipeline on. Asserted, against each arm's own
//! friction law computed here: every run finishes (the reference is placed, or fitted into the
//! ring of an arm with a hole in its workspace; identification, training and every loop run);
//! every identified friction pair lies within 0.02 N·m of the law (0.5 % of the breakaway torque
//! on joints above 4 N·m) and the pairs span 0.2 to 4.9
//! rad/s both ways; the gravity net is within 1 % RMS and 5 % at worst of each joint's largest
//! torque over the whole turn; in the joint loop NN compensation settles at most 1.5 × as far
//! from the targets as the ideal compensator (issue 24's targets); on the emulated real arm with
//! its sensor noise switched off, the true friction law tracks better than no compensation.
//!
//! Printed, not asserted, because on some of these arms they miss issue 24's targets for causes
//! its notes and `scripts/bench-family` put down to the law's scatter, the sensors or the arm:
//! sim NN/perfect (target ≤ 1.10; stick–slip, see the last column, the share of the perfect
//! run's samples with a joint at rest, and the ratio chaotic in small changes), none/perfect
//! (≥ 5), real NN/none (≤ 0.3; the emulated sensors' noise floor: printed beside it are the true
//! law fed the measured speed over none, and NN/none and true law/none with the noise off) and the
//! friction nets' error (2 % on the example arms).
//! Needs the FMU binary: `cargo build --release -p neurarm-fmu` (scripts/test builds it).

use std::path::Path;
use std::sync::Mutex;

use neurarm::experiments::paper::{compute, PaperRun};
use neurarm::experiments::{Arms, GravityDesign, NoProgress, Settings};
use neurarm_physics::config::ArmConfig;
use neurarm_physics::family::{random_arm, FAMILY_MAX_JOINTS, FAMILY_MIN_JOINTS};

use crate::quality;

/// Seeds of the family arms run here, for every joint count.
const SEEDS: [u64; 2] = [1, 2];

#[test]
fn the_quick_paper_run_holds_on_the_random_family_of_arms() {
    let cases: Vec<(u64, usize)> = (FAMILY_MIN_JOINTS..=FAMILY_MAX_JOINTS).flat_map(|j| SEEDS.iter().map(move |&s| (s, j))).collect();
    let next = Mutex::new(cases.into_iter());
    let rows = Mutex::new(Vec::new());
    let failures = Mutex::new(Vec::new());
    // Two arms at a time, one thread each: the machine's two cores.
    std::thread::scope(|scope| {
        for _ in 0..2 {
            scope.spawn(|| loop {
                let Some((seed, joints)) = next.lock().unwrap().next() else { break };
                match std::panic::catch_unwind(|| run_one(seed, joints)) {
                    Ok(row) => rows.lock().unwrap().push(row),
                    Err(e) => {
                        let why = e.downcast_ref::<String>().cloned().or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()));
                        failures.lock().unwrap().push(format!("seed {seed}, {joints} joints: {}", why.unwrap_or_default()));
                    }
                }
            });
        }
    });
    let mut rows = rows.into_inner().unwrap();
    rows.sort_by_key(|r: &String| r.clone());
    eprintln!(
        "seed joints | sim NN/perfect none/perfect real NN/none | real, true positions: perfect/none, noise off NN/none, perfect/none | worst friction net sim, real | gravity RMS, largest (quick) | joint NN/ideal | perfect run: joint at rest"
    );
    for r in &rows {
        eprintln!("{r}");
    }
    let failures = failures.into_inner().unwrap();
    assert!(failures.is_empty(), "{} of {} family arms failed:\n{}", failures.len(), rows.len() + failures.len(), failures.join("\n"));
}

/// A run of `neurarm paper` into `out`: the experiments, then their report.
fn run_paper(out: &Path, arms: &Arms, settings: &Settings, log: &mut dyn FnMut(&str)) -> anyhow::Result<PaperRun> {
    let run = compute(out, arms, settings, &NoProgress, log)?;
    neurarm::report::write_report(out, &run).map_err(anyhow::Error::msg)?;
    Ok(run)
}

/// One family arm's quick run and checks; a row of its figures.
fn run_one(seed: u64, joints: usize) -> String {
    let config = random_arm(seed, joints);
    let out = tempfile::tempdir().unwrap();
    let settings = Settings { gravity_design: Some(GravityDesign::Sampled { poses: 200 }), threads: 1, ..Settings::quick() };
    let arms = Arms::new(config.clone(), None, None).unwrap_or_else(|e| panic!("the arm is refused: {e}"));
    let run = run_paper(out.path(), &arms, &settings, &mut |_| {}).unwrap_or_else(|e| panic!("the run fails: {e:#}"));
    let r = &run.results;
    assert_eq!(r.setup.joints, joints);
    let real: ArmConfig = r.setup.real.clone();
    let (worst_net, worst_real_net) = quality::check_friction(out.path(), &config, &real, None);
    let t = r.table_1.mse_m2.to_array();
    let (nn_perfect, none_perfect, real_nn_none) = (t[1] / t[0], t[2] / t[0], t[3] / t[4]);
    let (rms, max) = quality::gravity_whole_turn(out.path(), &config);
    let settled = &r.joint_loop.settled_rad;
    let joint_ratio = settled[1].iter().zip(&settled[0]).map(|(nn, ideal)| nn / ideal).fold(0.0, f64::max);
    // Issue 24's gravity and joint-loop targets hold on every family arm.
    for i in 0..joints {
        assert!(
            rms[i] < 0.01 && max[i] < 0.05,
            "joint {}: gravity net off by {:.2} % RMS, {:.2} % at worst",
            i + 1,
            100.0 * rms[i],
            100.0 * max[i]
        );
    }
    assert!(joint_ratio <= 1.5, "joint loop: NN settles {joint_ratio:.2} × as far from the targets as the ideal compensator");
    // With the emulated sensors' noise switched off, the real arm's own friction law beats no
    // compensation (how much noise costs on each arm is printed, not asserted: on some arms the
    // noisy run happens to track better, see issue 24's notes).
    let sensors = &r.table_1.real_sensors;
    assert!(r.table_1.diagnostic_failures.is_empty(), "diagnostic loops failed: {:?}", r.table_1.diagnostic_failures);
    let [quiet_perfect, quiet_nn, quiet_none] = sensors.quiet_mse_m2.expect("the emulated real arm has sensor noise");
    assert!(
        quiet_perfect < quiet_none,
        "noise off, the true friction law tracks no better ({quiet_perfect:.3e} m²) than no compensation ({quiet_none:.3e} m²)"
    );
    format!(
        "{seed:4} {joints:6} | {nn_perfect:14.3} {none_perfect:12.1} {real_nn_none:12.3} | {:.3} {:.3} {:.3} | {:.2} %, real {:.2} % | {:.2} %, {:.2} % | {joint_ratio:.2} | {:.1} %",
        sensors.perfect_over_none.unwrap_or(f64::NAN),
        quiet_nn / quiet_none,
        quiet_perfect / quiet_none,
        100.0 * worst_net,
        100.0 * worst_real_net,
        100.0 * rms.iter().cloned().fold(0.0, f64::max),
        100.0 * max.iter().cloned().fold(0.0, f64::max),
        100.0 * r.table_1.resting_share.sim_perfect,
    )
}

/// An arm whose viscous friction is stiff for its light distal links (seed 14, 8 joints: a decay
/// rate of 3781 1/s in some poses): at the identification's usual 1 ms RK4 step its gravity
/// sweep diverged to NaN torques within 13 s; the step chosen for it keeps the sweep stable.
#[test]
fn a_stiff_arm_gets_an_identification_step_it_is_stable_at() {
    use neurarm::experiments::{build_fmus, design_poses, gravity_sweep, identification_internal_step, IDENTIFICATION_INTERNAL_STEP_S};
    let arms = Arms::new(random_arm(14, 8), None, None).unwrap();
    let arm = &arms.nominal.arm;
    let pose = [0.170, 1.731, 1.054, 0.886, 5.302, 1.651, 6.172, 3.798];
    let rate = neurarm_physics::arm::largest_viscous_rate(arm, &pose).unwrap();
    let step = identification_internal_step(arm);
    assert!(rate * IDENTIFICATION_INTERNAL_STEP_S > 2.785, "RK4 at 1 ms is unstable here: rate {rate} 1/s");
    assert!(rate * step <= 2.0, "step {step} s at rate {rate} 1/s");
    let settings = Settings { threads: 1, ..Settings::paper() };
    let dir = tempfile::tempdir().unwrap();
    let fmus = build_fmus(dir.path(), &arms, &settings).unwrap();
    let (poses, _) = design_poses(settings.design_for(8), 8, settings.seed + 17);
    let sweep = gravity_sweep(&fmus.arm, &fmus.joint_controller, arm, &poses[..40], None, &settings).unwrap();
    assert!(!sweep.pairs.is_empty() && sweep.pairs.iter().all(|(_, t)| t.iter().all(|v| v.is_finite())));
    // The arms whose identification was measured at 1 ms keep it.
    assert_eq!(identification_internal_step(&neurarm_physics::arm::ArmParams::default_four_link()), IDENTIFICATION_INTERNAL_STEP_S);
}
