//! The port contracts that let blocks stand in for one another in a loop.
//!
//! Every compensator has inputs `q_i` [rad] and `qd_i` [rad/s]; outputs per joint the
//! friction part `tau_friction_i`, the gravity part `tau_gravity_i` and their sum over the
//! enabled parts `tau_comp_i` [N·m]; tunable Boolean parameters `enable_friction`,
//! `enable_gravity`. Every controller has the inputs a compensator's `tau_comp_i` and an arm's
//! measurements feed: `q_i`, `qd_i`, `tau_comp_i`.

use neurarm_fmi_export::{BooleanVar, RealVar, TableBuilder, Values};

use neurarm_physics::arm::{OperatingChange, ParamError};

use crate::names::{self, joint};
use crate::per_joint;
use crate::units::{KILOGRAM, METRE, NEWTON_METRE, RADIAN, RADIAN_PER_SECOND};

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
        let q = per_joint(b, joints, |b, i| b.input(joint(names::ANGLE, i + 1), RADIAN, 0.0, format!("Angle of joint {}", i + 1)));
        let qd = per_joint(b, joints, |b, i| {
            b.input(joint(names::VELOCITY, i + 1), RADIAN_PER_SECOND, 0.0, format!("Velocity of joint {}", i + 1))
        });
        let source = parts.source;
        let capital = |s: &str| s[..1].to_uppercase() + &s[1..];
        let friction = per_joint(b, joints, |b, i| {
            let deps: &[RealVar] = if parts.friction { std::slice::from_ref(&qd[i]) } else { &[] };
            b.output(
                joint(names::FRICTION_TORQUE, i + 1),
                NEWTON_METRE,
                format!("{} friction torque of joint {}", capital(source), i + 1),
                deps,
            )
        });
        let gravity = per_joint(b, joints, |b, i| {
            let deps: &[RealVar] = if parts.gravity { &q } else { &[] };
            b.output(
                joint(names::GRAVITY_TORQUE, i + 1),
                NEWTON_METRE,
                format!("{} gravity torque of joint {}", capital(source), i + 1),
                deps,
            )
        });
        let total = per_joint(b, joints, |b, i| {
            let mut deps: Vec<RealVar> = if parts.gravity { q.clone() } else { Vec::new() };
            if parts.friction {
                deps.push(qd[i]);
            }
            b.output(
                joint(names::COMPENSATION_TORQUE, i + 1),
                NEWTON_METRE,
                format!("Compensating torque of joint {}: the sum of the enabled parts", i + 1),
                &deps,
            )
        });
        let enable_friction =
            b.tunable_flag(names::ENABLE_FRICTION, enable.0 && parts.friction, format!("Add the {source} friction torques"));
        let enable_gravity = b.tunable_flag(names::ENABLE_GRAVITY, enable.1 && parts.gravity, format!("Add the {source} gravity torques"));
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
        let q = per_joint(b, joints, |b, i| {
            b.input(joint(names::ANGLE, i + 1), RADIAN, q_start[i], format!("Measured angle of joint {}", i + 1))
        });
        let qd = per_joint(b, joints, |b, i| {
            b.input(joint(names::VELOCITY, i + 1), RADIAN_PER_SECOND, 0.0, format!("Measured velocity of joint {}", i + 1))
        });
        let tau_comp = per_joint(b, joints, |b, i| {
            let what =
                format!("Compensating (or feed-forward) torque added to the command of joint {} (a compensator's tau_comp, or 0)", i + 1);
            b.input(joint(names::COMPENSATION_TORQUE, i + 1), NEWTON_METRE, 0.0, what)
        });
        Self { q, qd, tau_comp }
    }
}

/// The tunable parameters of an arm that drifts while it works (see
/// [`OperatingChange`]): per joint `coulomb_scale_i`, `viscous_scale_i` [-] (1: as
/// identified), and `payload_mass` [kg], `payload_offset` [m] at the tip. The arm and the
/// ideal compensator share them, so "perfect compensation" can follow the same change.
#[derive(Clone, Debug)]
pub struct DriftPorts {
    /// Factor on joint i's Coulomb (and static) friction.
    pub coulomb_scale: Vec<RealVar>,
    /// Factor on joint i's viscous friction.
    pub viscous_scale: Vec<RealVar>,
    /// Payload mass.
    pub payload_mass: RealVar,
    /// Payload position beyond the tip.
    pub payload_offset: RealVar,
}

impl DriftPorts {
    /// Declares them in `b` for `joints` joints, all starting at no change.
    pub fn declare(b: &mut TableBuilder, joints: usize) -> Self {
        let coulomb_scale = per_joint(b, joints, |b, i| {
            b.tunable(
                joint(names::COULOMB_SCALE, i + 1),
                None,
                1.0,
                format!("Factor on the Coulomb and static friction of joint {}, both directions (1: as configured)", i + 1),
            )
        });
        let viscous_scale = per_joint(b, joints, |b, i| {
            b.tunable(
                joint(names::VISCOUS_SCALE, i + 1),
                None,
                1.0,
                format!("Factor on the viscous friction of joint {}, both directions (1: as configured)", i + 1),
            )
        });
        let payload_mass = b.tunable(names::PAYLOAD_MASS, KILOGRAM, 0.0, "Point mass held at the tip (0: none)");
        let payload_offset =
            b.tunable(names::PAYLOAD_OFFSET, METRE, 0.0, "Position of the payload beyond the tip along the last link (0: at the tip)");
        Self { coulomb_scale, viscous_scale, payload_mass, payload_offset }
    }

    /// Reads the change in `values` into `change` (sized for the joints); returns whether it
    /// differs from what `change` held. Allocates nothing.
    pub fn read(&self, values: &Values, change: &mut OperatingChange) -> bool {
        let mut changed = false;
        let mut take = |slot: &mut f64, value: f64| {
            // Compared by bits, so a NaN set by mistake is seen (and refused) once.
            if slot.to_bits() != value.to_bits() {
                *slot = value;
                changed = true;
            }
        };
        for (slot, &v) in change.coulomb_scale.iter_mut().zip(&self.coulomb_scale) {
            take(slot, values[v]);
        }
        for (slot, &v) in change.viscous_scale.iter_mut().zip(&self.viscous_scale) {
            take(slot, values[v]);
        }
        take(&mut change.payload_mass_kg, values[self.payload_mass]);
        take(&mut change.payload_offset_m, values[self.payload_offset]);
        changed
    }
}

/// A refusal of an [`OperatingChange`] in the FMU's variable names: `coulomb_scale[1]` is
/// `coulomb_scale_2`, `payload_mass_kg` is `payload_mass`.
pub fn drift_error(e: &ParamError) -> String {
    let text = e.to_string();
    // The physics' field names on the left, the FMU's variables on the right.
    for (field, family) in [("coulomb_scale", names::COULOMB_SCALE), ("viscous_scale", names::VISCOUS_SCALE)] {
        if let Some(rest) = text.strip_prefix(&format!("{field}[")) {
            if let Some((index, tail)) = rest.split_once(']') {
                if let Ok(i) = index.parse::<usize>() {
                    return format!("{}{tail}", joint(family, i + 1));
                }
            }
        }
    }
    text.replacen("payload_mass_kg", names::PAYLOAD_MASS, 1).replacen("payload_offset_m", names::PAYLOAD_OFFSET, 1)
}
