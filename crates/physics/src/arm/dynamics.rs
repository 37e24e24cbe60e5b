//! Rigid-body dynamics of the planar arm, `τ = H(q) q̈ + C(q,q̇) q̇ + g(q)` (friction apart),
//! in two independent formulations:
//!
//! * **closed form (Lagrange)**: with rᵢₐ the lever of link a in the position of link i's centre
//!   of mass (lₐ for a < i, cᵢ for a = i) and θ the absolute angles,
//!   `H_jk = Σ_{i ≥ max(j,k)} [Iᵢ + mᵢ Σ_{a=j..i} Σ_{b=k..i} rᵢₐ rᵢ_b cos(θₐ − θ_b)]`;
//!   C q̇ from the Christoffel symbols of the analytic derivative ∂H/∂q; g from the gradient of
//!   the potential energy.
//! * **recursive Newton–Euler** ([`inverse_dynamics_rnea`]): link accelerations outwards, forces
//!   and moments inwards. Gravity enters as an upward acceleration of the base.
//!
//! Tests check each against the other, against Pinocchio's values, and against finite
//! differences of the energies. The integrator uses the mass matrix (via the centre-of-mass
//! Jacobians, O(n³)) and the O(n) Newton–Euler bias.
//!
//! Every algorithm is a function `f(&params, &mut data, q, …, out)` that allocates nothing,
//! its scratch space in [`ArmData`]; the functions without `_into` (or `_with`) are
//! conveniences that make the data and the output for one call.

use nalgebra::{DMatrix, DVector};

use super::kinematics::absolute_angles_into;
use super::params::ArmParams;

/// Lever of link `a`'s angle in the position of link `i`'s centre of mass [m] (`a <= i`).
#[inline]
fn lever(params: &ArmParams, i: usize, a: usize) -> f64 {
    if a < i {
        params.links[a].length_m
    } else {
        params.links[i].com_m
    }
}

/// Mass (inertia) matrix H(q) [kg·m²], closed form, into `out` (n×n).
pub fn mass_matrix_into(params: &ArmParams, data: &mut ArmData, q: &[f64], out: &mut DMatrix<f64>) {
    let n = params.dof();
    absolute_angles_into(q, &mut data.theta);
    // Each cos(θₐ − θ_b) once (n² of them) instead of in the innermost loop (O(n⁵) calls, most
    // of an 8-joint identification's time); the same values, so the sums are bit for bit.
    let theta = &data.theta;
    for a in 0..n {
        for b in 0..n {
            data.pair_trig[a * n + b] = (theta[a] - theta[b]).cos();
        }
    }
    let cos_difference = &data.pair_trig;
    for k in 0..n {
        for j in 0..n {
            let mut h = 0.0;
            for i in j.max(k)..n {
                let link = &params.links[i];
                let mut sum = 0.0;
                for a in j..=i {
                    for b in k..=i {
                        sum += lever(params, i, a) * lever(params, i, b) * cos_difference[a * n + b];
                    }
                }
                h += link.inertia_kgm2 + link.mass_kg * sum;
            }
            out[(j, k)] = h;
        }
    }
}

/// Mass matrix H(q) [kg·m²], closed form: [`mass_matrix_into`] into a new matrix.
pub fn mass_matrix(params: &ArmParams, q: &[f64]) -> DMatrix<f64> {
    let n = params.dof();
    let mut h = DMatrix::zeros(n, n);
    mass_matrix_into(params, &mut ArmData::new(params), q, &mut h);
    h
}

/// Fills `data.pair_trig` with sin(θₐ − θ_b) at `[a*n + b]` for the angles `q` [rad]: each
/// once (n² of them) instead of in the innermost loop of [`mass_matrix_derivative_entry`].
fn fill_sin_differences(params: &ArmParams, data: &mut ArmData, q: &[f64]) {
    let n = params.dof();
    absolute_angles_into(q, &mut data.theta);
    let theta = &data.theta;
    for a in 0..n {
        for b in 0..n {
            data.pair_trig[a * n + b] = (theta[a] - theta[b]).sin();
        }
    }
}

