//! "Hardware-like" effects that let a simulated arm stand in for a real one: encoder
//! quantisation and measurement noise on what the controller sees, and torque saturation on
//! what the motors apply. Each is off by default; random effects draw from a seeded generator
//! so a run is repeatable. Results obtained with them are *emulated* real-robot results.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use super::integrator::ArmState;
use super::params::{check_within, limits, ParamError};

/// Which hardware-like effects are on, and how strong they are.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct HardwareEffects {
    /// Encoder resolution per joint [counts per revolution]; measured angles are rounded to a
    /// whole count. `None`, or 0 for a joint: exact angles.
    pub encoder_counts_per_rev: Option<Vec<f64>>,
    /// Standard deviation of the white Gaussian noise added to each measured angle [rad].
    pub q_noise_std_rad: f64,
    /// Standard deviation of the white Gaussian noise added to each measured velocity [rad/s].
    pub qd_noise_std_rad_s: f64,
    /// Largest torque each motor can apply [N·m]; commands beyond it are clipped. `None`, or 0
    /// for a joint: no limit.
    pub torque_limit_nm: Option<Vec<f64>>,
    /// Seed of the noise generator.
    pub seed: u64,
}

impl HardwareEffects {
    /// Checks every value against an arm of `dof` joints, each within its
    /// [`limits`](super::params::limits): encoder counts 0 (off) or 1 to 1e12 per revolution,
    /// torque limits up to 1e6 N·m, angle noise up to π rad, velocity noise up to 1e5 rad/s.
    pub fn validate(&self, dof: usize) -> Result<(), ParamError> {
        // What is wrong with one entry of each list, if anything (NaN fails every comparison).
        type Problem = fn(f64) -> Option<&'static str>;
        let encoder: Problem = |x| match x {
            _ if x == 0.0 => None,
            _ if !(x >= 1.0) => Some("must be 0 (off) or at least 1 count per revolution"),
            _ if !(x <= limits::ENCODER_COUNTS) => Some("must be at most 1e12 counts per revolution (limits::ENCODER_COUNTS)"),
            _ => None,
        };
        let torque: Problem = |x| match x {
            _ if !(x >= 0.0) => Some("must be >= 0 (0: off)"),
            _ if !(x <= limits::TORQUE_NM) => Some("must be at most 1e6 N·m (limits::TORQUE_NM)"),
            _ => None,
        };
        for (name, list, problem) in
            [("encoder_counts_per_rev", &self.encoder_counts_per_rev, encoder), ("torque_limit_nm", &self.torque_limit_nm, torque)]
        {
            if let Some(v) = list {
                if v.len() != dof {
                    return Err(ParamError::Invalid {
                        name: format!("{name} (length)"),
                        value: v.len() as f64,
                        why: "needs one entry per joint",
                    });
                }
                for (i, &x) in v.iter().enumerate() {
                    if let Some(why) = problem(x) {
                        return Err(ParamError::Invalid { name: format!("{name}[{i}]"), value: x, why });
                    }
                }
            }
        }
        let q = self.q_noise_std_rad;
        let half_turn = "must be at most π rad (limits::ANGLE_NOISE_RAD)";
        check_within(|| "q_noise_std_rad".into(), q, q >= 0.0, "must be >= 0", limits::ANGLE_NOISE_RAD, half_turn)?;
        let qd = self.qd_noise_std_rad_s;
        let speed = "must be at most 1e5 rad/s (limits::SPEED_RAD_S)";
        check_within(|| "qd_noise_std_rad_s".into(), qd, qd >= 0.0, "must be >= 0", limits::SPEED_RAD_S, speed)?;
        Ok(())
    }

    /// True if the measured state can differ from the true one.
    pub fn distorts_measurements(&self) -> bool {
        self.encoder_counts_per_rev.is_some() || self.q_noise_std_rad > 0.0 || self.qd_noise_std_rad_s > 0.0
    }
}

/// Turns the true state into what a controller would read from encoders and velocity estimates.
#[derive(Clone, Debug)]
pub struct Sensors {
    effects: HardwareEffects,
    rng: ChaCha8Rng,
    q_noise: Normal<f64>,
    qd_noise: Normal<f64>,
}

