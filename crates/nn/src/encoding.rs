//! How a net's physical inputs become the values its first layer sees, and the net together
//! with that encoding.
//!
//! Gravity is 2π-periodic in every joint angle. The paper's net takes the raw angles and is
//! right only on the span it was trained on; a net given each angle as a point on the circle
//! (cos, sin) is periodic by construction, wherever it is evaluated.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use crate::mlp::Mlp;

/// The encoding of a net's inputs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InputEncoding {
    /// The inputs as they are (the paper's nets).
    #[default]
    Raw,
    /// Each input angle qᵢ [rad] as (cos qᵢ, sin qᵢ): the net is 2π-periodic in every input.
    JointAngles,
    /// The link angles φⱼ = q₁ + … + qⱼ [rad] of a serial chain of revolute joints (each
    /// link's direction relative to the base) as (cos φⱼ, sin φⱼ): periodic in every input.
    /// These are built from the kinematics alone; for a planar arm the gravity torques are a
    /// linear map of them, whose coefficients (masses, centres of mass, the base's tilt) the
    /// net has to learn.
    LinkAngles,
    /// Each input velocity v [rad/s] as sign(v) ln(1 + |v|/v₀), v₀ =
    /// [`LOG_SPEED_SCALE_RAD_S`]: a friction net's input. Friction jumps at zero speed (the
    /// Coulomb step); on the raw velocity a tansig net can only bridge that jump with a
    /// neuron whose slope is the step over the lowest identified speed, which the training
    /// does not reach, so it rises to the Coulomb level over tens of mrad/s. The logarithm
    /// gives the speeds from v₀ to the top speed equal room, so the step becomes an ordinary
    /// slope, while the encoding stays odd, continuous and monotonic (0 at rest).
    LogSpeed,
}

/// The speed v₀ of [`InputEncoding::LogSpeed`] [rad/s]: below it the encoding is nearly
/// linear (v/v₀), above it logarithmic.
pub const LOG_SPEED_SCALE_RAD_S: f64 = 1e-3;

impl InputEncoding {
    /// Every encoding, for listing in messages.
    pub const ALL: [InputEncoding; 4] =
        [InputEncoding::Raw, InputEncoding::JointAngles, InputEncoding::LinkAngles, InputEncoding::LogSpeed];

    /// The encodings of a gravity net (of angles).
    pub const ANGLES: [InputEncoding; 3] = [InputEncoding::Raw, InputEncoding::JointAngles, InputEncoding::LinkAngles];

