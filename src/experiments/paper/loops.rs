//! The closed-loop stages of a run: the NN compensators, the loops of Table 1 and the
//! joint-space gravity compensation, and the loops that say what bounds Table 1's ratios.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use super::{
    Cases, JointLoopResults, LawSensitivity, Ratios, SensorLimit, Stages, Table1, DIAGNOSTIC_LOOPS, FINE_LAW_ERROR, LAW_ERROR, LOOPS,
    PAPER_TABLE_1,
};
use crate::experiments::*;
use neurarm_models::names;

/// The NN compensator FMUs the loops use, each with only the part it compensates.
pub(super) struct NnCompensators {
    /// The simulated arm's friction nets.
    friction: PathBuf,
    /// The real arm's friction nets.
    friction_real: PathBuf,
    /// The gravity net.
    gravity: PathBuf,
}

/// The closed loops of Table 1 and the joint-space loop, with their figures.
pub(super) struct ClosedLoops {
    /// The runs, in the order of [`LOOPS`].
    pub loops: Vec<LoopRun>,
    /// Table 1 (its diagnostics to come).
    table_1: Table1,
    /// The joint-space loop's figures.
    pub joint_loop: JointLoopResults,
    /// The Table 1 systems the diagnostic loops vary.
    bases: DiagnosticBases,
}

/// The Table 1 systems the [`DIAGNOSTIC_LOOPS`] are built from.
struct DiagnosticBases {
    sim_perfect: SystemSpec,
    real_nn: SystemSpec,
    real_perfect: SystemSpec,
    real_none: SystemSpec,
}

