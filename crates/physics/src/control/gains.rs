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
    /// term becomes (I − J⁺J)(k_s (q_rest − q) − k q̇), giving every point of the task one pose to
    /// return to. Default 0: with high joint friction it lets the redundant joints come to rest
    /// and stick (docs/decisions/0001-null-space-damping.md).
    #[serde(default)]
    pub null_stiffness: f64,
}

/// The default null-space damping of [`TaskSpaceGains`] [1/s]. Only this damping holds the
/// self-motion of a redundant arm, on which a compensator's friction error acts unseen by the
/// task. No value suits every arm, and the perfectly compensated arm tracks worse the harder it
/// is damped (docs/decisions/0001-null-space-damping.md); `neurarm paper --tracking-gains
/// kp,kd,k` sets it.
pub const DEFAULT_NULL_DAMPING: f64 = 10.0;

impl Default for TaskSpaceGains {
    fn default() -> Self {
        Self { kp: 1000.0, kd: 160.0, null_damping: DEFAULT_NULL_DAMPING, null_stiffness: 0.0 }
    }
}
