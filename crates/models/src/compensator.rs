//! The `NnCompensator` FMU: the paper's learned compensating torques as a block.
//!
//! Ports as every compensator ([`CompensatorPorts`]): joint i's friction part is joint i's
//! friction net of `qd_i`; the gravity part is output i of the gravity net of all angles. A
//! periodic gravity net (angles encoded on the circle) takes the angles as they come; a raw
//! one (the paper's) gets each angle wrapped into the turn [min, min + 2π) of its training
//! data, as gravity is 2π-periodic. A disabled part's outputs are 0. The block is static: outputs follow the
//! inputs at once (direct feedthrough), steps change nothing.

use std::path::Path;

use neurarm_fmi_export::{Model, ModelDescription, ModelError, StaticModel, TableBuilder, Values};
use neurarm_nn::{EncodedNet, InputEncoding, NetKind, Signal, WeightsFile};
use serde::{Deserialize, Serialize};

use crate::names;
use crate::ports::{CompensatorPorts, Parts};
use crate::{describe, BuildError, ModelKind};

/// Spec of an NN compensator; its weights files live beside the spec in `resources/`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NnCompensatorSpec {
    /// Number of joints.
    pub joints: usize,
    /// File of each joint's friction net, in order; empty for no friction part.
    pub friction: Vec<String>,
    /// File of the gravity net, if any.
    pub gravity: Option<String>,
    /// Start value of the `enable_friction` parameter.
    pub enable_friction: bool,
    /// Start value of the `enable_gravity` parameter.
    pub enable_gravity: bool,
}

impl NnCompensatorSpec {
    /// A compensator of `joints` joints from its nets' files in `resources/`: `friction` one per
    /// joint in joint order (empty: no friction part) and `gravity`; each part given is switched
    /// on, and only those.
    pub fn of_nets(joints: usize, friction: Vec<String>, gravity: Option<String>) -> Self {
        Self { joints, enable_friction: !friction.is_empty(), enable_gravity: gravity.is_some(), friction, gravity }
    }

    /// The adaptive compensator of the same nets and switches, learning by `law`.
    pub fn adaptive(self, law: crate::AdaptationLaw) -> crate::AdaptiveCompensatorSpec {
        let Self { joints, friction, gravity, enable_friction, enable_gravity } = self;
        crate::AdaptiveCompensatorSpec { joints, friction, gravity, enable_friction, enable_gravity, law }
    }
}

impl ModelKind for NnCompensatorSpec {
    fn build(&self, identifier: &str, resources: Option<&Path>) -> Result<Box<dyn Model>, BuildError> {
        check_switches((self.enable_friction, self.enable_gravity), &self.friction, self.gravity.as_deref())?;
        let (friction, gravity, crc) = load_nets(resources, self.joints, &self.friction, self.gravity.as_deref())?;
        let enable = (self.enable_friction, self.enable_gravity);
        Ok(Box::new(NnCompensatorModel::new(identifier, self.joints, &friction, gravity.as_ref(), enable, crc)?))
    }

    fn resource_files(&self) -> Vec<String> {
        self.friction.iter().chain(&self.gravity).cloned().collect()
    }

    fn equations_html(&self) -> &'static str {
        EQUATIONS_HTML
    }
}

/// Refuses a part switched on (`enable` = friction, gravity) that the spec gives no nets for:
/// it would add nothing while saying it does.
pub(crate) fn check_switches(enable: (bool, bool), friction: &[String], gravity: Option<&str>) -> Result<(), BuildError> {
    if enable.0 && friction.is_empty() {
        return Err(BuildError::Spec(
            "enable_friction = true, but friction = [] names no friction nets: list one weights file per joint, or set enable_friction = false".into(),
        ));
    }
    if enable.1 && gravity.is_none() {
        return Err(BuildError::Spec(
            "enable_gravity = true, but no gravity net is named: give gravity = \"<weights file>\", or set enable_gravity = false".into(),
        ));
    }
    Ok(())
}

