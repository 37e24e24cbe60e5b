//! The paper's control loops as FMUs: `TaskSpaceController` (computed torque in task space
//! for the redundant arm), `JointController` (joint P control with a compensation input) and
//! `IdealCompensator` (the true friction and gravity of an arm: "perfect compensation").
//!
//! All three are static in their inputs (outputs follow inputs at once, direct feedthrough);
//! the task-space controller and the built-in joint sequence also depend on time, which
//! advances with each step.

use nalgebra::Vector2;

use crate::arm::{end_effector_position, gravity_torques, ArmParams};
use crate::control::{computed_torque, paper_reference, task_space_acceleration, TaskReference, TaskSpaceGains};
use crate::fmi2::codec::{Put, Reader};
use crate::fmi2::description::{Causality, Kind, ModelDescription, TableBuilder, Variability};
use crate::fmi2::model::{Model, StaticModel, Values};

fn per_joint(b: &mut TableBuilder, n: usize, f: impl Fn(&mut TableBuilder, usize) -> u32) -> Vec<u32> {
    (0..n).map(|i| f(b, i)).collect()
}

fn read(values: &Values, vrs: &[u32], out: &mut [f64]) {
    for (o, &vr) in out.iter_mut().zip(vrs) {
        *o = values.reals[vr as usize];
    }
}

fn tunable(b: &mut TableBuilder, name: String, unit: &'static str, start: f64, what: String) -> u32 {
    b.push(name, Causality::Parameter, Variability::Tunable, Kind::Real { start: Some(start), unit }, what)
}

fn save_time(time: f64, out: &mut Vec<u8>) {
    out.put_f64s(&[time]);
}

fn load_time(bytes: &[u8]) -> Result<f64, String> {
    let mut r = Reader::new(bytes);
    let t = r.f64s(1)?;
    r.finish()?;
    Ok(t[0])
}

/// Task-space computed-torque control of a planar arm tracking the paper's reference
/// `x_d(t) = c + (0.2 (cos t + sin 2t), 0.15 (sin t + cos 2t))` [m] around the centre c:
/// `u = J⁺ (ẍ_d + K_d (ẋ_d − ẋ) + K_p (x_d − x) − J̇q̇) − k_null (I − J⁺J) q̇`,
/// `τ = Ĥ(q) u + Ĉ(q, q̇) q̇ + ĝ(q) + τ_comp`, with Ĥ, Ĉ, ĝ from the controller's model of the
/// arm (friction is left to `tau_comp`).
pub struct TaskSpaceControllerModel {
    description: ModelDescription,
    model: ArmParams,
    q: Vec<u32>,
    qd: Vec<u32>,
    tau_comp: Vec<u32>,
    tau: Vec<u32>,
    reference: [u32; 2],
    error: [u32; 2],
    kp: u32,
    kd: u32,
    null_damping: u32,
    centre: [u32; 2],
    time: f64,
    buf: [Vec<f64>; 3],
}

