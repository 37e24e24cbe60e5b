//! The models neurarm ships as FMUs, on the [`neurarm_fmi_export`] layer, and the registry the one
//! FMU binary uses to make them.
//!
//! Every `.fmu` carries the same binary and a spec file, `resources/neurarm.toml`, that says
//! which model it is and with which parameters; [`instantiate`] reads it. The GUID in the
//! model description is a hash of the description made from that spec, so a binary, spec and
//! XML that do not belong together are refused at instantiation.
//!
//! One model kind is one file here: its spec (the `[model]` table of the spec file), its
//! model, and the [`ModelKind`] entry that builds it, names its resource files and documents
//! its equations. [`ModelSpec`] lists the kinds.

#![forbid(unsafe_code)]

pub mod adaptive;
pub mod compensator;
pub mod ideal;
pub mod joint;
pub mod names;
pub mod planar_arm;
pub mod ports;
pub mod signals;
pub mod task_space;
pub mod units;

use std::path::{Path, PathBuf};

use neurarm_fmi_export::{DefaultExperiment, DescriptionError, Model, ModelDescription, ModelError, RealVar, TableBuilder, Variable};
use serde::{Deserialize, Serialize};

pub use adaptive::{AdaptationLaw, AdaptiveCompensatorSpec};
pub use compensator::{check_compensator_nets, NetsError, NnCompensatorSpec};
pub use ideal::IdealCompensatorSpec;
pub use joint::JointControllerSpec;
pub use planar_arm::PlanarArmSpec;
pub use signals::{GainSpec, IntegratorSpec};
pub use task_space::TaskSpaceControllerSpec;

/// Name of the spec file in an FMU's `resources/` folder.
pub const SPEC_FILE: &str = "neurarm.toml";