/// ∂H_jk/∂q_l, closed form [kg·m²/rad], from the sines of [`fill_sin_differences`].
fn mass_matrix_derivative_entry(params: &ArmParams, sin_difference: &[f64], l: usize, j: usize, k: usize) -> f64 {
    let n = params.dof();
    // With ∂θₐ/∂q_l = [l <= a], the term of (a, b) has the weight [l <= a] − [l <= b]: only
    // the b on the other side of l from a count (+1 for a ≥ l > b, −1 for a < l ≤ b), so the
    // loop over b visits just those.
    let mut s = 0.0;
    for i in j.max(k)..n {
        let m = params.links[i].mass_kg;
        for a in j..=i {
            let (others, w) = if l <= a { (k..l.min(i + 1), 1.0) } else { (k.max(l)..i + 1, -1.0) };
            for b in others {
                s -= m * lever(params, i, a) * lever(params, i, b) * sin_difference[a * n + b] * w;
            }
        }
    }
    s
}

/// ∂H_jk/∂q_l for all j, k, l, closed form [kg·m²/rad], into `data.dh` at `[l·n² + j·n + k]`.
fn mass_matrix_derivative(params: &ArmParams, data: &mut ArmData, q: &[f64]) {
    let n = params.dof();
    fill_sin_differences(params, data, q);
    for l in 0..n {
        for j in 0..n {
            for k in 0..n {
                data.dh[(l * n + j) * n + k] = mass_matrix_derivative_entry(params, &data.pair_trig, l, j, k);
            }
        }
    }
}

/// Coriolis and centrifugal torques C(q,q̇)·q̇ [N·m] when joint `joint` (0-based) alone moves,
/// at `speed` [rad/s]: `Γ_j,ff q̇_f²`, from the n³ entries of ∂H/∂q it needs instead of all
/// n³·n; equal, bit for bit, to [`coriolis_centrifugal_into`] with that speed vector.
pub fn coriolis_of_one_joint_into(params: &ArmParams, data: &mut ArmData, q: &[f64], joint: usize, speed: f64, out: &mut [f64]) {
    let n = params.dof();
    fill_sin_differences(params, data, q);
    let f = joint;
    for (j, o) in out.iter_mut().enumerate().take(n) {
        // Γ_jff = ½(∂H_jf/∂q_f + ∂H_jf/∂q_f − ∂H_ff/∂q_j), as `christoffel` adds them.
        let d_jf = mass_matrix_derivative_entry(params, &data.pair_trig, f, j, f);
        let d_ff = mass_matrix_derivative_entry(params, &data.pair_trig, j, f, f);
        let gamma = 0.5 * (d_jf + d_jf - d_ff);
        *o = gamma * speed * speed;
    }
}

/// The fastest decay rate viscous friction gives the arm at pose `q` [1/s]: the largest
/// eigenvalue of H(q)⁻¹ B, B the diagonal of each joint's largest viscous slope (of both
/// directions; a viscous term that falls with speed is steepest at rest). An explicit
/// integrator's step must stay below its stability bound over this rate (RK4: 2.785 / rate);
/// light distal links behind strongly damped joints make it thousands per second. `None` when
/// H is not positive definite.
pub fn largest_viscous_rate(params: &ArmParams, q: &[f64]) -> Option<f64> {
    let h = mass_matrix(params, q);
    let l = h.cholesky()?;
    let l_inverse = l.l().try_inverse()?;
    let n = params.dof();
    let slopes = DVector::from_iterator(n, params.friction.iter().map(|f| f.positive.viscous_nms_rad.max(f.negative.viscous_nms_rad)));
    let scaled = &l_inverse * DMatrix::from_diagonal(&slopes) * l_inverse.transpose();
    Some(scaled.symmetric_eigen().eigenvalues.max())
}

/// Christoffel symbol `Γ_jkl = ½(∂H_jk/∂q_l + ∂H_jl/∂q_k − ∂H_kl/∂q_j)` from `data.dh`.
#[inline]
fn christoffel(dh: &[f64], n: usize, j: usize, k: usize, l: usize) -> f64 {
    0.5 * (dh[(l * n + j) * n + k] + dh[(k * n + j) * n + l] - dh[(j * n + k) * n + l])
}

/// Coriolis and centrifugal torques C(q,q̇)·q̇ [N·m], from the Christoffel symbols
/// `Γ_jkl = ½(∂H_jk/∂q_l + ∂H_jl/∂q_k − ∂H_kl/∂q_j)`, into `out` (n).
pub fn coriolis_centrifugal_into(params: &ArmParams, data: &mut ArmData, q: &[f64], qd: &[f64], out: &mut [f64]) {
    let n = params.dof();
    mass_matrix_derivative(params, data, q);
    for (j, o) in out.iter_mut().enumerate().take(n) {
        let mut c = 0.0;
        for k in 0..n {
            for l in 0..n {
                c += christoffel(&data.dh, n, j, k, l) * qd[k] * qd[l];
            }
        }
        *o = c;
    }
}