impl TaskSpaceControllerModel {
    /// A controller named `identifier` using `model` (the controller's idea of the arm),
    /// default gains `gains`, reference centre `centre` [m], and start values `q_start` of the
    /// angle inputs [rad] (a pose away from singularities, so initial outputs exist).
    pub fn new(identifier: &str, model: ArmParams, gains: TaskSpaceGains, centre: [f64; 2], q_start: &[f64]) -> Result<Self, String> {
        model.validate().map_err(|e| e.to_string())?;
        let n = model.dof();
        if n < 2 {
            return Err("task-space control of a planar position needs at least 2 joints".into());
        }
        if q_start.len() != n {
            return Err(format!("{} start angles for {n} joints", q_start.len()));
        }
        let mut b = TableBuilder::new();
        let q = per_joint(&mut b, n, |b, i| b.input(format!("q_{}", i + 1), "rad", q_start[i], format!("Measured angle of joint {}", i + 1)));
        let qd = per_joint(&mut b, n, |b, i| b.input(format!("qd_{}", i + 1), "rad/s", 0.0, format!("Measured velocity of joint {}", i + 1)));
        let tau_comp = per_joint(&mut b, n, |b, i| {
            b.input(format!("tau_comp_{}", i + 1), "N.m", 0.0, format!("Compensating torque added to joint {} (friction model, NN, or 0)", i + 1))
        });
        let all: Vec<u32> = q.iter().chain(&qd).chain(&tau_comp).copied().collect();
        let tau = per_joint(&mut b, n, |b, i| b.output(format!("tau_{}", i + 1), "N.m", format!("Torque command of joint {}", i + 1), &all));
        let reference = [b.output("x_ref", "m", "Reference x_d(t)", &[]), b.output("y_ref", "m", "Reference y_d(t)", &[])];
        let error = [b.output("error_x", "m", "Tracking error x_d − x", &q), b.output("error_y", "m", "Tracking error y_d − y", &q)];
        let kp = tunable(&mut b, "kp".into(), "1/s2", gains.kp, "Position gain K_p".into());
        let kd = tunable(&mut b, "kd".into(), "1/s", gains.kd, "Velocity gain K_d".into());
        let null_damping = tunable(&mut b, "null_damping".into(), "1/s", gains.null_damping, "Null-space damping k_null: self-motion decays as -k_null (I - J#J) qd".into());
        let centre = [
            b.parameter("centre_x", "m", centre[0], "x of the reference's centre"),
            b.parameter("centre_y", "m", centre[1], "y of the reference's centre"),
        ];
        let text = format!("Task-space computed-torque controller for a {n}-joint planar arm, the paper's reference (neurarm)");
        let description = ModelDescription::new(identifier, text, b.finish())?;
        Ok(Self {
            description,
            model,
            q,
            qd,
            tau_comp,
            tau,
            reference,
            error,
            kp,
            kd,
            null_damping,
            centre,
            time: 0.0,
            buf: [vec![0.0; n], vec![0.0; n], vec![0.0; n]],
        })
    }

    fn compute(&mut self, values: &mut Values) -> Result<(), String> {
        let [q, qd, comp] = &mut self.buf;
        read(values, &self.q, q);
        read(values, &self.qd, qd);
        read(values, &self.tau_comp, comp);
        let r = |vr: u32| values.reals[vr as usize];
        let centre = Vector2::new(r(self.centre[0]), r(self.centre[1]));
        let gains = TaskSpaceGains { kp: r(self.kp), kd: r(self.kd), null_damping: r(self.null_damping) };
        let (position, velocity, acceleration) = paper_reference(self.time, centre);
        let x = end_effector_position(&self.model, q);
        values.reals[self.reference[0] as usize] = position.x;
        values.reals[self.reference[1] as usize] = position.y;
        values.reals[self.error[0] as usize] = position.x - x.x;
        values.reals[self.error[1] as usize] = position.y - x.y;
        let reference = TaskReference { position, velocity, acceleration };
        let u = task_space_acceleration(&self.model, q, qd, &reference, &gains)
            .ok_or_else(|| format!("no control law at t = {} s: the inputs q = {q:?}, qd = {qd:?} are not finite", self.time))?;
        let tau = computed_torque(&self.model, q, qd, &u, comp);
        for (&vr, t) in self.tau.iter().zip(tau.iter()) {
            values.reals[vr as usize] = *t;
        }
        Ok(())
    }
}

impl Model for TaskSpaceControllerModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }
    fn initialize(&mut self, values: &mut Values, start_time: f64) -> Result<(), String> {
        self.time = start_time;
        self.compute(values)
    }
    fn update_outputs(&mut self, values: &mut Values) -> Result<(), String> {
        self.compute(values)
    }
    fn do_step(&mut self, values: &mut Values, time: f64, step: f64) -> Result<(), String> {
        self.time = time + step;
        self.compute(values)
    }
    fn reset(&mut self) {
        self.time = 0.0;
    }
    fn save_state(&self, out: &mut Vec<u8>) {
        save_time(self.time, out);
    }
    fn load_state(&mut self, _values: &Values, bytes: &[u8]) -> Result<(), String> {
        self.time = load_time(bytes)?;
        Ok(())
    }
}

