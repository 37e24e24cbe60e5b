//! The figures of a paper run: what `results.json` holds ([`PaperResults`], serialised as
//! it is) and the data beside them that the report plots ([`PaperRun`]).

use serde::Serialize;

use super::adaptation;
use super::friction::FrictionNetError;
use super::gravity::GravityNetErrors;
use super::gravity_study::GravityStudy;
use super::{Arms, FrictionPair, GravityDesign, GravityPair, LoopRun, RealOrigin, Settings};
use neurarm_nn::{InputEncoding, WeightsFile};
use neurarm_physics::config::ArmConfig;

/// How much sim NN/perfect can tell: the simulated arm tracked with its own true friction law
/// off by ∓[`LAW_ERROR`](super::paper::LAW_ERROR) (every joint's Coulomb and viscous parts
/// scaled by 1 ∓ it), MSE over the perfect run's (Table 1's measured MSEs).
///
/// Where even the true law 1 % off tracks several times worse than the exact one (a perfect
/// run with µm errors), NN/perfect ≤ 1.10 asks more of the nets than 1 % accuracy; where the
/// two scaled runs scatter around 1 (stick–slip), a ratio near 1 is within that scatter.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct LawSensitivity {
    /// The relative error applied [1].
    pub law_error: f64,
    /// The law scaled by 1 − `law_error`: MSE over perfect's (`None` if the loop failed, see
    /// [`Table1::diagnostic_failures`]).
    pub low_over_perfect: Option<f64>,
    /// The law scaled by 1 + `law_error`: MSE over perfect's (`None` if the loop failed).
    pub high_over_perfect: Option<f64>,
}

impl LawSensitivity {
    /// How far the scaled laws moved the ratio from 1, either way: the larger of |low − 1| and
    /// |high − 1| [1] (`None` unless both loops ran). Above the target's margin (0.10 for
    /// NN/perfect ≤ 1.10), a compensator as close to the law as `law_error` may miss the target
    /// by the law's own scatter.
    pub fn largest_move(&self) -> Option<f64> {
        Some((self.low_over_perfect? - 1.0).abs().max((self.high_over_perfect? - 1.0).abs()))
    }
}

/// What the real arm's sensors cost its friction compensation, from the
/// [`DIAGNOSTIC_LOOPS`](super::paper::DIAGNOSTIC_LOOPS); all MSEs from the true positions
/// [m²], ratios over the uncompensated run of the same sensors. A compensator reads the measured
/// speed, and a friction law with a step at zero speed switches on its noise near a reversal, so
/// even the true law can track worse than none: real NN/none is then bounded by the sensors, not
/// the nets. Quiet runs keep the encoders' quantisation and switch off only the noise
/// (`q_noise_std`, `qd_noise_std` at 0).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct SensorLimit {
    /// The real arm's true friction law fed the same measured speed as the NN [m²] (`None` if
    /// the loop failed, see [`Table1::diagnostic_failures`]).
    pub perfect_mse_m2: Option<f64>,
    /// `perfect_mse_m2` over the uncompensated run's (Table 1's real none, true positions).
    pub perfect_over_none: Option<f64>,
    /// With the noise off, if the real arm has any and all three loops ran: true law, NN,
    /// none [m²].
    pub quiet_mse_m2: Option<[f64; 3]>,
    /// With the noise off: NN / none.
    pub quiet_nn_over_none: Option<f64>,
    /// With the noise off: true law / none.
    pub quiet_perfect_over_none: Option<f64>,
}

/// One figure per case of Table 1 [unit as named by the field holding it].
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Cases {
    /// Simulated arm, perfect (true-model) friction compensation.
    pub sim_perfect: f64,
    /// Simulated arm, NN friction compensation.
    pub sim_nn: f64,
    /// Simulated arm, no friction compensation.
    pub sim_none: f64,
    /// Real arm, NN friction compensation (net trained on the real arm's data).
    pub real_nn: f64,
    /// Real arm, no friction compensation.
    pub real_none: f64,
}

impl Cases {
    /// From the five values in Table 1's order.
    pub fn from_array(v: [f64; 5]) -> Self {
        Self { sim_perfect: v[0], sim_nn: v[1], sim_none: v[2], real_nn: v[3], real_none: v[4] }
    }

    /// The five values in Table 1's order.
    pub fn to_array(&self) -> [f64; 5] {
        [self.sim_perfect, self.sim_nn, self.sim_none, self.real_nn, self.real_none]
    }
}

