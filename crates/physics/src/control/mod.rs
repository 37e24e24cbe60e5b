//! Control laws of the paper as plain functions of the arm model: task-space computed torque
//! for the redundant arm (pseudo-inverse with null-space damping) and joint-space P control
//! with gravity compensation. Nothing here knows about FMI; the controller FMUs wrap these.
//!
//! The task-space law runs in [`TaskSpaceData`], made once per arm: [`task_space_torque_into`]
//! allocates nothing. [`task_space_acceleration`] and [`computed_torque`] are conveniences
//! over the same code for one call.

pub mod holds;

use nalgebra::{DMatrix, DVector, Matrix2, Vector2};

use crate::arm::{inverse_dynamics_rnea_into, jacobian, jacobian_dot_qd, jacobian_into, ArmData, ArmParams};

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
    /// The rule for an arm of reach R = Σ lᵢ: scale R / 1 m and centre (0.45 R, 0.10 R). The
    /// paper's curve then stays between 0.23 R and 0.84 R from the first joint, inside the
    /// workspace and away from the stretched (singular) pose; for the default 1 m arm it is the
    /// paper's size around (0.45, 0.10) m.
    ///
    /// An arm whose longest link is longer than the others together cannot reach a disc of
    /// radius `hole` = 2 l_max − R around its first joint; where that disc cuts into the curve
    /// (the default would be refused by [`ReferencePlacement::check`]), the curve is fitted
    /// into the ring the arm does reach, with the same margins as the default leaves in a
    /// whole disc: centred on the same bearing, 23 % of the ring's width from its inner edge
    /// and 16 % from its outer one, and shrunk until it fits ([`ReferencePlacement::fitted`]
    /// says so).
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

/// Moore–Penrose pseudo-inverse J⁺ (n×2) of a 2×n Jacobian `jac` into `out`, with `jac_t`
/// (n×2) and `jjt_inverse` (2×2) as scratch. Away from singular poses this is Jᵀ (J Jᵀ)⁻¹;
/// where J loses rank (σ_min < 1e-6 σ_max) it is Jᵀ (J Jᵀ)⁺ with the lost direction dropped
/// (the identity J⁺ = Jᵀ (J Jᵀ)⁺ holds for any J), from the closed-form eigenvectors of the
/// 2×2 matrix J Jᵀ. So J⁺ exists at every pose: any master that starts its connections at
/// zero (q = 0 is the stretched, singular pose) gets a bounded answer. Returns false, leaving
/// `out` meaningless, only when J is not finite.
pub fn pseudo_inverse_into(jac: &DMatrix<f64>, jac_t: &mut DMatrix<f64>, jjt_inverse: &mut DMatrix<f64>, out: &mut DMatrix<f64>) -> bool {
    if !jac.iter().all(|v| v.is_finite()) {
        return false;
    }
    let m = jacobian_product_into(jac, jac_t);
    pseudo_inverse_from(&m, jac_t, jjt_inverse, out);
    true
}

/// Jᵀ into `jac_t` and J Jᵀ returned.
fn jacobian_product_into(jac: &DMatrix<f64>, jac_t: &mut DMatrix<f64>) -> Matrix2<f64> {
    jac.transpose_to(jac_t);
    let mut m = Matrix2::zeros();
    jac.mul_to(jac_t, &mut m);
    m
}

/// J⁺ = Jᵀ (J Jᵀ)⁺ into `out` from `m` = J Jᵀ and `jac_t` = Jᵀ ([`pseudo_inverse_into`]).
fn pseudo_inverse_from(m: &Matrix2<f64>, jac_t: &DMatrix<f64>, jjt_inverse: &mut DMatrix<f64>, out: &mut DMatrix<f64>) {
    // det(JJᵀ)/‖JJᵀ‖² ≈ (σ₂/σ₁)²: the fast form while σ₂/σ₁ > 1e-6.
    let regular = m.determinant().abs() > 1e-12 * m.norm_squared();
    match m.try_inverse().filter(|_| regular) {
        Some(inv) => jjt_inverse.copy_from(&inv),
        None => jjt_inverse.copy_from(&rank_cut_inverse(m)),
    }
    jac_t.mul_to(jjt_inverse, out);
}

