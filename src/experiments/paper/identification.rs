//! The identification stages of a run: friction on both arms and its nets, then gravity on
//! the simulated arm and its nets (and, if asked for, the gravity study).

use std::path::PathBuf;

use anyhow::{bail, Context, Result};

use super::{FrictionJoint, GravityResults, Stages, LOW_SPEED_RANGE_RAD_S};
use crate::experiments::friction::{friction_net_error, pair_error, FrictionCurve};
use crate::experiments::gravity::gravity_pair_error;
use crate::experiments::gravity_study::{gravity_study, GravityStudy};
use crate::experiments::*;
use crate::table::write_text_atomic;
use neurarm_nn::{InputEncoding, WeightsFile};

/// What the friction identification found, per arm (simulated, then real) and joint.
pub(super) struct FrictionData {
    /// Binned pairs per joint: simulated arm, then real arm.
    pub pairs: [Vec<Vec<FrictionPair>>; 2],
    /// Levels kept per joint: the simulated arm's joints, then the real arm's.
    pub levels: Vec<usize>,
    /// The measured speed's noise per joint [rad/s].
    pub speed_noise: [Vec<f64>; 2],
}

/// The trained friction nets.
pub(super) struct FrictionNets {
    /// The simulated arm's joints, then the real arm's.
    pub nets: Vec<WeightsFile>,
    /// Per arm, each net as (its name in a compensator FMU, its file).
    pub files: [Vec<(String, PathBuf)>; 2],
    /// The figures of each joint, in the order of `nets`.
    pub joints: Vec<FrictionJoint>,
}

/// What the gravity identification measured.
pub(super) struct GravityMeasured {
    /// The averaged pairs, friction taken out as the settings ask.
    pub pairs: Vec<GravityPair>,
    /// The plain averages.
    pub uncorrected: Vec<GravityPair>,
    /// Pass pairs measured again.
    pub repeated: usize,
    /// Poses left out.
    pub dropped: Vec<Vec<f64>>,
    /// The design of the poses.
    pub design: GravityDesign,
    /// The span of each angle the design covers [rad].
    pub span: f64,
    /// The simulated arm's friction curves, taken out of each pass when the settings ask.
    pub curves: Vec<FrictionCurve>,
}

impl GravityMeasured {
    /// The friction taken out of each pass, if any.
    fn correction(&self, settings: &Settings) -> Option<&[FrictionCurve]> {
        settings.gravity_friction_correction.then_some(self.curves.as_slice())
    }
}

/// The trained gravity nets.
pub(super) struct GravityNets {
    /// Their figures (the study left to its own stage).
    pub results: GravityResults,
    /// The compensator's net.
    pub path: PathBuf,
}