impl Stages<'_> {
    /// The NN compensator FMUs from the nets `friction_files` (per arm) and `gravity_net`: the
    /// full one (both nets) is the deliverable; the loops use ones exported with only the part
    /// they compensate.
    pub(super) fn nn_compensators(&self, friction_files: &[Vec<(String, PathBuf)>; 2], gravity_net: &Path) -> Result<NnCompensators> {
        let nn = |identifier: &str, friction: &[(String, PathBuf)], gravity: bool| {
            export_nn_compensator(
                &self.fmu_dir.join(format!("{identifier}.fmu")),
                identifier,
                self.arms.joints(),
                friction,
                gravity.then_some(gravity_net),
                self.settings.platforms.as_deref(),
            )
        };
        nn("NnCompensator", &friction_files[0], true)?;
        Ok(NnCompensators {
            friction: nn("NnFrictionCompensator", &friction_files[0], false)?,
            friction_real: nn("NnFrictionCompensatorReal", &friction_files[1], false)?,
            gravity: nn("NnGravityCompensator", &[], true)?,
        })
    }

    /// Table 1 and the gravity-compensation runs as system files (paths relative to
    /// `systems/`) and SSP archives, run in parallel; a loop that fails fails the run.
    pub(super) fn closed_loops(&mut self, fmus: &Fmus, nn: &NnCompensators) -> Result<ClosedLoops> {
        std::fs::create_dir_all(&self.systems_dir).with_context(|| self.systems_dir.display().to_string())?;
        let (model, settings) = (self.model(), self.settings);
        let rel = |p: &Path| self.systems_relative(p);
        let (arm, arm_real) = (rel(&fmus.arm), rel(&fmus.arm_real));
        let (task, joint) = (rel(&fmus.task_controller), rel(&fmus.joint_controller));
        let start = tracking_start(model, &self.arms.placement)?;
        let tracking = |arm: &Path, comp: Option<PathBuf>| tracking_system(arm, &task, comp.as_deref(), &start, settings);
        let joint_gains = joint_loop_gains(model, settings);
        let joint_space = |comp: Option<PathBuf>| gravity_compensation_system(&arm, &joint, comp.as_deref(), &joint_gains, settings);
        let specs: Vec<SystemSpec> = vec![
            tracking(&arm, Some(rel(&fmus.ideal_friction))),
            tracking(&arm, Some(rel(&nn.friction))),
            tracking(&arm, None),
            tracking(&arm_real, Some(rel(&nn.friction_real))),
            tracking(&arm_real, None),
            joint_space(Some(rel(&fmus.ideal_gravity))),
            joint_space(Some(rel(&nn.gravity))),
            joint_space(None),
        ];
        for (name, spec) in LOOPS.iter().zip(&specs) {
            self.write_loop_files(name, "", spec)?;
        }
        let loops = self.run_loops("closed loops", &LOOPS, specs, |name, outcome| {
            let hint = if name.starts_with("tracking") { "--tracking-gains" } else { "--joint-gains" };
            outcome.with_context(|| format!("loop {name} ({hint})"))
        })?;
        let bases = DiagnosticBases {
            sim_perfect: tracking(&arm, Some(rel(&fmus.ideal_friction))),
            real_nn: tracking(&arm_real, Some(rel(&nn.friction_real))),
            real_perfect: tracking(&arm_real, Some(rel(&fmus.ideal_friction_real))),
            real_none: tracking(&arm_real, None),
        };
        let n = self.arms.joints();
        let joint_loop = JointLoopResults {
            kp: joint_gains.iter().map(|g| g.0).collect(),
            kd: joint_gains.iter().map(|g| g.1).collect(),
            rms_rad: [0, 1, 2].map(|k| joint_rms_errors(&loops[5 + k], n)),
            settled_rad: [0, 1, 2].map(|k| joint_settled_errors(&loops[5 + k], n)),
        };
        let table_1 = table_1(&loops);
        self.lap("closed loops");
        Ok(ClosedLoops { loops, table_1, joint_loop, bases })
    }

    /// Runs the [`DIAGNOSTIC_LOOPS`] beside Table 1 (the quiet ones only if the real arm has
    /// sensor noise) and returns Table 1 with their figures. A diagnostic loop that fails
    /// (goes unstable) takes only its own figures with it: it is logged and recorded.
    pub(super) fn diagnostic_loops(&mut self, closed: &ClosedLoops) -> Result<Table1> {
        let hardware = &self.arms.real.hardware;
        let noisy = hardware.q_noise_std_rad > 0.0 || hardware.qd_noise_std_rad_s > 0.0;
        let specs = diagnostic_specs(&closed.bases, self.arms.joints(), noisy);
        for (name, spec) in DIAGNOSTIC_LOOPS.iter().zip(&specs) {
            self.write_loop_files(name, " (what bounds Table 1's ratios)", spec)?;
        }
        let runs = self.run_loops("diagnostic loops", &DIAGNOSTIC_LOOPS, specs, |name, outcome| Ok((name, outcome)))?;
        let table_1 = diagnostic_figures(&runs, noisy, &closed.table_1);
        for failure in &table_1.diagnostic_failures {
            (self.log)(&format!("diagnostic loop {failure} (its figures are left out)"));
        }
        self.lap("diagnostic loops");
        Ok(table_1)
    }
}

/// Table 1 from the first five `loops` (its diagnostics left empty).
fn table_1(loops: &[LoopRun]) -> Table1 {
    let errors: Vec<TrackingErrors> = loops[..5].iter().map(tracking_errors).collect();
    let pick = |f: &dyn Fn(&TrackingErrors) -> f64| Cases::from_array([0, 1, 2, 3, 4].map(|k| f(&errors[k])));
    let mse = pick(&|e| e.measured_mse_m2);
    let paper = Cases::from_array(PAPER_TABLE_1);
    let log_ratio: f64 = (0..5).map(|k| (paper.to_array()[k] / mse.to_array()[k]).ln()).sum::<f64>() / 5.0;
    Table1 {
        mse_m2: mse,
        true_mse_m2: pick(&|e| e.true_mse_m2),
        rms_mm: pick(&|e| e.true_rms_mm),
        sum_m2: pick(&|e| e.measured_sum_m2),
        samples: errors[0].samples,
        resting_share: pick(&|e| e.resting_share),
        ratios: Ratios::of(&mse),
        sim_law_sensitivity: LawSensitivity::default(),
        sim_law_sensitivity_fine: LawSensitivity::default(),
        real_sensors: SensorLimit::default(),
        diagnostic_failures: Vec::new(),
        paper_m2: paper,
        paper_over_ours: log_ratio.exp(),
    }
}

