//! The models neurarm ships as FMUs, and the factory the FMU binary uses to make them.
//!
//! Every `.fmu` carries the same binary and a spec file, `resources/neurarm.toml`, that says
//! which model it is and with which parameters; [`instantiate`] reads it. The GUID in the
//! model description is a hash of the description made from that spec, so a binary, spec and
//! XML that do not belong together are refused at instantiation.

pub mod planar_arm;

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::arm::ArmState;
use crate::config::ArmConfig;
use crate::fmi2::description::ModelDescription;
use crate::fmi2::model::Model;

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

    /// The model this spec describes.
    pub fn build(&self) -> Result<Box<dyn Model>, String> {
        check_identifier(&self.identifier)?;
        match &self.model {
            ModelSpec::PlanarArm { config, q0, qd0 } => Ok(Box::new(planar_arm::PlanarArmModel::new(
                &self.identifier,
                config.clone(),
                ArmState { q: q0.clone(), qd: qd0.clone() },
            )?)),
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
    spec.build().map_err(|e| format!("{}: {e}", path.display()))
}

/// Writes the FMU for `spec` to `path` (app builds only: needs the packager).
#[cfg(feature = "app")]
pub fn export_fmu(spec: &FmuSpec, path: &Path) -> Result<(), String> {
    let model = spec.build()?;
    let binary = crate::fmi2::package::find_binary()?;
    let equations = match spec.model {
        ModelSpec::PlanarArm { .. } => planar_arm::EQUATIONS_HTML,
    };
    crate::fmi2::package::write_fmu(path, model.description(), &binary, &[(SPEC_FILE, spec.to_toml().into_bytes())], equations)
        .map_err(|e| format!("writing {}: {e}", path.display()))
}
