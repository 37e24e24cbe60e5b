//! The paper's task-space reference (a curve around a centre, scaled), where it is placed in an
//! arm's plane, and the desired end-effector motion the task-space law follows.

use nalgebra::Vector2;

use crate::arm::ArmParams;

/// The paper's task-space reference around `centre` [m] at time `t` [s]:
/// x_d = centre + (0.2 (cos t + sin 2t), 0.15 (sin t + cos 2t)). The curve (period 2π s) starts
/// at centre + (0.2, 0.15) and passes through `centre` itself where sin t = −1/2.
/// Returns position [m], velocity [m/s] and acceleration [m/s²].
pub fn paper_reference(t: f64, centre: Vector2<f64>) -> (Vector2<f64>, Vector2<f64>, Vector2<f64>) {
    scaled_reference(t, centre, 1.0)
}

/// The paper's reference scaled by `scale` about `centre` [m]:
/// x_d = centre + scale · (0.2 (cos t + sin 2t), 0.15 (sin t + cos 2t)), at time `t` [s].
/// Returns position [m], velocity [m/s] and acceleration [m/s²].
pub fn scaled_reference(t: f64, centre: Vector2<f64>, scale: f64) -> (Vector2<f64>, Vector2<f64>, Vector2<f64>) {
    let (s1, c1, s2, c2) = (t.sin(), t.cos(), (2.0 * t).sin(), (2.0 * t).cos());
    let x = centre + scale * Vector2::new(0.2 * (c1 + s2), 0.15 * (s1 + c2));
    let xd = scale * Vector2::new(0.2 * (-s1 + 2.0 * c2), 0.15 * (c1 - 2.0 * s2));
    let xdd = scale * Vector2::new(0.2 * (-c1 - 4.0 * s2), 0.15 * (-s1 - 4.0 * c2));
    (x, xd, xdd)
}

/// Where the paper's curve sits in an arm's plane: its centre [m] and scale (1 is the
/// paper's size, 0.4 m × 0.3 m across).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferencePlacement {
    /// Centre of the curve [m], from the first joint.
    pub centre: Vector2<f64>,
    /// Scale of the curve.
    pub scale: f64,
}

/// Why a reference cannot be tracked by an arm.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PlacementError {
    /// The curve goes too far from the base.
    #[error(
        "the reference goes {farthest:.3} m from the first joint, so the arm needs a reach of {needed:.3} m (5 % from the stretched pose); it has {reach:.3} m (the sum of its link lengths)"
    )]
    TooFar {
        /// Farthest distance of the curve [m].
        farthest: f64,
        /// Reach needed [m].
        needed: f64,
        /// Reach the arm has [m].
        reach: f64,
    },
    /// The curve comes too near the base for an arm whose longest link exceeds the others.
    #[error(
        "the reference comes {nearest:.3} m near the first joint; the arm cannot reach within {hole:.3} m of it (its longest link is longer than the others together), and needs 5 % of its reach more room"
    )]
    TooNear {
        /// Nearest distance of the curve [m].
        nearest: f64,
        /// Radius the arm cannot reach [m].
        hole: f64,
    },
    /// Scale or centre not finite, or scale not positive.
    #[error("the reference's scale must be > 0 and its centre finite (scale {scale}, centre ({x}, {y}))")]
    Invalid {
        /// The scale given.
        scale: f64,
        /// x of the centre [m].
        x: f64,
        /// y of the centre [m].
        y: f64,
    },
}

