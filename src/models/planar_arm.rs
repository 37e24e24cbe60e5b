//! The `PlanarArm` FMU: the arm of [`crate::arm`] behind the FMI layer.
//!
//! Inputs: joint torques `tau_i` [N·m]. Outputs: joint angles `q_i` [rad] and velocities
//! `qd_i` [rad/s], end-effector position `x`, `y` [m] and velocity `xd`, `yd` [m/s], and the
//! measured angles and velocities `q_meas_i`, `qd_meas_i` (equal to the true ones unless
//! hardware-like effects are on). Parameters: every field of [`ArmConfig`], one table below
//! ([`JOINT_PARAMETERS`], [`ARM_PARAMETERS`]), plus the initial state `q0_i`, `qd0_i`.

use crate::arm::{end_effector_state, ArmSimulator, ArmState, FrictionBranch, Sensors};
use crate::config::ArmConfig;
use crate::fmi2::codec::{Put, Reader};
use crate::fmi2::description::{Causality, Kind, ModelDescription, TableBuilder, Variability};
use crate::fmi2::model::{Model, Values};

/// A real parameter of one joint: FMU name prefix (the variable is `{name}_{i}`), unit,
/// description, and how it maps to and from the configuration.
pub struct JointParameter {
    /// Name prefix.
    pub name: &'static str,
    /// Unit.
    pub unit: &'static str,
    /// Description; `{}` is replaced by the joint number.
    pub description: &'static str,
    get: fn(&ArmConfig, usize) -> f64,
    set: fn(&mut ArmConfig, usize, f64),
}

/// A real parameter of the whole arm.
pub struct ArmParameter {
    /// Name.
    pub name: &'static str,
    /// Unit.
    pub unit: &'static str,
    /// Description.
    pub description: &'static str,
    get: fn(&ArmConfig) -> f64,
    set: fn(&mut ArmConfig, f64),
}

fn branch(c: &mut ArmConfig, i: usize, positive: bool) -> &mut FrictionBranch {
    let f = &mut c.arm.friction[i];
    if positive {
        &mut f.positive
    } else {
        &mut f.negative
    }
}

fn branch_ref(c: &ArmConfig, i: usize, positive: bool) -> &FrictionBranch {
    let f = &c.arm.friction[i];
    if positive {
        &f.positive
    } else {
        &f.negative
    }
}

/// A per-joint optional list where 0 means "off" for that joint (torque limit, encoder).
fn optional_entry(list: &Option<Vec<f64>>, i: usize) -> f64 {
    list.as_ref().map_or(0.0, |l| l[i])
}

fn set_optional_entry(list: &mut Option<Vec<f64>>, n: usize, i: usize, v: f64) {
    let l = list.get_or_insert_with(|| vec![0.0; n]);
    l[i] = v;
    if l.iter().all(|&x| x == 0.0) {
        *list = None;
    }
}

/// A friction parameter: one field of one direction's branch.
macro_rules! friction {
    ($name:literal, $unit:literal, $desc:literal, $positive:expr, $field:ident) => {
        JointParameter {
            name: $name,
            unit: $unit,
            description: $desc,
            get: |c, i| branch_ref(c, i, $positive).$field,
            set: |c, i, v| branch(c, i, $positive).$field = v,
        }
    };
}

/// The viscous fall-off of one direction: 0 in the FMU stands for "linear" (`None`).
macro_rules! falloff {
    ($name:literal, $desc:literal, $positive:expr) => {
        JointParameter {
            name: $name,
            unit: "rad/s",
            description: $desc,
            get: |c, i| branch_ref(c, i, $positive).viscous_falloff_rad_s.unwrap_or(0.0),
            set: |c, i, v| branch(c, i, $positive).viscous_falloff_rad_s = (v != 0.0).then_some(v),
        }
    };
}

/// A per-joint entry of an optional hardware list, 0 standing for "off" for that joint.
macro_rules! hardware_entry {
    ($name:literal, $unit:literal, $desc:literal, $field:ident) => {
        JointParameter {
            name: $name,
            unit: $unit,
            description: $desc,
            get: |c, i| optional_entry(&c.hardware.$field, i),
            set: |c, i, v| {
                let n = c.arm.links.len();
                set_optional_entry(&mut c.hardware.$field, n, i, v)
            },
        }
    };
}

