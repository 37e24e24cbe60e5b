//! The `NnCompensator` FMU: the paper's learned compensating torques as a block.
//!
//! Inputs: joint angles `q_i` [rad] and velocities `qd_i` [rad/s]. Outputs: per joint the
//! friction part `tau_friction_i` (joint i's friction net of `qd_i`), the gravity part
//! `tau_gravity_i` (output i of the gravity net of all angles, each wrapped into the turn
//! [min, min + 2π) of the net's training data, as gravity is 2π-periodic) and their sum over the enabled
//! parts, `tau_comp_i` [N·m]. Tunable Boolean parameters `enable_friction` and
//! `enable_gravity` switch the parts; a disabled part's outputs are 0. The block is static:
//! outputs follow the inputs at once (direct feedthrough), steps change nothing.

use crate::fmi2::description::{Causality, Kind, ModelDescription, TableBuilder, Variability};
use crate::fmi2::model::{StaticModel, Values};
use crate::nn::{Mlp, WeightsFile};

/// Value references of the compensator's variables.
#[derive(Clone, Debug)]
struct Layout {
    q: Vec<u32>,
    qd: Vec<u32>,
    friction: Vec<u32>,
    gravity: Vec<u32>,
    total: Vec<u32>,
    enable_friction: u32,
    enable_gravity: u32,
}

/// The compensator behind the FMU.
pub struct NnCompensatorModel {
    description: ModelDescription,
    layout: Layout,
    friction: Vec<Mlp>,
    gravity: Option<Mlp>,
    hidden: Vec<f64>,
    x: Vec<f64>,
    y: Vec<f64>,
}

fn check_signals(file: &WeightsFile, what: &str, n_in: usize, n_out: usize) -> Result<Mlp, String> {
    let net = file.network().map_err(|e| format!("{what}: {e}"))?;
    if net.inputs() != n_in || net.outputs() != n_out {
        return Err(format!("{what}: a {}-input, {}-output net where {n_in} inputs and {n_out} outputs are needed", net.inputs(), net.outputs()));
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
    ) -> Result<Self, String> {
        if joints == 0 {
            return Err("the compensator needs at least one joint".into());
        }
        if friction.is_empty() && gravity.is_none() {
            return Err("give friction nets, a gravity net, or both".into());
        }
        if !friction.is_empty() && friction.len() != joints {
            return Err(format!("{} friction nets for {joints} joints: give one per joint", friction.len()));
        }
        let friction: Vec<Mlp> = friction
            .iter()
            .enumerate()
            .map(|(i, f)| check_signals(f, &format!("friction net of joint {}", i + 1), 1, 1))
            .collect::<Result<_, _>>()?;
        let gravity = gravity.map(|g| check_signals(g, "gravity net", joints, joints)).transpose()?;
        let mut b = TableBuilder::new();
        let per_joint = |b: &mut TableBuilder, f: &dyn Fn(&mut TableBuilder, usize) -> u32| (0..joints).map(|i| f(b, i)).collect::<Vec<u32>>();
        let q = per_joint(&mut b, &|b, i| b.input(format!("q_{}", i + 1), "rad", 0.0, format!("Angle of joint {}", i + 1)));
        let qd = per_joint(&mut b, &|b, i| b.input(format!("qd_{}", i + 1), "rad/s", 0.0, format!("Velocity of joint {}", i + 1)));
        let has_friction = !friction.is_empty();
        let has_gravity = gravity.is_some();
        let friction_vr = per_joint(&mut b, &|b, i| {
            let deps: &[u32] = if has_friction { std::slice::from_ref(&qd[i]) } else { &[] };
            b.output(format!("tau_friction_{}", i + 1), "N.m", format!("Learned friction torque of joint {}", i + 1), deps)
        });
        let gravity_vr = per_joint(&mut b, &|b, i| {
            let deps: &[u32] = if has_gravity { &q } else { &[] };
            b.output(format!("tau_gravity_{}", i + 1), "N.m", format!("Learned gravity torque of joint {}", i + 1), deps)
        });
        let total = per_joint(&mut b, &|b, i| {
            let mut deps: Vec<u32> = if has_gravity { q.clone() } else { Vec::new() };
            if has_friction {
                deps.push(qd[i]);
            }
            b.output(format!("tau_comp_{}", i + 1), "N.m", format!("Compensating torque of joint {}: the sum of the enabled parts", i + 1), &deps)
        });
        let flag = |b: &mut TableBuilder, name: &str, on: bool, what: &str| {
            b.push(name, Causality::Parameter, Variability::Tunable, Kind::Boolean { start: Some(on) }, what)
        };
        let enable_friction = flag(&mut b, "enable_friction", enable.0 && has_friction, "Add the friction nets' torques");
        let enable_gravity = flag(&mut b, "enable_gravity", enable.1 && has_gravity, "Add the gravity net's torques");
        let parts = match (has_friction, has_gravity) {
            (true, true) => "friction and gravity",
            (true, false) => "friction",
            _ => "gravity",
        };
        let text = format!("NN compensator of {parts} torques for {joints} joints (neurarm; weights crc32 {fingerprint:08x})");
        let description = ModelDescription::new(identifier, text, b.finish())?;
        let widest = friction.iter().chain(&gravity).map(Mlp::hidden).max().unwrap_or(1);
        Ok(Self {
            description,
            layout: Layout { q, qd, friction: friction_vr, gravity: gravity_vr, total, enable_friction, enable_gravity },
            friction,
            gravity,
            hidden: vec![0.0; widest],
            x: vec![0.0; joints],
            y: vec![0.0; joints],
        })
    }

}

