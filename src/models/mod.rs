//! The models neurarm ships as FMUs, and the factory the FMU binary uses to make them.
//!
//! Every `.fmu` carries the same binary and a spec file, `resources/neurarm.toml`, that says
//! which model it is and with which parameters; [`instantiate`] reads it. The GUID in the
//! model description is a hash of the description made from that spec, so a binary, spec and
//! XML that do not belong together are refused at instantiation.

pub mod compensator;
pub mod controllers;
pub mod planar_arm;
pub mod signals;

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::arm::{ArmParams, ArmState};
use crate::control::TaskSpaceGains;
use crate::config::ArmConfig;
use crate::fmi2::description::ModelDescription;
use crate::fmi2::model::Model;
use crate::nn::WeightsFile;

/// Name of the spec file in an FMU's `resources/` folder.
pub const SPEC_FILE: &str = "neurarm.toml";

/// Which model an FMU holds, and its parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", deny_unknown_fields)]
pub enum ModelSpec {
    /// The planar arm.
    PlanarArm {
        /// The arm's configuration: the parameters' start values.
        config: ArmConfig,
        /// Initial joint angles [rad].
        q0: Vec<f64>,
        /// Initial joint velocities [rad/s].
        qd0: Vec<f64>,
    },
    /// The NN compensator; weights files live beside the spec in `resources/`.
    NnCompensator {
        /// Number of joints.
        joints: usize,
        /// File of each joint's friction net, in order; empty for no friction part.
        friction: Vec<String>,
        /// File of the gravity net, if any.
        gravity: Option<String>,
        /// Start value of the `enable_friction` parameter.
        enable_friction: bool,
        /// Start value of the `enable_gravity` parameter.
        enable_gravity: bool,
    },
    /// Task-space computed-torque controller with the paper's reference.
    TaskSpaceController {
        /// The controller's model of the arm (its friction is not used).
        model: ArmParams,
        /// Default gains.
        gains: TaskSpaceGains,
        /// Default centre of the reference [m].
        centre: [f64; 2],
        /// Start values of the angle inputs [rad]: a pose where J has full rank.
        q_start: Vec<f64>,
    },
    /// Joint-space P(D) controller with a compensation input.
    JointController {
        /// Number of joints.
        joints: usize,
        /// Default position gain of every joint [N·m/rad].
        kp: f64,
        /// Default velocity gain of every joint [N·m·s/rad].
        kd: f64,
        /// Default of `use_sequence`.
        use_sequence: bool,
    },
    /// The true friction and gravity of an arm, as a compensator.
    IdealCompensator {
        /// The arm.
        arm: ArmParams,
        /// Start value of `enable_friction`.
        enable_friction: bool,
        /// Start value of `enable_gravity`.
        enable_gravity: bool,
    },
    /// Test block y' = u.
    Integrator {
        /// Start value of y0.
        y0: f64,
    },
    /// Test block y = k u.
    Gain {
        /// Start value of k.
        k: f64,
    },
}

/// The content of `resources/neurarm.toml`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FmuSpec {
    /// Model identifier: the FMU's name and the name of its binary.
    pub identifier: String,
    /// The model.
    pub model: ModelSpec,
}

impl FmuSpec {
    /// A PlanarArm FMU of `config`, starting at rest at q = 0.
    pub fn planar_arm(identifier: &str, config: ArmConfig) -> Self {
        let n = config.arm.dof();
        Self { identifier: identifier.to_owned(), model: ModelSpec::PlanarArm { config, q0: vec![0.0; n], qd0: vec![0.0; n] } }
    }

    /// The model this spec describes, for specs that need no files beside them.
    pub fn build(&self) -> Result<Box<dyn Model>, String> {
        self.build_from(None)
    }

    /// The model this spec describes, reading any weights files from `resources`.
    pub fn build_from(&self, resources: Option<&Path>) -> Result<Box<dyn Model>, String> {
        check_identifier(&self.identifier)?;
        match &self.model {
            ModelSpec::PlanarArm { config, q0, qd0 } => Ok(Box::new(planar_arm::PlanarArmModel::new(
                &self.identifier,
                config.clone(),
                ArmState { q: q0.clone(), qd: qd0.clone() },
            )?)),
            ModelSpec::TaskSpaceController { model, gains, centre, q_start } => {
                Ok(Box::new(controllers::TaskSpaceControllerModel::new(&self.identifier, model.clone(), *gains, *centre, q_start)?))
            }
            ModelSpec::JointController { joints, kp, kd, use_sequence } => {
                Ok(Box::new(controllers::JointControllerModel::new(&self.identifier, *joints, *kp, *kd, *use_sequence)?))
            }
            ModelSpec::IdealCompensator { arm, enable_friction, enable_gravity } => {
                Ok(Box::new(controllers::IdealCompensatorModel::new(&self.identifier, arm.clone(), (*enable_friction, *enable_gravity))?))
            }
            ModelSpec::Integrator { y0 } => Ok(Box::new(signals::IntegratorModel::new(&self.identifier, *y0)?)),
            ModelSpec::Gain { k } => Ok(Box::new(signals::GainModel::new(&self.identifier, *k)?)),
            ModelSpec::NnCompensator { joints, friction, gravity, enable_friction, enable_gravity } => {
                let dir = resources.ok_or("the compensator reads its weights from resources/, and none was given")?;
                let mut crc = crc32fast::Hasher::new();
                let mut load = |name: &str| -> Result<WeightsFile, String> {
                    let path = dir.join(name);
                    let text = std::fs::read_to_string(&path).map_err(|e| format!("weights file {}: {e}", path.display()))?;
                    crc.update(text.as_bytes());
                    WeightsFile::from_json(&text, &path.display().to_string()).map_err(|e| e.to_string())
                };
                let friction = friction.iter().map(|f| load(f)).collect::<Result<Vec<_>, _>>()?;
                let gravity = gravity.as_deref().map(&mut load).transpose()?;
                Ok(Box::new(compensator::NnCompensatorModel::new(
                    &self.identifier,
                    *joints,
                    &friction,
                    gravity.as_ref(),
                    (*enable_friction, *enable_gravity),
                    crc.finalize(),
                )?))
            }
        }
    }