impl Sensors {
    /// Sensors with `effects`, checked against an arm of `dof` joints.
    pub fn new(effects: HardwareEffects, dof: usize) -> Result<Self, ParamError> {
        effects.validate(dof)?;
        let normal = |s: f64| Normal::new(0.0, s).expect("validated standard deviation");
        Ok(Self {
            rng: ChaCha8Rng::seed_from_u64(effects.seed),
            q_noise: normal(effects.q_noise_std_rad),
            qd_noise: normal(effects.qd_noise_std_rad_s),
            effects,
        })
    }

    /// Position in the noise generator's stream, to save and restore a run exactly.
    pub fn stream_position(&self) -> u128 {
        self.rng.get_word_pos()
    }

    /// Continues the seeded noise sequence from `position` (see [`Sensors::stream_position`]).
    pub fn set_stream_position(&mut self, position: u128) {
        self.rng = ChaCha8Rng::seed_from_u64(self.effects.seed);
        self.rng.set_word_pos(position);
    }

    /// Back to the first sample of the seeded noise sequence.
    pub fn reset(&mut self) {
        self.rng = ChaCha8Rng::seed_from_u64(self.effects.seed);
    }

    /// Measured angles [rad] and velocities [rad/s] of `state`, written into `q_out`, `qd_out`:
    /// angle = quantise(true angle) + noise, velocity = true velocity + noise.
    pub fn measure(&mut self, state: &ArmState, q_out: &mut [f64], qd_out: &mut [f64]) {
        for i in 0..state.q.len() {
            let mut q = state.q[i];
            if let Some(&counts) = self.effects.encoder_counts_per_rev.as_ref().map(|c| &c[i]) {
                if counts > 0.0 {
                    let resolution = std::f64::consts::TAU / counts;
                    q = (q / resolution).round() * resolution;
                }
            }
            if self.effects.q_noise_std_rad > 0.0 {
                q += self.q_noise.sample(&mut self.rng);
            }
            let mut qd = state.qd[i];
            if self.effects.qd_noise_std_rad_s > 0.0 {
                qd += self.qd_noise.sample(&mut self.rng);
            }
            q_out[i] = q;
            qd_out[i] = qd;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantisation_rounds_to_whole_counts() {
        let effects = HardwareEffects { encoder_counts_per_rev: Some(vec![4096.0]), ..Default::default() };
        let mut s = Sensors::new(effects, 1).unwrap();
        let res = std::f64::consts::TAU / 4096.0;
        let (mut q, mut qd) = ([0.0], [0.0]);
        s.measure(&ArmState { q: vec![10.4 * res], qd: vec![0.3] }, &mut q, &mut qd);
        assert!((q[0] - 10.0 * res).abs() < 1e-15);
        assert_eq!(qd[0], 0.3);
    }

    #[test]
    fn noise_is_seeded_and_has_the_asked_spread() {
        let effects = HardwareEffects { q_noise_std_rad: 0.01, seed: 7, ..Default::default() };
        let draw = |effects: HardwareEffects| {
            let mut s = Sensors::new(effects, 1).unwrap();
            let state = ArmState::at_rest(vec![0.0]);
            (0..20000)
                .map(|_| {
                    let (mut q, mut qd) = ([0.0], [0.0]);
                    s.measure(&state, &mut q, &mut qd);
                    q[0]
                })
                .collect::<Vec<_>>()
        };
        let a = draw(effects.clone());
        assert_eq!(a, draw(effects.clone()));
        assert_ne!(a, draw(HardwareEffects { seed: 8, ..effects }));
        let std = (a.iter().map(|x| x * x).sum::<f64>() / a.len() as f64).sqrt();
        assert!((std - 0.01).abs() < 0.0005, "std {std}");
    }

    #[test]
    fn wrong_lengths_and_negative_noise_are_rejected() {
        let e = HardwareEffects { torque_limit_nm: Some(vec![1.0]), ..Default::default() };
        assert!(e.validate(2).is_err());
        let e = HardwareEffects { torque_limit_nm: Some(vec![1.0, -1.0]), ..Default::default() };
        assert!(e.validate(2).is_err());
        let e = HardwareEffects { q_noise_std_rad: -1.0, ..Default::default() };
        assert!(e.validate(2).is_err());
    }
}