/// The systems of the [`DIAGNOSTIC_LOOPS`] of an arm of `n` joints, in their order: the
/// simulated arm's true law scaled, the real arm's true law, then (if `noisy`) the real arm's
/// loops with the sensor noise off.
fn diagnostic_specs(bases: &DiagnosticBases, n: usize, noisy: bool) -> Vec<SystemSpec> {
    let set = |mut spec: SystemSpec, unit: &str, values: &[(String, f64)]| {
        if let Some(entry) = spec.fmu.iter_mut().find(|f| f.name == unit) {
            for (name, value) in values {
                entry.parameters.insert(name.clone(), neurarm_cosim::Value::Real(*value));
            }
        }
        spec
    };
    let law_scaled = |scale: f64| {
        let values: Vec<(String, f64)> = (1..=n)
            .flat_map(|i| [(names::joint(names::COULOMB_SCALE, i), scale), (names::joint(names::VISCOUS_SCALE, i), scale)])
            .collect();
        set(bases.sim_perfect.clone(), COMPENSATOR_UNIT, &values)
    };
    let quiet =
        |spec: &SystemSpec| set(spec.clone(), ARM_UNIT, &[(names::ANGLE_NOISE_STD.into(), 0.0), (names::VELOCITY_NOISE_STD.into(), 0.0)]);
    let mut specs = vec![
        law_scaled(1.0 - LAW_ERROR),
        law_scaled(1.0 + LAW_ERROR),
        law_scaled(1.0 - FINE_LAW_ERROR),
        law_scaled(1.0 + FINE_LAW_ERROR),
        bases.real_perfect.clone(),
    ];
    if noisy {
        specs.extend([quiet(&bases.real_perfect), quiet(&bases.real_nn), quiet(&bases.real_none)]);
    }
    specs
}

/// `table_1` with the figures of the diagnostic `runs` (name, outcome) and their failures,
/// each recorded as "name: why".
fn diagnostic_figures(runs: &[(&str, Result<LoopRun, LoopError>)], noisy: bool, table_1: &Table1) -> Table1 {
    let failures: Vec<String> = runs.iter().filter_map(|(name, r)| r.as_ref().err().map(|e| format!("{name}: {}", e.recorded()))).collect();
    let errors: Vec<Option<TrackingErrors>> = runs.iter().map(|(_, r)| r.as_ref().ok().map(tracking_errors)).collect();
    let measured = |k: usize| errors[k].as_ref().map(|e| e.measured_mse_m2);
    let true_mse = |k: usize| errors.get(k).and_then(|e| e.as_ref()).map(|e| e.true_mse_m2);
    let sensitivity = |error: f64, low: usize| LawSensitivity {
        law_error: error,
        low_over_perfect: measured(low).map(|m| m / table_1.mse_m2.sim_perfect),
        high_over_perfect: measured(low + 1).map(|m| m / table_1.mse_m2.sim_perfect),
    };
    let quiet_mse = match (noisy, true_mse(5), true_mse(6), true_mse(7)) {
        (true, Some(p), Some(nn), Some(none)) => Some([p, nn, none]),
        _ => None,
    };
    let real_sensors = SensorLimit {
        perfect_mse_m2: true_mse(4),
        perfect_over_none: true_mse(4).map(|m| m / table_1.true_mse_m2.real_none),
        quiet_mse_m2: quiet_mse,
        quiet_nn_over_none: quiet_mse.map(|m| m[1] / m[2]),
        quiet_perfect_over_none: quiet_mse.map(|m| m[0] / m[2]),
    };
    Table1 {
        sim_law_sensitivity: sensitivity(LAW_ERROR, 0),
        sim_law_sensitivity_fine: sensitivity(FINE_LAW_ERROR, 2),
        real_sensors,
        diagnostic_failures: failures,
        ..table_1.clone()
    }
}
