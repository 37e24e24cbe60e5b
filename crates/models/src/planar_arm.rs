//! The `PlanarArm` FMU: the arm of [`neurarm_physics::arm`] behind the FMI layer.
//!
//! Inputs: joint torques `tau_i` [N·m]. Outputs: joint angles `q_i` [rad] and velocities
//! `qd_i` [rad/s], end-effector position `x`, `y` [m] and velocity `xd`, `yd` [m/s], and the
//! measured angles and velocities `q_meas_i`, `qd_meas_i` (equal to the true ones unless
//! hardware-like effects are on). Parameters: every field of [`ArmConfig`], one table below
//! ([`JOINT_PARAMETERS`], [`ARM_PARAMETERS`]), plus the initial state `q0_i`, `qd0_i`.
//! Tunable, so a host can change them while the arm runs ([`DriftPorts`]): `coulomb_scale_i`,
//! `viscous_scale_i` (factors on joint i's friction) and a payload at the tip, `payload_mass`,
//! `payload_offset`; the next step runs with the changed arm.

use std::path::Path;

use neurarm_fmi_export::codec::{Put, Reader, StateError};
use neurarm_fmi_export::{Causality, IntegerVar, Model, ModelDescription, ModelError, RealVar, TableBuilder, Unit, Values, Variability};
use neurarm_physics::arm::{
    end_effector_state, ArmParams, ArmSimulator, ArmState, FrictionBranch, OperatingChange, ParamError, Sensors, StepError,
};
use neurarm_physics::config::ArmConfig;
use serde::{Deserialize, Serialize};

use crate::names::{self, joint};
use crate::ports::{drift_error, DriftPorts};
use crate::units::*;
use crate::{describe, BuildError, ModelKind};

/// Spec of a planar arm.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanarArmSpec {
    /// The arm's configuration: the parameters' start values.
    pub config: ArmConfig,
    /// Initial joint angles [rad].
    pub q0: Vec<f64>,
    /// Initial joint velocities [rad/s].
    pub qd0: Vec<f64>,
}

impl ModelKind for PlanarArmSpec {
    fn build(&self, identifier: &str, _resources: Option<&Path>) -> Result<Box<dyn Model>, BuildError> {
        let initial = ArmState { q: self.q0.clone(), qd: self.qd0.clone() };
        Ok(Box::new(PlanarArmModel::new(identifier, self.config.clone(), initial)?))
    }

    fn equations_html(&self) -> &'static str {
        EQUATIONS_HTML
    }
}

