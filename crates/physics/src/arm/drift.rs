//! How a working arm drifts away from the model it was identified as: each joint's friction
//! scaled (the lubricant warms and the viscous part falls, seals wear and the Coulomb part
//! rises) and a payload gripped at the tip. [`OperatingChange::apply_into`] turns an arm's
//! parameters into those of the changed arm without allocating, so a simulator can follow a
//! change that ramps every step.

use serde::{Deserialize, Serialize};

use super::params::{check_within, limits, ArmParams, ParamError};

/// Largest friction scale [-]: a thousandfold change is no longer drift of the same joint.
pub const MAX_FRICTION_SCALE: f64 = 1e3;

/// A change of a working arm against its identified parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OperatingChange {
    /// Factor on each joint's Coulomb and static friction, both directions [-] (1: as
    /// identified). Static friction scales with Coulomb so the breakaway level stays above it.
    pub coulomb_scale: Vec<f64>,
    /// Factor on each joint's viscous coefficient, both directions [-] (1: as identified).
    pub viscous_scale: Vec<f64>,
    /// Point mass held at the tip [kg] (0: none).
    pub payload_mass_kg: f64,
    /// Where the payload sits beyond the tip, along the last link [m] (0: at the tip;
    /// negative: on the last link).
    pub payload_offset_m: f64,
}

impl OperatingChange {
    /// No change for an arm of `joints` joints.
    pub fn none(joints: usize) -> Self {
        Self { coulomb_scale: vec![1.0; joints], viscous_scale: vec![1.0; joints], payload_mass_kg: 0.0, payload_offset_m: 0.0 }
    }

    /// Whether this changes nothing.
    pub fn is_none(&self) -> bool {
        self.coulomb_scale.iter().chain(&self.viscous_scale).all(|&s| s == 1.0) && self.payload_mass_kg == 0.0
    }

    /// Refuses, by name, a scale that is negative, not finite or above
    /// [`MAX_FRICTION_SCALE`], a payload mass that is negative or beyond
    /// [`limits::MASS_KG`], an offset beyond [`limits::LENGTH_M`], or lists that are not one
    /// entry per joint of `arm`.
    pub fn check(&self, arm: &ArmParams) -> Result<(), ParamError> {
        let n = arm.dof();
        for (what, list) in [("coulomb_scale", &self.coulomb_scale), ("viscous_scale", &self.viscous_scale)] {
            if list.len() != n {
                return Err(ParamError::Invalid {
                    name: format!("{what} (length)"),
                    value: list.len() as f64,
                    why: "needs one entry per joint",
                });
            }
            for (i, &s) in list.iter().enumerate() {
                let why = "must be at most 1e3 (drift::MAX_FRICTION_SCALE)";
                check_within(|| format!("{what}[{i}]"), s, s >= 0.0, "must be >= 0", MAX_FRICTION_SCALE, why)?;
            }
        }
        let m = self.payload_mass_kg;
        check_within(
            || "payload_mass_kg".into(),
            m,
            m >= 0.0,
            "must be >= 0",
            limits::MASS_KG,
            "must be at most 1e5 kg (limits::MASS_KG)",
        )?;
        let d = self.payload_offset_m;
        check_within(|| "payload_offset_m".into(), d, true, "must be finite", limits::LENGTH_M, "must be at most 100 m (limits::LENGTH_M)")
    }

    /// Writes the parameters of `base` changed by `self` into `out`, reusing its storage
    /// (no allocation once `out` has `base`'s joint count). The payload joins the last link:
    /// its mass adds to the link's, its centre of mass moves to the common one and its
    /// inertia about that centre gains both bodies' parallel-axis terms. Checked first
    /// ([`OperatingChange::check`]); `out` is untouched on error.
    pub fn apply_into(&self, base: &ArmParams, out: &mut ArmParams) -> Result<(), ParamError> {
        self.check(base)?;
        out.copy_from(base);
        for (i, f) in out.friction.iter_mut().enumerate() {
            for branch in [&mut f.positive, &mut f.negative] {
                branch.coulomb_nm *= self.coulomb_scale[i];
                branch.static_nm *= self.coulomb_scale[i];
                branch.viscous_nms_rad *= self.viscous_scale[i];
            }
        }
        let mp = self.payload_mass_kg;
        if mp > 0.0 {
            let link = out.links.last_mut().expect("a checked arm has a link");
            let (m, c, inertia) = (link.mass_kg, link.com_m, link.inertia_kgm2);
            let at = link.length_m + self.payload_offset_m;
            let total = m + mp;
            let com = (m * c + mp * at) / total;
            link.mass_kg = total;
            link.com_m = com;
            link.inertia_kgm2 = inertia + m * (c - com).powi(2) + mp * (at - com).powi(2);
        }
        // The scaled friction can exceed the limits of a valid arm: say so by the arm's names.
        out.validate().inspect_err(|_| out.copy_from(base))
    }

