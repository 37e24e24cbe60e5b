//! The `AdaptiveCompensator` FMU: the offline-trained friction and gravity nets of the
//! `NnCompensator` as its start, whose output layers keep learning from a signal the
//! controller gives while the robot works.
//!
//! # The law
//! Each net is `τ̂ = α (LW a(x) + b2) + β`: its hidden layer `a(x)` (tanh of the scaled input)
//! stays as trained, and the output row of each torque, in torque units `w = α [LW, b2]`, is
//! linear in the regressor `φ = [a(x); 1]`. With `s_i` the learning signal of joint i (see
//! below), per friction net i and gravity output i, between communication points:
//!
//! `ẇ_i = γ φ_i s_i − σ (w_i − w⁰_i)`, then `w_i` projected onto `|w_i − w⁰_i| ≤ ρ / |φ|max`,
//!
//! with γ the gain (`gain_friction`, `gain_gravity`), σ the leakage (`leakage`, 1/s),
//! w⁰ the offline weights, ρ the bound (`bound_friction`, `bound_gravity`, N·m) and
//! `|φ|max = √(H + 1)` the largest norm a regressor of H tanh units and a bias can have. It is
//! stepped with explicit Euler over each communication step, from the inputs at its start.
//!
//! Why: with the compensation error `δ = f − τ̂ = −(w − w*)ᵀφ` for some ideal output weights
//! w*, the tracking error of a computed-torque loop obeys `ë + K_d ė + K_p e = J H⁻¹ δ` (task
//! space) and of a PD loop `H q̈ + … = K_p e − K_d q̇ + δ` (joint space). The Lyapunov function
//! `V = ½ |ė + λe|² + ½ (K_p + λK_d − λ²)|e|² + Σ (w_i − w*_i)²/(2γ)` (task space, 0 < λ < K_d)
//! has `V̇ = −(K_d − λ)|ė|² − λK_p|e|² + Σ_i (w_i − w*_i)·(ẇ_i/γ − φ_i s_i)` for
//! `s = H⁻¹Jᵀ(ė + λe)`, so the law above without leakage makes `V̇ ≤ 0` when the nets' hidden
//! layers can represent the true friction (w* exists); the joint-space P(D) loop gives the same
//! with `s = ė + λe` and the arm's energy in V (Tomei's adaptive gravity compensation). The
//! controllers of this crate output exactly these signals (`s_i`). When the hidden layer cannot
//! represent the change, or the signal is noise, the σ-leakage (σ-modification) keeps the
//! weights from drifting, pulling them back to the offline net, and the projection bounds them
//! by construction: **at every input the adapted torque differs from the offline net's by at
//! most ρ**, whatever the signal, so the compensation stays a bounded disturbance of a stable
//! loop. With `adapt` false nothing changes and the block is the `NnCompensator`, bit for bit.
//!
//! The adapted output layers are the FMU's state: `fmi2GetFMUstate`/`fmi2SetFMUstate` and
//! serialisation carry them, so a host can save and resume learning. Outputs
//! `adapted_friction_i`, `adapted_gravity_i` [N·m] show how far each torque may now differ
//! from the offline net's (`|w_i − w⁰_i| |φ|max`, at most the bound).

use std::path::Path;

use neurarm_fmi_export::codec::{Put, Reader};
use neurarm_fmi_export::{
    BooleanVar, Causality, Model, ModelDescription, ModelError, RealVar, StringVar, TableBuilder, Values, Variability,
};
use neurarm_nn::{EncodedNet, WeightsFile};
use serde::{Deserialize, Serialize};

use crate::compensator::{load_nets, NetCompensator};
use crate::names::{self, joint};
use crate::units::NEWTON_METRE;
use crate::{describe, per_joint, BuildError, ModelKind};

/// Spec of an adaptive compensator; its weights files live beside the spec in `resources/`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdaptiveCompensatorSpec {
    /// Number of joints.
    pub joints: usize,
    /// File of each joint's friction net, in order; empty for no friction part.
    pub friction: Vec<String>,
    /// File of the gravity net, if any.
    pub gravity: Option<String>,
    /// Start value of `enable_friction`.
    pub enable_friction: bool,
    /// Start value of `enable_gravity`.
    pub enable_gravity: bool,
    /// Start values of the law's parameters.
    #[serde(default)]
    pub law: AdaptationLaw,
}

