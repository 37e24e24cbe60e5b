//! How many measured poses a gravity net needs: the error over the whole turn against the
//! number of poses, for the paper's grid and for sampled designs, and for each way the net can
//! see the angles. The paper concludes that gravity data grow as x^(a·DOF); this measures it.

use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use serde::Serialize;

use super::friction::FrictionCurve;
use super::gravity::{design_poses, design_span, gravity_net_errors, measure_gravity, sampled_poses_drawn, train_gravity_net};
use super::{parallel, GravityDesign, Settings};
use neurarm_nn::InputEncoding;
use neurarm_physics::arm::ArmParams;

/// Sizes of the sampled designs of the study, up to its largest.
const SAMPLED_SIZES: [usize; 8] = [25, 50, 100, 200, 400, 800, 1600, 3200];

/// One net of the study.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StudyPoint {
    /// The design its pairs were measured on.
    pub design: GravityDesign,
    /// Poses measured.
    pub poses: usize,
    /// How the net saw the angles.
    pub encoding: InputEncoding,
    /// Whole-turn RMS error per joint, as a share of the joint's own largest gravity torque.
    pub rms_share: Vec<f64>,
    /// Whole-turn largest error per joint, as a share of the joint's own largest torque.
    pub max_share: Vec<f64>,
    /// Training time [s] (wall clock, sharing the cores with the study's other trainings).
    pub train_s: f64,
}

impl StudyPoint {
    /// The worst joint's RMS share.
    pub fn worst_rms_share(&self) -> f64 {
        self.rms_share.iter().copied().fold(0.0, f64::max)
    }
    /// The worst joint's largest-error share.
    pub fn worst_max_share(&self) -> f64 {
        self.max_share.iter().copied().fold(0.0, f64::max)
    }
}

/// The study of one arm.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct GravityStudy {
    /// Joints of the arm.
    pub joints: usize,
    /// Largest design measured [poses].
    pub largest: usize,
    /// Every net, grid designs first, then sampled, each in growing size.
    pub points: Vec<StudyPoint>,
    /// Wall time of the measurements [s].
    pub measure_s: f64,
    /// Wall time of the trainings [s].
    pub train_s: f64,
}

/// Measures the study on the simulated arm: every kⁿ grid from 3 points per joint (or more, to
/// reach the trainer's fewest samples) up to
/// `largest` poses, each swept on its own, and the sampled designs of `SAMPLED_SIZES` up to
/// `largest` (and `largest` itself) as the first N poses drawn of one sweep of `largest`
/// sampled poses; on each, one net per encoding (the run's hidden size and epochs), tested on
/// the whole turn. The passes are corrected as the run's own identification is.
pub fn gravity_study(
    arm_fmu: &Path,
    controller: &Path,
    model: &ArmParams,
    correction: Option<&[FrictionCurve]>,
    largest: usize,
    settings: &Settings,
) -> Result<GravityStudy> {
    let n = model.dof();
    let started = Instant::now();
    let mut designs: Vec<(GravityDesign, Vec<super::GravityPair>)> = Vec::new();
    // The smallest grid from 3 points per joint that the trainer's split can take.
    let fewest = neurarm_nn::lm::minimum_samples(neurarm_nn::TrainSettings::default().split);
    let mut k: usize = 3;
    while k.saturating_pow(n as u32) < fewest {
        k += 1;
    }
    while k.saturating_pow(n as u32) <= largest {
        let design = GravityDesign::Grid { per_joint: k };
        let (poses, _) = design_poses(design, n, 0);
        let sweep = measure_gravity(arm_fmu, controller, model, &poses, false, correction, settings, &|| {})?;
        designs.push((design, sweep.pairs));
        k += 1;
    }
    let drawn = sampled_poses_drawn(largest, n, settings.seed + 17);
    let (order, poses): (Vec<usize>, Vec<Vec<f64>>) = drawn.into_iter().unzip();
    let sweep = measure_gravity(arm_fmu, controller, model, &poses, true, correction, settings, &|| {})?;
    let mut sizes: Vec<usize> = SAMPLED_SIZES.iter().copied().filter(|&s| s < largest).collect();
    sizes.push(largest);
    for size in sizes {
        let drawn_before = |pair: usize| order[sweep.pose_index[pair]] < size;
        let pairs = (0..sweep.pairs.len()).filter(|&k| drawn_before(k)).map(|k| sweep.pairs[k].clone()).collect();
        designs.push((GravityDesign::Sampled { poses: size }, pairs));
    }
    // A design whose passes gave too few pairs to train on is left out.
    designs.retain(|(_, pairs)| pairs.len() >= fewest);
    let measure_s = started.elapsed().as_secs_f64();
    let started = Instant::now();
    let encodings = [InputEncoding::LinkAngles, InputEncoding::JointAngles, InputEncoding::Raw];
    // Largest trainings first, so the workers end together.
    let mut tasks: Vec<(usize, InputEncoding)> = (0..designs.len()).flat_map(|d| encodings.map(|e| (d, e))).collect();
    tasks.sort_by_key(|&(d, _)| std::cmp::Reverse(designs[d].1.len()));
    let trained = parallel(
        tasks.clone(),
        settings.threads,
        |(d, encoding)| {
            let (design, pairs) = &designs[d];
            let t0 = Instant::now();
            let net = train_gravity_net(pairs, encoding, settings, &mut |_| {})?;
            let train_s = t0.elapsed().as_secs_f64();
            let errors = gravity_net_errors(&net, model, design_span(*design), settings)?;
            Ok(StudyPoint {
                design: *design,
                poses: pairs.len(),
                encoding,
                rms_share: errors.whole_turn.rms_share,
                max_share: errors.whole_turn.max_share,
                train_s,
            })
        },
        || {},
    )?;
    let mut points: Vec<(usize, StudyPoint)> = tasks.iter().map(|t| t.0).zip(trained).collect();
    points.sort_by_key(|(d, p)| (*d, encodings.iter().position(|e| *e == p.encoding)));
    Ok(GravityStudy {
        joints: n,
        largest,
        points: points.into_iter().map(|(_, p)| p).collect(),
        measure_s,
        train_s: started.elapsed().as_secs_f64(),
    })
}
