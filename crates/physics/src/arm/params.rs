//! Parameters of a planar n-R arm: geometry, inertia, gravity, joint friction and the integrator.
//!
//! Parameters are plain immutable data (the "model" half of a MuJoCo-style model/data split);
//! scratch space lives in [`crate::arm::ArmData`].

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

/// Why a set of parameters cannot describe an arm.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ParamError {
    /// The arm has no links.
    #[error("the arm needs at least one joint")]
    NoJoints,
    /// `friction` and `links` differ in length.
    #[error("{links} links but {friction} friction entries: give one per joint")]
    FrictionCount {
        /// Number of links.
        links: usize,
        /// Number of friction entries.
        friction: usize,
    },
    /// A value is out of its range.
    #[error("{name} = {value} is invalid: {why}")]
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

impl ArmParams {
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

    /// Gravitational acceleration in the plane of motion, along −y [m/s²].
    pub fn in_plane_gravity(&self) -> f64 {
        self.gravity_m_s2 * self.base_angle_rad.sin()
    }

    /// Checks every value; the first problem found is returned.
    pub fn validate(&self) -> Result<(), ParamError> {
        if self.links.is_empty() {
            return Err(ParamError::NoJoints);
        }
        if self.friction.len() != self.links.len() {
            return Err(ParamError::FrictionCount { links: self.links.len(), friction: self.friction.len() });
        }
        for (i, l) in self.links.iter().enumerate() {
            check(|| format!("links[{i}].length_m"), l.length_m, l.length_m > 0.0, "must be > 0")?;
            check(|| format!("links[{i}].mass_kg"), l.mass_kg, l.mass_kg > 0.0, "must be > 0")?;
            check(|| format!("links[{i}].com_m"), l.com_m, true, "must be finite")?;
            check(|| format!("links[{i}].inertia_kgm2"), l.inertia_kgm2, l.inertia_kgm2 >= 0.0, "must be >= 0")?;
        }
        for (i, f) in self.friction.iter().enumerate() {
            f.validate(i)?;
        }
        check(|| "gravity_m_s2".into(), self.gravity_m_s2, self.gravity_m_s2 >= 0.0, "must be >= 0")?;
        check(|| "base_angle_rad".into(), self.base_angle_rad, true, "must be finite")?;
        Ok(())
    }
}

impl Default for ArmParams {
    fn default() -> Self {
        Self::default_four_link()
    }
}