/// The parameters of the adaptation law (start values of the FMU's tunable parameters).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AdaptationLaw {
    /// Adapt (`adapt`); false: the offline nets as they are.
    pub adapt: bool,
    /// γ of the friction nets (`gain_friction`) [N·m per unit of φ·s·s].
    pub gain_friction: f64,
    /// γ of the gravity net (`gain_gravity`).
    pub gain_gravity: f64,
    /// σ, the pull back to the offline weights (`leakage`) [1/s].
    pub leakage: f64,
    /// ρ of the friction nets (`bound_friction`): largest change of a friction torque [N·m].
    pub bound_friction: f64,
    /// ρ of the gravity net (`bound_gravity`): largest change of a gravity torque [N·m].
    pub bound_gravity: f64,
}

impl Default for AdaptationLaw {
    /// Tuned on the built-in arm's drift and payload runs of `neurarm paper` (see its report):
    /// friction γ = 1 learns the drift while the weights stay well inside their bound when
    /// nothing changes; gravity γ = 100 settles a payload within one 3-s target segment;
    /// σ = 0.1 1/s forgets in about 10 s what the signal no longer confirms; the bounds are 2
    /// N·m (above the built-in arm's largest Coulomb level, 1.5 N·m) and 5 N·m (twice the
    /// largest gravity torque of a payload of 30 % of its last link).
    fn default() -> Self {
        Self { adapt: true, gain_friction: 1.0, gain_gravity: 100.0, leakage: 0.1, bound_friction: 2.0, bound_gravity: 5.0 }
    }
}

impl ModelKind for AdaptiveCompensatorSpec {
    fn build(&self, identifier: &str, resources: Option<&Path>) -> Result<Box<dyn Model>, BuildError> {
        crate::compensator::check_switches((self.enable_friction, self.enable_gravity), &self.friction, self.gravity.as_deref())?;
        let (friction, gravity, crc) = load_nets(resources, self.joints, &self.friction, self.gravity.as_deref())?;
        let enable = (self.enable_friction, self.enable_gravity);
        Ok(Box::new(AdaptiveCompensatorModel::new(identifier, self.joints, &friction, gravity.as_ref(), enable, self.law, crc)?))
    }

    fn resource_files(&self) -> Vec<String> {
        self.friction.iter().chain(&self.gravity).cloned().collect()
    }

    fn equations_html(&self) -> &'static str {
        EQUATIONS_HTML
    }
}

/// One adapted output row: torque `i` of a friction net (`net = Some(i)`) or of the gravity
/// net (`None`), its offline row `[LW, b2]` in the net's scaled units, and the output gain α.
struct Row {
    friction_net: Option<usize>,
    output: usize,
    offline: Vec<f64>,
    alpha: f64,
}

/// The variables of the law.
struct LawPorts {
    signal: Vec<RealVar>,
    adapt: BooleanVar,
    gain_friction: RealVar,
    gain_gravity: RealVar,
    leakage: RealVar,
    bound_friction: RealVar,
    bound_gravity: RealVar,
    adapted_friction: Vec<RealVar>,
    adapted_gravity: Vec<RealVar>,
    nets_folder: StringVar,
}

/// The adaptive compensator behind the FMU.
pub struct AdaptiveCompensatorModel {
    description: ModelDescription,
    core: NetCompensator,
    law: LawPorts,
    rows: Vec<Row>,
    /// Regressor scratch of a friction net: its hidden layer and the bias, H + 1.
    phi: Vec<f64>,
    /// The gravity net's regressor, shared by all its outputs.
    phi_gravity: Vec<f64>,
    /// The offline weights files (friction nets in joint order, then the gravity net), for
    /// writing the adapted nets with their signals and training record.
    files: Vec<WeightsFile>,
}

/// Output rows of `net` as (LW row, b2) in one vector, and α of each output (1 for an output
/// whose training targets were constant: the scaling passes it through).
fn output_rows(net: &EncodedNet) -> Vec<(Vec<f64>, f64)> {
    let m = &net.mlp;
    (0..m.outputs())
        .map(|k| {
            let mut row: Vec<f64> = m.lw.row(k).iter().copied().collect();
            row.push(m.b2[k]);
            let span = m.output_scaling.max[k] - m.output_scaling.min[k];
            (row, if span > 0.0 { span / 2.0 } else { 1.0 })
        })
        .collect()
}