    /// Files this spec needs in `resources/`.
    pub fn resource_files(&self) -> Vec<String> {
        match &self.model {
            ModelSpec::NnCompensator { friction, gravity, .. } => friction.iter().chain(gravity).cloned().collect(),
            _ => Vec::new(),
        }
    }

    /// The model description this spec gives.
    pub fn description(&self) -> Result<ModelDescription, String> {
        Ok(self.build()?.description().clone())
    }

    /// The spec as TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("specs serialise to TOML")
    }

    /// Parses a spec.
    pub fn from_toml(text: &str) -> Result<Self, String> {
        toml::from_str(text).map_err(|e| e.to_string().trim_end().to_owned())
    }
}

/// A model identifier must be usable as a C identifier and a file name.
pub fn check_identifier(id: &str) -> Result<(), String> {
    let mut chars = id.chars();
    let ok = chars.next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_') && chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
    if ok {
        Ok(())
    } else {
        Err(format!("model identifier '{id}' must start with a letter or '_' and hold only letters, digits and '_'"))
    }
}

/// The factory behind every neurarm FMU binary: reads `resources/neurarm.toml`.
pub fn instantiate(resources: &Path) -> Result<Box<dyn Model>, String> {
    let path = resources.join(SPEC_FILE);
    let text = std::fs::read_to_string(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    let spec = FmuSpec::from_toml(&text).map_err(|e| format!("{}: {e}", path.display()))?;
    spec.build_from(Some(resources)).map_err(|e| format!("{}: {e}", path.display()))
}

/// Writes the FMU for `spec` to `path`, with the files it names taken from `sources` (app
/// builds only: needs the packager). The files are checked by building the model from them
/// exactly as the FMU will at instantiation.
#[cfg(feature = "app")]
pub fn export_fmu(spec: &FmuSpec, sources: &[(String, std::path::PathBuf)], path: &Path) -> Result<(), String> {
    let staging = tempfile::tempdir().map_err(|e| format!("temporary folder: {e}"))?;
    let mut resources = vec![(SPEC_FILE.to_owned(), spec.to_toml().into_bytes())];
    for name in spec.resource_files() {
        let source = sources.iter().find(|(n, _)| *n == name).map(|(_, p)| p).ok_or_else(|| format!("no source file given for {name}"))?;
        let bytes = std::fs::read(source).map_err(|e| format!("{}: {e}", source.display()))?;
        std::fs::write(staging.path().join(&name), &bytes).map_err(|e| format!("staging {name}: {e}"))?;
        resources.push((name, bytes));
    }
    let model = spec.build_from(Some(staging.path())).map_err(|e| {
        // Name the user's file, not the staging copy.
        sources.iter().fold(e, |e, (name, p)| e.replace(&staging.path().join(name).display().to_string(), &p.display().to_string()))
    })?;
    let binary = crate::fmi2::package::find_binary()?;
    let equations = match spec.model {
        ModelSpec::PlanarArm { .. } => planar_arm::EQUATIONS_HTML,
        ModelSpec::NnCompensator { .. } => compensator::EQUATIONS_HTML,
        ModelSpec::TaskSpaceController { .. } => controllers::TASK_SPACE_HTML,
        ModelSpec::JointController { .. } => controllers::JOINT_HTML,
        ModelSpec::IdealCompensator { .. } => controllers::IDEAL_HTML,
        ModelSpec::Integrator { .. } => signals::INTEGRATOR_HTML,
        ModelSpec::Gain { .. } => signals::GAIN_HTML,
    };
    let files: Vec<(&str, Vec<u8>)> = resources.iter().map(|(n, b)| (n.as_str(), b.clone())).collect();
    crate::fmi2::package::write_fmu(path, model.description(), &binary, &files, equations)
        .map_err(|e| format!("writing {}: {e}", path.display()))
}