/// Why a model could not be built from its spec.
#[derive(Debug, thiserror::Error)]
pub enum BuildError {
    /// The variable table is not a valid FMU interface (e.g. a bad model identifier).
    #[error(transparent)]
    Description(#[from] DescriptionError),
    /// The arm's parameters are out of range.
    #[error(transparent)]
    Params(#[from] neurarm_physics::arm::ParamError),
    /// The spec is inconsistent.
    #[error("{0}")]
    Spec(String),
    /// The compensator's nets do not fit together.
    #[error(transparent)]
    Nets(#[from] NetsError),
    /// The adaptation law's parameters are out of range.
    #[error(transparent)]
    Law(#[from] adaptive::LawError),
    /// The spec file is no valid spec.
    #[error(transparent)]
    SpecFile(#[from] SpecFileError),
    /// A weights file is missing or invalid.
    #[error("weights file {path}: {message}")]
    Weights {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The model needs files from `resources/` and none was given.
    #[error("the compensator reads its weights from resources/, and none was given")]
    NoResources,
}

/// One kind of model: how to build it from its spec, which files it needs beside the spec
/// in `resources/`, and its equations for `documentation/index.html`.
pub trait ModelKind {
    /// The model called `identifier`, reading the files it names from `resources`.
    fn build(&self, identifier: &str, resources: Option<&Path>) -> Result<Box<dyn Model>, BuildError>;

    /// Files this model reads from `resources/`.
    fn resource_files(&self) -> Vec<String> {
        Vec::new()
    }

    /// The model's equations as an HTML fragment.
    fn equations_html(&self) -> &'static str;
}

/// Which model an FMU holds, and its parameters: the `[model]` table of the spec file, with
/// `kind` naming the variant.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind")]
pub enum ModelSpec {
    /// The planar arm.
    PlanarArm(PlanarArmSpec),
    /// The NN compensator; weights files live beside the spec in `resources/`.
    NnCompensator(NnCompensatorSpec),
    /// The NN compensator whose output layers keep learning; weights files as the NN one's.
    AdaptiveCompensator(AdaptiveCompensatorSpec),
    /// Task-space computed-torque controller with the paper's reference.
    TaskSpaceController(TaskSpaceControllerSpec),
    /// Joint-space P(D) controller with a compensation input.
    JointController(JointControllerSpec),
    /// The true friction and gravity of an arm, as a compensator.
    IdealCompensator(IdealCompensatorSpec),
    /// Test block y' = u.
    Integrator(IntegratorSpec),
    /// Test block y = k u.
    Gain(GainSpec),
}

impl ModelSpec {
    /// The registry entry of this kind.
    pub fn kind(&self) -> &dyn ModelKind {
        match self {
            ModelSpec::PlanarArm(s) => s,
            ModelSpec::NnCompensator(s) => s,
            ModelSpec::AdaptiveCompensator(s) => s,
            ModelSpec::TaskSpaceController(s) => s,
            ModelSpec::JointController(s) => s,
            ModelSpec::IdealCompensator(s) => s,
            ModelSpec::Integrator(s) => s,
            ModelSpec::Gain(s) => s,
        }
    }
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
    pub fn planar_arm(identifier: &str, config: neurarm_physics::config::ArmConfig) -> Self {
        let n = config.arm.dof();
        Self {
            identifier: identifier.to_owned(),
            model: ModelSpec::PlanarArm(PlanarArmSpec { config, q0: vec![0.0; n], qd0: vec![0.0; n] }),
        }
    }

    /// The model this spec describes, for specs that need no files beside them.
    pub fn build(&self) -> Result<Box<dyn Model>, BuildError> {
        self.build_from(None)
    }

    /// The model this spec describes, reading any files it names from `resources`.
    pub fn build_from(&self, resources: Option<&Path>) -> Result<Box<dyn Model>, BuildError> {
        self.model.kind().build(&self.identifier, resources)
    }

    /// Files this spec needs in `resources/`.
    pub fn resource_files(&self) -> Vec<String> {
        self.model.kind().resource_files()
    }

    /// The model's equations as an HTML fragment, for `documentation/index.html`.
    pub fn equations_html(&self) -> &'static str {
        self.model.kind().equations_html()
    }

    /// The model description this spec gives.
    pub fn description(&self) -> Result<ModelDescription, BuildError> {
        Ok(self.build()?.description().clone())
    }

    /// The spec as TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).expect("specs serialise to TOML")
    }

    /// Parses a spec.
    pub fn from_toml(text: &str) -> Result<Self, SpecFileError> {
        toml::from_str(text).map_err(SpecFileError)
    }
}

/// A spec file that is no valid spec (TOML syntax, an unknown key or kind, a wrong type). Its
/// message is the TOML parser's, with line and column.
#[derive(Debug, thiserror::Error)]
#[error("{}", .0.to_string().trim_end())]
pub struct SpecFileError(toml::de::Error);

/// The factory behind every neurarm FMU binary: reads `resources/neurarm.toml`.
pub fn instantiate(resources: Option<&Path>) -> Result<Box<dyn Model>, ModelError> {
    let resources = resources.ok_or_else(|| ModelError::msg("the resource location is NULL: this FMU reads its model from resources/"))?;
    if !resources.is_dir() {
        return Err(ModelError::msg(format!("resource folder '{}' does not exist", resources.display())));
    }
    let path = resources.join(SPEC_FILE);
    let text = neurarm_physics::text_file::read_text(&path, neurarm_physics::text_file::MAX_CONFIG_BYTES)
        .map_err(|e| ModelError::msg(format!("cannot read {}: {e}", path.display())))?;
    let spec = FmuSpec::from_toml(&text).map_err(|e| ModelError::msg(format!("{}: {e}", path.display())))?;
    spec.build_from(Some(resources)).map_err(|e| ModelError::msg(format!("{}: {e}", path.display())))
}

/// The path of the file `name` in `resources`: a plain file name, so a spec cannot make the
/// FMU read files outside its own resources (`../../secret`, `/etc/passwd`).
pub(crate) fn resource_file(resources: &Path, name: &str) -> Result<PathBuf, BuildError> {
    let mut parts = Path::new(name).components();
    match (parts.next(), parts.next()) {
        (Some(std::path::Component::Normal(part)), None) if part == name => Ok(resources.join(name)),
        _ => Err(BuildError::Spec(format!("resource file '{name}' is not a plain file name in resources/"))),
    }
}

/// One real variable per joint, made by `add(b, i)` for i = 0 … n − 1 (variable `…_{i + 1}`).
pub(crate) fn per_joint(b: &mut TableBuilder, n: usize, add: impl Fn(&mut TableBuilder, usize) -> RealVar) -> Vec<RealVar> {
    (0..n).map(|i| add(b, i)).collect()
}

/// A neurarm model description: generated by neurarm, suggesting 0 to 10 s at a 1 ms step.
/// A start value that is not a finite number (a spec saying `k = nan`) is refused by name.
pub(crate) fn describe(identifier: &str, text: String, variables: Vec<Variable>) -> Result<ModelDescription, BuildError> {
    for v in &variables {
        if let neurarm_fmi_export::Kind::Real { start: Some(start), .. } = v.kind {
            if !start.is_finite() {
                return Err(BuildError::Spec(format!("the start value of '{}' is {start}, not a finite number", v.name)));
            }
        }
    }
    Ok(ModelDescription::new(identifier, text, variables)?
        .with_generation_tool(concat!("neurarm ", env!("CARGO_PKG_VERSION")))
        .with_default_experiment(DefaultExperiment { start_time: 0.0, stop_time: 10.0, step_size: 1e-3 }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_round_trip_and_refuse_unknown_keys() {
        let spec = FmuSpec { identifier: "Gain".into(), model: ModelSpec::Gain(GainSpec { k: 2.5 }) };
        let text = spec.to_toml();
        assert!(text.contains("kind = \"Gain\""), "{text}");
        assert_eq!(FmuSpec::from_toml(&text).unwrap(), spec);
        let e = FmuSpec::from_toml(&text.replace("k = 2.5", "k = 2.5\ngain = 3.0")).unwrap_err();
        assert!(e.to_string().contains("unknown field `gain`"), "{e}");
        let e = FmuSpec::from_toml(&text.replace("kind = \"Gain\"", "kind = \"Wheel\"")).unwrap_err();
        assert!(e.to_string().contains("Wheel"), "{e}");
    }

    #[test]
    fn a_start_value_that_is_not_finite_is_refused_when_the_model_is_built() {
        // Found by fuzzing the resources: the layer refused the instance while the spec built.
        for k in ["nan", "inf", "-inf"] {
            let spec = FmuSpec::from_toml(&format!("identifier = \"G\"\n[model]\nkind = \"Gain\"\nk = {k}\n")).unwrap();
            let e = spec.build().err().expect("refused").to_string();
            assert!(e.starts_with("the start value of 'k' is") && e.ends_with("not a finite number"), "{e}");
        }
    }

    #[test]
    fn a_bad_identifier_is_refused_by_name() {
        let spec = FmuSpec { identifier: "my-gain".into(), model: ModelSpec::Gain(GainSpec { k: 1.0 }) };
        let e = spec.build().err().unwrap().to_string();
        assert!(e.contains("model identifier 'my-gain'"), "{e}");
    }
}