impl AdaptiveCompensatorModel {
    /// An adaptive compensator from the nets a [`crate::compensator::NnCompensatorModel`]
    /// takes (same checks), its law starting as `law`.
    pub fn new(
        identifier: &str,
        joints: usize,
        friction: &[WeightsFile],
        gravity: Option<&WeightsFile>,
        enable: (bool, bool),
        law: AdaptationLaw,
        fingerprint: u32,
    ) -> Result<Self, BuildError> {
        check_law(&law)?;
        let mut b = TableBuilder::new();
        let (core, which) = NetCompensator::new(&mut b, joints, friction, gravity, enable)?;
        let signal = per_joint(&mut b, joints, |b, i| {
            b.input(
                joint(names::LEARNING_SIGNAL, i + 1),
                None,
                0.0,
                format!("Learning signal of joint {}: a controller's s_{} (0: nothing to learn)", i + 1, i + 1),
            )
        });
        let adapt = b.tunable_flag(names::ADAPT, law.adapt, "Adapt the nets' output layers (false: the offline nets, as NnCompensator)");
        let gain_friction = b.tunable(names::GAIN_FRICTION, None, law.gain_friction, "Adaptation gain of the friction nets, gamma");
        let gain_gravity = b.tunable(names::GAIN_GRAVITY, None, law.gain_gravity, "Adaptation gain of the gravity net, gamma");
        let leakage = b.tunable(
            names::LEAKAGE,
            crate::units::PER_SECOND,
            law.leakage,
            "Leakage sigma: the rate the weights are pulled back to the offline net's",
        );
        let bound_friction = b.tunable(
            names::BOUND_FRICTION,
            NEWTON_METRE,
            law.bound_friction,
            "Largest change of a friction torque from the offline net's the adaptation may make",
        );
        let bound_gravity = b.tunable(
            names::BOUND_GRAVITY,
            NEWTON_METRE,
            law.bound_gravity,
            "Largest change of a gravity torque from the offline net's the adaptation may make",
        );
        let adapted_friction = per_joint(&mut b, joints, |b, i| {
            b.output(
                joint(names::ADAPTED_FRICTION, i + 1),
                NEWTON_METRE,
                format!("Largest change of joint {}'s friction torque the adapted net now makes (at most bound_friction)", i + 1),
                &[],
            )
        });
        let adapted_gravity = per_joint(&mut b, joints, |b, i| {
            b.output(
                joint(names::ADAPTED_GRAVITY, i + 1),
                NEWTON_METRE,
                format!("Largest change of joint {}'s gravity torque the adapted net now makes (at most bound_gravity)", i + 1),
                &[],
            )
        });
        let nets_folder = b.string(
            names::NETS_FOLDER,
            Causality::Parameter,
            Variability::Tunable,
            Some(String::new()),
            "Folder to write the adapted nets into at fmi2Terminate (friction_i.json, gravity.json; empty: none)",
        );
        let text = format!("Adaptive NN compensator of {which} torques for {joints} joints (neurarm; weights crc32 {fingerprint:08x})");
        let description = describe(identifier, text, b.finish())?;
        let mut rows = Vec::new();
        for (i, net) in core.friction.iter().enumerate() {
            let (offline, alpha) = output_rows(net).remove(0);
            rows.push(Row { friction_net: Some(i), output: 0, offline, alpha });
        }
        if let Some(g) = &core.gravity {
            for (k, (offline, alpha)) in output_rows(g).into_iter().enumerate() {
                rows.push(Row { friction_net: None, output: k, offline, alpha });
            }
        }
        let widest = core.friction.iter().chain(&core.gravity).map(EncodedNet::hidden).max().unwrap_or(1);
        let law = LawPorts {
            signal,
            adapt,
            gain_friction,
            gain_gravity,
            leakage,
            bound_friction,
            bound_gravity,
            adapted_friction,
            adapted_gravity,
            nets_folder,
        };
        let files = friction.iter().chain(gravity).cloned().collect();
        let phi_gravity = vec![0.0; core.gravity.as_ref().map_or(0, EncodedNet::hidden) + 1];
        Ok(Self { description, core, law, rows, phi: vec![0.0; widest + 1], phi_gravity, files })
    }