/// Table 1 and what it takes to read it.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Table1 {
    /// MSE from the measured position (the controller's error), as the paper [m²].
    pub mse_m2: Cases,
    /// MSE from the arm's true position [m²].
    pub true_mse_m2: Cases,
    /// RMS distance to the true position [mm].
    pub rms_mm: Cases,
    /// Sum of the squared distances over the samples, measured [m²].
    pub sum_m2: Cases,
    /// Samples per run.
    pub samples: usize,
    /// Share of the samples with some joint at rest (see
    /// [`super::tracking::TrackingErrors::resting_share`]).
    pub resting_share: Cases,
    /// Ratios of the measured MSEs.
    pub ratios: Ratios,
    /// How sim NN/perfect reacts to a true law 1 % off.
    pub sim_law_sensitivity: LawSensitivity,
    /// How it reacts to a true law 0.1 % off ([`FINE_LAW_ERROR`](super::paper::FINE_LAW_ERROR)).
    pub sim_law_sensitivity_fine: LawSensitivity,
    /// What the real arm's sensors cost its compensation.
    pub real_sensors: SensorLimit,
    /// The [`DIAGNOSTIC_LOOPS`](super::paper::DIAGNOSTIC_LOOPS) that failed, each "name: why" (a loop that goes unstable, e.g.
    /// the real arm's true law on a quiet but quantised speed): their figures are missing, the
    /// rest of the run stands.
    pub diagnostic_failures: Vec<String>,
    /// The paper's values [m²].
    pub paper_m2: Cases,
    /// Geometric mean over the five cases of paper / ours (measured MSE).
    pub paper_over_ours: f64,
}

/// The ratios of Table 1 the paper's claims rest on.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct Ratios {
    /// sim NN / sim perfect (the paper: 1.14).
    pub sim_nn_over_perfect: f64,
    /// sim none / sim perfect (the paper: 17.7).
    pub sim_none_over_perfect: f64,
    /// sim none / sim NN (the paper: 15.5).
    pub sim_none_over_nn: f64,
    /// real NN / real none (the paper: 0.24).
    pub real_nn_over_none: f64,
}

impl Ratios {
    /// The ratios of `m`.
    pub fn of(m: &Cases) -> Self {
        Self {
            sim_nn_over_perfect: m.sim_nn / m.sim_perfect,
            sim_none_over_perfect: m.sim_none / m.sim_perfect,
            sim_none_over_nn: m.sim_none / m.sim_nn,
            real_nn_over_none: m.real_nn / m.real_none,
        }
    }
}

/// The friction identification of one joint of one arm.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FrictionJoint {
    /// "sim" or "real".
    pub arm: String,
    /// Joint, from 1.
    pub joint: usize,
    /// Torque levels that moved the joint, both directions.
    pub levels: usize,
    /// Training pairs (bins plus the pair at rest).
    pub pairs: usize,
    /// Largest |pair − true law| over the moving pairs [N·m], and where [rad/s].
    pub pair_error_nm: f64,
    /// Velocity of that largest pair error [rad/s].
    pub pair_error_at_rad_s: f64,
    /// The trained net against the true law over 0.2 ≤ |q̇| ≤ the top speed.
    pub net_error: FrictionNetError,
    /// `net_error.rms_nm` as a share of the joint's largest friction torque.
    pub net_error_share: f64,
    /// The trained net against the true law at low speed, [`LOW_SPEED_RANGE_RAD_S`](super::paper::LOW_SPEED_RANGE_RAD_S), where
    /// it crosses the Coulomb step.
    pub low_speed_error: FrictionNetError,
    /// The measured speed's noise the identification found (a standard deviation) [rad/s].
    pub speed_noise_rad_s: f64,
    /// How the net sees the speed: "log_speed" when it was trained on the Coulomb step,
    /// "raw" (the paper's) when the noise left no room below the lowest pairs (see
    /// [`crate::experiments::train_friction_net`]).
    pub encoding: String,
}

/// The gravity identification.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct GravityResults {
    /// The design of the poses.
    pub design: GravityDesign,
    /// Whether the design is the default for the joint count (not given by the user).
    pub default_design: bool,
    /// Poses measured.
    pub pairs: usize,
    /// Pass pairs measured again because a joint was not steady in a measuring window.
    pub repeated_passes: usize,
    /// Poses left out because their passes stayed unsteady (angles in [0, 2π) [rad]).
    pub dropped_poses: Vec<Vec<f64>>,
    /// Whether each pass had the identified friction taken out before averaging.
    pub friction_correction: bool,
    /// Largest |averaged torque − true gravity at the averaged angles| of the pairs trained
    /// on [N·m].
    pub pair_error_nm: f64,
    /// The same for the plain average of the passes (the paper's procedure) [N·m].
    pub pair_error_uncorrected_nm: f64,
    /// Hidden neurons of the net.
    pub hidden: usize,
    /// How the compensator's gravity net sees the angles.
    pub encoding: InputEncoding,
    /// The compensator's net against the true gravity on random poses.
    pub net: GravityNetErrors,
    /// Error against the number of measured poses (with `--gravity-study`).
    pub study: Option<GravityStudy>,
    /// The paper's raw-angle net trained on the same pairs, for comparison (when the
    /// compensator's net is a periodic one).
    pub raw_net: Option<GravityNetErrors>,
    /// RMS error per joint as a share of the largest gravity torque of any joint (the paper's
    /// reading), over the trained span for a raw net and the whole turn for a periodic one;
    /// see `net` for each joint's own share.
    pub net_error_share: Vec<f64>,
}