/// Parameters of each joint, in table order; the FMU variable of joint i is `{name}_{i}`.
pub const JOINT_PARAMETERS: [JointParameter; 16] = [
    JointParameter { name: "length", unit: "m", description: "Length of link {}", get: |c, i| c.arm.links[i].length_m, set: |c, i, v| c.arm.links[i].length_m = v },
    JointParameter { name: "mass", unit: "kg", description: "Mass of link {}", get: |c, i| c.arm.links[i].mass_kg, set: |c, i, v| c.arm.links[i].mass_kg = v },
    JointParameter {
        name: "com",
        unit: "m",
        description: "Distance from joint {} to the centre of mass of its link",
        get: |c, i| c.arm.links[i].com_m,
        set: |c, i, v| c.arm.links[i].com_m = v,
    },
    JointParameter {
        name: "inertia",
        unit: "kg.m2",
        description: "Moment of inertia of link {} about its centre of mass",
        get: |c, i| c.arm.links[i].inertia_kgm2,
        set: |c, i, v| c.arm.links[i].inertia_kgm2 = v,
    },
    friction!("coulomb_pos", "N.m", "Coulomb friction of joint {}, positive velocity", true, coulomb_nm),
    friction!("static_pos", "N.m", "Static (breakaway) friction of joint {}, positive velocity", true, static_nm),
    friction!("stribeck_velocity_pos", "rad/s", "Stribeck velocity of joint {}, positive velocity", true, stribeck_velocity_rad_s),
    friction!("viscous_pos", "N.m.s/rad", "Viscous friction coefficient of joint {} at low speed, positive velocity", true, viscous_nms_rad),
    falloff!("viscous_falloff_pos", "Speed at which the viscous slope of joint {} has halved, positive velocity (0: linear)", true),
    friction!("coulomb_neg", "N.m", "Coulomb friction of joint {}, negative velocity (magnitude)", false, coulomb_nm),
    friction!("static_neg", "N.m", "Static (breakaway) friction of joint {}, negative velocity (magnitude)", false, static_nm),
    friction!("stribeck_velocity_neg", "rad/s", "Stribeck velocity of joint {}, negative velocity", false, stribeck_velocity_rad_s),
    friction!("viscous_neg", "N.m.s/rad", "Viscous friction coefficient of joint {} at low speed, negative velocity", false, viscous_nms_rad),
    falloff!("viscous_falloff_neg", "Speed at which the viscous slope of joint {} has halved, negative velocity (0: linear)", false),
    hardware_entry!("torque_limit", "N.m", "Largest torque motor {} can apply (0: no limit)", torque_limit_nm),
    hardware_entry!("encoder_counts", "", "Encoder counts per revolution of joint {} (0: exact angles)", encoder_counts_per_rev),
];

/// Parameters of the whole arm, in table order.
pub const ARM_PARAMETERS: [ArmParameter; 5] = [
    ArmParameter { name: "gravity", unit: "m/s2", description: "Magnitude of gravitational acceleration", get: |c| c.arm.gravity_m_s2, set: |c, v| c.arm.gravity_m_s2 = v },
    ArmParameter {
        name: "base_angle",
        unit: "rad",
        description: "Tilt of the arm's plane: 0 horizontal (no gravity torque), pi/2 vertical (gravity along -y)",
        get: |c| c.arm.base_angle_rad,
        set: |c, v| c.arm.base_angle_rad = v,
    },
    ArmParameter { name: "internal_step", unit: "s", description: "Longest RK4 sub-step inside a communication step", get: |c| c.integrator.internal_step_s, set: |c, v| c.integrator.internal_step_s = v },
    ArmParameter { name: "q_noise_std", unit: "rad", description: "Standard deviation of the noise on measured angles", get: |c| c.hardware.q_noise_std_rad, set: |c, v| c.hardware.q_noise_std_rad = v },
    ArmParameter {
        name: "qd_noise_std",
        unit: "rad/s",
        description: "Standard deviation of the noise on measured velocities",
        get: |c| c.hardware.qd_noise_std_rad_s,
        set: |c, v| c.hardware.qd_noise_std_rad_s = v,
    },
];

/// Value references of the arm's variables.
#[derive(Clone, Debug)]
struct Layout {
    tau: Vec<u32>,
    q: Vec<u32>,
    qd: Vec<u32>,
    ee: [u32; 4],
    q_meas: Vec<u32>,
    qd_meas: Vec<u32>,
    /// `joint_params[p][i]`: parameter p of joint i.
    joint_params: Vec<Vec<u32>>,
    q0: Vec<u32>,
    qd0: Vec<u32>,
    arm_params: Vec<u32>,
    seed: u32,
}