/// Reads a compensator's weights files (`friction` in joint order, `gravity`) from
/// `resources` and checks that they fit together ([`check_compensator_nets`]), naming a bad
/// file; returns the nets and the CRC-32 of their text, for the model description.
pub(crate) fn load_nets(
    resources: Option<&Path>,
    joints: usize,
    friction: &[String],
    gravity: Option<&str>,
) -> Result<(Vec<WeightsFile>, Option<WeightsFile>, u32), BuildError> {
    let dir = resources.ok_or(BuildError::NoResources)?;
    neurarm_physics::arm::check_joint_count(joints)?;
    if friction.len() > joints {
        return Err(BuildError::Spec(format!("{} friction nets for {joints} joints", friction.len())));
    }
    let mut crc = crc32fast::Hasher::new();
    let mut load = |name: &str| -> Result<WeightsFile, BuildError> {
        let path = crate::resource_file(dir, name)?;
        let text = neurarm_physics::text_file::read_text(&path, neurarm_nn::read_limits::FILE_BYTES)
            .map_err(|e| BuildError::Weights { path: path.clone(), message: e.to_string() })?;
        crc.update(text.as_bytes());
        WeightsFile::from_json(&text, &path.display().to_string()).map_err(|e| BuildError::Spec(e.to_string()))
    };
    let friction_nets = friction.iter().map(|f| load(f)).collect::<Result<Vec<_>, _>>()?;
    let gravity_net = gravity.map(&mut load).transpose()?;
    // Named by their resource files, so a refusal says which file is wrong.
    let named: Vec<(&str, &WeightsFile)> = friction.iter().map(String::as_str).zip(&friction_nets).collect();
    check_compensator_nets(&named, gravity.zip(gravity_net.as_ref()))?;
    Ok((friction_nets, gravity_net, crc.finalize()))
}

/// Why nets do not fit together as a compensator ([`check_compensator_nets`]); each names the
/// net by the name it was given with (its file).
#[derive(Debug, thiserror::Error)]
pub enum NetsError {
    /// A net whose weights do not make a network.
    #[error("{name}: {reason}")]
    Invalid {
        /// The net's name.
        name: String,
        /// What is wrong with it.
        reason: String,
    },
    /// Two friction nets with the same weights.
    #[error("{name} and {other} hold the same net: give each joint its own friction net")]
    SameFrictionNet {
        /// The later net.
        name: String,
        /// The earlier net with the same weights.
        other: String,
    },
    /// The gravity net is also given as a friction net.
    #[error("{name} and {other} hold the same net")]
    GravityAlsoFriction {
        /// The gravity net.
        name: String,
        /// The friction net with the same weights.
        other: String,
    },
    /// A gravity net given as a friction net.
    #[error("{name} is a gravity net, given as the friction net of joint {joint}")]
    GravityAsFriction {
        /// The net's name.
        name: String,
        /// The joint it was given for (1-based).
        joint: usize,
    },
    /// A friction net given out of joint order.
    #[error("{name} is the friction net of joint {claimed} (by its {by}), given as net {joint} of {count}: give them in joint order (given: {order})")]
    JointOrder {
        /// The net's name.
        name: String,
        /// The joint the net says it is for (1-based).
        claimed: usize,
        /// What says so: its recorded joint or its input's name.
        by: &'static str,
        /// Its place in the list (1-based).
        joint: usize,
        /// How many friction nets were given.
        count: usize,
        /// The names given, in order.
        order: String,
    },
    /// A friction net given as the gravity net.
    #[error("{name} is the {described}, given as the gravity net")]
    FrictionAsGravity {
        /// The net's name.
        name: String,
        /// What the net is.
        described: String,
    },
    /// A gravity net without one torque output per angle input.
    #[error("{name}: a gravity net has one torque output per angle input, not {inputs} inputs and {outputs} outputs")]
    GravityShape {
        /// The net's name.
        name: String,
        /// Its inputs.
        inputs: usize,
        /// Its outputs.
        outputs: usize,
    },
    /// Friction nets for another joint count than the gravity net's.
    #[error("{friction} friction nets but the gravity net {name} is for {joints} joints: give one friction net per joint")]
    JointCount {
        /// The friction nets given.
        friction: usize,
        /// The gravity net's name.
        name: String,
        /// The gravity net's joints.
        joints: usize,
    },
    /// A recorded unit other than the compensator's.
    #[error("{name}: {what} '{signal}' is in {unit}, the compensator works in {expected}")]
    Unit {
        /// The net's name.
        name: String,
        /// "input" or "output".
        what: &'static str,
        /// The signal's name.
        signal: String,
        /// Its recorded unit.
        unit: String,
        /// The unit the compensator works in.
        expected: &'static str,
    },
    /// No net at all.
    #[error("give friction nets, a gravity net, or both")]
    NoNets,
}