    /// The nets as they are now, as weights files named as `export compensator` and the
    /// spec take them: `friction_i.json` per joint, `gravity.json`. Each keeps its offline
    /// file's signals and training record, with the adapted output layer.
    pub fn adapted_nets(&self) -> Vec<(String, WeightsFile)> {
        let friction = self.core.friction.len();
        self.files
            .iter()
            .enumerate()
            .map(|(k, file)| {
                let net = if k < friction { &self.core.friction[k] } else { self.core.gravity.as_ref().expect("a gravity file has a net") };
                let mut file = file.clone();
                for (o, row) in file.lw.iter_mut().enumerate() {
                    row.copy_from_slice(net.mlp.lw.row(o).iter().copied().collect::<Vec<_>>().as_slice());
                }
                file.b2 = net.mlp.b2.iter().copied().collect();
                let name = if k < friction { format!("friction_{}.json", k + 1) } else { "gravity.json".to_owned() };
                (name, file)
            })
            .collect()
    }

    /// Writes [`Self::adapted_nets`] into `folder` (made if missing), each file through a
    /// temporary file and a rename, so none is left half-written.
    pub fn write_adapted_nets(&self, folder: &Path) -> Result<(), WriteError> {
        std::fs::create_dir_all(folder).map_err(|source| WriteError { path: folder.to_path_buf(), source })?;
        for (name, file) in self.adapted_nets() {
            let path = folder.join(&name);
            // A name no other writer uses (this process, this instance), in the same folder so
            // the rename is atomic.
            let partial = folder.join(format!(".{name}.partial-{}-{:p}", std::process::id(), self));
            let written = std::fs::write(&partial, file.to_json()).and_then(|()| std::fs::rename(&partial, &path));
            if let Err(e) = written {
                let _ = std::fs::remove_file(&partial);
                return Err(WriteError { path, source: e });
            }
        }
        Ok(())
    }

    fn net(&self, row: &Row) -> &EncodedNet {
        net_of(&self.core, row)
    }