/// The eigenvalues (λ₁, λ₂), λ₁ ≥ λ₂ ≥ 0, of the symmetric positive semi-definite 2×2 `m`
/// (J Jᵀ: σ₁², σ₂²), in closed form.
fn eigenvalues(m: &Matrix2<f64>) -> (f64, f64) {
    let (a, b, c) = (m[(0, 0)], 0.5 * (m[(0, 1)] + m[(1, 0)]), m[(1, 1)]);
    let half_gap = (0.25 * (a - c) * (a - c) + b * b).sqrt();
    (0.5 * (a + c) + half_gap, (0.5 * (a + c) - half_gap).max(0.0))
}

/// (J Jᵀ)⁺ of the symmetric positive semi-definite 2×2 `m` = J Jᵀ, keeping the eigenvalue
/// λ₂ only if σ₂ = √λ₂ exceeds 1e-6 σ₁.
fn rank_cut_inverse(m: &Matrix2<f64>) -> Matrix2<f64> {
    let (a, b, c) = (m[(0, 0)], 0.5 * (m[(0, 1)] + m[(1, 0)]), m[(1, 1)]);
    let (largest, smallest) = eigenvalues(m);
    if !(largest > 0.0) {
        return Matrix2::zeros();
    }
    // Eigenvector of the largest eigenvalue from the better-conditioned row of m − λ₁I.
    let v = if a >= c { Vector2::new(largest - c, b) } else { Vector2::new(b, largest - a) };
    let v = if v.norm() > 0.0 { v.normalize() } else { Vector2::new(1.0, 0.0) };
    let w = Vector2::new(-v.y, v.x);
    let mut inverse = v * v.transpose() / largest;
    if smallest > 1e-12 * largest {
        inverse += w * w.transpose() / smallest;
    }
    inverse
}

/// Moore–Penrose pseudo-inverse J⁺ (n×2) of a 2×n Jacobian: [`pseudo_inverse_into`] into a
/// new matrix. `None` only when J is not finite.
pub fn pseudo_inverse(jac: &DMatrix<f64>) -> Option<DMatrix<f64>> {
    let n = jac.ncols();
    let (mut jac_t, mut jjt_inverse, mut out) = (DMatrix::zeros(n, 2), DMatrix::zeros(2, 2), DMatrix::zeros(n, 2));
    pseudo_inverse_into(jac, &mut jac_t, &mut jjt_inverse, &mut out).then_some(out)
}

/// The singular-value margin ε of the task-space law's inverse as a share of the arm's reach
/// (ε = 0.05 R [m/rad]; see [`damped_inverse_into`]).
pub const SINGULAR_MARGIN_SHARE: f64 = 0.05;

/// The task-space law's inverse J# (n×2) of a 2×n Jacobian into `out`: the Moore–Penrose
/// pseudo-inverse ([`pseudo_inverse_into`], the same numbers) while J's smallest singular value
/// σ₂ is at least `margin` ε [m/rad], and within ε of a singular pose the damped least-squares
/// inverse Jᵀ (J Jᵀ + λ² I)⁻¹ with λ² = ε² − σ₂², which shrinks to 0 at σ₂ = ε (so J# is
/// continuous there) and lifts J Jᵀ's smallest eigenvalue to ε² (so ‖J#‖ ≤ 1/ε: the joint
/// accelerations stay bounded through a singular pose, where J⁺ grows as 1/σ₂).
///
/// Why: the task fixes only the end effector, and a redundant arm's self-motion wanders. In
/// long runs it carried the 3- and 6-joint example arms into singular poses (σ₂ 0.003 and
/// 0.03 m/rad), where J⁺ asked for accelerations that threw the joints past 100 rad/s.
/// u = J# a is the minimiser of ‖J u − a‖² + λ² ‖u‖²: near the singular pose the task
/// acceleration along the lost direction is followed only partly. Returns false, leaving `out`
/// meaningless, only when J is not finite.
pub fn damped_inverse_into(
    jac: &DMatrix<f64>,
    margin: f64,
    jac_t: &mut DMatrix<f64>,
    jjt_inverse: &mut DMatrix<f64>,
    out: &mut DMatrix<f64>,
) -> bool {
    if !jac.iter().all(|v| v.is_finite()) {
        return false;
    }
    let mut m = jacobian_product_into(jac, jac_t);
    let damping = margin * margin - eigenvalues(&m).1;
    if !(damping > 0.0) {
        pseudo_inverse_from(&m, jac_t, jjt_inverse, out);
        return true;
    }
    m[(0, 0)] += damping;
    m[(1, 1)] += damping;
    match m.try_inverse() {
        Some(inv) => jjt_inverse.copy_from(&inv),
        None => return false,
    }
    jac_t.mul_to(jjt_inverse, out);
    true
}

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
    /// [`TaskSpaceData`] has one, [`TaskSpaceData::set_rest_pose`]): the null-space term becomes
    /// (I − J⁺J)(k_s (q_rest − q) − k q̇). Damping alone leaves the self-motion free to drift
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