/// The built-in joint targets of the `JointController` [rad]: segment k holds for
/// [`SEQUENCE_SEGMENT_S`] seconds from t = k·T; joint i of an n-joint arm uses column i mod 4.
/// With the base turned 90° (gravity along −y), the first target is the hanging pose
/// (q_1 = −π/2, the others 0); the next segments move every joint away from it.
pub const JOINT_SEQUENCE: [[f64; 4]; 5] = [
    [-std::f64::consts::FRAC_PI_2, 0.0, 0.0, 0.0],
    [-std::f64::consts::FRAC_PI_4, 0.5, -0.5, 0.5],
    [0.0, -0.7, 0.7, -0.7],
    [-1.0, 1.0, 0.5, -1.0],
    [-0.5, -0.5, -1.0, 1.0],
];

/// Duration of one segment of [`JOINT_SEQUENCE`] [s].
pub const SEQUENCE_SEGMENT_S: f64 = 3.0;

/// The built-in target of joint `i` at time `t` [s]; the last segment holds after its end.
pub fn sequence_target(i: usize, t: f64) -> f64 {
    let k = ((t / SEQUENCE_SEGMENT_S).floor().max(0.0) as usize).min(JOINT_SEQUENCE.len() - 1);
    JOINT_SEQUENCE[k][i % 4]
}

/// Joint-space control `τ_i = τ_comp,i + K_p,i (q_d,i − q_i) + K_d,i (q̇_d,i − q̇_i)`. The
/// paper's law is K_d = 0 with gravity compensation as `tau_comp`. The target q_d is the
/// built-in [`JOINT_SEQUENCE`] (with q̇_d = 0) or, with `use_sequence` false, the inputs
/// `q_ref_i`, `qd_ref_i`.
pub struct JointControllerModel {
    description: ModelDescription,
    q: Vec<u32>,
    qd: Vec<u32>,
    tau_comp: Vec<u32>,
    q_ref: Vec<u32>,
    qd_ref: Vec<u32>,
    tau: Vec<u32>,
    target: Vec<u32>,
    kp: Vec<u32>,
    kd: Vec<u32>,
    use_sequence: u32,
    time: f64,
}

impl JointControllerModel {
    /// A controller for `joints` joints with gains `kp` [N·m/rad] and `kd` [N·m·s/rad] on
    /// every joint, following the built-in sequence if `use_sequence`.
    pub fn new(identifier: &str, joints: usize, kp: f64, kd: f64, use_sequence: bool) -> Result<Self, String> {
        if joints == 0 {
            return Err("the controller needs at least one joint".into());
        }
        let n = joints;
        let mut b = TableBuilder::new();
        let q = per_joint(&mut b, n, |b, i| b.input(format!("q_{}", i + 1), "rad", 0.0, format!("Measured angle of joint {}", i + 1)));
        let qd = per_joint(&mut b, n, |b, i| b.input(format!("qd_{}", i + 1), "rad/s", 0.0, format!("Measured velocity of joint {}", i + 1)));
        let tau_comp = per_joint(&mut b, n, |b, i| b.input(format!("tau_comp_{}", i + 1), "N.m", 0.0, format!("Compensating (or feed-forward) torque of joint {}", i + 1)));
        let q_ref = per_joint(&mut b, n, |b, i| b.input(format!("q_ref_{}", i + 1), "rad", 0.0, format!("Target angle of joint {} when use_sequence is false", i + 1)));
        let qd_ref = per_joint(&mut b, n, |b, i| b.input(format!("qd_ref_{}", i + 1), "rad/s", 0.0, format!("Target velocity of joint {} when use_sequence is false", i + 1)));
        let tau = per_joint(&mut b, n, |b, i| {
            let deps = [q[i], qd[i], tau_comp[i], q_ref[i], qd_ref[i]];
            b.output(format!("tau_{}", i + 1), "N.m", format!("Torque command of joint {}", i + 1), &deps)
        });
        let target = per_joint(&mut b, n, |b, i| b.output(format!("q_target_{}", i + 1), "rad", format!("Active target angle of joint {}", i + 1), &[q_ref[i]]));
        let kp = per_joint(&mut b, n, |b, i| tunable(b, format!("kp_{}", i + 1), "N.m/rad", kp, format!("Position gain of joint {}", i + 1)));
        let kd = per_joint(&mut b, n, |b, i| tunable(b, format!("kd_{}", i + 1), "N.m.s/rad", kd, format!("Velocity gain of joint {} (0 in the paper)", i + 1)));
        let use_sequence = b.push(
            "use_sequence",
            Causality::Parameter,
            Variability::Tunable,
            Kind::Boolean { start: Some(use_sequence) },
            "Follow the built-in target sequence (true) or the q_ref/qd_ref inputs (false)",
        );
        let text = format!("Joint-space P(D) controller with a compensation input for {n} joints (neurarm)");
        let description = ModelDescription::new(identifier, text, b.finish())?;
        Ok(Self { description, q, qd, tau_comp, q_ref, qd_ref, tau, target, kp, kd, use_sequence, time: 0.0 })
    }