impl ReferencePlacement {
    /// The rule for an arm of reach R = Σ lᵢ: scale R / 1 m and centre (0.45 R, 0.10 R), so the
    /// curve stays between 0.23 R and 0.84 R from the first joint, inside the workspace and away
    /// from the stretched (singular) pose; for the default 1 m arm it is the paper's. An arm whose
    /// longest link exceeds the others together cannot reach within 2 l_max − R of its first
    /// joint; where that hole cuts into the curve, the curve is centred on the same bearing in the
    /// ring the arm reaches, 23 % of its width from the inner edge and 16 % from the outer one,
    /// and shrunk until it fits ([`ReferencePlacement::fitted`] says so).
    pub fn for_arm(arm: &ArmParams) -> Self {
        let reach: f64 = arm.links.iter().map(|l| l.length_m).sum();
        let default = Self { centre: Vector2::new(0.45 * reach, 0.10 * reach), scale: reach };
        if default.check(arm).is_ok() {
            return default;
        }
        let hole = workspace_hole(arm);
        let width = reach - hole;
        let (inner, outer) = (hole + 0.23 * width, reach - 0.16 * width);
        let bearing = Vector2::new(0.45, 0.10).normalize();
        let centre = bearing * (0.5 * (inner + outer));
        // The curve's nearest and farthest distances move monotonically with its scale about
        // a centre this far out: bisect for the largest scale within the ring.
        let fits = |scale: f64| {
            let (near, far) = Self { centre, scale }.distance_range();
            near >= inner && far <= outer
        };
        let (mut lo, mut hi) = (0.0, reach);
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if fits(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Self { centre, scale: lo }
    }

    /// Whether this placement is the one [`ReferencePlacement::for_arm`] fits into the ring
    /// of an arm with a hole in its workspace (rather than the default by the reach).
    pub fn fitted(&self, arm: &ArmParams) -> bool {
        let reach: f64 = arm.links.iter().map(|l| l.length_m).sum();
        *self == Self::for_arm(arm) && self.scale != reach
    }

    /// The nearest and farthest distance of the curve from the first joint [m] (over a period,
    /// sampled every 1 ms).
    pub fn distance_range(&self) -> (f64, f64) {
        let steps = (std::f64::consts::TAU / 1e-3).ceil() as usize;
        (0..steps)
            .map(|k| scaled_reference(k as f64 * 1e-3, self.centre, self.scale).0.norm())
            .fold((f64::INFINITY, 0.0), |(lo, hi), d| (lo.min(d), hi.max(d)))
    }

    /// Checks that `arm` can track the curve: it stays within 95 % of the reach and, for an arm
    /// whose longest link is longer than all the others together (a hole in its workspace),
    /// 5 % of the reach outside that hole.
    pub fn check(&self, arm: &ArmParams) -> Result<(), PlacementError> {
        let (x, y) = (self.centre.x, self.centre.y);
        if !(self.scale > 0.0 && self.scale.is_finite() && x.is_finite() && y.is_finite()) {
            return Err(PlacementError::Invalid { scale: self.scale, x, y });
        }
        let reach: f64 = arm.links.iter().map(|l| l.length_m).sum();
        let hole = workspace_hole(arm);
        let (nearest, farthest) = self.distance_range();
        if farthest > 0.95 * reach {
            return Err(PlacementError::TooFar { farthest, needed: farthest / 0.95, reach });
        }
        if hole > 0.0 && nearest < hole + 0.05 * reach {
            return Err(PlacementError::TooNear { nearest, hole });
        }
        Ok(())
    }
}

/// Radius of the disc around the first joint a planar arm cannot reach [m]: 2 l_max − R
/// when its longest link outreaches all the others together, else 0.
pub fn workspace_hole(arm: &ArmParams) -> f64 {
    let reach: f64 = arm.links.iter().map(|l| l.length_m).sum();
    let longest = arm.links.iter().map(|l| l.length_m).fold(0.0, f64::max);
    (2.0 * longest - reach).max(0.0)
}

/// Desired end-effector motion: position [m], velocity [m/s], acceleration [m/s²].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TaskReference {
    /// x_d.
    pub position: Vector2<f64>,
    /// ẋ_d.
    pub velocity: Vector2<f64>,
    /// ẍ_d.
    pub acceleration: Vector2<f64>,
}