    fn net_mut<'a>(core: &'a mut NetCompensator, row: &Row) -> &'a mut EncodedNet {
        match row.friction_net {
            Some(i) => &mut core.friction[i],
            None => core.gravity.as_mut().expect("a gravity row has a gravity net"),
        }
    }

    /// The row's current weights `[LW_k, b2_k]`, read one by one.
    fn weight(net: &EncodedNet, output: usize, j: usize) -> f64 {
        let m = &net.mlp;
        if j < m.hidden() {
            m.lw[(output, j)]
        } else {
            m.b2[output]
        }
    }

    /// |θ − θ⁰| of a row, in the net's scaled units.
    fn distance(&self, row: &Row) -> f64 {
        let net = self.net(row);
        row.offline.iter().enumerate().map(|(j, &w0)| (Self::weight(net, row.output, j) - w0).powi(2)).sum::<f64>().sqrt()
    }

    /// How far each torque may now differ from the offline net's [N·m], into the outputs.
    fn write_adapted(&self, values: &mut Values) {
        let joints = self.core.ports.joints();
        for i in 0..joints {
            values[self.law.adapted_friction[i]] = 0.0;
            values[self.law.adapted_gravity[i]] = 0.0;
        }
        for row in &self.rows {
            let reach = row.alpha * self.distance(row) * (row.offline.len() as f64).sqrt();
            let slot = match row.friction_net {
                Some(i) => self.law.adapted_friction[i],
                None => self.law.adapted_gravity[row.output],
            };
            values[slot] = reach;
        }
    }

    /// One explicit-Euler step of the law over `h` [s] with the inputs in `values`, then the
    /// projection. Allocates nothing.
    fn adapt(&mut self, values: &Values, h: f64) -> Result<(), ModelError> {
        let law = AdaptationLaw {
            adapt: values[self.law.adapt],
            gain_friction: values[self.law.gain_friction],
            gain_gravity: values[self.law.gain_gravity],
            leakage: values[self.law.leakage],
            bound_friction: values[self.law.bound_friction],
            bound_gravity: values[self.law.bound_gravity],
        };
        if !law.adapt {
            return Ok(());
        }
        check_law(&law).map_err(ModelError::msg)?;
        if law.leakage * h >= 1.0 {
            return Err(ModelError::msg(format!(
                "leakage × step = {} × {h} s must be below 1 for the discrete law to pull the weights back rather than past the offline ones",
                law.leakage
            )));
        }
        let p = &self.core.ports;
        let use_friction = values[p.enable_friction] && !self.core.friction.is_empty();
        let use_gravity = values[p.enable_gravity] && self.core.gravity.is_some();
        if use_gravity {
            // One regressor for every gravity output: the hidden layer at the angles.
            self.core.gravity_input(values);
            let g = self.core.gravity.as_ref().expect("checked");
            g.encoding.encode_into(&self.core.x, &mut self.core.features);
            let hidden = g.hidden();
            hidden_layer(g, &self.core.features, &mut self.phi_gravity[..hidden]);
            self.phi_gravity[hidden] = 1.0;
        }
        for r in 0..self.rows.len() {
            let row = &self.rows[r];
            let (used, gain, bound, joint) = match row.friction_net {
                Some(i) => (use_friction, law.gain_friction, law.bound_friction, i),
                None => (use_gravity, law.gain_gravity, law.bound_gravity, row.output),
            };
            // A friction row does not learn at rest: its output is 0 there whatever the weights
            // (`EncodedNet::friction_torque`).
            if !used || row.friction_net.is_some() && values[self.core.ports.qd[joint]] == 0.0 {
                continue;
            }
            // The regressor: the hidden layer at the current input, and the bias.
            let hidden = net_of(&self.core, row).hidden();
            let phi: &[f64] = match row.friction_net {
                Some(_) => {
                    let net = net_of(&self.core, row);
                    let mut feature = [0.0];
                    net.encoding.encode_into(&[values[self.core.ports.qd[joint]]], &mut feature);
                    hidden_layer(net, &feature, &mut self.phi[..hidden]);
                    self.phi[hidden] = 1.0;
                    &self.phi[..hidden + 1]
                }
                None => &self.phi_gravity,
            };
            let s = values[self.law.signal[joint]];
            // In the net's scaled units θ = w / α: θ̇ = (γ / α) φ s − σ (θ − θ⁰).
            let rate = gain / row.alpha * s;
            let radius = bound / (row.alpha * ((hidden + 1) as f64).sqrt());
            let output = row.output;
            let net = Self::net_mut(&mut self.core, row);
            let mut distance2 = 0.0;
            for (j, (&phi_j, &w0)) in phi.iter().zip(&row.offline).enumerate() {
                let w = Self::weight(net, output, j);
                let next = w + h * (rate * phi_j - law.leakage * (w - w0));
                set_weight(net, output, j, next);
                distance2 += (next - w0).powi(2);
            }
            let distance = distance2.sqrt();
            if distance > radius {
                let shrink = radius / distance;
                for (j, &w0) in row.offline.iter().enumerate() {
                    let w = Self::weight(net, output, j);
                    set_weight(net, output, j, w0 + (w - w0) * shrink);
                }
            }
        }
        Ok(())
    }
}

fn net_of<'a>(core: &'a NetCompensator, row: &Row) -> &'a EncodedNet {
    match row.friction_net {
        Some(i) => &core.friction[i],
        None => core.gravity.as_ref().expect("a gravity row has a gravity net"),
    }
}

/// The hidden layer of `net` at the (encoded) input `x`, into `out`: tanh(IW x̃ + b1).
fn hidden_layer(net: &EncodedNet, x: &[f64], out: &mut [f64]) {
    let m = &net.mlp;
    for (j, a) in out.iter_mut().enumerate() {
        let mut sum = m.b1[j];
        for (i, &xi) in x.iter().enumerate() {
            sum += m.iw[(j, i)] * m.input_scaling.apply(i, xi);
        }
        *a = sum.tanh();
    }
}

fn set_weight(net: &mut EncodedNet, output: usize, j: usize, value: f64) {
    let m = &mut net.mlp;
    if j < m.hidden() {
        m.lw[(output, j)] = value;
    } else {
        m.b2[output] = value;
    }
}

/// Refuses gains, leakage or bounds that are negative or not finite, naming the parameter.
/// A file or folder that could not be written.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", path.display())]
pub struct WriteError {
    /// The file or folder.
    pub path: std::path::PathBuf,
    /// What failed.
    pub source: std::io::Error,
}

/// A parameter of an adaptation law that is negative or not finite.
#[derive(Debug, thiserror::Error)]
#[error("{name} = {value} must be a finite number >= 0")]
pub struct LawError {
    /// The parameter.
    pub name: &'static str,
    /// Its value.
    pub value: f64,
}