/// Coriolis and centrifugal torques C(q,q̇)·q̇ [N·m]: [`coriolis_centrifugal_into`] into a
/// new vector.
pub fn coriolis_centrifugal(params: &ArmParams, q: &[f64], qd: &[f64]) -> DVector<f64> {
    let mut c = DVector::zeros(params.dof());
    coriolis_centrifugal_into(params, &mut ArmData::new(params), q, qd, c.as_mut_slice());
    c
}

/// The Coriolis matrix C(q,q̇) [kg·m²/s] with `C_jk = Σ_l Γ_jkl q̇_l`, into `out` (n×n);
/// `C q̇` equals [`coriolis_centrifugal`], and with this choice Ḣ − 2C is skew-symmetric.
pub fn coriolis_matrix_into(params: &ArmParams, data: &mut ArmData, q: &[f64], qd: &[f64], out: &mut DMatrix<f64>) {
    let n = params.dof();
    mass_matrix_derivative(params, data, q);
    for k in 0..n {
        for j in 0..n {
            out[(j, k)] = (0..n).map(|l| christoffel(&data.dh, n, j, k, l) * qd[l]).sum();
        }
    }
}

/// The Coriolis matrix C(q,q̇) [kg·m²/s]: [`coriolis_matrix_into`] into a new matrix.
pub fn coriolis_matrix(params: &ArmParams, q: &[f64], qd: &[f64]) -> DMatrix<f64> {
    let n = params.dof();
    let mut c = DMatrix::zeros(n, n);
    coriolis_matrix_into(params, &mut ArmData::new(params), q, qd, &mut c);
    c
}

/// Gravity torques g(q) [N·m]: the gradient of the potential energy, closed form, into `out`.
pub fn gravity_torques_into(params: &ArmParams, data: &mut ArmData, q: &[f64], out: &mut [f64]) {
    let n = params.dof();
    absolute_angles_into(q, &mut data.theta);
    let theta = &data.theta;
    let g = params.in_plane_gravity();
    for (j, o) in out.iter_mut().enumerate().take(n) {
        let mut s = 0.0;
        for i in j..n {
            let mut lever_sum = 0.0;
            for a in j..=i {
                lever_sum += lever(params, i, a) * theta[a].cos();
            }
            s += params.links[i].mass_kg * lever_sum;
        }
        *o = g * s;
    }
}

/// Gravity torques g(q) [N·m]: [`gravity_torques_into`] into a new vector.
pub fn gravity_torques(params: &ArmParams, q: &[f64]) -> DVector<f64> {
    let mut g = DVector::zeros(params.dof());
    gravity_torques_into(params, &mut ArmData::new(params), q, g.as_mut_slice());
    g
}

/// Inverse dynamics without friction, closed form: H q̈ + C q̇ + g [N·m], into `out`.
pub fn inverse_dynamics_into(params: &ArmParams, data: &mut ArmData, q: &[f64], qd: &[f64], qdd: &[f64], out: &mut [f64]) {
    let n = params.dof();
    let mut h = std::mem::take(&mut data.mass);
    mass_matrix_into(params, data, q, &mut h);
    let mut bias = std::mem::take(&mut data.bias);
    coriolis_centrifugal_into(params, data, q, qd, bias.as_mut_slice());
    let hq = out;
    for (j, o) in hq.iter_mut().enumerate().take(n) {
        *o = (0..n).map(|k| h[(j, k)] * qdd[k]).sum::<f64>() + bias[j];
    }
    gravity_torques_into(params, data, q, bias.as_mut_slice());
    for (o, g) in hq.iter_mut().zip(bias.iter()) {
        *o += g;
    }
    data.mass = h;
    data.bias = bias;
}

/// Inverse dynamics without friction, closed form: [`inverse_dynamics_into`] into a new vector.
pub fn inverse_dynamics(params: &ArmParams, q: &[f64], qd: &[f64], qdd: &[f64]) -> DVector<f64> {
    let mut tau = DVector::zeros(params.dof());
    inverse_dynamics_into(params, &mut ArmData::new(params), q, qd, qdd, tau.as_mut_slice());
    tau
}