    /// The name used in files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            InputEncoding::Raw => "raw",
            InputEncoding::JointAngles => "joint_angles",
            InputEncoding::LinkAngles => "link_angles",
            InputEncoding::LogSpeed => "log_speed",
        }
    }

    /// Parses [`InputEncoding::name`] (a `-` may stand for `_`).
    pub fn parse(text: &str) -> Result<Self, UnknownEncoding> {
        let wanted = text.trim().replace('-', "_");
        Self::ALL.into_iter().find(|e| e.name() == wanted).ok_or_else(|| UnknownEncoding { text: text.into() })
    }

    /// True when the encoded net is 2π-periodic in every input.
    pub fn is_periodic(self) -> bool {
        matches!(self, InputEncoding::JointAngles | InputEncoding::LinkAngles)
    }

    /// True for an encoding of angles (what a gravity net takes); false for one of speeds.
    pub fn is_of_angles(self) -> bool {
        self != InputEncoding::LogSpeed
    }

    /// Number of values the first layer sees for `inputs` physical inputs.
    pub fn features(self, inputs: usize) -> usize {
        match self {
            InputEncoding::Raw | InputEncoding::LogSpeed => inputs,
            InputEncoding::JointAngles | InputEncoding::LinkAngles => 2 * inputs,
        }
    }

    /// Encodes one sample `x` into `out` (length [`InputEncoding::features`]); for the
    /// periodic forms `out` is (cos, sin) of each angle in turn. Allocates nothing.
    #[inline]
    pub fn encode_into(self, x: &[f64], out: &mut [f64]) {
        match self {
            InputEncoding::Raw => out.copy_from_slice(x),
            InputEncoding::LogSpeed => {
                for (o, v) in out.iter_mut().zip(x) {
                    *o = (v.abs() / LOG_SPEED_SCALE_RAD_S).ln_1p().copysign(*v);
                }
            }
            InputEncoding::JointAngles => {
                for (i, q) in x.iter().enumerate() {
                    let (s, c) = q.sin_cos();
                    out[2 * i] = c;
                    out[2 * i + 1] = s;
                }
            }
            InputEncoding::LinkAngles => {
                // Each link's cosine and sine from the previous link's by the angle-sum
                // formulas would drift with the joint count; summing the angles does not.
                let mut phi = 0.0;
                for (i, q) in x.iter().enumerate() {
                    phi += q;
                    let (s, c) = phi.sin_cos();
                    out[2 * i] = c;
                    out[2 * i + 1] = s;
                }
            }
        }
    }

    /// Encodes every column of `x` (one row per input, one column per sample).
    pub fn encode_all(self, x: &DMatrix<f64>) -> DMatrix<f64> {
        let mut out = DMatrix::zeros(self.features(x.nrows()), x.ncols());
        let mut column = vec![0.0; x.nrows()];
        let mut encoded = vec![0.0; out.nrows()];
        for c in 0..x.ncols() {
            column.iter_mut().zip(x.column(c).iter()).for_each(|(d, s)| *d = *s);
            self.encode_into(&column, &mut encoded);
            out.column_mut(c).iter_mut().zip(&encoded).for_each(|(d, s)| *d = *s);
        }
        out
    }
}

/// A name that is none of [`InputEncoding::ALL`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown input encoding '{text}': use one of {}", InputEncoding::ALL.map(InputEncoding::name).join(", "))]
pub struct UnknownEncoding {
    /// The name given.
    pub text: String,
}

/// A two-layer net behind its input encoding: what a weights file describes.
#[derive(Clone, Debug, PartialEq)]
pub struct EncodedNet {
    /// How the physical inputs are encoded.
    pub encoding: InputEncoding,
    /// The net, on the encoded inputs.
    pub mlp: Mlp,
}

impl EncodedNet {
    /// Number of physical inputs.
    pub fn inputs(&self) -> usize {
        match self.encoding {
            InputEncoding::Raw | InputEncoding::LogSpeed => self.mlp.inputs(),
            InputEncoding::JointAngles | InputEncoding::LinkAngles => self.mlp.inputs() / 2,
        }
    }
    /// Number of hidden neurons.
    pub fn hidden(&self) -> usize {
        self.mlp.hidden()
    }
    /// Number of outputs.
    pub fn outputs(&self) -> usize {
        self.mlp.outputs()
    }
    /// Number of encoded values the first layer sees.
    pub fn features(&self) -> usize {
        self.mlp.inputs()
    }

    /// Evaluates one sample (original units) into `out`, with `features` (length
    /// [`EncodedNet::features`]) and `hidden` (length H) as scratch; allocates nothing.
    pub fn evaluate_into(&self, x: &[f64], features: &mut [f64], hidden: &mut [f64], out: &mut [f64]) {
        self.encoding.encode_into(x, features);
        self.mlp.evaluate_into(features, hidden, out);
    }

    /// A friction net's torque at joint speed `speed` [rad/s] → [N·m], with `hidden` (length H)
    /// as scratch; allocates nothing. Exactly 0 at a speed of exactly 0: the torque on a joint at
    /// rest is stiction's, decided by the arm, and the net never saw that speed (its value there
    /// is an extrapolation between its two branches, which on a stuck joint acts as a bias).
    pub fn friction_torque(&self, speed: f64, hidden: &mut [f64]) -> f64 {
        if speed == 0.0 {
            return 0.0;
        }
        let (mut feature, mut out) = ([0.0], [0.0]);
        self.evaluate_into(&[speed], &mut feature, hidden, &mut out);
        out[0]
    }