/// The FMU's variable table and layout for `config`, an arm of n joints.
fn table(identifier: &str, config: &ArmConfig, initial: &ArmState) -> Result<(ModelDescription, Layout), String> {
    let n = config.arm.dof();
    let seed = i32::try_from(config.hardware.seed).map_err(|_| format!("noise seed {} does not fit an FMI Integer", config.hardware.seed))?;
    let mut b = TableBuilder::new();
    let joints = |f: &mut dyn FnMut(usize) -> u32| (0..n).map(f).collect::<Vec<u32>>();
    let tau = joints(&mut |i| b.input(format!("tau_{}", i + 1), "N.m", 0.0, format!("Torque command of joint {}", i + 1)));
    let q = joints(&mut |i| b.output(format!("q_{}", i + 1), "rad", format!("Angle of joint {} relative to link {}", i + 1, i), &[]));
    let qd = joints(&mut |i| b.output(format!("qd_{}", i + 1), "rad/s", format!("Velocity of joint {}", i + 1), &[]));
    let ee = [
        b.output("x", "m", "End-effector position, x", &[]),
        b.output("y", "m", "End-effector position, y", &[]),
        b.output("xd", "m/s", "End-effector velocity, x", &[]),
        b.output("yd", "m/s", "End-effector velocity, y", &[]),
    ];
    let q_meas = joints(&mut |i| b.output(format!("q_meas_{}", i + 1), "rad", format!("Measured angle of joint {} (encoder, noise)", i + 1), &[]));
    let qd_meas = joints(&mut |i| b.output(format!("qd_meas_{}", i + 1), "rad/s", format!("Measured velocity of joint {} (noise)", i + 1), &[]));
    let joint_params = JOINT_PARAMETERS
        .iter()
        .map(|p| {
            (0..n)
                .map(|i| b.parameter(format!("{}_{}", p.name, i + 1), p.unit, (p.get)(config, i), p.description.replace("{}", &(i + 1).to_string())))
                .collect()
        })
        .collect();
    let q0 = joints(&mut |i| b.parameter(format!("q0_{}", i + 1), "rad", initial.q[i], format!("Initial angle of joint {}", i + 1)));
    let qd0 = joints(&mut |i| b.parameter(format!("qd0_{}", i + 1), "rad/s", initial.qd[i], format!("Initial velocity of joint {}", i + 1)));
    let arm_params = ARM_PARAMETERS.iter().map(|p| b.parameter(p.name, p.unit, (p.get)(config), p.description)).collect();
    let seed = b.push("noise_seed", Causality::Parameter, Variability::Fixed, Kind::Integer { start: Some(seed) }, "Seed of the measurement noise");
    let description = ModelDescription::new(identifier, format!("Planar {n}-R arm with joint friction (neurarm)"), b.finish())?;
    Ok((description, Layout { tau, q, qd, ee, q_meas, qd_meas, joint_params, q0, qd0, arm_params, seed }))
}

/// The arm model behind the FMU.
pub struct PlanarArmModel {
    description: ModelDescription,
    layout: Layout,
    /// The configuration the FMU was exported with: its shape (joint count) and start values.
    template: ArmConfig,
    running: Option<(ArmSimulator, Sensors)>,
    state: ArmState,
    tau: Vec<f64>,
    q_meas: Vec<f64>,
    qd_meas: Vec<f64>,
}

impl PlanarArmModel {
    /// The model for `config`, starting from `initial`, named `identifier`.
    pub fn new(identifier: &str, config: ArmConfig, initial: ArmState) -> Result<Self, String> {
        config.validate().map_err(|e| e.to_string())?;
        let n = config.arm.dof();
        if initial.q.len() != n || initial.qd.len() != n {
            return Err(format!("the initial state has {} angles and {} velocities for {n} joints", initial.q.len(), initial.qd.len()));
        }
        let (description, layout) = table(identifier, &config, &initial)?;
        Ok(Self { description, layout, template: config, running: None, state: initial, tau: vec![0.0; n], q_meas: vec![0.0; n], qd_meas: vec![0.0; n] })
    }

    /// The configuration in `values`, checked.
    fn config_from(&self, values: &Values) -> Result<(ArmConfig, ArmState), String> {
        let mut c = self.template.clone();
        let n = c.arm.dof();
        let read = |vrs: &[u32]| -> Vec<f64> { vrs.iter().map(|&vr| values.reals[vr as usize]).collect() };
        let initial = ArmState { q: read(&self.layout.q0), qd: read(&self.layout.qd0) };
        debug_assert_eq!(initial.q.len(), n);
        for (p, vrs) in JOINT_PARAMETERS.iter().zip(&self.layout.joint_params) {
            for (i, &vr) in vrs.iter().enumerate() {
                (p.set)(&mut c, i, values.reals[vr as usize]);
            }
        }
        for (p, &vr) in ARM_PARAMETERS.iter().zip(&self.layout.arm_params) {
            (p.set)(&mut c, values.reals[vr as usize]);
        }
        let seed = values.integers[self.layout.seed as usize];
        c.hardware.seed = u64::try_from(seed).map_err(|_| format!("noise_seed = {seed} must be >= 0"))?;
        // Name problems by the FMU's parameter names, not the configuration's fields.
        c.validate().map_err(|e| format!("invalid parameter: {e} (FMU names: length_i, mass_i, coulomb_pos_i, …; i from 1)"))?;
        Ok((c, initial))
    }

