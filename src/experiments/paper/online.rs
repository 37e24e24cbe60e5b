//! The online-adaptation stage of a run ([`crate::experiments::adaptation`]): friction drift,
//! payload and steady operation on the real arm, each with perfect, static, adaptive and no
//! compensation.

use std::path::{Path, PathBuf};

use anyhow::Result;

use super::{Stages, ADAPTATION_LOOPS};
use crate::experiments::adaptation::{self, AdaptationResults, AdaptationSettings};
use crate::experiments::*;
use crate::export::export_fmu_for;
use neurarm_models::{names, AdaptationLaw, FmuSpec, IdealCompensatorSpec, ModelSpec};

/// The compensators only the adaptation runs use.
struct AdaptationFmus {
    /// The real arm's ideal gravity compensator (base turned 90°).
    perfect_gravity: PathBuf,
    /// The adaptive compensator from the real arm's friction nets.
    adaptive_friction: PathBuf,
    /// The adaptive compensator from the gravity net.
    adaptive_gravity: PathBuf,
}

impl Stages<'_> {
    /// The online-adaptation runs on the real arm: exports their compensators into `fmu/`
    /// (from the real arm's friction nets `real_friction` and the gravity net `gravity_net`),
    /// writes their system files and runs them. A run that fails (a long tracking run of some
    /// arm drifting into a singular pose) is recorded, not fatal: the rest of the paper stands,
    /// and its figures read NaN.
    pub(super) fn online_adaptation(
        &mut self,
        fmus: &Fmus,
        real_friction: &[(String, PathBuf)],
        gravity_net: &Path,
    ) -> Result<(AdaptationResults, Vec<LoopRun>)> {
        let exported = self.adaptive_compensators(real_friction, gravity_net)?;
        let (specs, payload_kg) = self.adaptation_specs(fmus, &exported)?;
        for (name, spec) in ADAPTATION_LOOPS.iter().zip(&specs) {
            self.write_loop_files(name, " (online adaptation)", spec)?;
        }
        let outcomes = self.run_loops("online adaptation", &ADAPTATION_LOOPS, specs, |_, outcome| Ok(outcome))?;
        let mut failures = Vec::new();
        let loops: Vec<LoopRun> = ADAPTATION_LOOPS
            .iter()
            .zip(outcomes)
            .map(|(name, outcome)| {
                outcome.unwrap_or_else(|e| {
                    failures.push((name.to_string(), e.recorded()));
                    LoopRun { columns: Vec::new(), rows: Vec::new() }
                })
            })
            .collect();
        let a = &self.settings.adaptation;
        let results = adaptation_figures(&loops, self.arms.joints(), a, payload_kg, failures);
        self.lap("online adaptation");
        Ok((results, loops))
    }

    /// Exports the compensators only the adaptation runs use into `fmu/`.
    fn adaptive_compensators(&self, real_friction: &[(String, PathBuf)], gravity_net: &Path) -> Result<AdaptationFmus> {
        let n = self.arms.joints();
        let a = &self.settings.adaptation;
        let export = |id: &str, model: ModelSpec, sources: &[(String, PathBuf)]| -> Result<PathBuf> {
            let path = self.fmu_dir.join(format!("{id}.fmu"));
            export_fmu_for(&FmuSpec { identifier: id.into(), model }, sources, &path, self.settings.platforms.as_deref())?;
            Ok(path)
        };
        let real = self.arms.real.arm.clone().with_base_angle(std::f64::consts::FRAC_PI_2);
        let ideal = ModelSpec::IdealCompensator(IdealCompensatorSpec { arm: real, enable_friction: false, enable_gravity: true });
        let perfect_gravity = export("IdealGravityCompensatorReal", ideal, &[])?;
        let adaptive = |id: &str, friction: &[(String, PathBuf)], gravity: Option<&Path>, law: AdaptationLaw| {
            let mut sources = friction.to_vec();
            if let Some(g) = gravity {
                sources.push(("gravity.json".into(), g.to_path_buf()));
            }
            let nets = neurarm_models::NnCompensatorSpec::of_nets(
                n,
                friction.iter().map(|(name, _)| name.clone()).collect(),
                gravity.map(|_| "gravity.json".to_owned()),
            );
            export(id, ModelSpec::AdaptiveCompensator(nets.adaptive(law)), &sources)
        };
        Ok(AdaptationFmus {
            perfect_gravity,
            adaptive_friction: adaptive("AdaptiveFrictionCompensatorReal", real_friction, None, a.friction_law)?,
            adaptive_gravity: adaptive("AdaptiveGravityCompensator", &[], Some(gravity_net), a.gravity_law)?,
        })
    }

    /// The systems of the [`ADAPTATION_LOOPS`] in their order, and the payload [kg].
    fn adaptation_specs(&self, fmus: &Fmus, exported: &AdaptationFmus) -> Result<(Vec<SystemSpec>, f64)> {
        let (n, settings) = (self.arms.joints(), self.settings);
        let rel = |p: &Path| self.systems_relative(p);
        let fmu = |id: &str| rel(&self.fmu_dir.join(format!("{id}.fmu")));
        let (arm_real, task, joint) = (fmu("PlanarArmReal"), fmu("TaskSpaceController"), fmu("JointController"));
        let (pf, pg) = (rel(&fmus.ideal_friction_real), rel(&exported.perfect_gravity));
        let (af, ag) = (rel(&exported.adaptive_friction), rel(&exported.adaptive_gravity));
        let (sf, sg) = (fmu("NnFrictionCompensatorReal"), fmu("NnGravityCompensator"));
        let friction_comps = adaptation::Compensators { perfect: &pf, static_nn: &sf, adaptive: &af };
        let gravity_comps = adaptation::Compensators { perfect: &pg, static_nn: &sg, adaptive: &ag };
        let start = tracking_start(self.model(), &self.arms.placement)?;
        let gains = joint_loop_gains(self.model(), settings);
        let payload_kg = settings.adaptation.payload_share * self.arms.real.arm.links[n - 1].mass_kg;
        let mut specs: Vec<SystemSpec> =
            (0..4).map(|c| adaptation::drift_system(&arm_real, &task, &friction_comps, c, &start, settings)).collect();
        specs.extend((0..4).map(|c| adaptation::payload_system(&arm_real, &joint, &gravity_comps, c, &gains, payload_kg, settings)));
        specs.extend([1, 2].map(|c| adaptation::steady_system(&arm_real, &task, &friction_comps, c, &start, settings)));
        Ok((specs, payload_kg))
    }
}

