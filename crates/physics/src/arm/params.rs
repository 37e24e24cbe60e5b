//! Parameters of a planar n-R arm: geometry, inertia, gravity, joint friction and the integrator.
//!
//! Parameters are plain immutable data (the "model" half of a MuJoCo-style model/data split);
//! scratch space lives in [`crate::arm::ArmData`].

pub use neurarm_nn::text::show_number;
use serde::{Deserialize, Serialize};

use super::friction::JointFriction;

/// One rigid link of the arm, attached to the previous link by a revolute joint at its start.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LinkParams {
    /// Distance from this link's joint to the next joint (or the end effector) [m].
    pub length_m: f64,
    /// Mass of the link [kg].
    pub mass_kg: f64,
    /// Distance from this link's joint to its centre of mass, along the link [m].
    pub com_m: f64,
    /// Moment of inertia about the centre of mass, about the axis normal to the plane [kg·m²].
    pub inertia_kgm2: f64,
}

impl LinkParams {
    /// A uniform slender rod of `length_m` and `mass_kg`: centre of mass at mid-link, inertia m·l²/12.
    pub fn uniform_rod(length_m: f64, mass_kg: f64) -> Self {
        Self { length_m, mass_kg, com_m: 0.5 * length_m, inertia_kgm2: mass_kg * length_m * length_m / 12.0 }
    }
}

/// Everything that defines the arm's rigid-body dynamics and joint friction.
///
/// Joint angles are relative: link i's absolute angle from +x is θᵢ = q₁ + … + qᵢ.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmParams {
    /// The links, from the base outwards; their number is the number of joints.
    pub links: Vec<LinkParams>,
    /// Friction of each joint, same order as `links`.
    pub friction: Vec<JointFriction>,
    /// Magnitude of the gravitational acceleration [m/s²].
    pub gravity_m_s2: f64,
    /// Tilt of the arm's plane about the x axis [rad]. 0: the arm moves in a horizontal plane
    /// and gravity exerts no joint torque; π/2: the plane is vertical and gravity acts along −y
    /// in the plane (the paper's gravity set-up). In general the in-plane gravity is g·sin(angle).
    pub base_angle_rad: f64,
}

/// Largest number of joints an arm may have. The paper's pipeline runs arms of 2 to 8 joints;
/// the mass matrix is n × n and its factorisation grows as n³ in every RK4 stage, so a step of
/// a 64-joint arm already costs a thousand times one of a 4-joint arm. 64 is eight times the
/// largest arm of the pipeline; a configuration or an FMU resource asking for more (a typo, or
/// a file that is not what it claims) is refused before anything is allocated for it.
pub const MAX_JOINTS: usize = 64;

/// The largest values that still describe a physical arm, so that a value that parses but
/// means nothing (`mass_kg = 1e300`) is refused by name instead of overflowing the dynamics to
/// infinity. Each is far beyond any robot arm, so no real arm is refused.
pub mod limits {
    /// Link length and distance to the centre of mass [m] (the longest crane booms are < 100 m).
    pub const LENGTH_M: f64 = 100.0;
    /// Link mass [kg] (100 t).
    pub const MASS_KG: f64 = 1e5;
    /// Moment of inertia about the centre of mass [kg·m²] (the largest mass at the largest
    /// length: 1e5 kg × (100 m)²).
    pub const INERTIA_KGM2: f64 = 1e9;
    /// Gravitational acceleration [m/s²] (ten times the Earth's).
    pub const GRAVITY_M_S2: f64 = 100.0;
    /// Tilt of the base, either way [rad]: one full turn.
    pub const BASE_ANGLE_RAD: f64 = std::f64::consts::TAU;
    /// Friction levels and torque limits [N·m].
    pub const TORQUE_NM: f64 = 1e6;
    /// Viscous friction coefficient [N·m·s/rad].
    pub const VISCOUS_NMS_RAD: f64 = 1e6;
    /// Speeds: Stribeck velocity, viscous fall-off and the velocity noise [rad/s] (about a
    /// million rpm).
    pub const SPEED_RAD_S: f64 = 1e5;
    /// Standard deviation of the angle noise [rad]: half a turn.
    pub const ANGLE_NOISE_RAD: f64 = std::f64::consts::PI;
    /// Encoder counts per revolution (0 is off; a 40-bit encoder has 1.1e12).
    pub const ENCODER_COUNTS: f64 = 1e12;
    /// Shortest and longest RK4 sub-step [s].
    pub const INTERNAL_STEP_S: (f64, f64) = (1e-9, 1.0);
}

/// Why a set of parameters cannot describe an arm.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// The arm has no links.
    #[error("the arm needs at least one joint")]
    NoJoints,
    /// The arm has more joints than [`MAX_JOINTS`].
    #[error("{0} joints: an arm may have at most {MAX_JOINTS}")]
    TooManyJoints(usize),
    /// `friction` and `links` differ in length.
    #[error("{links} links but {friction} friction entries: give one per joint")]
    FrictionCount {
        /// Number of links.
        links: usize,
        /// Number of friction entries.
        friction: usize,
    },
    /// A value is out of its range.
    #[error("{name} = {} is invalid: {why}", show_number(*.value))]
    Invalid {
        /// Which parameter, e.g. `links[2].mass_kg`.
        name: String,
        /// The value given.
        value: f64,
        /// What it must be.
        why: &'static str,
    },
}