/// Checks that the nets fit together as a compensator and returns its joint count: each
/// friction net in its place (the file's recorded kind and joint, or for a net of unspecified
/// kind an input named `qd_J`, must say joint i for the i-th net), no net given twice, a gravity
/// net that is one, recorded units that are the compensator's (rad, rad/s, N·m; an empty unit
/// is not checked), and as many friction nets as the gravity net has angles. Each net comes
/// with the name messages use for it (its file).
pub fn check_compensator_nets(friction: &[(&str, &WeightsFile)], gravity: Option<(&str, &WeightsFile)>) -> Result<usize, NetsError> {
    for (place, (name, file)) in friction.iter().enumerate() {
        check_friction_net(friction, place, name, file)?;
    }
    let joints = match gravity {
        Some((name, file)) => check_gravity_net(friction, name, file)?,
        None => friction.len(),
    };
    if joints == 0 {
        return Err(NetsError::NoNets);
    }
    Ok(joints)
}

/// Checks the friction net at `place` (0-based) of `friction`, called `name`.
fn check_friction_net(friction: &[(&str, &WeightsFile)], place: usize, name: &str, file: &WeightsFile) -> Result<(), NetsError> {
    let joint = place + 1;
    file.network().map_err(|e| NetsError::Invalid { name: name.to_owned(), reason: e.to_string() })?;
    if let Some((other, _)) = friction[..place].iter().find(|(_, f)| same_weights(f, file)) {
        return Err(NetsError::SameFrictionNet { name: name.to_owned(), other: (*other).to_owned() });
    }
    let claimed = match file.kind {
        NetKind::Friction => file.joint,
        NetKind::Gravity => return Err(NetsError::GravityAsFriction { name: name.to_owned(), joint }),
        NetKind::Unspecified => file.inputs.first().and_then(|s| names::joint_of(&s.name, names::VELOCITY)),
    };
    if let Some(claimed) = claimed.filter(|&c| c != joint) {
        return Err(NetsError::JointOrder {
            name: name.to_owned(),
            claimed,
            by: if file.kind == NetKind::Friction { "recorded joint" } else { "input's name" },
            joint,
            count: friction.len(),
            order: friction.iter().map(|(n, _)| *n).collect::<Vec<_>>().join(", "),
        });
    }
    check_units(name, "input", &file.inputs, "rad/s")?;
    check_units(name, "output", &file.outputs, "N.m")
}

/// Checks the gravity net `name` against the friction nets; its joint count.
fn check_gravity_net(friction: &[(&str, &WeightsFile)], name: &str, file: &WeightsFile) -> Result<usize, NetsError> {
    file.network().map_err(|e| NetsError::Invalid { name: name.to_owned(), reason: e.to_string() })?;
    if file.kind == NetKind::Friction {
        return Err(NetsError::FrictionAsGravity { name: name.to_owned(), described: file.describe() });
    }
    if let Some((other, _)) = friction.iter().find(|(_, f)| same_weights(f, file)) {
        return Err(NetsError::GravityAlsoFriction { name: name.to_owned(), other: (*other).to_owned() });
    }
    check_units(name, "input", &file.inputs, "rad")?;
    check_units(name, "output", &file.outputs, "N.m")?;
    let n = file.inputs.len();
    if file.outputs.len() != n {
        return Err(NetsError::GravityShape { name: name.to_owned(), inputs: n, outputs: file.outputs.len() });
    }
    if !friction.is_empty() && friction.len() != n {
        return Err(NetsError::JointCount { friction: friction.len(), name: name.to_owned(), joints: n });
    }
    Ok(n)
}