/// Scratch space of the task-space law for one arm, made once: the Jacobian J, its
/// pseudo-inverse J⁺, the null-space projector I − J⁺J, the joint accelerations u and the
/// rigid-body data of the computed torque.
#[derive(Clone, Debug)]
pub struct TaskSpaceData {
    jacobian: DMatrix<f64>,
    jacobian_t: DMatrix<f64>,
    jjt_inverse: DMatrix<f64>,
    pseudo_inverse: DMatrix<f64>,
    pinv_j: DMatrix<f64>,
    null_projector: DMatrix<f64>,
    qd: DVector<f64>,
    task_acceleration: DVector<f64>,
    task: DVector<f64>,
    null_motion: DVector<f64>,
    /// The null-space term before projection: k_s (q_rest − q) − k q̇ [rad/s²].
    null_target: DVector<f64>,
    rest_pose: DVector<f64>,
    has_rest_pose: bool,
    u: DVector<f64>,
    /// ε of [`damped_inverse_into`]: [`SINGULAR_MARGIN_SHARE`] of the reach [m/rad].
    singular_margin: f64,
    arm: ArmData,
}

impl TaskSpaceData {
    /// Scratch space for the arm of `model`.
    pub fn new(model: &ArmParams) -> Self {
        let n = model.dof();
        Self {
            jacobian: DMatrix::zeros(2, n),
            jacobian_t: DMatrix::zeros(n, 2),
            jjt_inverse: DMatrix::zeros(2, 2),
            pseudo_inverse: DMatrix::zeros(n, 2),
            pinv_j: DMatrix::zeros(n, n),
            null_projector: DMatrix::zeros(n, n),
            qd: DVector::zeros(n),
            task_acceleration: DVector::zeros(2),
            task: DVector::zeros(n),
            null_motion: DVector::zeros(n),
            null_target: DVector::zeros(n),
            rest_pose: DVector::zeros(n),
            has_rest_pose: false,
            u: DVector::zeros(n),
            singular_margin: SINGULAR_MARGIN_SHARE * model.links.iter().map(|l| l.length_m).sum::<f64>(),
            arm: ArmData::new(model),
        }
    }

    /// ε of the task-space law's inverse [m/rad] (see [`damped_inverse_into`]).
    pub fn singular_margin(&self) -> f64 {
        self.singular_margin
    }

    /// Gives the self-motion a rest pose `q_rest` [rad], one angle per joint (see
    /// [`TaskSpaceGains::null_stiffness`]); `None` leaves it damped only. Each joint's
    /// distance to its rest angle is taken within (−π, π], so a joint that has turned a whole
    /// revolution is home. Allocates nothing; panics when `q_rest` has not one angle per joint.
    pub fn set_rest_pose(&mut self, q_rest: Option<&[f64]>) {
        self.has_rest_pose = q_rest.is_some();
        if let Some(q) = q_rest {
            self.rest_pose.copy_from_slice(q);
        }
    }

    /// The rest pose of the self-motion [rad], if any.
    pub fn rest_pose(&self) -> Option<&[f64]> {
        self.has_rest_pose.then_some(self.rest_pose.as_slice())
    }