/// Kinetic energy ½ q̇ᵀ H q̇ [J], with `data`'s scratch space.
pub fn kinetic_energy_with(params: &ArmParams, data: &mut ArmData, q: &[f64], qd: &[f64]) -> f64 {
    let n = params.dof();
    let mut h = std::mem::take(&mut data.mass);
    mass_matrix_into(params, data, q, &mut h);
    let mut e = 0.0;
    for j in 0..n {
        e += qd[j] * (0..n).map(|k| h[(j, k)] * qd[k]).sum::<f64>();
    }
    data.mass = h;
    0.5 * e
}

/// Kinetic energy ½ q̇ᵀ H q̇ [J].
pub fn kinetic_energy(params: &ArmParams, q: &[f64], qd: &[f64]) -> f64 {
    kinetic_energy_with(params, &mut ArmData::new(params), q, qd)
}

/// Potential energy Σ mᵢ g y_cᵢ [J], zero with every centre of mass at y = 0.
pub fn potential_energy(params: &ArmParams, q: &[f64]) -> f64 {
    let g = params.in_plane_gravity();
    let mut theta = 0.0;
    let mut joint_y = 0.0;
    let mut energy = 0.0;
    for (link, &qi) in params.links.iter().zip(q) {
        theta += qi;
        energy += link.mass_kg * g * (joint_y + link.com_m * theta.sin());
        joint_y += link.length_m * theta.sin();
    }
    energy
}

/// Inverse dynamics without friction by the recursive Newton–Euler algorithm [N·m], into `out`.
pub fn inverse_dynamics_rnea_into(params: &ArmParams, data: &mut ArmData, q: &[f64], qd: &[f64], qdd: &[f64], out: &mut [f64]) {
    rnea_into(params, q, qd, Some(qdd), params.in_plane_gravity(), data, out);
}

/// Inverse dynamics by the recursive Newton–Euler algorithm [N·m]:
/// [`inverse_dynamics_rnea_into`] into a new vector.
pub fn inverse_dynamics_rnea(params: &ArmParams, q: &[f64], qd: &[f64], qdd: &[f64]) -> DVector<f64> {
    let mut tau = DVector::zeros(params.dof());
    inverse_dynamics_rnea_into(params, &mut ArmData::new(params), q, qd, qdd, tau.as_mut_slice());
    tau
}

/// Scratch space of the dynamics of one arm (the "data" beside the immutable parameters, as
/// in MuJoCo's mjData and Pinocchio's Data), made once by [`ArmData::new`]; every `*_into`
/// and `*_with` function works in it without allocating.
#[derive(Clone, Debug)]
pub struct ArmData {
    n: usize,
    /// Absolute link angles [rad].
    theta: Vec<f64>,
    /// ∂H/∂q, n³ entries.
    dh: Vec<f64>,
    /// cos or sin of θₐ − θ_b at `[a*n + b]`, for the closed-form mass matrix and its derivative.
    pair_trig: Vec<f64>,
    /// A mass matrix.
    mass: DMatrix<f64>,
    /// A joint-torque vector.
    bias: DVector<f64>,
    cos: Vec<f64>,
    sin: Vec<f64>,
    /// ∂p_cᵢ/∂q_j as (x, y) at `[i*n + j]`, j <= i.
    com_jacobian: Vec<[f64; 2]>,
    /// Centre-of-mass acceleration of each link, (x, y) [m/s²].
    com_accel: Vec<[f64; 2]>,
    /// Angular acceleration of each link [rad/s²].
    angular_accel: Vec<f64>,
}

impl ArmData {
    /// Scratch space for the arm of `params` (sized by its number of joints).
    pub fn new(params: &ArmParams) -> Self {
        let n = params.dof();
        Self {
            n,
            theta: vec![0.0; n],
            dh: vec![0.0; n * n * n],
            pair_trig: vec![0.0; n * n],
            mass: DMatrix::zeros(n, n),
            bias: DVector::zeros(n),
            cos: vec![0.0; n],
            sin: vec![0.0; n],
            com_jacobian: vec![[0.0; 2]; n * n],
            com_accel: vec![[0.0; 2]; n],
            angular_accel: vec![0.0; n],
        }
    }