    /// The changed parameters of `base` (allocating; see [`OperatingChange::apply_into`]).
    pub fn applied(&self, base: &ArmParams) -> Result<ArmParams, ParamError> {
        let mut out = base.clone();
        self.apply_into(base, &mut out)?;
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::arm::{gravity_torques, jacobian, mass_matrix, LinkParams};

    fn pose() -> Vec<f64> {
        vec![0.3, -0.8, 1.1, 0.4]
    }

    #[test]
    fn a_payload_adds_a_point_mass_at_the_tip_to_the_mass_matrix_and_gravity() {
        // Independent formulation: H' = H + m_p J_pᵀ J_p and g' = g + m_p g₀ J_pᵀ ŷ, with J_p
        // the Jacobian of the payload's point (the tip of an arm whose last link is longer).
        let base = ArmParams::default_four_link().with_base_angle(std::f64::consts::FRAC_PI_2);
        for offset in [0.0, 0.07, -0.05] {
            let change = OperatingChange { payload_mass_kg: 0.24, payload_offset_m: offset, ..OperatingChange::none(4) };
            let changed = change.applied(&base).unwrap();
            let mut reach = base.clone();
            let last = reach.links.len() - 1;
            reach.links[last].length_m += offset;
            let q = pose();
            let jp = jacobian(&reach, &q);
            let h = mass_matrix(&base, &q) + 0.24 * jp.transpose() * &jp;
            let g = gravity_torques(&base, &q) + 0.24 * base.in_plane_gravity() * jp.row(1).transpose();
            assert!((mass_matrix(&changed, &q) - h).abs().max() < 1e-12, "offset {offset}");
            assert!((gravity_torques(&changed, &q) - g).abs().max() < 1e-12, "offset {offset}");
        }
    }

    #[test]
    fn friction_scales_multiply_each_part_in_both_directions() {
        let base = ArmParams::default_four_link();
        let change = OperatingChange {
            coulomb_scale: vec![1.3, 1.0, 1.0, 0.5],
            viscous_scale: vec![0.6, 1.0, 2.0, 1.0],
            ..OperatingChange::none(4)
        };
        let changed = change.applied(&base).unwrap();
        for v in [-2.0, -0.3, 0.4, 3.0] {
            let f0 = base.friction[0].torque(v);
            let (fc, b) = (base.friction[0].positive.coulomb_nm, base.friction[0].positive.viscous_nms_rad);
            assert!((changed.friction[0].torque(v) - (f0 + v.signum() * 0.3 * fc - 0.4 * b * v)).abs() < 1e-12);
            assert_eq!(changed.friction[1].torque(v), base.friction[1].torque(v));
        }
        assert_eq!(changed.friction[3].positive.static_nm, 0.5 * base.friction[3].positive.static_nm);
        assert_eq!(changed.links, base.links, "no payload, the links as they were");
        assert!(OperatingChange::none(4).is_none() && !change.is_none());
    }

    #[test]
    fn bad_changes_are_refused_by_name_and_leave_the_output_alone() {
        let base = ArmParams::default_four_link();
        let mut out = base.clone();
        out.links[0] = LinkParams::uniform_rod(0.5, 3.0);
        let before = out.clone();
        for (change, name) in [
            (OperatingChange { coulomb_scale: vec![1.0, -0.1, 1.0, 1.0], ..OperatingChange::none(4) }, "coulomb_scale[1]"),
            (OperatingChange { viscous_scale: vec![1.0, 1.0, f64::NAN, 1.0], ..OperatingChange::none(4) }, "viscous_scale[2]"),
            (OperatingChange { viscous_scale: vec![1.0; 3], ..OperatingChange::none(4) }, "viscous_scale (length)"),
            (OperatingChange { payload_mass_kg: -1.0, ..OperatingChange::none(4) }, "payload_mass_kg"),
            (OperatingChange { payload_offset_m: f64::INFINITY, ..OperatingChange::none(4) }, "payload_offset_m"),
        ] {
            let e = change.apply_into(&base, &mut out).unwrap_err().to_string();
            assert!(e.starts_with(name), "{e}");
            assert_eq!(out, before);
        }
    }
}
