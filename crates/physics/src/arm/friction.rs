//! Joint friction: Coulomb + viscous (the paper's simulation model) and the shapes the paper saw
//! on the real robot (Stribeck effect, sign asymmetry, viscous friction that falls with speed).
//!
//! # The friction law
//! For a joint moving at velocity v ≠ 0 the friction torque opposes the motion:
//! `f(v) = sign(v) · m(|v|)`, with the magnitude taken from the branch of the sign of v:
//!
//! ```text
//! m(s) = F_c + (F_s − F_c)·exp(−(s/v_s)²) + b·v_f·ln(1 + s/v_f)
//! ```
//!
//! `F_c` Coulomb level, `F_s` static (breakaway) level, `v_s` Stribeck velocity, `b` viscous
//! coefficient at low speed, `v_f` the speed at which the viscous slope b/(1 + s/v_f) has
//! halved; no `v_f` means linear viscous friction (the limit v_f → ∞). The logarithm keeps the
//! viscous torque growing without bound while its slope falls, the shape the paper saw on
//! joints 2 and 3 of the real robot.
//!
//! # At zero velocity
//! The law jumps from −F_s⁻ to +F_s⁺ at v = 0. The integrator does not smooth this jump; it
//! uses stick–slip logic (see [`crate::arm::integrator`]): a joint at rest stays exactly at rest
//! while the torque needed to hold it lies within [−F_s⁻, F_s⁺], and breaks away otherwise.
//! For a constant-torque experiment this means a torque below the breakaway level gives no
//! motion at all (not a slow creep, as a tanh approximation would), and with a Stribeck dip
//! the steady velocities in the dip, where m(s) falls with s, cannot be reached: such a
//! joint jumps from rest straight to the rising branch of the curve.

use serde::{Deserialize, Serialize};

use super::params::{check_within, limits, ParamError};

/// Friction magnitudes for one direction of motion.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrictionBranch {
    /// Coulomb friction level [N·m].
    pub coulomb_nm: f64,
    /// Static (breakaway) friction level at zero velocity [N·m]; `>= coulomb_nm`. Equal to
    /// `coulomb_nm` means no Stribeck effect.
    pub static_nm: f64,
    /// Stribeck velocity: how fast friction falls from the static to the Coulomb level [rad/s].
    pub stribeck_velocity_rad_s: f64,
    /// Viscous coefficient at low speed [N·m·s/rad].
    pub viscous_nms_rad: f64,
    /// Speed at which the viscous slope has halved [rad/s]; `None` keeps the viscous torque
    /// linear in speed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub viscous_falloff_rad_s: Option<f64>,
}

impl FrictionBranch {
    /// Coulomb + viscous: `coulomb_nm` [N·m] plus `viscous_nms_rad` [N·m·s/rad] times speed.
    pub const fn coulomb_viscous(coulomb_nm: f64, viscous_nms_rad: f64) -> Self {
        Self { coulomb_nm, static_nm: coulomb_nm, stribeck_velocity_rad_s: 1.0, viscous_nms_rad, viscous_falloff_rad_s: None }
    }

    /// Friction magnitude at speed `speed_rad_s >= 0` [N·m]; at 0 it is the static level.
    #[inline]
    pub fn magnitude(&self, speed_rad_s: f64) -> f64 {
        let s = speed_rad_s;
        let stribeck = if self.static_nm != self.coulomb_nm {
            let r = s / self.stribeck_velocity_rad_s;
            (self.static_nm - self.coulomb_nm) * (-r * r).exp()
        } else {
            0.0
        };
        let viscous = match self.viscous_falloff_rad_s {
            Some(vf) => self.viscous_nms_rad * vf * (s / vf).ln_1p(),
            None => self.viscous_nms_rad * s,
        };
        self.coulomb_nm + stribeck + viscous
    }

    fn validate(&self, name: impl Fn() -> String) -> Result<(), ParamError> {
        let f = |field: &str| format!("{}.{field}", name());
        let torque = "must be at most 1e6 N·m (limits::TORQUE_NM)";
        let speed = "must be at most 1e5 rad/s (limits::SPEED_RAD_S)";
        check_within(|| f("coulomb_nm"), self.coulomb_nm, self.coulomb_nm >= 0.0, "must be >= 0", limits::TORQUE_NM, torque)?;
        let above = self.static_nm >= self.coulomb_nm;
        check_within(|| f("static_nm"), self.static_nm, above, "must be >= coulomb_nm", limits::TORQUE_NM, torque)?;
        let v = self.stribeck_velocity_rad_s;
        check_within(|| f("stribeck_velocity_rad_s"), v, v > 0.0, "must be > 0", limits::SPEED_RAD_S, speed)?;
        let b = self.viscous_nms_rad;
        let viscous = "must be at most 1e6 N·m·s/rad (limits::VISCOUS_NMS_RAD)";
        check_within(|| f("viscous_nms_rad"), b, b >= 0.0, "must be >= 0", limits::VISCOUS_NMS_RAD, viscous)?;
        if let Some(vf) = self.viscous_falloff_rad_s {
            check_within(|| f("viscous_falloff_rad_s"), vf, vf > 0.0, "must be > 0", limits::SPEED_RAD_S, speed)?;
        }
        Ok(())
    }
}