    /// Number of joints this data is sized for.
    pub fn dof(&self) -> usize {
        self.n
    }

    /// Computes the sines and cosines of the absolute angles of `q`, which the `*_at_angles`
    /// functions read.
    pub(crate) fn set_angles(&mut self, q: &[f64]) {
        let mut theta = 0.0;
        for i in 0..self.n {
            theta += q[i];
            let (s, c) = theta.sin_cos();
            self.sin[i] = s;
            self.cos[i] = c;
        }
    }
}

/// Mass matrix into `h` (row-major n×n) as `Σᵢ mᵢ J_cᵢᵀ J_cᵢ + Iᵢ aᵢ aᵢᵀ`, without allocating,
/// at the angles last given to [`ArmData::set_angles`].
pub(crate) fn mass_matrix_at_angles(params: &ArmParams, ws: &mut ArmData, h: &mut [f64]) {
    let n = ws.n;
    // Centre-of-mass Jacobian columns of link i, built from the centre of mass inwards.
    for i in 0..n {
        let c = params.links[i].com_m;
        let mut v = [-c * ws.sin[i], c * ws.cos[i]];
        ws.com_jacobian[i * n + i] = v;
        for j in (0..i).rev() {
            let l = params.links[j].length_m;
            v[0] -= l * ws.sin[j];
            v[1] += l * ws.cos[j];
            ws.com_jacobian[i * n + j] = v;
        }
    }
    for j in 0..n {
        for k in j..n {
            let mut s = 0.0;
            for i in k..n {
                let link = &params.links[i];
                let a = ws.com_jacobian[i * n + j];
                let b = ws.com_jacobian[i * n + k];
                s += link.inertia_kgm2 + link.mass_kg * (a[0] * b[0] + a[1] * b[1]);
            }
            h[j * n + k] = s;
            h[k * n + j] = s;
        }
    }
}

/// Recursive Newton–Euler: τ for accelerations `qdd` (zero if `None`) under in-plane gravity
/// `gravity` [m/s², along −y], written into `tau`, without allocating.
pub(crate) fn rnea_into(params: &ArmParams, q: &[f64], qd: &[f64], qdd: Option<&[f64]>, gravity: f64, ws: &mut ArmData, tau: &mut [f64]) {
    ws.set_angles(q);
    rnea_at_angles(params, qd, qdd, gravity, ws, tau);
}

/// [`rnea_into`] at the angles last given to [`ArmData::set_angles`].
pub(crate) fn rnea_at_angles(params: &ArmParams, qd: &[f64], qdd: Option<&[f64]>, gravity: f64, ws: &mut ArmData, tau: &mut [f64]) {
    let n = ws.n;
    // Outward pass. Gravity is an upward acceleration of the base.
    let mut joint_acc = [0.0, gravity];
    let (mut omega, mut alpha) = (0.0, 0.0);
    for i in 0..n {
        omega += qd[i];
        alpha += qdd.map_or(0.0, |a| a[i]);
        let link = &params.links[i];
        let (c, s) = (ws.cos[i], ws.sin[i]);
        // Acceleration of a point at distance r along the link: tangential α r, centripetal ω² r.
        let rel = |r: f64| [r * (-alpha * s - omega * omega * c), r * (alpha * c - omega * omega * s)];
        let at_com = rel(link.com_m);
        ws.com_accel[i] = [joint_acc[0] + at_com[0], joint_acc[1] + at_com[1]];
        ws.angular_accel[i] = alpha;
        let at_tip = rel(link.length_m);
        joint_acc = [joint_acc[0] + at_tip[0], joint_acc[1] + at_tip[1]];
    }
    // Inward pass: force f on link i from link i−1, moment n about joint i.
    let (mut force, mut moment) = ([0.0, 0.0], 0.0);
    for i in (0..n).rev() {
        let link = &params.links[i];
        let (c, s) = (ws.cos[i], ws.sin[i]);
        let inertial = [link.mass_kg * ws.com_accel[i][0], link.mass_kg * ws.com_accel[i][1]];
        let cross = |r: f64, f: [f64; 2]| r * (c * f[1] - s * f[0]);
        moment += link.inertia_kgm2 * ws.angular_accel[i] + cross(link.com_m, inertial) + cross(link.length_m, force);
        force = [force[0] + inertial[0], force[1] + inertial[1]];
        tau[i] = moment;
    }
}
