//! A seeded family of random planar arms: arms nobody wrote by hand, for testing that the
//! pipeline serves any arm and not just the examples it was tuned on.
//!
//! [`random_arm`] draws, from a seed and a joint count (2–8):
//! - link lengths 0.1–1 m, each drawn on a log scale, so short and long links mix;
//! - masses from a linear density of 0.8–4 kg/m times the length, plus a motor or gripper of
//!   0–40 % of that at the link's far end (inner links carry the next motors);
//! - centres of mass where that point mass and the rod put them, moved by ±15 % of the length;
//! - inertias about the centre of mass either from that geometry (rod plus point mass) or
//!   drawn, 0.5–2 × the geometric value, as a user copying a data sheet might give them;
//! - a base tilt: the plane horizontal (a third of the arms), or tilted by 0.05–1.2 rad, so
//!   gravity acts in the plane with g·sin(tilt) during the tracking runs;
//! - per joint, friction scaled to the torque the joint must carry (its outboard mass
//!   moment under full gravity): Coulomb 2–12 % of it plus 0.05 N·m, viscous 0.15–1 s/rad
//!   times the Coulomb level; each joint independently with Stribeck break-away (static
//!   1.1–1.7 × Coulomb, Stribeck speed 0.03–0.2 rad/s) or not, asymmetric between the
//!   directions (each negative level 0.6–1.4 × the positive one) or not, and viscous friction
//!   that falls with speed (halved slope at 1–4 rad/s) or not.
//!
//! The same seed and joint count always give the same arm, on every machine.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::arm::{ArmParams, FrictionBranch, JointFriction, LinkParams};
use crate::config::ArmConfig;

/// Fewest joints of a family arm.
pub const FAMILY_MIN_JOINTS: usize = 2;
/// Most joints of a family arm.
pub const FAMILY_MAX_JOINTS: usize = 8;

/// What [`random_arm`] chose beyond the numbers, for a reader of a failing case.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct FamilyTraits {
    /// Whether the inertias were computed from the geometry (else drawn around it).
    pub inertia_from_geometry: bool,
    /// Per joint: Stribeck break-away.
    pub stribeck: Vec<bool>,
    /// Per joint: different friction in the two directions.
    pub asymmetric: Vec<bool>,
    /// Per joint: viscous friction falling with speed.
    pub falling_viscous: Vec<bool>,
}

/// Standard gravity the family arms carry [m/s²].
const GRAVITY_M_S2: f64 = 9.81;

/// The arm of `seed` with `joints` joints (see the module documentation), with what was
/// chosen. Panics when `joints` is outside 2–8: a test or bench passes a constant.
pub fn random_arm_with_traits(seed: u64, joints: usize) -> (ArmConfig, FamilyTraits) {
    assert!((FAMILY_MIN_JOINTS..=FAMILY_MAX_JOINTS).contains(&joints), "a family arm has 2 to 8 joints, not {joints}");
    // One stream per (seed, joints), so the 3-joint arm of seed 5 does not share its first
    // draws with the 4-joint arm of seed 5.
    let mut rng = ChaCha8Rng::seed_from_u64(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (joints as u64));
    let log_uniform = |rng: &mut ChaCha8Rng, lo: f64, hi: f64| (rng.gen_range(lo.ln()..hi.ln())).exp();
    let inertia_from_geometry = rng.gen_bool(0.5);
    let mut links = Vec::with_capacity(joints);
    for _ in 0..joints {
        let length = log_uniform(&mut rng, 0.1, 1.0);
        let rod = rng.gen_range(0.8..4.0) * length;
        let tip = rng.gen_range(0.0..0.4) * rod;
        let mass = rod + tip;
        // Centre of mass of the rod (at mid-link) and the point mass at the far end, moved.
        let geometric_com = (rod * 0.5 * length + tip * length) / mass;
        let com = (geometric_com + rng.gen_range(-0.15..0.15) * length).clamp(0.1 * length, 0.9 * length);
        // Rod about its middle, carried to the centre of mass, plus the point mass's share.
        let geometric_inertia = rod * length * length / 12.0 + rod * (0.5 * length - com).powi(2) + tip * (length - com).powi(2);
        let inertia = if inertia_from_geometry { geometric_inertia } else { geometric_inertia * log_uniform(&mut rng, 0.5, 2.0) };
        links.push(LinkParams {
            length_m: round(length, 4),
            mass_kg: round(mass, 4),
            com_m: round(com, 4),
            inertia_kgm2: round(inertia, 6),
        });
    }
    let base_angle_rad = if rng.gen_bool(1.0 / 3.0) { 0.0 } else { round(rng.gen_range(0.05..1.2), 4) };
    let mut traits = FamilyTraits { inertia_from_geometry, stribeck: Vec::new(), asymmetric: Vec::new(), falling_viscous: Vec::new() };
    let mut friction = Vec::with_capacity(joints);
    let loads = ArmParams { links: links.clone(), friction: Vec::new(), gravity_m_s2: GRAVITY_M_S2, base_angle_rad: 0.0 };
    for j in 0..joints {
        let load_nm = loads.gravity_load_nm(j);
        let coulomb = 0.05 + rng.gen_range(0.02..0.12) * load_nm;
        let viscous = coulomb * rng.gen_range(0.15..1.0);
        let stribeck = rng.gen_bool(0.5);
        let asymmetric = rng.gen_bool(0.5);
        let falling = rng.gen_bool(0.3);
        let (breakaway, stribeck_speed) = if stribeck { (rng.gen_range(1.1..1.7), rng.gen_range(0.03..0.2)) } else { (1.0, 1.0) };
        let falloff = falling.then(|| round(rng.gen_range(1.0..4.0), 3));
        let branch = |scale_c: f64, scale_v: f64, speed: f64| FrictionBranch {
            coulomb_nm: round(coulomb * scale_c, 4),
            static_nm: round(coulomb * scale_c * breakaway, 4),
            stribeck_velocity_rad_s: round(speed, 4),
            viscous_nms_rad: round(viscous * scale_v, 4),
            viscous_falloff_rad_s: falloff,
        };
        let positive = branch(1.0, 1.0, stribeck_speed);
        let negative = if asymmetric {
            let speed = if stribeck { rng.gen_range(0.03..0.2) } else { 1.0 };
            branch(rng.gen_range(0.6..1.4), rng.gen_range(0.6..1.4), speed)
        } else {
            positive
        };
        friction.push(JointFriction { positive, negative });
        traits.stribeck.push(stribeck);
        traits.asymmetric.push(asymmetric);
        traits.falling_viscous.push(falling);
    }
    let arm = ArmParams { links, friction, gravity_m_s2: GRAVITY_M_S2, base_angle_rad };
    let config = ArmConfig { arm, ..ArmConfig::default() };
    (config, traits)
}

