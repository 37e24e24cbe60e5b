//! The `NnCompensator` FMU: the paper's learned compensating torques as a block.
//!
//! Ports as every compensator ([`CompensatorPorts`]): joint i's friction part is joint i's
//! friction net of `qd_i`; the gravity part is output i of the gravity net of all angles. A
//! periodic gravity net (angles encoded on the circle) takes the angles as they come; a raw
//! one (the paper's) gets each angle wrapped into the turn [min, min + 2π) of its training
//! data, as gravity is 2π-periodic. A disabled part's outputs are 0. The block is static: outputs follow the
//! inputs at once (direct feedthrough), steps change nothing.

use std::path::Path;

use fmi2_export::{Model, ModelDescription, ModelError, StaticModel, TableBuilder, Values};
use neurarm_physics::nn::{EncodedNet, InputEncoding, WeightsFile};
use serde::{Deserialize, Serialize};

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

impl ModelKind for NnCompensatorSpec {
    fn build(&self, identifier: &str, resources: Option<&Path>) -> Result<Box<dyn Model>, BuildError> {
        let dir = resources.ok_or(BuildError::NoResources)?;
        let mut crc = crc32fast::Hasher::new();
        let mut load = |name: &str| -> Result<WeightsFile, BuildError> {
            let path = dir.join(name);
            let text = std::fs::read_to_string(&path).map_err(|e| BuildError::Weights { path: path.clone(), message: e.to_string() })?;
            crc.update(text.as_bytes());
            WeightsFile::from_json(&text, &path.display().to_string()).map_err(|e| BuildError::Spec(e.to_string()))
        };
        let friction = self.friction.iter().map(|f| load(f)).collect::<Result<Vec<_>, _>>()?;
        let gravity = self.gravity.as_deref().map(&mut load).transpose()?;
        let enable = (self.enable_friction, self.enable_gravity);
        Ok(Box::new(NnCompensatorModel::new(identifier, self.joints, &friction, gravity.as_ref(), enable, crc.finalize())?))
    }

    fn resource_files(&self) -> Vec<String> {
        self.friction.iter().chain(&self.gravity).cloned().collect()
    }

    fn equations_html(&self) -> &'static str {
        EQUATIONS_HTML
    }
}

/// The compensator behind the FMU.
pub struct NnCompensatorModel {
    description: ModelDescription,
    ports: CompensatorPorts,
    friction: Vec<EncodedNet>,
    gravity: Option<EncodedNet>,
    features: Vec<f64>,
    hidden: Vec<f64>,
    x: Vec<f64>,
    y: Vec<f64>,
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
        if joints == 0 {
            return Err(BuildError::Spec("the compensator needs at least one joint".into()));
        }
        if friction.is_empty() && gravity.is_none() {
            return Err(BuildError::Spec("give friction nets, a gravity net, or both".into()));
        }
        if !friction.is_empty() && friction.len() != joints {
            return Err(BuildError::Spec(format!("{} friction nets for {joints} joints: give one per joint", friction.len())));
        }
        let friction: Vec<EncodedNet> = friction
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let what = format!("friction net of joint {}", i + 1);
                if f.encoding != InputEncoding::Raw {
                    return Err(BuildError::Spec(format!(
                        "{what}: its input is encoded as '{}'; a friction net takes the velocity as it is",
                        f.encoding.name()
                    )));
                }
                check_signals(f, &what, 1, 1)
            })
            .collect::<Result<_, _>>()?;
        let gravity = gravity.map(|g| check_signals(g, "gravity net", joints, joints)).transpose()?;
        let mut b = TableBuilder::new();
        let parts = Parts { friction: !friction.is_empty(), gravity: gravity.is_some(), source: "learned" };
        let ports = CompensatorPorts::declare(&mut b, joints, parts, enable);
        let which = match (parts.friction, parts.gravity) {
            (true, true) => "friction and gravity",
            (true, false) => "friction",
            _ => "gravity",
        };
        let text = format!("NN compensator of {which} torques for {joints} joints (neurarm; weights crc32 {fingerprint:08x})");
        let description = describe(identifier, text, b.finish())?;
        let widest = friction.iter().chain(&gravity).map(EncodedNet::hidden).max().unwrap_or(1);
        let features = vec![0.0; gravity.as_ref().map_or(1, EncodedNet::features)];
        let (x, y) = (vec![0.0; joints], vec![0.0; joints]);
        Ok(Self { description, ports, friction, gravity, features, hidden: vec![0.0; widest], x, y })
    }
}

impl StaticModel for NnCompensatorModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }

    fn compute(&mut self, values: &mut Values, _time: f64) -> Result<(), ModelError> {
        let p = &self.ports;
        let use_friction = values[p.enable_friction] && !self.friction.is_empty();
        let use_gravity = values[p.enable_gravity] && self.gravity.is_some();
        match (&self.gravity, use_gravity) {
            (Some(g), true) => {
                if g.encoding.is_periodic() {
                    for i in 0..p.joints() {
                        self.x[i] = values[p.q[i]];
                    }
                } else {
                    // Gravity is 2π-periodic in every revolute angle and a raw net is not:
                    // bring each angle into the turn the net was trained on, [min, min + 2π)
                    // of its training data, so angles outside that range are not extrapolated.
                    for i in 0..p.joints() {
                        let low = g.mlp.input_scaling.min[i];
                        self.x[i] = low + (values[p.q[i]] - low).rem_euclid(std::f64::consts::TAU);
                    }
                }
                g.evaluate_into(&self.x, &mut self.features, &mut self.hidden[..g.hidden()], &mut self.y);
            }
            _ => self.y.fill(0.0),
        }
        for i in 0..p.joints() {
            let friction = if use_friction {
                let mut out = [0.0];
                let h = self.friction[i].hidden();
                self.friction[i].mlp.evaluate_into(&[values[p.qd[i]]], &mut self.hidden[..h], &mut out);
                out[0]
            } else {
                0.0
            };
            p.write(values, i, friction, self.y[i]);
        }
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