    fn compute(&mut self, values: &mut Values) {
        let sequence = values.booleans[self.use_sequence as usize];
        for i in 0..self.q.len() {
            let r = |vr: &[u32]| values.reals[vr[i] as usize];
            let (target, target_velocity) = if sequence { (sequence_target(i, self.time), 0.0) } else { (r(&self.q_ref), r(&self.qd_ref)) };
            let tau = r(&self.tau_comp) + r(&self.kp) * (target - r(&self.q)) + r(&self.kd) * (target_velocity - r(&self.qd));
            values.reals[self.tau[i] as usize] = tau;
            values.reals[self.target[i] as usize] = target;
        }
    }
}

impl Model for JointControllerModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }
    fn initialize(&mut self, values: &mut Values, start_time: f64) -> Result<(), String> {
        self.time = start_time;
        self.compute(values);
        Ok(())
    }
    fn update_outputs(&mut self, values: &mut Values) -> Result<(), String> {
        self.compute(values);
        Ok(())
    }
    fn do_step(&mut self, values: &mut Values, time: f64, step: f64) -> Result<(), String> {
        self.time = time + step;
        self.compute(values);
        Ok(())
    }
    fn reset(&mut self) {
        self.time = 0.0;
    }
    fn save_state(&self, out: &mut Vec<u8>) {
        save_time(self.time, out);
    }
    fn load_state(&mut self, _values: &Values, bytes: &[u8]) -> Result<(), String> {
        self.time = load_time(bytes)?;
        Ok(())
    }
}

/// The true friction and gravity torques of an arm, with the interface of the NN
/// compensator: "perfect compensation". Friction at exactly zero velocity is 0 (the true
/// value there is any torque up to breakaway).
pub struct IdealCompensatorModel {
    description: ModelDescription,
    arm: ArmParams,
    q: Vec<u32>,
    qd: Vec<u32>,
    friction: Vec<u32>,
    gravity: Vec<u32>,
    total: Vec<u32>,
    enable_friction: u32,
    enable_gravity: u32,
    angles: Vec<f64>,
}