/// The arm of `seed` with `joints` joints: [`random_arm_with_traits`] without the traits.
pub fn random_arm(seed: u64, joints: usize) -> ArmConfig {
    random_arm_with_traits(seed, joints).0
}

/// `x` to `digits` decimals, so a family arm's TOML reads as a person would write it.
fn round(x: f64, digits: i32) -> f64 {
    let k = 10f64.powi(digits);
    (x * k).round() / k
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_family_arm_is_valid_and_in_range() {
        for joints in FAMILY_MIN_JOINTS..=FAMILY_MAX_JOINTS {
            for seed in 0..50 {
                let (c, t) = random_arm_with_traits(seed, joints);
                c.validate().unwrap_or_else(|e| panic!("seed {seed}, {joints} joints: {e}"));
                assert_eq!(c.arm.dof(), joints);
                assert_eq!(t.stribeck.len(), joints);
                for l in &c.arm.links {
                    assert!((0.1..=1.0).contains(&l.length_m), "{l:?}");
                    assert!(l.com_m > 0.0 && l.com_m < l.length_m, "{l:?}");
                    assert!(l.mass_kg > 0.0 && l.inertia_kgm2 > 0.0, "{l:?}");
                }
                assert!((0.0..1.2).contains(&c.arm.base_angle_rad));
            }
        }
    }

    #[test]
    fn a_seed_gives_one_arm_and_seeds_differ() {
        assert_eq!(random_arm(3, 4), random_arm(3, 4));
        assert_ne!(random_arm(3, 4), random_arm(4, 4));
        assert_ne!(random_arm(3, 4).arm.links[..3], random_arm(3, 5).arm.links[..3]);
    }

    #[test]
    fn the_family_mixes_every_friction_feature_and_tilt() {
        let (mut stribeck, mut asym, mut falling, mut tilted, mut flat, mut geometric, mut given) = (0, 0, 0, 0, 0, 0, 0);
        for seed in 0..40 {
            let (c, t) = random_arm_with_traits(seed, 4);
            stribeck += t.stribeck.iter().filter(|&&b| b).count();
            asym += t.asymmetric.iter().filter(|&&b| b).count();
            falling += t.falling_viscous.iter().filter(|&&b| b).count();
            if c.arm.base_angle_rad > 0.0 {
                tilted += 1
            } else {
                flat += 1
            }
            if t.inertia_from_geometry {
                geometric += 1
            } else {
                given += 1
            }
            for (f, (s, a)) in c.arm.friction.iter().zip(t.stribeck.iter().zip(&t.asymmetric)) {
                assert_eq!(f.positive.static_nm > f.positive.coulomb_nm, *s);
                assert_eq!(f.positive != f.negative, *a);
            }
        }
        for (what, count) in [
            ("stribeck", stribeck),
            ("asymmetric", asym),
            ("falling", falling),
            ("tilted", tilted),
            ("flat", flat),
            ("geometric", geometric),
            ("given", given),
        ] {
            assert!(count >= 5, "{what}: {count}");
        }
    }
}
