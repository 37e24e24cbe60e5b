//! The holds of the identification experiments: the control laws that keep the joints not
//! being measured where they should be while a friction run drives one joint, and the
//! computed torque that carries the arm through the gravity sweep's slow passes. Both are
//! critically damped (K_p = ω², K_d = 2ω) at their bandwidth ω; the functions work on plain
//! slices so the experiments' step loops allocate nothing.

use nalgebra::DMatrix;

use crate::arm::{inverse_dynamics_rnea_into, ArmData, ArmParams};

/// Bandwidth of the friction runs' rigid hold of the joints not driven [rad/s]: K_p = 400 1/s²,
/// K_d = 40 1/s. Higher bandwidths let sensor noise jitter the held joints, whose friction then
/// adds to the driven joint's (docs/decisions/0006-friction-hold.md).
pub const FRICTION_HOLD_RAD_S: f64 = 20.0;

/// Bandwidth of the gravity sweep's computed-torque hold [rad/s]: critically damped at it in
/// every pose.
pub const GRAVITY_HOLD_RAD_S: f64 = 80.0;

/// The accelerations [rad/s²] with which the friction hold pulls every joint back to 0, from
/// the angles `q` [rad] and speeds `qd` [rad/s], into `u`: u = −2ω q̇ − ω² q with
/// ω = [`FRICTION_HOLD_RAD_S`]. The driven joint's entry is overwritten by the caller.
pub fn friction_hold_accelerations_into(q: &[f64], qd: &[f64], u: &mut [f64]) {
    for i in 0..u.len() {
        u[i] = -2.0 * FRICTION_HOLD_RAD_S * qd[i] - FRICTION_HOLD_RAD_S * FRICTION_HOLD_RAD_S * q[i];
    }
}

/// The torques [N·m] of the friction hold while joint `driven` moves freely, into `tau`:
/// τ_h = S u_h + c_h for the held joints h, with `h` the rigid-body mass matrix H [kg·m²],
/// `c` the Coriolis and centrifugal torques [N·m], `u` the hold's accelerations [rad/s²]
/// ([`friction_hold_accelerations_into`]; its `driven` entry is set to 0 here) and
/// S = H_hh − H_hf H_fh / H_ff the held joints' inertia while the driven joint f moves freely,
/// so they settle exactly once it runs at constant speed (docs/decisions/0006-friction-hold.md).
/// The driven joint's entry is left to the caller (its own torque replaces it).
pub fn friction_hold_torques_into(h: &DMatrix<f64>, c: &[f64], u: &mut [f64], driven: usize, tau: &mut [f64]) {
    let n = u.len();
    u[driven] = 0.0;
    let coupling: f64 = (0..n).map(|k| h[(driven, k)] * u[k]).sum::<f64>() / h[(driven, driven)];
    for i in 0..n {
        tau[i] = (0..n).map(|k| h[(i, k)] * u[k]).sum::<f64>() - h[(i, driven)] * coupling + c[i];
    }
}

/// The gravity hold's accelerations [rad/s²] into `u`: u = q̈_d + K_d (q̇_d − q̇) + K_p (q_d − q)
/// with K_p = ω², K_d = 2ω, ω = [`GRAVITY_HOLD_RAD_S`]; `reference` holds q_d [rad] then q̇_d
/// [rad/s], `acceleration` q̈_d [rad/s²], `state` the measured q [rad] then q̇ [rad/s].
pub fn gravity_hold_accelerations_into(reference: &[f64], acceleration: &[f64], state: &[f64], u: &mut [f64]) {
    let n = u.len();
    for i in 0..n {
        u[i] = acceleration[i]
            + 2.0 * GRAVITY_HOLD_RAD_S * (reference[n + i] - state[n + i])
            + GRAVITY_HOLD_RAD_S * GRAVITY_HOLD_RAD_S * (reference[i] - state[i]);
    }
}

/// The gravity hold's computed torque [N·m] into `tau`: τ = Ĥ(q) u + Ĉ(q, q̇) q̇ by inverse
/// dynamics of `model` (the sweep passes the gravity-free, frictionless rigid body: gravity is
/// what it identifies), u from [`gravity_hold_accelerations_into`] (into the scratch `u`).
/// Arguments as there; `data` is `model`'s workspace.
pub fn gravity_hold_torques_into(
    model: &ArmParams,
    data: &mut ArmData,
    reference: &[f64],
    acceleration: &[f64],
    state: &[f64],
    u: &mut [f64],
    tau: &mut [f64],
) {
    let n = u.len();
    gravity_hold_accelerations_into(reference, acceleration, state, u);
    inverse_dynamics_rnea_into(model, data, &state[..n], &state[n..], u, tau);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_holds_are_critically_damped_at_their_bandwidths() {
        let mut u = [0.0; 2];
        friction_hold_accelerations_into(&[0.01, 0.0], &[0.0, 0.1], &mut u);
        assert_eq!(u, [-400.0 * 0.01, -40.0 * 0.1]);
        gravity_hold_accelerations_into(&[0.01, 0.0, 0.0, 0.1], &[1.0, 0.0], &[0.0; 4], &mut u);
        assert_eq!(u, [1.0 + 6400.0 * 0.01, 160.0 * 0.1]);
    }

    #[test]
    fn the_friction_hold_leaves_the_driven_joint_free() {
        // H with coupling: the driven joint 0 gets no net acceleration from the held ones.
        let h = DMatrix::from_row_slice(2, 2, &[2.0, 0.5, 0.5, 1.0]);
        let mut u = [3.0, -4.0];
        let mut tau = [0.0; 2];
        friction_hold_torques_into(&h, &[0.0, 0.0], &mut u, 0, &mut tau);
        assert_eq!(u[0], 0.0);
        // τ_h = S u_h with S = 1 − 0.25 / 2.
        assert!((tau[1] - (1.0 - 0.125) * -4.0).abs() < 1e-12, "{tau:?}");
        assert!(tau[0].abs() < 1e-12, "{tau:?}");
    }
}