/// Whether two files hold the same weights (whatever their names say).
fn same_weights(a: &WeightsFile, b: &WeightsFile) -> bool {
    a.iw == b.iw
        && a.b1 == b.b1
        && a.lw == b.lw
        && a.b2 == b.b2
        && a.input_scaling == b.input_scaling
        && a.output_scaling == b.output_scaling
}

/// Refuses a recorded unit other than `expected` (N·m also as `N·m` or `Nm`).
fn check_units(name: &str, what: &'static str, signals: &[Signal], expected: &'static str) -> Result<(), NetsError> {
    let same = |unit: &str| unit == expected || (expected == "N.m" && matches!(unit, "N·m" | "Nm" | "N m"));
    match signals.iter().find(|s| !s.unit.is_empty() && !same(&s.unit)) {
        Some(s) => Err(NetsError::Unit { name: name.to_owned(), what, signal: s.name.clone(), unit: s.unit.clone(), expected }),
        None => Ok(()),
    }
}

/// The compensator behind the FMU.
pub struct NnCompensatorModel {
    description: ModelDescription,
    core: NetCompensator,
}

fn check_signals(file: &WeightsFile, what: &str, n_in: usize, n_out: usize) -> Result<EncodedNet, BuildError> {
    let net = file.network().map_err(|e| BuildError::Spec(format!("{what}: {e}")))?;
    if net.inputs() != n_in || net.outputs() != n_out {
        return Err(BuildError::Spec(format!(
            "{what}: a {}-input, {}-output net where {n_in} inputs and {n_out} outputs are needed",
            net.inputs(),
            net.outputs()
        )));
    }
    Ok(net)
}

/// The nets of a compensator, its ports and scratch space: what the NN and the adaptive
/// compensator share.
pub(crate) struct NetCompensator {
    pub(crate) ports: CompensatorPorts,
    pub(crate) friction: Vec<EncodedNet>,
    pub(crate) gravity: Option<EncodedNet>,
    pub(crate) features: Vec<f64>,
    pub(crate) hidden: Vec<f64>,
    pub(crate) x: Vec<f64>,
    y: Vec<f64>,
}

impl NetCompensator {
    /// Checks the nets (see [`NnCompensatorModel::new`]) and declares the compensator's ports
    /// in `b`; returns it and the name of its parts ("friction and gravity", …).
    pub(crate) fn new(
        b: &mut TableBuilder,
        joints: usize,
        friction: &[WeightsFile],
        gravity: Option<&WeightsFile>,
        enable: (bool, bool),
    ) -> Result<(Self, &'static str), BuildError> {
        neurarm_physics::arm::check_joint_count(joints)?;
        let names: Vec<String> = (1..=friction.len()).map(|i| format!("friction net {i}")).collect();
        let named: Vec<(&str, &WeightsFile)> = names.iter().map(String::as_str).zip(friction).collect();
        let found = check_compensator_nets(&named, gravity.map(|g| ("the gravity net", g)))?;
        if found != joints {
            return Err(BuildError::Spec(format!("the nets are for {found} joints, the compensator for {joints}")));
        }
        let friction: Vec<EncodedNet> = friction
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let what = format!("friction net of joint {}", i + 1);
                if !matches!(f.encoding, InputEncoding::Raw | InputEncoding::LogSpeed) {
                    return Err(BuildError::Spec(format!(
                        "{what}: its input is encoded as '{}'; a friction net takes the velocity raw or as '{}'",
                        f.encoding.name(),
                        InputEncoding::LogSpeed.name()
                    )));
                }
                check_signals(f, &what, 1, 1)
            })
            .collect::<Result<_, _>>()?;
        let gravity = gravity.map(|g| check_signals(g, "gravity net", joints, joints)).transpose()?;
        let parts = Parts { friction: !friction.is_empty(), gravity: gravity.is_some(), source: "learned" };
        let ports = CompensatorPorts::declare(b, joints, parts, enable);
        let which = match (parts.friction, parts.gravity) {
            (true, true) => "friction and gravity",
            (true, false) => "friction",
            _ => "gravity",
        };
        let widest = friction.iter().chain(&gravity).map(EncodedNet::hidden).max().unwrap_or(1);
        let features = vec![0.0; gravity.as_ref().map_or(1, EncodedNet::features)];
        let (x, y) = (vec![0.0; joints], vec![0.0; joints]);
        Ok((Self { ports, friction, gravity, features, hidden: vec![0.0; widest], x, y }, which))
    }

    /// The gravity net's input for the angles in `values`, into `self.x`: the angles as they
    /// come for a periodic net; for a raw one (the paper's) each angle brought into the turn
    /// the net was trained on, [min, min + 2π) of its training data, as gravity is
    /// 2π-periodic in every revolute angle and a raw net is not (angles outside that range
    /// are not extrapolated).
    pub(crate) fn gravity_input(&mut self, values: &Values) {
        let Some(g) = &self.gravity else { return };
        let p = &self.ports;
        if g.encoding.is_periodic() {
            for i in 0..p.joints() {
                self.x[i] = values[p.q[i]];
            }
        } else {
            for i in 0..p.joints() {
                let low = g.mlp.input_scaling.min[i];
                self.x[i] = low + (values[p.q[i]] - low).rem_euclid(std::f64::consts::TAU);
            }
        }
    }

    /// Writes the outputs for the inputs and switches in `values`.
    pub(crate) fn compute(&mut self, values: &mut Values) {
        let use_friction = values[self.ports.enable_friction] && !self.friction.is_empty();
        let use_gravity = values[self.ports.enable_gravity] && self.gravity.is_some();
        if use_gravity {
            self.gravity_input(values);
            let g = self.gravity.as_ref().expect("checked");
            g.evaluate_into(&self.x, &mut self.features, &mut self.hidden[..g.hidden()], &mut self.y);
        } else {
            self.y.fill(0.0);
        }
        let p = &self.ports;
        for i in 0..p.joints() {
            let friction = if use_friction {
                let net = &self.friction[i];
                net.friction_torque(values[p.qd[i]], &mut self.hidden[..net.hidden()])
            } else {
                0.0
            };
            p.write(values, i, friction, self.y[i]);
        }
    }
}