fn check_law(law: &AdaptationLaw) -> Result<(), LawError> {
    for (name, value) in [
        (names::GAIN_FRICTION, law.gain_friction),
        (names::GAIN_GRAVITY, law.gain_gravity),
        (names::LEAKAGE, law.leakage),
        (names::BOUND_FRICTION, law.bound_friction),
        (names::BOUND_GRAVITY, law.bound_gravity),
    ] {
        if !(value.is_finite() && value >= 0.0) {
            return Err(LawError { name, value });
        }
    }
    Ok(())
}

impl Model for AdaptiveCompensatorModel {
    fn description(&self) -> &ModelDescription {
        &self.description
    }

    fn initialize(&mut self, values: &mut Values, _start_time: f64) -> Result<(), ModelError> {
        self.core.compute(values);
        self.write_adapted(values);
        Ok(())
    }

    fn update_outputs(&mut self, values: &mut Values, _time: f64) -> Result<(), ModelError> {
        self.core.compute(values);
        Ok(())
    }

    fn do_step(&mut self, values: &mut Values, _time: f64, step: f64) -> Result<(), ModelError> {
        self.adapt(values, step)?;
        self.core.compute(values);
        self.write_adapted(values);
        Ok(())
    }

    fn terminate(&mut self, values: &Values) -> Result<(), ModelError> {
        let folder = &values[self.law.nets_folder];
        if folder.is_empty() {
            return Ok(());
        }
        self.write_adapted_nets(Path::new(folder)).map_err(|e| ModelError::msg(format!("writing the adapted nets: {e}")))
    }

    fn reset(&mut self) {
        for r in 0..self.rows.len() {
            let row = &self.rows[r];
            let output = row.output;
            let net = Self::net_mut(&mut self.core, row);
            for (j, &w0) in row.offline.iter().enumerate() {
                set_weight(net, output, j, w0);
            }
        }
    }

    fn save_state(&self, out: &mut Vec<u8>) {
        for row in &self.rows {
            let net = self.net(row);
            out.put_u32(row.offline.len() as u32);
            for j in 0..row.offline.len() {
                out.put_f64(Self::weight(net, row.output, j));
            }
        }
    }

    fn load_state(&mut self, values: &Values, bytes: &[u8]) -> Result<(), ModelError> {
        let mut r = Reader::new(bytes);
        let mut weights = Vec::with_capacity(self.rows.iter().map(|row| row.offline.len()).sum());
        for row in &self.rows {
            let w = r.finite_f64s("adapted weights", row.offline.len())?;
            // Weights the projection could not have left are an altered state.
            let bound = values[if row.friction_net.is_some() { self.law.bound_friction } else { self.law.bound_gravity }];
            let radius = bound / (row.alpha * (row.offline.len() as f64).sqrt());
            let distance = w.iter().zip(&row.offline).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
            if distance > radius * (1.0 + 1e-9) {
                return Err(ModelError::msg(format!(
                    "the saved adapted weights are {distance} from the offline ones, beyond the bound's {radius}: not a state this FMU made"
                )));
            }
            weights.extend(w);
        }
        r.finish()?;
        let mut k = 0;
        for i in 0..self.rows.len() {
            let row = &self.rows[i];
            let output = row.output;
            let net = Self::net_mut(&mut self.core, row);
            for j in 0..row.offline.len() {
                set_weight(net, output, j, weights[k]);
                k += 1;
            }
        }
        Ok(())
    }
}

/// The equations, for the FMU's `documentation/index.html`.
pub const EQUATIONS_HTML: &str = "<p>The NnCompensator's nets (<code>y = LW tanh(IW x̃ + b1) + b2</code>, \
scaled), whose output layers adapt. Per joint i, with the regressor φ = [tanh(IW x̃ + b1); 1] of its friction \
net (x = qd_i) or of the gravity net (x = q) and w_i = α[LW_i, b2_i] the output row in N·m:</p>\
<p><code>dw_i/dt = gain · φ s_i − leakage · (w_i − w⁰_i)</code>, then w_i projected onto \
<code>|w_i − w⁰_i| ≤ bound / √(H+1)</code>, so no torque differs from the offline net's by more than \
<code>bound</code>. s_i is the controller's learning signal: H⁻¹Jᵀ(ė + λe) of the task-space controller, \
ė + λe of the joint controller. Explicit Euler over each communication step from the inputs at its start. \
With <code>adapt</code> false the block is the NnCompensator. The adapted weights are the FMU state.</p>";