    /// The joint accelerations u [rad/s²] of the last [`task_space_acceleration_into`].
    pub fn acceleration(&self) -> &[f64] {
        self.u.as_slice()
    }

    /// The Jacobian J [m/rad] of the last call.
    pub fn jacobian(&self) -> &DMatrix<f64> {
        &self.jacobian
    }

    /// The inverse J# [rad/m] of the last call: J⁺, damped near a singular pose ([`damped_inverse_into`]).
    pub fn pseudo_inverse(&self) -> &DMatrix<f64> {
        &self.pseudo_inverse
    }

    /// I − J#J of the last call: the null-space projector I − J⁺J away from singular poses.
    pub fn null_projector(&self) -> &DMatrix<f64> {
        &self.null_projector
    }
}

/// Joint accelerations the task-space law asks for,
/// u = J# (ẍ_d + K_d (ẋ_d − ẋ) + K_p (x_d − x) − J̇q̇) + (I − J#J)(k_s (q_rest − q) − k q̇)
/// [rad/s²], into `data` ([`TaskSpaceData::acceleration`]), J# the pseudo-inverse J⁺, damped
/// within [`TaskSpaceData::singular_margin`] of a singular pose ([`damped_inverse_into`]);
/// without a rest pose in `data` the k_s term is left out. False when the inputs are not
/// finite.
pub fn task_space_acceleration_into(
    model: &ArmParams,
    data: &mut TaskSpaceData,
    q: &[f64],
    qd: &[f64],
    reference: &TaskReference,
    gains: &TaskSpaceGains,
) -> bool {
    let d = data;
    jacobian_into(model, q, d.jacobian.as_mut_slice());
    if !damped_inverse_into(&d.jacobian, d.singular_margin, &mut d.jacobian_t, &mut d.jjt_inverse, &mut d.pseudo_inverse) {
        return false;
    }
    d.qd.copy_from_slice(qd);
    let x = crate::arm::end_effector_position(model, q);
    let xd = Vector2::new((d.jacobian.row(0) * &d.qd)[0], (d.jacobian.row(1) * &d.qd)[0]);
    let a =
        reference.acceleration + gains.kd * (reference.velocity - xd) + gains.kp * (reference.position - x) - jacobian_dot_qd(model, q, qd);
    d.task_acceleration.copy_from_slice(a.as_slice());
    d.pseudo_inverse.mul_to(&d.task_acceleration, &mut d.task);
    d.pseudo_inverse.mul_to(&d.jacobian, &mut d.pinv_j);
    d.null_projector.fill_with_identity();
    d.null_projector -= &d.pinv_j;
    if d.has_rest_pose && gains.null_stiffness != 0.0 {
        for i in 0..q.len() {
            d.null_target[i] = gains.null_stiffness * wrapped_angle(d.rest_pose[i] - q[i]) - gains.null_damping * qd[i];
        }
        d.null_projector.mul_to(&d.null_target, &mut d.null_motion);
        for ((u, t), m) in d.u.iter_mut().zip(d.task.iter()).zip(d.null_motion.iter()) {
            *u = t + m;
        }
    } else {
        // Damping only, computed as −k (N q̇) rather than N (−k q̇): the same in exact
        // arithmetic, and the rounding the long closed loops were measured with (they are
        // sensitive to it, see issue 24's notes).
        d.null_projector.mul_to(&d.qd, &mut d.null_motion);
        for ((u, t), m) in d.u.iter_mut().zip(d.task.iter()).zip(d.null_motion.iter()) {
            *u = t - gains.null_damping * m;
        }
    }
    d.u.iter().all(|u| u.is_finite())
}

/// `angle` [rad] moved by whole turns into (−π, π].
pub fn wrapped_angle(angle: f64) -> f64 {
    let tau = std::f64::consts::TAU;
    let a = angle - tau * (angle / tau).round();
    if a <= -std::f64::consts::PI {
        a + tau
    } else {
        a
    }
}