/// The joint-space loop with gravity compensation.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct JointLoopResults {
    /// Position gain per joint [N·m/rad].
    pub kp: Vec<f64>,
    /// Velocity gain per joint [N·m·s/rad].
    pub kd: Vec<f64>,
    /// RMS of q_target − q per joint [rad]: ideal, NN, none.
    pub rms_rad: [Vec<f64>; 3],
    /// Settled error per joint [rad] (see [`joint_settled_errors`](super::joint_settled_errors)): ideal, NN, none.
    pub settled_rad: [Vec<f64>; 3],
}

/// The arm, the reference and the gains of a run.
#[derive(Clone, Debug, Serialize)]
pub struct RunSetup {
    /// Joints.
    pub joints: usize,
    /// Reach: the sum of the link lengths [m].
    pub reach_m: f64,
    /// The nominal arm.
    pub nominal: ArmConfig,
    /// The real arm.
    pub real: ArmConfig,
    /// Where the real arm comes from.
    pub real_origin: RealOrigin,
    /// Centre of the reference [m].
    pub reference_centre_m: [f64; 2],
    /// Scale of the reference (1 = the paper's 0.4 m × 0.3 m).
    pub reference_scale: f64,
    /// Nearest and farthest distance of the reference from the first joint [m].
    pub reference_distance_m: [f64; 2],
    /// [`gravity_scale`](super::gravity_scale) of the arm.
    pub gravity_scale: f64,
    /// (K_p [N·m/rad], K_d [N·m·s/rad]) per joint of the hold in the friction runs.
    pub hold_gains: Vec<[f64; 2]>,
}

/// Every figure of a run: what `results.json` holds and `report.md` shows.
#[derive(Clone, Debug, Serialize)]
pub struct PaperResults {
    /// neurarm's version.
    pub neurarm_version: String,
    /// The settings of the run.
    pub settings: Settings,
    /// The arm and the gains.
    pub setup: RunSetup,
    /// Table 1.
    pub table_1: Table1,
    /// Friction identification, sim joints then real joints.
    pub friction: Vec<FrictionJoint>,
    /// Gravity identification.
    pub gravity: GravityResults,
    /// The joint-space loop.
    pub joint_loop: JointLoopResults,
    /// Online adaptation: friction drift, payload, steady operation.
    pub adaptation: adaptation::AdaptationResults,
    /// Seconds per stage.
    pub timings_s: Vec<(String, f64)>,
    /// Seconds in all.
    pub total_s: f64,
}

/// What a run computed: the figures and the data the report plots and writes.
#[derive(Clone, Debug)]
pub struct PaperRun {
    /// Every figure.
    pub results: PaperResults,
    /// Binned friction pairs per joint: simulated arm, then real arm.
    pub friction_pairs: [Vec<Vec<FrictionPair>>; 2],
    /// Friction nets: the simulated arm's joints, then the real arm's.
    pub friction_nets: Vec<WeightsFile>,
    /// The gravity pairs.
    pub gravity_pairs: Vec<GravityPair>,
    /// The closed-loop runs, in the order of [`LOOPS`](super::paper::LOOPS).
    pub loops: Vec<LoopRun>,
    /// The adaptation runs, in the order of [`ADAPTATION_LOOPS`](super::paper::ADAPTATION_LOOPS).
    pub adaptation_loops: Vec<LoopRun>,
    /// The arms.
    pub arms: Arms,
}

#[cfg(test)]
mod tests {
    use super::LawSensitivity;

    #[test]
    fn the_largest_move_is_the_scaled_law_furthest_from_one_either_way() {
        let sensitivity = |low, high| LawSensitivity { law_error: 0.001, low_over_perfect: low, high_over_perfect: high };
        // The 6-joint example's stick–slip: 0.1 % low slows the loop, 0.1 % high leaves it.
        let moved = sensitivity(Some(1.639), Some(0.994)).largest_move().unwrap();
        assert!((moved - 0.639).abs() < 1e-12, "{moved}");
        // A downward move counts as much as an upward one (seed 5 of the family: 0.37 × perfect).
        let moved = sensitivity(Some(0.37), Some(1.05)).largest_move().unwrap();
        assert!((moved - 0.63).abs() < 1e-12, "{moved}");
        // A loop that failed leaves no figure.
        assert_eq!(sensitivity(None, Some(1.2)).largest_move(), None);
        assert_eq!(sensitivity(Some(1.2), None).largest_move(), None);
    }
}