    /// Evaluates one sample (original units).
    pub fn evaluate(&self, x: &[f64]) -> Vec<f64> {
        let mut features = vec![0.0; self.features()];
        let mut hidden = vec![0.0; self.hidden()];
        let mut out = vec![0.0; self.outputs()];
        self.evaluate_into(x, &mut features, &mut hidden, &mut out);
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{MinMaxScaling, TrainReport, TrainSettings, WeightsFile};
    use rand::{Rng, SeedableRng};

    fn random_net(encoding: InputEncoding, inputs: usize, seed: u64) -> EncodedNet {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let features = encoding.features(inputs);
        let scaling = |rows: usize| MinMaxScaling { min: vec![-1.0; rows], max: vec![1.0; rows] };
        EncodedNet { encoding, mlp: Mlp::nguyen_widrow(7, scaling(features), scaling(3), &mut rng) }
    }

    #[test]
    fn link_angles_are_the_circle_points_of_the_running_sums() {
        let q = [0.3, -1.2, 2.5];
        let mut out = [0.0; 6];
        InputEncoding::LinkAngles.encode_into(&q, &mut out);
        let sums: [f64; 3] = [0.3, 0.3 - 1.2, 0.3 - 1.2 + 2.5];
        for (j, phi) in sums.iter().enumerate() {
            assert!((out[2 * j] - phi.cos()).abs() < 1e-15 && (out[2 * j + 1] - phi.sin()).abs() < 1e-15);
        }
        InputEncoding::JointAngles.encode_into(&q, &mut out);
        assert_eq!(out[2..4], [(-1.2f64).cos(), (-1.2f64).sin()]);
        let mut raw = [0.0; 3];
        InputEncoding::Raw.encode_into(&q, &mut raw);
        assert_eq!(raw, q);
    }

    #[test]
    fn periodic_nets_repeat_every_turn_in_every_input_and_raw_ones_do_not() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        for encoding in [InputEncoding::LinkAngles, InputEncoding::JointAngles] {
            let net = random_net(encoding, 3, 1);
            for _ in 0..200 {
                let q: Vec<f64> = (0..3).map(|_| rng.gen_range(-10.0..10.0)).collect();
                let y = net.evaluate(&q);
                for i in 0..3 {
                    let mut turned = q.clone();
                    turned[i] += std::f64::consts::TAU * rng.gen_range(-3..=3) as f64;
                    let again = net.evaluate(&turned);
                    assert!(y.iter().zip(&again).all(|(a, b)| (a - b).abs() <= 1e-12), "{encoding:?}: {y:?} vs {again:?}");
                }
            }
        }
        let raw = random_net(InputEncoding::Raw, 3, 1);
        let y = raw.evaluate(&[0.1, 0.2, 0.3]);
        assert!(raw.evaluate(&[0.1 + std::f64::consts::TAU, 0.2, 0.3]).iter().zip(&y).any(|(a, b)| (a - b).abs() > 1e-6));
    }

    /// The report of a net that was never trained (for weights files built by hand).
    fn untrained_report() -> TrainReport {
        TrainReport {
            epochs: 0,
            best_epoch: 0,
            stop_reason: crate::StopReason::Epochs,
            restart: 0,
            train_mse: 0.0,
            validation_mse: None,
            test_mse: None,
            counts: [1, 0, 0],
        }
    }