impl NnCompensatorModel {
    /// A compensator for `joints` joints from one friction net per joint (1 input: the joint's
    /// velocity; 1 output: its friction torque), or none, and a gravity net (all angles in,
    /// all gravity torques out), or none; at least one part is needed. `fingerprint` (of the
    /// weights) goes into the description, so other weights give another GUID.
    pub fn new(
        identifier: &str,
        joints: usize,
        friction: &[WeightsFile],
        gravity: Option<&WeightsFile>,
        enable: (bool, bool),
        fingerprint: u32,
    ) -> Result<Self, BuildError> {
        let mut b = TableBuilder::new();
        let (core, which) = NetCompensator::new(&mut b, joints, friction, gravity, enable)?;
        let text = format!("NN compensator of {which} torques for {joints} joints (neurarm; weights crc32 {fingerprint:08x})");
        let description = describe(identifier, text, b.finish())?;
        Ok(Self { description, core })
    }
}

impl StaticModel for NnCompensatorModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }

    fn compute(&mut self, values: &mut Values, _time: f64) -> Result<(), ModelError> {
        self.core.compute(values);
        Ok(())
    }
}

/// The equations, for the FMU's `documentation/index.html`.
pub const EQUATIONS_HTML: &str = "<p>Each net is <code>y = LW tanh(IW x̃ + b1) + b2</code> on inputs \
scaled to [-1, 1] (mapminmax), with outputs scaled back to N·m. Per joint i:</p>\
<p><code>tau_friction_i = f_i(qd_i)</code>, <code>tau_gravity = g(q_1, …, q_n)</code>. A periodic gravity net \
sees each joint angle, or each link angle φ_j = q_1 + … + q_j, as (cos, sin) before scaling; a raw one \
sees each angle first brought into the turn it was trained on, [min_i, min_i + 2π) (gravity is 2π-periodic); \
<code>tau_comp_i = enable_friction·tau_friction_i + enable_gravity·tau_gravity_i</code>.</p>\
<p>The block is static: its outputs follow its inputs without delay, and a step changes nothing. \
The weights are read from <code>resources/</code> at instantiation; their CRC-32 is part of the \
model description, so the GUID changes with them.</p>";