/// Joint accelerations the task-space law asks for: [`task_space_acceleration_into`] into a
/// new vector, without a rest pose; `None` when the inputs are not finite.
pub fn task_space_acceleration(
    model: &ArmParams,
    q: &[f64],
    qd: &[f64],
    reference: &TaskReference,
    gains: &TaskSpaceGains,
) -> Option<DVector<f64>> {
    let mut data = TaskSpaceData::new(model);
    task_space_acceleration_into(model, &mut data, q, qd, reference, gains).then_some(data.u)
}

/// Computed torque τ = Ĥ(q) u + Ĉ(q,q̇) q̇ + ĝ(q) + τ_comp [N·m] into `out`, with `model` the
/// controller's model of the arm (friction excluded: that is what `tau_comp` is for).
pub fn computed_torque_into(model: &ArmParams, data: &mut ArmData, q: &[f64], qd: &[f64], u: &[f64], tau_comp: &[f64], out: &mut [f64]) {
    inverse_dynamics_rnea_into(model, data, q, qd, u, out);
    for (t, c) in out.iter_mut().zip(tau_comp) {
        *t += c;
    }
}

/// Computed torque: [`computed_torque_into`] into a new vector.
pub fn computed_torque(model: &ArmParams, q: &[f64], qd: &[f64], u: &DVector<f64>, tau_comp: &[f64]) -> DVector<f64> {
    let mut tau = DVector::zeros(model.dof());
    computed_torque_into(model, &mut ArmData::new(model), q, qd, u.as_slice(), tau_comp, tau.as_mut_slice());
    tau
}

/// The whole task-space law: the accelerations of [`task_space_acceleration_into`] turned
/// into joint torques by [`computed_torque_into`], plus `tau_comp` [N·m], into `out`. False
/// when the inputs are not finite.
#[allow(clippy::too_many_arguments)] // the law's inputs, each a different quantity
pub fn task_space_torque_into(
    model: &ArmParams,
    data: &mut TaskSpaceData,
    q: &[f64],
    qd: &[f64],
    reference: &TaskReference,
    gains: &TaskSpaceGains,
    tau_comp: &[f64],
    out: &mut [f64],
) -> bool {
    if !task_space_acceleration_into(model, data, q, qd, reference, gains) {
        return false;
    }
    computed_torque_into(model, &mut data.arm, q, qd, data.u.as_slice(), tau_comp, out);
    true
}

/// Scratch space of [`task_learning_signal_into`] for one arm, made once.
#[derive(Clone, Debug)]
pub struct LearningSignalData {
    arm: ArmData,
    mass: DMatrix<f64>,
    jacobian: Vec<f64>,
}

impl LearningSignalData {
    /// Scratch space for the arm of `model`.
    pub fn new(model: &ArmParams) -> Self {
        let n = model.dof();
        Self { arm: ArmData::new(model), mass: DMatrix::zeros(n, n), jacobian: vec![0.0; 2 * n] }
    }
}

/// The joint-space learning signal of task-space computed torque, `s = Ĥ⁻¹ Jᵀ (ė + λ e)` with
/// `e = x_d − x`, `ė = ẋ_d − J q̇` [1/(kg·s)], into `out` (one entry per joint). An error
/// `δ` in the compensating torque enters the task-space error dynamics as `J Ĥ⁻¹ δ`; along `s`
/// the Lyapunov function of those dynamics falls when a compensator's weights move with
/// `φ s` (see the adaptive compensator). `lambda` [1/s] must lie in (0, K_d). Allocates
/// nothing; returns false, leaving `out` alone, when the inputs are not finite or Ĥ is not
/// positive definite.
pub fn task_learning_signal_into(
    model: &ArmParams,
    data: &mut LearningSignalData,
    q: &[f64],
    qd: &[f64],
    reference: &TaskReference,
    lambda: f64,
    out: &mut [f64],
) -> bool {
    let n = model.dof();
    if !q.iter().chain(qd).all(|v| v.is_finite()) {
        return false;
    }
    let x = crate::arm::end_effector_position(model, q);
    jacobian_into(model, q, &mut data.jacobian);
    let (mut xd_x, mut xd_y) = (0.0, 0.0);
    for j in 0..n {
        xd_x += data.jacobian[2 * j] * qd[j];
        xd_y += data.jacobian[2 * j + 1] * qd[j];
    }
    let vx = reference.velocity.x - xd_x + lambda * (reference.position.x - x.x);
    let vy = reference.velocity.y - xd_y + lambda * (reference.position.y - x.y);
    let mut rhs = [0.0; crate::arm::MAX_JOINTS];
    for j in 0..n {
        rhs[j] = data.jacobian[2 * j] * vx + data.jacobian[2 * j + 1] * vy;
    }
    crate::arm::mass_matrix_into(model, &mut data.arm, q, &mut data.mass);
    if !crate::linalg::cholesky_solve_in_place(data.mass.as_mut_slice(), n, &mut rhs[..n]) {
        return false;
    }
    out[..n].copy_from_slice(&rhs[..n]);
    true
}