/// Checks that `value` is finite and satisfies `ok`, naming the parameter otherwise.
pub(crate) fn check(name: impl FnOnce() -> String, value: f64, ok: bool, why: &'static str) -> Result<(), ParamError> {
    if value.is_finite() && ok {
        Ok(())
    } else {
        Err(ParamError::Invalid { name: name(), value, why })
    }
}

/// Checks that `value` is finite, satisfies `ok` (`why` says how) and is at most `max` in
/// magnitude (`beyond` says what that limit is), naming the parameter otherwise.
pub(crate) fn check_within(
    name: impl Fn() -> String,
    value: f64,
    ok: bool,
    why: &'static str,
    max: f64,
    beyond: &'static str,
) -> Result<(), ParamError> {
    check(&name, value, ok, why)?;
    check(name, value, value.abs() <= max, beyond)
}

/// Checks the number of joints against [`MAX_JOINTS`].
pub fn check_joint_count(joints: usize) -> Result<(), ParamError> {
    match joints {
        0 => Err(ParamError::NoJoints),
        n if n > MAX_JOINTS => Err(ParamError::TooManyJoints(n)),
        _ => Ok(()),
    }
}

impl ArmParams {
    /// Makes `self` a copy of `other`, reusing its storage: no allocation when the joint
    /// counts match (the derived `clone_from` would clone afresh).
    pub fn copy_from(&mut self, other: &ArmParams) {
        self.links.clone_from(&other.links);
        self.friction.clone_from(&other.friction);
        self.gravity_m_s2 = other.gravity_m_s2;
        self.base_angle_rad = other.base_angle_rad;
    }

    /// The project's default 4-link arm (DESIGN.md): 0.25 m uniform links of 2.0, 1.6, 1.2 and
    /// 0.8 kg, g = 9.81 m/s², horizontal plane (no gravity torque), and the default geared-arm
    /// Coulomb + viscous friction of [`JointFriction::default_for_joint`].
    pub fn default_four_link() -> Self {
        let masses = [2.0, 1.6, 1.2, 0.8];
        Self {
            links: masses.iter().map(|&m| LinkParams::uniform_rod(0.25, m)).collect(),
            friction: (0..4).map(JointFriction::default_for_joint).collect(),
            gravity_m_s2: 9.81,
            base_angle_rad: 0.0,
        }
    }

    /// The default arm without friction, with the base turned by `base_angle_rad`.
    pub fn frictionless(mut self) -> Self {
        self.friction = vec![JointFriction::none(); self.links.len()];
        self
    }

    /// The same arm with its base turned to `base_angle_rad` [rad].
    pub fn with_base_angle(mut self, base_angle_rad: f64) -> Self {
        self.base_angle_rad = base_angle_rad;
        self
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.links.len()
    }

    /// The gravity torque joint `joint` (0-based) carries with every outboard link stretched out
    /// level under the full `gravity_m_s2`, whatever the base tilt [N·m]: the largest it can
    /// carry when no centre of mass lies behind its joint. A scale for the torques the joint's
    /// motor must be able to give.
    pub fn gravity_load_nm(&self, joint: usize) -> f64 {
        let mut reach_before = 0.0;
        let mut moment = 0.0;
        for link in &self.links[joint..] {
            moment += link.mass_kg * (reach_before + link.com_m);
            reach_before += link.length_m;
        }
        self.gravity_m_s2 * moment.abs()
    }

    /// Gravitational acceleration in the plane of motion, along −y [m/s²].
    pub fn in_plane_gravity(&self) -> f64 {
        self.gravity_m_s2 * self.base_angle_rad.sin()
    }

    /// Checks every value, each within its [`limits`]; the first problem found is returned.
    pub fn validate(&self) -> Result<(), ParamError> {
        check_joint_count(self.links.len())?;
        if self.friction.len() != self.links.len() {
            return Err(ParamError::FrictionCount { links: self.links.len(), friction: self.friction.len() });
        }
        for (i, l) in self.links.iter().enumerate() {
            let length = "must be at most 100 m (limits::LENGTH_M)";
            check_within(|| format!("links[{i}].length_m"), l.length_m, l.length_m > 0.0, "must be > 0", limits::LENGTH_M, length)?;
            let mass = "must be at most 1e5 kg (limits::MASS_KG)";
            check_within(|| format!("links[{i}].mass_kg"), l.mass_kg, l.mass_kg > 0.0, "must be > 0", limits::MASS_KG, mass)?;
            check_within(|| format!("links[{i}].com_m"), l.com_m, true, "must be finite", limits::LENGTH_M, length)?;
            let inertia = "must be at most 1e9 kg·m² (limits::INERTIA_KGM2)";
            let ok = l.inertia_kgm2 >= 0.0;
            check_within(|| format!("links[{i}].inertia_kgm2"), l.inertia_kgm2, ok, "must be >= 0", limits::INERTIA_KGM2, inertia)?;
        }
        for (i, f) in self.friction.iter().enumerate() {
            f.validate(i)?;
        }
        let g = self.gravity_m_s2;
        check_within(
            || "gravity_m_s2".into(),
            g,
            g >= 0.0,
            "must be >= 0",
            limits::GRAVITY_M_S2,
            "must be at most 100 m/s² (limits::GRAVITY_M_S2)",
        )?;
        let turn = "must be within one turn, ±2π (limits::BASE_ANGLE_RAD)";
        check_within(|| "base_angle_rad".into(), self.base_angle_rad, true, "must be finite", limits::BASE_ANGLE_RAD, turn)?;
        Ok(())
    }
}

impl Default for ArmParams {
    fn default() -> Self {
        Self::default_four_link()
    }
}