    fn write_outputs(&mut self, values: &mut Values) {
        let (_, sensors) = self.running.as_mut().expect("outputs are written only while running");
        let params = &self.template.arm;
        let l = &self.layout;
        for i in 0..self.state.q.len() {
            values.reals[l.q[i] as usize] = self.state.q[i];
            values.reals[l.qd[i] as usize] = self.state.qd[i];
        }
        for (vr, v) in l.ee.iter().zip(end_effector_state(params, &self.state.q, &self.state.qd)) {
            values.reals[*vr as usize] = v;
        }
        sensors.measure(&self.state, &mut self.q_meas, &mut self.qd_meas);
        for i in 0..self.state.q.len() {
            values.reals[l.q_meas[i] as usize] = self.q_meas[i];
            values.reals[l.qd_meas[i] as usize] = self.qd_meas[i];
        }
    }

    fn start(&mut self, values: &Values) -> Result<ArmState, String> {
        let (config, initial) = self.config_from(values)?;
        let (sim, sensors) = config.build().map_err(|e| e.to_string())?;
        self.template = config;
        self.running = Some((sim, sensors));
        Ok(initial)
    }
}

impl Model for PlanarArmModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }

    fn initialize(&mut self, values: &mut Values, _start_time: f64) -> Result<(), String> {
        self.state = self.start(values)?;
        if let Some((i, v)) = self.state.q.iter().chain(&self.state.qd).enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(format!("initial state entry {i} = {v} is not finite"));
        }
        self.write_outputs(values);
        Ok(())
    }

    fn do_step(&mut self, values: &mut Values, _time: f64, step: f64) -> Result<(), String> {
        for (t, &vr) in self.tau.iter_mut().zip(&self.layout.tau) {
            *t = values.reals[vr as usize];
        }
        let (sim, _) = self.running.as_mut().ok_or("the arm is not initialized")?;
        sim.step(&mut self.state, &self.tau, step).map_err(|e| e.to_string())?;
        if let Some(v) = self.state.q.iter().chain(&self.state.qd).find(|v| !v.is_finite()) {
            return Err(format!("the state became {v}: the torques or parameters drive the arm beyond what the integrator can follow"));
        }
        self.write_outputs(values);
        Ok(())
    }

    fn reset(&mut self) {
        self.running = None;
    }

    fn save_state(&self, out: &mut Vec<u8>) {
        out.put_u8(self.running.is_some() as u8);
        out.put_f64s(&self.state.q);
        out.put_f64s(&self.state.qd);
        let position = self.running.as_ref().map_or(0, |(_, s)| s.stream_position());
        out.put_u64(position as u64);
        out.put_u64((position >> 64) as u64);
    }

    fn load_state(&mut self, values: &Values, bytes: &[u8]) -> Result<(), String> {
        let n = self.state.q.len();
        let mut r = Reader::new(bytes);
        let running = r.u8()?;
        let q = r.f64s(n)?;
        let qd = r.f64s(n)?;
        let position = r.u64()? as u128 | (r.u64()? as u128) << 64;
        r.finish()?;
        match running {
            0 => self.running = None,
            1 => {
                self.start(values)?;
                if let Some((_, sensors)) = self.running.as_mut() {
                    sensors.set_stream_position(position);
                }
            }
            b => return Err(format!("invalid running flag {b}")),
        }
        self.state = ArmState { q, qd };
        Ok(())
    }
}

/// The equations, for the FMU's `documentation/index.html`.
pub const EQUATIONS_HTML: &str = "<p>Joint angles are relative: link i's absolute angle is \
θ<sub>i</sub> = q<sub>1</sub> + … + q<sub>i</sub>. The arm obeys</p>\
<p><code>H(q) q̈ + C(q, q̇) q̇ + g(q) + f(q̇) = τ</code></p>\
<p>with H the mass matrix, C q̇ the Coriolis and centrifugal torques, g the gravity torques of the \
in-plane gravity g·sin(base_angle) along −y, and f the joint friction, per direction of motion: \
<code>f(v) = sign(v)·(F<sub>c</sub> + (F<sub>s</sub> − F<sub>c</sub>) exp(−(v/v<sub>s</sub>)²) + \
b·v<sub>f</sub>·ln(1 + |v|/v<sub>f</sub>))</code> (linear b·|v| when v<sub>f</sub> = 0). A joint at rest \
stays at rest while the torque needed to hold it is below its static level (stick–slip). The state is \
integrated with fixed-step RK4, in equal sub-steps no longer than <code>internal_step</code> per \
communication step; torques are held constant over a communication step. Outputs: \
<code>x = Σ l<sub>i</sub> cos θ<sub>i</sub></code>, <code>y = Σ l<sub>i</sub> sin θ<sub>i</sub></code>, \
their time derivatives, and measured angles and velocities (quantised to the encoder resolution and \
with Gaussian noise when those parameters are non-zero).</p>";