impl Stages<'_> {
    /// Friction identification on both arms, every joint and direction in parallel; the hold
    /// is tuned on the nominal model (all the user knows) for both.
    pub(super) fn identify_friction(&mut self, fmus: &Fmus) -> Result<FrictionData> {
        let (n, model, settings, progress) = (self.arms.joints(), self.model(), self.settings, self.progress);
        let tasks: Vec<(bool, usize, f64)> =
            [false, true].iter().flat_map(|&real| (0..n).flat_map(move |j| [(real, j, 1.0), (real, j, -1.0)])).collect();
        progress.start("friction identification", tasks.len() as u64);
        let runs = parallel(
            tasks.clone(),
            settings.threads,
            |(real, joint, dir)| {
                friction_run(if real { &fmus.arm_real } else { &fmus.arm }, &fmus.joint_controller, model, joint, dir, settings)
                    .with_context(|| {
                        let arm = if real { "real" } else { "simulated" };
                        format!("friction identification, {arm} arm, joint {} driven {}", joint + 1, if dir > 0.0 { "+" } else { "−" })
                    })
            },
            || progress.advance(),
        )?;
        progress.finish();
        let mut data = FrictionData { pairs: [Vec::new(), Vec::new()], levels: Vec::new(), speed_noise: [Vec::new(), Vec::new()] };
        for (k, real) in [false, true].into_iter().enumerate() {
            for joint in 0..n {
                let mine: Vec<&FrictionRun> =
                    runs.iter().zip(&tasks).filter(|(_, t)| t.0 == real && t.1 == joint).map(|(r, _)| r).collect();
                let rigid = settings.friction_hold == FrictionHold::Rigid;
                let inertia = rigid.then(|| held_inertia(model, joint));
                let identified = pairs_of_runs(&mine, &run_options(settings, inertia));
                data.levels.push(identified.kept());
                data.speed_noise[k].push(identified.speed_noise_rad_s());
                let binned = identified.pairs;
                if binned.len() < 4 {
                    let arm = if real { "real" } else { "simulated" };
                    bail!("friction identification, {arm} arm, joint {}: only {} training pairs", joint + 1, binned.len());
                }
                data.pairs[k].push(binned);
            }
        }
        self.lap("friction identification");
        Ok(data)
    }

    /// One net per joint of either arm, trained in parallel on its pairs; each written to
    /// `nets/` and judged against the arm's true friction law.
    pub(super) fn train_friction_nets(&mut self, identified: &FrictionData) -> Result<FrictionNets> {
        let (n, settings, progress) = (self.arms.joints(), self.settings, self.progress);
        progress.start("friction nets", 2 * n as u64);
        let nets = parallel(
            (0..2 * n).collect(),
            settings.threads,
            |i: usize| train_friction_net(i % n, &identified.pairs[i / n][i % n], identified.speed_noise[i / n][i % n], settings.seed),
            || progress.advance(),
        )?;
        progress.finish();
        let mut files: [Vec<(String, PathBuf)>; 2] = [Vec::new(), Vec::new()];
        let mut joints = Vec::new();
        for (i, net) in nets.iter().enumerate() {
            let (k, joint) = (i / n, i % n);
            let tag = if k == 0 { "sim" } else { "real" };
            let path = self.net_dir.join(format!("friction_{tag}_joint{}.json", joint + 1));
            write_text_atomic(&path, &net.to_json()).with_context(|| format!("writing {}", path.display()))?;
            files[k].push((format!("friction_{}.json", joint + 1), path));
            joints.push(self.friction_joint(net, identified, i)?);
        }
        self.lap("training friction nets");
        Ok(FrictionNets { nets, files, joints })
    }

    /// The figures of net `i` (the simulated arm's joints, then the real arm's) against its
    /// arm's true friction law.
    fn friction_joint(&self, net: &WeightsFile, identified: &FrictionData, i: usize) -> Result<FrictionJoint> {
        let n = self.arms.joints();
        let (k, joint) = (i / n, i % n);
        let law = if k == 0 { &self.arms.nominal.arm.friction[joint] } else { &self.arms.real.arm.friction[joint] };
        let pairs = &identified.pairs[k][joint];
        let (pair_error_nm, pair_error_at_rad_s) = pair_error(pairs, law);
        let net_error = friction_net_error(net, law, 0.2, self.settings.max_velocity)?;
        let low_speed_error = friction_net_error(net, law, LOW_SPEED_RANGE_RAD_S.0, LOW_SPEED_RANGE_RAD_S.1)?;
        Ok(FrictionJoint {
            arm: if k == 0 { "sim" } else { "real" }.into(),
            joint: joint + 1,
            levels: identified.levels[i],
            pairs: pairs.len(),
            pair_error_nm,
            pair_error_at_rad_s,
            net_error,
            net_error_share: net_error.share(),
            low_speed_error,
            speed_noise_rad_s: identified.speed_noise[k][joint],
            encoding: net.encoding.name().into(),
        })
    }

    /// Gravity identification on the simulated arm: the design's poses split between the
    /// workers, each pass corrected with the simulated arm's friction pairs `sim_pairs`.
    pub(super) fn identify_gravity(&mut self, fmus: &Fmus, sim_pairs: &[Vec<FrictionPair>]) -> Result<GravityMeasured> {
        let (n, settings, progress) = (self.arms.joints(), self.settings, self.progress);
        let design = settings.design_for(n);
        let (poses, span) = design_poses(design, n, settings.seed + 17);
        progress.start("gravity identification", settings.threads.min(poses.len()) as u64);
        let curves: Vec<FrictionCurve> = sim_pairs.iter().map(|p| FrictionCurve::new(p)).collect();
        let correction = settings.gravity_friction_correction.then_some(curves.as_slice());
        let wrap = matches!(design, GravityDesign::Sampled { .. });
        let sweep =
            measure_gravity(&fmus.arm, &fmus.joint_controller, self.model(), &poses, wrap, correction, settings, &|| progress.advance())?;
        progress.finish();
        self.lap("gravity identification");
        Ok(GravityMeasured {
            pairs: sweep.pairs,
            uncorrected: sweep.pairs_uncorrected,
            repeated: sweep.repeated,
            dropped: sweep.dropped,
            design,
            span,
            curves,
        })
    }

    /// The compensator's gravity net and, beside a periodic one, the paper's raw-angle net on
    /// the same pairs, trained in parallel, written to `nets/` and judged against the true
    /// gravity.
    pub(super) fn train_gravity_nets(&mut self, measured: &GravityMeasured) -> Result<GravityNets> {
        let (n, model, settings, progress) = (self.arms.joints(), self.model(), self.settings, self.progress);
        let mut encodings = vec![settings.gravity_encoding];
        if settings.gravity_encoding != InputEncoding::Raw {
            encodings.push(InputEncoding::Raw);
        }
        let what = format!("gravity nets ({n} angles, {} hidden)", settings.gravity_hidden);
        progress.start(&what, (settings.gravity_epochs * encodings.len()) as u64);
        let train = |encoding| train_gravity_net(&measured.pairs, encoding, settings, &mut |_| progress.advance());
        let mut nets = parallel(encodings, settings.threads, train, || {})?;
        progress.finish();
        let raw_net = (nets.len() > 1).then(|| nets.remove(1));
        let gravity_net = nets.remove(0);
        let path = self.net_dir.join("gravity.json");
        write_text_atomic(&path, &gravity_net.to_json()).with_context(|| format!("writing {}", path.display()))?;
        let net_errors = gravity_net_errors(&gravity_net, model, measured.span, settings)?;
        let raw_errors = match &raw_net {
            Some(raw) => {
                let raw_path = self.net_dir.join("gravity_raw.json");
                write_text_atomic(&raw_path, &raw.to_json()).with_context(|| format!("writing {}", raw_path.display()))?;
                Some(gravity_net_errors(raw, model, measured.span, settings)?)
            }
            None => None,
        };
        let results = GravityResults {
            design: measured.design,
            default_design: settings.gravity_design.is_none(),
            pairs: measured.pairs.len(),
            repeated_passes: measured.repeated,
            dropped_poses: measured.dropped.clone(),
            friction_correction: settings.gravity_friction_correction,
            pair_error_nm: gravity_pair_error(&measured.pairs, model),
            pair_error_uncorrected_nm: gravity_pair_error(&measured.uncorrected, model),
            hidden: settings.gravity_hidden,
            encoding: settings.gravity_encoding,
            net_error_share: {
                let region = net_errors.span.as_ref().unwrap_or(&net_errors.whole_turn);
                let largest = region.largest_torque_nm.iter().copied().fold(0.0, f64::max);
                region.rms_nm.iter().map(|e| e / largest).collect()
            },
            net: net_errors,
            raw_net: raw_errors,
            study: None,
        };
        self.lap("training gravity net");
        Ok(GravityNets { results, path })
    }

    /// The gravity study (see [`gravity_study`]) up to `largest` poses, its passes corrected as
    /// the identification's were.
    pub(super) fn gravity_study(&mut self, fmus: &Fmus, measured: &GravityMeasured, largest: usize) -> Result<GravityStudy> {
        self.progress.start(&format!("gravity study (up to {largest} poses)"), 1);
        let correction = measured.correction(self.settings);
        let study = gravity_study(&fmus.arm, &fmus.joint_controller, self.model(), correction, largest, self.settings)?;
        self.progress.finish();
        self.lap("gravity study");
        Ok(study)
    }
}