impl IdealCompensatorModel {
    /// The ideal compensator of `arm`.
    pub fn new(identifier: &str, arm: ArmParams, enable: (bool, bool)) -> Result<Self, String> {
        arm.validate().map_err(|e| e.to_string())?;
        let n = arm.dof();
        let mut b = TableBuilder::new();
        let q = per_joint(&mut b, n, |b, i| b.input(format!("q_{}", i + 1), "rad", 0.0, format!("Angle of joint {}", i + 1)));
        let qd = per_joint(&mut b, n, |b, i| b.input(format!("qd_{}", i + 1), "rad/s", 0.0, format!("Velocity of joint {}", i + 1)));
        let friction = per_joint(&mut b, n, |b, i| b.output(format!("tau_friction_{}", i + 1), "N.m", format!("True friction torque of joint {}", i + 1), &[qd[i]]));
        let gravity = per_joint(&mut b, n, |b, i| b.output(format!("tau_gravity_{}", i + 1), "N.m", format!("True gravity torque of joint {}", i + 1), &q));
        let total = per_joint(&mut b, n, |b, i| {
            let mut deps = q.clone();
            deps.push(qd[i]);
            b.output(format!("tau_comp_{}", i + 1), "N.m", format!("Compensating torque of joint {}: the sum of the enabled parts", i + 1), &deps)
        });
        let flag = |b: &mut TableBuilder, name: &str, on: bool, what: &str| b.push(name, Causality::Parameter, Variability::Tunable, Kind::Boolean { start: Some(on) }, what);
        let enable_friction = flag(&mut b, "enable_friction", enable.0, "Add the true friction torques");
        let enable_gravity = flag(&mut b, "enable_gravity", enable.1, "Add the true gravity torques");
        let text = format!("Ideal compensator: the true friction and gravity torques of a {n}-joint planar arm (neurarm)");
        let description = ModelDescription::new(identifier, text, b.finish())?;
        Ok(Self { description, arm, q, qd, friction, gravity, total, enable_friction, enable_gravity, angles: vec![0.0; n] })
    }

}

impl StaticModel for IdealCompensatorModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }

    fn compute(&mut self, values: &mut Values) {
        let use_friction = values.booleans[self.enable_friction as usize];
        let use_gravity = values.booleans[self.enable_gravity as usize];
        read(values, &self.q, &mut self.angles);
        let g = if use_gravity { Some(gravity_torques(&self.arm, &self.angles)) } else { None };
        for i in 0..self.q.len() {
            let f = if use_friction { self.arm.friction[i].torque(values.reals[self.qd[i] as usize]) } else { 0.0 };
            let gi = g.as_ref().map_or(0.0, |g| g[i]);
            values.reals[self.friction[i] as usize] = f;
            values.reals[self.gravity[i] as usize] = gi;
            values.reals[self.total[i] as usize] = f + gi;
        }
    }
}

/// Equations of the task-space controller, for `documentation/index.html`.
pub const TASK_SPACE_HTML: &str = "<p>Reference (centre c = (centre_x, centre_y)): \
<code>x_d(t) = c + (0.2 (cos t + sin 2t), 0.15 (sin t + cos 2t))</code> [m].</p>\
<p><code>u = J# (ẍ_d + K_d (ẋ_d − ẋ) + K_p (x_d − x) − J̇q̇) − k_null (I − J#J) q̇</code>, with J# the Moore–Penrose pseudo-inverse \
(Jᵀ(JJᵀ)⁻¹ away from singular poses; at a singular pose the direction J has lost gets no acceleration); the last term damps the self-motion of the redundant joints, which the task does not fix.</p>\
<p><code>τ = Ĥ(q) u + Ĉ(q, q̇) q̇ + ĝ(q) + tau_comp</code>, Ĥ, Ĉ, ĝ from the controller's own arm model \
(in resources/neurarm.toml). Non-finite inputs fail the step with fmi2Error.</p>";

/// Equations of the joint controller, for `documentation/index.html`.
pub const JOINT_HTML: &str = "<p><code>τ_i = tau_comp_i + kp_i (q_d,i − q_i) + kd_i (q̇_d,i − q̇_i)</code>; \
the paper's law has kd = 0 and gravity compensation as tau_comp. With use_sequence the targets follow a \
built-in sequence of 5 segments of 3 s (q̇_d = 0); otherwise the inputs q_ref_i, qd_ref_i.</p>";

/// Equations of the ideal compensator, for `documentation/index.html`.
pub const IDEAL_HTML: &str = "<p><code>tau_friction_i = f_i(qd_i)</code> (the arm's own friction law, 0 at rest), \
<code>tau_gravity = g(q)</code> (the arm's gravity torques), <code>tau_comp_i</code> their enabled sum.</p>";