impl StaticModel for NnCompensatorModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }

    fn compute(&mut self, values: &mut Values) {
        let l = &self.layout;
        let n = l.q.len();
        let use_friction = values.booleans[l.enable_friction as usize] && !self.friction.is_empty();
        let use_gravity = values.booleans[l.enable_gravity as usize] && self.gravity.is_some();
        for i in 0..n {
            let f = if use_friction {
                let mut out = [0.0];
                let h = self.friction[i].hidden();
                self.friction[i].evaluate_into(&[values.reals[l.qd[i] as usize]], &mut self.hidden[..h], &mut out);
                out[0]
            } else {
                0.0
            };
            values.reals[l.friction[i] as usize] = f;
        }
        match (&self.gravity, use_gravity) {
            (Some(g), true) => {
                // Gravity is 2π-periodic in every revolute angle: bring each angle into the
                // turn the net was trained on, [min, min + 2π) of its training data, so angles
                // outside that range are not extrapolated.
                for i in 0..n {
                    let low = g.input_scaling.min[i];
                    self.x[i] = low + (values.reals[l.q[i] as usize] - low).rem_euclid(std::f64::consts::TAU);
                }
                g.evaluate_into(&self.x, &mut self.hidden[..g.hidden()], &mut self.y);
            }
            _ => self.y.fill(0.0),
        }
        for i in 0..n {
            values.reals[l.gravity[i] as usize] = self.y[i];
            values.reals[l.total[i] as usize] = values.reals[l.friction[i] as usize] + self.y[i];
        }
    }
}

/// The equations, for the FMU's `documentation/index.html`.
pub const EQUATIONS_HTML: &str = "<p>Each net is <code>y = LW tanh(IW x̃ + b1) + b2</code> on inputs \
scaled to [-1, 1] (mapminmax), with outputs scaled back to N·m. Per joint i:</p>\
<p><code>tau_friction_i = f_i(qd_i)</code>, <code>tau_gravity = g(q_1, …, q_n)</code> with each angle first \
brought into the turn the gravity net was trained on, [min_i, min_i + 2π) (gravity is 2π-periodic), \
<code>tau_comp_i = enable_friction·tau_friction_i + enable_gravity·tau_gravity_i</code>.</p>\
<p>The block is static: its outputs follow its inputs without delay, and a step changes nothing. \
The weights are read from <code>resources/</code> at instantiation; their CRC-32 is part of the \
model description, so the GUID changes with them.</p>";