/// Why the arm cannot start or go on.
#[derive(Debug, thiserror::Error)]
pub enum ArmError {
    /// A parameter set through the FMU is out of range.
    #[error("invalid parameter: {0} (FMU names: length_i, mass_i, coulomb_pos_i, …; i from 1)")]
    Parameter(ParamError),
    /// The noise seed is negative.
    #[error("{} = {0} must be >= 0", names::NOISE_SEED)]
    NegativeSeed(i32),
    /// The initial state is not finite.
    #[error("initial state entry {index} = {value} is not finite")]
    InitialState {
        /// Position in q then qd.
        index: usize,
        /// The value.
        value: f64,
    },
    /// The integrator refused the step.
    #[error(transparent)]
    Step(#[from] StepError),
    /// The state left the finite numbers.
    #[error("the state became {0}: the torques or parameters drive the arm beyond what the integrator can follow")]
    Diverged(f64),
    /// A step before initialization.
    #[error("the arm is not initialized")]
    NotInitialized,
    /// A saved state with a bad flag.
    #[error(transparent)]
    State(#[from] StateError),
}

/// A real parameter of one joint: its family of [`names`] (the variable of joint i is
/// [`names::joint`]`(name, i)`), unit, description, and how it maps to and from the configuration.
pub struct JointParameter {
    /// Family name.
    pub name: &'static str,
    /// Unit, if any.
    pub unit: Option<Unit>,
    /// Description; `{}` is replaced by the joint number.
    pub description: &'static str,
    get: fn(&ArmConfig, usize) -> f64,
    set: fn(&mut ArmConfig, usize, f64),
}

/// A real parameter of the whole arm.
pub struct ArmParameter {
    /// Name, one of [`names`].
    pub name: &'static str,
    /// Unit, if any.
    pub unit: Option<Unit>,
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

/// A parameter of one link: one field of its [`LinkParams`](neurarm_physics::arm::LinkParams).
macro_rules! link {
    ($name:expr, $unit:expr, $desc:literal, $field:ident) => {
        JointParameter {
            name: $name,
            unit: Some($unit),
            description: $desc,
            get: |c, i| c.arm.links[i].$field,
            set: |c, i, v| c.arm.links[i].$field = v,
        }
    };
}

/// A friction parameter: one field of one direction's branch.
macro_rules! friction {
    ($name:expr, $unit:expr, $desc:literal, $positive:expr, $field:ident) => {
        JointParameter {
            name: $name,
            unit: Some($unit),
            description: $desc,
            get: |c, i| branch_ref(c, i, $positive).$field,
            set: |c, i, v| branch(c, i, $positive).$field = v,
        }
    };
}

/// The viscous fall-off of one direction: 0 in the FMU stands for "linear" (`None`).
macro_rules! falloff {
    ($name:expr, $desc:literal, $positive:expr) => {
        JointParameter {
            name: $name,
            unit: Some(RADIAN_PER_SECOND),
            description: $desc,
            get: |c, i| branch_ref(c, i, $positive).viscous_falloff_rad_s.unwrap_or(0.0),
            set: |c, i, v| branch(c, i, $positive).viscous_falloff_rad_s = (v != 0.0).then_some(v),
        }
    };
}

/// A per-joint entry of an optional hardware list, 0 standing for "off" for that joint.
macro_rules! hardware_entry {
    ($name:expr, $unit:expr, $desc:literal, $field:ident) => {
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

/// Parameters of each joint, in table order; the FMU variable of joint i is `{name}_{i}`
/// ([`names::joint`]).
pub const JOINT_PARAMETERS: [JointParameter; 16] = [
    link!(names::LENGTH, METRE, "Length of link {}", length_m),
    link!(names::MASS, KILOGRAM, "Mass of link {}", mass_kg),
    link!(names::CENTRE_OF_MASS, METRE, "Distance from joint {} to the centre of mass of its link", com_m),
    link!(names::INERTIA, KILOGRAM_METRE_SQUARED, "Moment of inertia of link {} about its centre of mass", inertia_kgm2),
    friction!(names::COULOMB_POS, NEWTON_METRE, "Coulomb friction of joint {}, positive velocity", true, coulomb_nm),
    friction!(names::STATIC_POS, NEWTON_METRE, "Static (breakaway) friction of joint {}, positive velocity", true, static_nm),
    friction!(
        names::STRIBECK_VELOCITY_POS,
        RADIAN_PER_SECOND,
        "Stribeck velocity of joint {}, positive velocity",
        true,
        stribeck_velocity_rad_s
    ),
    friction!(
        names::VISCOUS_POS,
        NEWTON_METRE_SECOND_PER_RADIAN,
        "Viscous friction coefficient of joint {} at low speed, positive velocity",
        true,
        viscous_nms_rad
    ),
    falloff!(names::VISCOUS_FALLOFF_POS, "Speed at which the viscous slope of joint {} has halved, positive velocity (0: linear)", true),
    friction!(names::COULOMB_NEG, NEWTON_METRE, "Coulomb friction of joint {}, negative velocity (magnitude)", false, coulomb_nm),
    friction!(names::STATIC_NEG, NEWTON_METRE, "Static (breakaway) friction of joint {}, negative velocity (magnitude)", false, static_nm),
    friction!(
        names::STRIBECK_VELOCITY_NEG,
        RADIAN_PER_SECOND,
        "Stribeck velocity of joint {}, negative velocity",
        false,
        stribeck_velocity_rad_s
    ),
    friction!(
        names::VISCOUS_NEG,
        NEWTON_METRE_SECOND_PER_RADIAN,
        "Viscous friction coefficient of joint {} at low speed, negative velocity",
        false,
        viscous_nms_rad
    ),
    falloff!(names::VISCOUS_FALLOFF_NEG, "Speed at which the viscous slope of joint {} has halved, negative velocity (0: linear)", false),
    hardware_entry!(names::TORQUE_LIMIT, Some(NEWTON_METRE), "Largest torque motor {} can apply (0: no limit)", torque_limit_nm),
    hardware_entry!(names::ENCODER_COUNTS, None, "Encoder counts per revolution of joint {} (0: exact angles)", encoder_counts_per_rev),
];

/// A parameter of the whole arm: one field of the configuration.
macro_rules! arm {
    ($name:expr, $unit:expr, $desc:literal, $($field:ident).+) => {
        ArmParameter { name: $name, unit: Some($unit), description: $desc, get: |c| c.$($field).+, set: |c, v| c.$($field).+ = v }
    };
}

/// Parameters of the whole arm, in table order.
pub const ARM_PARAMETERS: [ArmParameter; 5] = [
    arm!(names::GRAVITY, METRE_PER_SECOND_SQUARED, "Magnitude of gravitational acceleration", arm.gravity_m_s2),
    arm!(
        names::BASE_ANGLE,
        RADIAN,
        "Tilt of the arm's plane: 0 horizontal (no gravity torque), pi/2 vertical (gravity along -y)",
        arm.base_angle_rad
    ),
    arm!(names::INTERNAL_STEP, Unit::SECOND, "Longest RK4 sub-step inside a communication step", integrator.internal_step_s),
    arm!(names::ANGLE_NOISE_STD, RADIAN, "Standard deviation of the noise on measured angles", hardware.q_noise_std_rad),
    arm!(
        names::VELOCITY_NOISE_STD,
        RADIAN_PER_SECOND,
        "Standard deviation of the noise on measured velocities",
        hardware.qd_noise_std_rad_s
    ),
];

/// Value references of the arm's variables.
#[derive(Clone, Debug)]
struct Layout {
    tau: Vec<RealVar>,
    q: Vec<RealVar>,
    qd: Vec<RealVar>,
    ee: [RealVar; 4],
    q_meas: Vec<RealVar>,
    qd_meas: Vec<RealVar>,
    /// `joint_params[p][i]`: parameter p of joint i.
    joint_params: Vec<Vec<RealVar>>,
    q0: Vec<RealVar>,
    qd0: Vec<RealVar>,
    arm_params: Vec<RealVar>,
    seed: IntegerVar,
    drift: DriftPorts,
}

/// The FMU's variable table and layout for `config`, an arm of n joints.
fn table(identifier: &str, config: &ArmConfig, initial: &ArmState) -> Result<(ModelDescription, Layout), BuildError> {
    let n = config.arm.dof();
    let seed = i32::try_from(config.hardware.seed)
        .map_err(|_| BuildError::Spec(format!("noise seed {} does not fit an FMI Integer", config.hardware.seed)))?;
    let mut b = TableBuilder::new();
    let joints = |f: &mut dyn FnMut(usize) -> RealVar| (0..n).map(f).collect::<Vec<RealVar>>();
    let tau = joints(&mut |i| b.input(joint(names::TORQUE, i + 1), NEWTON_METRE, 0.0, format!("Torque command of joint {}", i + 1)));
    let q = joints(&mut |i| b.output(joint(names::ANGLE, i + 1), RADIAN, format!("Angle of joint {} relative to link {}", i + 1, i), &[]));
    let qd = joints(&mut |i| b.output(joint(names::VELOCITY, i + 1), RADIAN_PER_SECOND, format!("Velocity of joint {}", i + 1), &[]));
    let ee = [
        b.output(names::END_EFFECTOR_X, METRE, "End-effector position, x", &[]),
        b.output(names::END_EFFECTOR_Y, METRE, "End-effector position, y", &[]),
        b.output(names::END_EFFECTOR_XD, METRE_PER_SECOND, "End-effector velocity, x", &[]),
        b.output(names::END_EFFECTOR_YD, METRE_PER_SECOND, "End-effector velocity, y", &[]),
    ];
    let q_meas = joints(&mut |i| {
        b.output(joint(names::MEASURED_ANGLE, i + 1), RADIAN, format!("Measured angle of joint {} (encoder, noise)", i + 1), &[])
    });
    let qd_meas = joints(&mut |i| {
        b.output(joint(names::MEASURED_VELOCITY, i + 1), RADIAN_PER_SECOND, format!("Measured velocity of joint {} (noise)", i + 1), &[])
    });
    let joint_params = JOINT_PARAMETERS
        .iter()
        .map(|p| {
            (0..n)
                .map(|i| b.parameter(joint(p.name, i + 1), p.unit, (p.get)(config, i), p.description.replace("{}", &(i + 1).to_string())))
                .collect()
        })
        .collect();
    let q0 =
        joints(&mut |i| b.parameter(joint(names::START_ANGLE, i + 1), RADIAN, initial.q[i], format!("Initial angle of joint {}", i + 1)));
    let qd0 = joints(&mut |i| {
        b.parameter(joint(names::START_VELOCITY, i + 1), RADIAN_PER_SECOND, initial.qd[i], format!("Initial velocity of joint {}", i + 1))
    });
    let arm_params = ARM_PARAMETERS.iter().map(|p| b.parameter(p.name, p.unit, (p.get)(config), p.description)).collect();
    let seed = b.integer(names::NOISE_SEED, Causality::Parameter, Variability::Fixed, Some(seed), "Seed of the measurement noise");
    let drift = DriftPorts::declare(&mut b, n);
    let description = describe(identifier, format!("Planar {n}-R arm with joint friction (neurarm)"), b.finish())?;
    Ok((description, Layout { tau, q, qd, ee, q_meas, qd_meas, joint_params, q0, qd0, arm_params, seed, drift }))
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
    /// The drift the simulator runs with (tunable parameters), and whether it was applied.
    change: OperatingChange,
    change_applied: bool,
    /// The configured arm changed by `change`: scratch, so a ramp allocates nothing.
    changed: ArmParams,
}

impl PlanarArmModel {
    /// The model for `config`, starting from `initial`, named `identifier`.
    pub fn new(identifier: &str, config: ArmConfig, initial: ArmState) -> Result<Self, BuildError> {
        config.validate()?;
        let n = config.arm.dof();
        if initial.q.len() != n || initial.qd.len() != n {
            return Err(BuildError::Spec(format!(
                "the initial state has {} angles and {} velocities for {n} joints",
                initial.q.len(),
                initial.qd.len()
            )));
        }
        let (description, layout) = table(identifier, &config, &initial)?;
        let changed = config.arm.clone();
        Ok(Self {
            change: OperatingChange::none(n),
            change_applied: true,
            changed,
            description,
            layout,
            template: config,
            running: None,
            state: initial,
            tau: vec![0.0; n],
            q_meas: vec![0.0; n],
            qd_meas: vec![0.0; n],
        })
    }

    /// The configuration in `values`, checked.
    fn config_from(&self, values: &Values) -> Result<(ArmConfig, ArmState), ArmError> {
        let mut c = self.template.clone();
        let n = c.arm.dof();
        let read = |vars: &[RealVar]| -> Vec<f64> { vars.iter().map(|&v| values[v]).collect() };
        let initial = ArmState { q: read(&self.layout.q0), qd: read(&self.layout.qd0) };
        debug_assert_eq!(initial.q.len(), n);
        for (p, vars) in JOINT_PARAMETERS.iter().zip(&self.layout.joint_params) {
            for (i, &v) in vars.iter().enumerate() {
                (p.set)(&mut c, i, values[v]);
            }
        }
        for (p, &v) in ARM_PARAMETERS.iter().zip(&self.layout.arm_params) {
            (p.set)(&mut c, values[v]);
        }
        let seed = values[self.layout.seed];
        c.hardware.seed = u64::try_from(seed).map_err(|_| ArmError::NegativeSeed(seed))?;
        // Name problems by the FMU's parameter names, not the configuration's fields.
        c.validate().map_err(ArmError::Parameter)?;
        Ok((c, initial))
    }

    fn write_outputs(&mut self, values: &mut Values) {
        let (_, sensors) = self.running.as_mut().expect("outputs are written only while running");
        let params = &self.template.arm;
        let l = &self.layout;
        values.write_reals(&l.q, &self.state.q);
        values.write_reals(&l.qd, &self.state.qd);
        values.write_reals(&l.ee, &end_effector_state(params, &self.state.q, &self.state.qd));
        sensors.measure(&self.state, &mut self.q_meas, &mut self.qd_meas);
        values.write_reals(&l.q_meas, &self.q_meas);
        values.write_reals(&l.qd_meas, &self.qd_meas);
    }

    fn start(&mut self, values: &Values) -> Result<ArmState, ArmError> {
        let (config, initial) = self.config_from(values)?;
        let (sim, sensors) = config.build().map_err(ArmError::Parameter)?;
        self.template = config;
        self.running = Some((sim, sensors));
        self.change = OperatingChange::none(self.state.q.len());
        self.change_applied = true;
        Ok(initial)
    }

    /// Follows the tunable drift parameters: when they changed since the last step (or were
    /// refused then), the simulator gets the configured arm changed by them. Allocates nothing.
    fn follow_drift(&mut self, values: &Values) -> Result<(), ModelError> {
        let changed = self.layout.drift.read(values, &mut self.change);
        if !changed && self.change_applied {
            return Ok(());
        }
        let (sim, _) = self.running.as_mut().ok_or(ArmError::NotInitialized)?;
        self.change_applied = false;
        self.change
            .apply_into(&self.template.arm, &mut self.changed)
            .map_err(|e| ModelError::msg(format!("the arm cannot take the change: {}", drift_error(&e))))?;
        sim.set_params(&self.changed).map_err(ArmError::Parameter)?;
        self.change_applied = true;
        Ok(())
    }
}

impl Model for PlanarArmModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }

    fn initialize(&mut self, values: &mut Values, _start_time: f64) -> Result<(), ModelError> {
        self.state = self.start(values)?;
        self.follow_drift(values)?;
        if let Some((index, &value)) = self.state.q.iter().chain(&self.state.qd).enumerate().find(|(_, v)| !v.is_finite()) {
            return Err(ArmError::InitialState { index, value }.into());
        }
        self.write_outputs(values);
        Ok(())
    }

    fn do_step(&mut self, values: &mut Values, _time: f64, step: f64) -> Result<(), ModelError> {
        values.read_reals(&self.layout.tau, &mut self.tau);
        self.follow_drift(values)?;
        let (sim, _) = self.running.as_mut().ok_or(ArmError::NotInitialized)?;
        sim.step(&mut self.state, &self.tau, step).map_err(ArmError::from)?;
        if let Some(&v) = self.state.q.iter().chain(&self.state.qd).find(|v| !v.is_finite()) {
            return Err(ArmError::Diverged(v).into());
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

    fn load_state(&mut self, values: &Values, bytes: &[u8]) -> Result<(), ModelError> {
        let n = self.state.q.len();
        let mut r = Reader::new(bytes);
        let running = r.u8()?;
        let q = r.finite_f64s("q", n)?;
        let qd = r.finite_f64s("qd", n)?;
        let position = r.u64()? as u128 | (r.u64()? as u128) << 64;
        r.finish()?;
        match running {
            0 => self.running = None,
            1 => {
                self.start(values)?;
                self.follow_drift(values)?;
                if let Some((_, sensors)) = self.running.as_mut() {
                    sensors.set_stream_position(position);
                }
            }
            b => return Err(ArmError::State(StateError::Invalid(format!("invalid running flag {b}"))).into()),
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
with Gaussian noise when those parameters are non-zero).</p>\
<p>Drift while running (tunable): joint i's Coulomb and static levels are multiplied by \
<code>coulomb_scale_i</code> and its viscous coefficient by <code>viscous_scale_i</code>; a point mass \
<code>payload_mass</code> at <code>payload_offset</code> beyond the tip joins the last link (mass, centre of \
mass and inertia combined). A change takes effect from the next step.</p>";
