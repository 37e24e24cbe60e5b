//! The gains of the task-space law and the default damping of the self-motion.

/// Gains and null-space damping of the task-space controller.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TaskSpaceGains {
    /// Position gain K_p [1/s²] (the paper: 1000).
    pub kp: f64,
    /// Velocity gain K_d [1/s] (the paper: 160).
    pub kd: f64,
    /// Damping of the self-motion in the null space of J [1/s]: the redundant joints get
    /// q̈_null = −k (I − J⁺J) q̇, so motion the task does not need dies out. Default
    /// [`DEFAULT_NULL_DAMPING`].
    pub null_damping: f64,
    /// Stiffness of the self-motion towards a rest pose [1/s²] (used when the
    /// [`TaskSpaceData`](super::TaskSpaceData) has one,
    /// [`TaskSpaceData::set_rest_pose`](super::TaskSpaceData::set_rest_pose)): the null-space
    /// term becomes (I − J⁺J)(k_s (q_rest − q) − k q̇). Damping alone leaves the self-motion free to drift
    /// (a small torque error moves the pose along the task's null space); the stiffness gives
    /// every point of the task one pose to return to. Default 0 (damping only): on arms with
    /// high joint friction a stiffness lets the redundant joints come to rest and stick, and
    /// the tracking error grows (measured in issue 24: a 6-joint arm's perfect-compensation
    /// MSE 1.2e-7 m² at k_s = 0, 3.2e-6 m² at 25), so it is an option to set, not a default.
    #[serde(default)]
    pub null_stiffness: f64,
}

/// The default null-space damping of [`TaskSpaceGains`] [1/s].
///
/// Friction a compensator gets wrong acts on the self-motion of a redundant arm, which the
/// task does not see; only this damping holds it, and it decides which joints stop and stick.
/// No value suits every arm (measured in issue 24 on the Table 1 loops of 20 family arms and
/// the example arms, with the same nets): at 20 1/s the 6-joint example's NN/perfect is 1.002
/// and no longer chaotic (4.86 at 10, where the law 0.1 % low gives 1.64), but the family has
/// as many arms whose ratio is chaotic as at 10 (7 against 9), other ones (seeds 11, 18, 19 go
/// from 0.44–1.04 to 1.24–2.06), and two arms fall below none/perfect 5; the perfectly
/// compensated arm tracks worse the harder the self-motion is damped (built-in arm: MSE ×3.7 at
/// 20, and its ratio turns chaotic at 30). So it stays at 10, and `neurarm paper
/// --tracking-gains kp,kd,k` sets it.
pub const DEFAULT_NULL_DAMPING: f64 = 10.0;

impl Default for TaskSpaceGains {
    fn default() -> Self {
        Self { kp: 1000.0, kd: 160.0, null_damping: DEFAULT_NULL_DAMPING, null_stiffness: 0.0 }
    }
}