    #[test]
    fn the_weights_file_keeps_the_encoding_and_reads_version_1_files_as_raw() {
        let net = random_net(InputEncoding::LinkAngles, 2, 3);
        let signals = |p: &str, n: usize| (0..n).map(|i| crate::Signal { name: format!("{p}_{i}"), unit: "rad".into() }).collect();
        let report = untrained_report();
        let file = WeightsFile::new(&net.mlp, signals("q", 2), signals("tau", 3), TrainSettings::default(), report)
            .with_encoding(InputEncoding::LinkAngles);
        let back = WeightsFile::from_json(&file.to_json(), "mem").unwrap();
        let again = back.network().unwrap();
        assert_eq!(again.encoding, InputEncoding::LinkAngles);
        assert_eq!(again.inputs(), 2);
        assert_eq!(again.evaluate(&[0.4, 1.0]), net.evaluate(&[0.4, 1.0]));
        // A version 1 file has no encoding field: raw inputs, and its first layer must match them.
        let mut old: serde_json::Value = serde_json::from_str(&file.to_json()).unwrap();
        old["version"] = 1.into();
        old.as_object_mut().unwrap().remove("encoding");
        let e = WeightsFile::from_json(&old.to_string(), "old.json").unwrap_err().to_string();
        assert!(e.contains("iw row 0 has 4 values, expected 2"), "{e}");
        old["version"] = 1.into();
        old["encoding"] = "link_angles".into();
        let e = WeightsFile::from_json(&old.to_string(), "old.json").unwrap_err().to_string();
        assert!(e.contains("version 1 file has raw inputs only"), "{e}");
        assert!(InputEncoding::parse("polar").unwrap_err().to_string().contains("raw, joint_angles, link_angles, log_speed"));
        assert_eq!(InputEncoding::parse("link-angles"), Ok(InputEncoding::LinkAngles));
    }

    #[test]
    fn the_log_speed_is_odd_continuous_and_increasing_and_linear_below_its_scale() {
        let encode = |v: f64| {
            let mut out = [0.0];
            InputEncoding::LogSpeed.encode_into(&[v], &mut out);
            out[0]
        };
        assert_eq!(encode(0.0), 0.0);
        // At the scale: ln 2; far below it v/v₀ (the first terms of ln(1 + x) = x − x²/2).
        assert!((encode(LOG_SPEED_SCALE_RAD_S) - std::f64::consts::LN_2).abs() < 1e-15);
        let tiny = 1e-9;
        assert!((encode(tiny) - tiny / LOG_SPEED_SCALE_RAD_S).abs() < 1e-11);
        let mut previous = f64::NEG_INFINITY;
        for k in -2000..=2000 {
            let v = k as f64 * 2.5e-3;
            let u = encode(v);
            assert_eq!(encode(-v), -u, "odd at {v}");
            assert!(u > previous, "increasing at {v}");
            previous = u;
        }
        // Far above the scale, logarithmic: a decade adds ln((1 + 5000) / (1 + 500)) ≈ ln 10.
        assert!((encode(5.0) - encode(0.5) - (5001.0f64 / 501.0).ln()).abs() < 1e-12);
        assert_eq!(InputEncoding::LogSpeed.features(1), 1);
        assert!(!InputEncoding::LogSpeed.is_periodic() && !InputEncoding::LogSpeed.is_of_angles());
    }

    #[test]
    fn a_friction_net_may_take_the_log_speed_and_a_gravity_net_may_not() {
        let net = random_net(InputEncoding::LogSpeed, 1, 5);
        let mlp = Mlp {
            output_scaling: MinMaxScaling { min: vec![-1.0], max: vec![1.0] },
            lw: net.mlp.lw.rows(0, 1).into_owned(),
            b2: net.mlp.b2.rows(0, 1).into_owned(),
            ..net.mlp.clone()
        };
        let net = EncodedNet { encoding: InputEncoding::LogSpeed, mlp };
        let signal = |n: &str, u: &str| vec![crate::Signal { name: n.into(), unit: u.into() }];
        let report = untrained_report();
        let file = WeightsFile::new(&net.mlp, signal("qd_1", "rad/s"), signal("tau_friction_1", "N.m"), TrainSettings::default(), report)
            .with_encoding(InputEncoding::LogSpeed);
        let friction = file.clone().friction_of_joint(1);
        let back = WeightsFile::from_json(&friction.to_json(), "mem").unwrap().network().unwrap();
        assert_eq!(back.encoding, InputEncoding::LogSpeed);
        // The encoded net at 3 mrad/s is the plain net at ln 4.
        assert_eq!(back.evaluate(&[3e-3]), net.mlp.evaluate(&[4f64.ln()]));
        let e = file.gravity().network().unwrap_err().to_string();
        assert!(e.contains("a gravity net takes angles"), "{e}");
    }
}
