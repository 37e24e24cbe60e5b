//! The port contracts that let blocks stand in for one another in a loop.
//!
//! Every compensator has inputs `q_i` [rad] and `qd_i` [rad/s]; outputs per joint the
//! friction part `tau_friction_i`, the gravity part `tau_gravity_i` and their sum over the
//! enabled parts `tau_comp_i` [N·m]; tunable Boolean parameters `enable_friction`,
//! `enable_gravity`. Every controller has the inputs a compensator's `tau_comp_i` and an arm's
//! measurements feed: `q_i`, `qd_i`, `tau_comp_i`.

use fmi2_export::{BooleanVar, RealVar, TableBuilder, Values};

use crate::per_joint;
use crate::units::{NEWTON_METRE, RADIAN, RADIAN_PER_SECOND};

/// The variables of a compensator.
#[derive(Clone, Debug)]
pub struct CompensatorPorts {
    /// Joint angles [rad].
    pub q: Vec<RealVar>,
    /// Joint velocities [rad/s].
    pub qd: Vec<RealVar>,
    /// Friction torque of each joint [N·m].
    pub friction: Vec<RealVar>,
    /// Gravity torque of each joint [N·m].
    pub gravity: Vec<RealVar>,
    /// Sum of the enabled parts [N·m].
    pub total: Vec<RealVar>,
    /// Adds the friction part.
    pub enable_friction: BooleanVar,
    /// Adds the gravity part.
    pub enable_gravity: BooleanVar,
}

/// Which parts a compensator has, and where their torques come from.
#[derive(Clone, Copy, Debug)]
pub struct Parts {
    /// It has a friction part (each `tau_friction_i` depends on `qd_i`).
    pub friction: bool,
    /// It has a gravity part (each `tau_gravity_i` depends on every angle).
    pub gravity: bool,
    /// The source of the torques in the descriptions, e.g. "learned" or "true".
    pub source: &'static str,
}

impl CompensatorPorts {
    /// Declares the ports of a compensator of `joints` joints with `parts` in `b`; the switches
    /// start as `enable`, and a part the compensator lacks starts switched off.
    pub fn declare(b: &mut TableBuilder, joints: usize, parts: Parts, enable: (bool, bool)) -> Self {
        let q = per_joint(b, joints, |b, i| b.input(format!("q_{}", i + 1), RADIAN, 0.0, format!("Angle of joint {}", i + 1)));
        let qd =
            per_joint(b, joints, |b, i| b.input(format!("qd_{}", i + 1), RADIAN_PER_SECOND, 0.0, format!("Velocity of joint {}", i + 1)));
        let source = parts.source;
        let capital = |s: &str| s[..1].to_uppercase() + &s[1..];
        let friction = per_joint(b, joints, |b, i| {
            let deps: &[RealVar] = if parts.friction { std::slice::from_ref(&qd[i]) } else { &[] };
            b.output(
                format!("tau_friction_{}", i + 1),
                NEWTON_METRE,
                format!("{} friction torque of joint {}", capital(source), i + 1),
                deps,
            )
        });
        let gravity = per_joint(b, joints, |b, i| {
            let deps: &[RealVar] = if parts.gravity { &q } else { &[] };
            b.output(format!("tau_gravity_{}", i + 1), NEWTON_METRE, format!("{} gravity torque of joint {}", capital(source), i + 1), deps)
        });
        let total = per_joint(b, joints, |b, i| {
            let mut deps: Vec<RealVar> = if parts.gravity { q.clone() } else { Vec::new() };
            if parts.friction {
                deps.push(qd[i]);
            }
            b.output(
                format!("tau_comp_{}", i + 1),
                NEWTON_METRE,
                format!("Compensating torque of joint {}: the sum of the enabled parts", i + 1),
                &deps,
            )
        });
        let enable_friction = b.tunable_flag("enable_friction", enable.0 && parts.friction, format!("Add the {source} friction torques"));
        let enable_gravity = b.tunable_flag("enable_gravity", enable.1 && parts.gravity, format!("Add the {source} gravity torques"));
        Self { q, qd, friction, gravity, total, enable_friction, enable_gravity }
    }

    /// Number of joints.
    pub fn joints(&self) -> usize {
        self.q.len()
    }

    /// Writes joint `i`'s parts (0 for a part switched off) and their sum.
    pub fn write(&self, values: &mut Values, i: usize, friction: f64, gravity: f64) {
        values[self.friction[i]] = friction;
        values[self.gravity[i]] = gravity;
        values[self.total[i]] = friction + gravity;
    }
}

/// The inputs every controller has: measured angles and velocities, and a compensating torque
/// added to its command.
#[derive(Clone, Debug)]
pub struct ControllerInputs {
    /// Measured angles [rad].
    pub q: Vec<RealVar>,
    /// Measured velocities [rad/s].
    pub qd: Vec<RealVar>,
    /// Compensating (or feed-forward) torques [N·m].
    pub tau_comp: Vec<RealVar>,
}

impl ControllerInputs {
    /// Declares them in `b` for `joints` joints, the angles starting at `q_start` [rad].
    pub fn declare(b: &mut TableBuilder, joints: usize, q_start: &[f64]) -> Self {
        let q =
            per_joint(b, joints, |b, i| b.input(format!("q_{}", i + 1), RADIAN, q_start[i], format!("Measured angle of joint {}", i + 1)));
        let qd = per_joint(b, joints, |b, i| {
            b.input(format!("qd_{}", i + 1), RADIAN_PER_SECOND, 0.0, format!("Measured velocity of joint {}", i + 1))
        });
        let tau_comp = per_joint(b, joints, |b, i| {
            let what =
                format!("Compensating (or feed-forward) torque added to the command of joint {} (a compensator's tau_comp, or 0)", i + 1);
            b.input(format!("tau_comp_{}", i + 1), NEWTON_METRE, 0.0, what)
        });
        Self { q, qd, tau_comp }
    }
}