/// The figures of the adaptation `loops` (in the order of [`ADAPTATION_LOOPS`]; a failed one
/// empty, with its `failures`) of an arm of `n` joints.
fn adaptation_figures(
    loops: &[LoopRun],
    n: usize,
    a: &AdaptationSettings,
    payload_kg: f64,
    failures: Vec<(String, String)>,
) -> AdaptationResults {
    let end = a.drift_duration_s;
    let drift_mse: [f64; 4] = std::array::from_fn(|c| adaptation::tracking_mse_between(&loops[c], end - a.drift_window_s, end));
    let before: [f64; 4] = std::array::from_fn(|c| adaptation::tracking_mse_between(&loops[c], 0.0, 2.0 * std::f64::consts::PI));
    let after = a.payload_time_s + a.payload_settle_s;
    let settled: [Vec<f64>; 4] = std::array::from_fn(|c| adaptation::settled_errors_after(&loops[4 + c], n, after));
    let settled_before: [Vec<f64>; 4] = std::array::from_fn(|c| {
        let run = &loops[4 + c];
        let kept: Vec<Vec<f64>> = run.rows.iter().filter(|r| r[0] < a.payload_time_s).cloned().collect();
        adaptation::settled_errors_after(&LoopRun { columns: run.columns.clone(), rows: kept }, n, 0.0)
    });
    let steady = [0, 1].map(|k| adaptation::tracking_mse_between(&loops[8 + k], 0.0, a.steady_duration_s));
    AdaptationResults {
        drift_mse_m2: drift_mse,
        drift_over_perfect: drift_mse.map(|m| m / drift_mse[0]),
        drift_before_mse_m2: before,
        drift_largest_adaptation_nm: adaptation::largest_adaptation(&loops[2], names::ADAPTED_FRICTION),
        payload_kg,
        payload_over_perfect: std::array::from_fn(|c| settled[c].iter().zip(&settled[0]).map(|(e, p)| e / p).collect()),
        payload_settled_rad: settled,
        payload_before_rad: settled_before,
        payload_largest_adaptation_nm: adaptation::largest_adaptation(&loops[6], names::ADAPTED_GRAVITY),
        steady_mse_m2: steady,
        steady_adaptive_over_static: steady[1] / steady[0],
        steady_largest_adaptation_nm: adaptation::largest_adaptation(&loops[9], names::ADAPTED_FRICTION),
        friction_bound_nm: a.friction_law.bound_friction,
        failures,
    }
}