/// Joint-space P control with gravity compensation: τ = ĝ + K_p (q_d − q) [N·m].
pub fn joint_p_torque(q: &[f64], q_target: &[f64], kp: f64, gravity_comp: &[f64]) -> DVector<f64> {
    DVector::from_fn(q.len(), |i, _| gravity_comp[i] + kp * (q_target[i] - q[i]))
}

/// Joint angles [rad] that put the end effector at `target` [m], found by Newton steps with
/// the pseudo-inverse from `seed` (so the answer is the solution reached by the smallest
/// joint motion from there, to first order). `None` if it does not converge to 1e-12 m or
/// meets a singular pose.
pub fn inverse_kinematics(model: &ArmParams, target: Vector2<f64>, seed: &[f64]) -> Option<Vec<f64>> {
    let mut q = seed.to_vec();
    for _ in 0..100 {
        let e = target - crate::arm::end_effector_position(model, &q);
        if e.norm() < 1e-12 {
            return Some(q);
        }
        let step = pseudo_inverse(&jacobian(model, &q))? * DVector::from_column_slice(e.as_slice());
        for (qi, d) in q.iter_mut().zip(step.iter()) {
            *qi += d;
        }
    }
    None
}

#[cfg(test)]
mod learning_signal_tests {
    use super::*;
    use crate::arm::inverse_dynamics_rnea;

    #[test]
    fn the_learning_signal_solves_h_s_equal_jt_v_by_recursive_newton_euler() {
        // Independent of the mass-matrix formulation: on the arm without gravity and friction
        // RNEA(q, 0, s) = H s, and Jᵀ v from finite differences of the forward kinematics.
        let model = ArmParams::default_four_link().frictionless();
        let q = [0.4, -0.9, 1.2, 0.3];
        let qd = [0.5, -0.2, 0.8, -1.1];
        let reference =
            TaskReference { position: Vector2::new(0.5, 0.2), velocity: Vector2::new(-0.1, 0.3), acceleration: Vector2::zeros() };
        let lambda = 20.0;
        let mut data = LearningSignalData::new(&model);
        let mut s = [0.0; 4];
        assert!(task_learning_signal_into(&model, &mut data, &q, &qd, &reference, lambda, &mut s));
        let hs = inverse_dynamics_rnea(&model, &q, &[0.0; 4], &s);
        let fk = |q: &[f64]| crate::arm::end_effector_position(&model, q);
        let eps = 1e-6;
        let columns: Vec<Vector2<f64>> = (0..4)
            .map(|j| {
                let (mut up, mut down) = (q, q);
                up[j] += eps;
                down[j] -= eps;
                (fk(&up) - fk(&down)) / (2.0 * eps)
            })
            .collect();
        let x = fk(&q);
        let xdot: Vector2<f64> = columns.iter().zip(&qd).map(|(c, v)| c * *v).sum();
        let v = reference.velocity - xdot + lambda * (reference.position - x);
        for j in 0..4 {
            let jt_v = columns[j].dot(&v);
            assert!((hs[j] - jt_v).abs() < 1e-7 * (1.0 + jt_v.abs()), "joint {j}: H s = {} vs Jᵀv = {jt_v}", hs[j]);
        }
        assert!(!task_learning_signal_into(&model, &mut data, &[f64::NAN, 0.0, 0.0, 0.0], &qd, &reference, lambda, &mut s));
    }
}