/// Friction of one joint: a branch for positive and one for negative velocity.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointFriction {
    /// Friction while the joint turns in the positive direction.
    pub positive: FrictionBranch,
    /// Friction while the joint turns in the negative direction (magnitudes, all >= 0).
    pub negative: FrictionBranch,
}

impl JointFriction {
    /// No friction at all.
    pub const fn none() -> Self {
        Self::symmetric(FrictionBranch::coulomb_viscous(0.0, 0.0))
    }

    /// The same branch for both directions.
    pub const fn symmetric(branch: FrictionBranch) -> Self {
        Self { positive: branch, negative: branch }
    }

    /// Default friction of joint `index` (0-based) of the default arm, Coulomb + viscous as in
    /// the paper's simulation model. The levels are those of a small geared laboratory arm:
    /// large enough that leaving friction uncompensated visibly hurts tracking, and falling
    /// outwards as the motors and gears get smaller:
    /// Coulomb 1.5, 1.2, 0.6, 0.3 N·m; viscous 0.8, 0.6, 0.3, 0.15 N·m·s/rad.
    /// Joints beyond the fourth get the fourth joint's values.
    pub fn default_for_joint(index: usize) -> Self {
        const COULOMB: [f64; 4] = [1.5, 1.2, 0.6, 0.3];
        const VISCOUS: [f64; 4] = [0.8, 0.6, 0.3, 0.15];
        let i = index.min(3);
        Self::symmetric(FrictionBranch::coulomb_viscous(COULOMB[i], VISCOUS[i]))
    }

    /// Friction torque at velocity `velocity_rad_s` [N·m], opposing motion: positive for
    /// positive velocity. At exactly zero velocity this returns 0; the torque a joint at rest
    /// gets is decided by the integrator's stick–slip logic, not by this function.
    #[inline]
    pub fn torque(&self, velocity_rad_s: f64) -> f64 {
        if velocity_rad_s > 0.0 {
            self.positive.magnitude(velocity_rad_s)
        } else if velocity_rad_s < 0.0 {
            -self.negative.magnitude(-velocity_rad_s)
        } else {
            0.0
        }
    }

    /// Friction torque [N·m] for a joint whose direction of motion is held at `direction`
    /// (+1 or −1) for an integration sub-step, at velocity `velocity_rad_s`. The speed used is
    /// the velocity's component along `direction`, floored at zero.
    #[inline]
    pub fn torque_in_direction(&self, direction: f64, velocity_rad_s: f64) -> f64 {
        let speed = (direction * velocity_rad_s).max(0.0);
        if direction > 0.0 {
            self.positive.magnitude(speed)
        } else {
            -self.negative.magnitude(speed)
        }
    }

    /// Breakaway torque for motion in `direction` (+1 or −1) [N·m], >= 0.
    #[inline]
    pub fn breakaway(&self, direction: f64) -> f64 {
        if direction > 0.0 {
            self.positive.static_nm
        } else {
            self.negative.static_nm
        }
    }

    /// True if the friction law jumps at zero velocity (some static level is non-zero), so the
    /// integrator must apply stick–slip logic to this joint.
    #[inline]
    pub fn is_discontinuous(&self) -> bool {
        self.positive.static_nm > 0.0 || self.negative.static_nm > 0.0
    }

    pub(crate) fn validate(&self, joint: usize) -> Result<(), ParamError> {
        self.positive.validate(|| format!("friction[{joint}].positive"))?;
        self.negative.validate(|| format!("friction[{joint}].negative"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn coulomb_viscous_is_linear_with_offset() {
        let f = JointFriction::symmetric(FrictionBranch::coulomb_viscous(1.5, 0.8));
        assert_eq!(f.torque(2.0), 1.5 + 1.6);
        assert_eq!(f.torque(-2.0), -(1.5 + 1.6));
        assert_eq!(f.torque(0.0), 0.0);
    }

    #[test]
    fn stribeck_starts_at_static_level_and_decays_to_coulomb() {
        let b = FrictionBranch {
            coulomb_nm: 1.0,
            static_nm: 1.6,
            stribeck_velocity_rad_s: 0.1,
            viscous_nms_rad: 0.0,
            viscous_falloff_rad_s: None,
        };
        assert_eq!(b.magnitude(0.0), 1.6);
        assert!((b.magnitude(1.0) - 1.0).abs() < 1e-12);
        assert!(b.magnitude(0.05) < 1.6 && b.magnitude(0.05) > 1.0);
    }

    #[test]
    fn viscous_falloff_halves_the_slope() {
        let b = FrictionBranch { viscous_falloff_rad_s: Some(2.0), ..FrictionBranch::coulomb_viscous(0.0, 1.0) };
        let slope = |s: f64| (b.magnitude(s + 1e-6) - b.magnitude(s - 1e-6)) / 2e-6;
        assert!((slope(1e-3) - 1.0).abs() < 1e-3);
        assert!((slope(2.0) - 0.5).abs() < 1e-8);
        assert!(slope(3.0) < slope(1.0));
        // Still rising without bound, unlike a saturating law.
        assert!(b.magnitude(1000.0) > 10.0);
    }
}
