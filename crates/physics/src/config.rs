//! An arm described in a TOML file: parameters, integrator settings and hardware-like effects.
//! The same file drives `neurarm simulate` and the arm FMU's export.

use std::path::Path;

use serde::{Deserialize, Serialize};

use crate::arm::{ArmParams, ArmSimulator, HardwareEffects, IntegratorSettings, ParamError, Sensors};

/// Everything needed to simulate one arm. Unknown keys are errors, so a misspelt parameter
/// cannot silently fall back to its default.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ArmConfig {
    /// Geometry, inertia, gravity and friction.
    pub arm: ArmParams,
    /// Integrator settings (default: 0.25 ms RK4 sub-steps).
    #[serde(default)]
    pub integrator: IntegratorSettings,
    /// Hardware-like effects (default: none).
    #[serde(default)]
    pub hardware: HardwareEffects,
}

/// Why a configuration file could not be used.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// The file could not be read. (The causes are fields of the message, not error sources,
    /// so a caller printing the chain does not print them twice.)
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        cause: std::io::Error,
    },
    /// The TOML is malformed or has an unknown or missing key.
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: String,
        /// The parser's message, with line and column.
        message: String,
    },
    /// A value is out of range.
    #[error("{path}: {problem}")]
    Invalid {
        /// The file.
        path: String,
        /// What is wrong.
        problem: ParamError,
    },
}

impl ArmConfig {
    /// Reads and checks a TOML file.
    pub fn from_toml_file(path: &Path) -> Result<Self, ConfigError> {
        let shown = path.display().to_string();
        let text = crate::text_file::read_text(path, crate::text_file::MAX_CONFIG_BYTES)
            .map_err(|cause| ConfigError::Io { path: shown.clone(), cause })?;
        Self::from_toml_str(&text).map_err(|e| match e {
            ConfigError::Parse { message, .. } => ConfigError::Parse { path: shown.clone(), message },
            ConfigError::Invalid { problem, .. } => ConfigError::Invalid { path: shown.clone(), problem },
            other => other,
        })
    }

    /// Parses and checks TOML text.
    pub fn from_toml_str(text: &str) -> Result<Self, ConfigError> {
        let config: Self =
            toml::from_str(text).map_err(|e| ConfigError::Parse { path: "<text>".into(), message: e.to_string().trim_end().to_owned() })?;
        config.validate().map_err(|problem| ConfigError::Invalid { path: "<text>".into(), problem })?;
        Ok(config)
    }

    /// The configuration as TOML text.
    pub fn to_toml_string(&self) -> String {
        toml::to_string_pretty(self).expect("every field serialises to TOML")
    }

    /// Checks every value, each within its [`limits`](crate::arm::params::limits) (the RK4
    /// sub-step between 1 ns and 1 s).
    pub fn validate(&self) -> Result<(), ParamError> {
        self.arm.validate()?;
        self.hardware.validate(self.arm.dof())?;
        let h = self.integrator.internal_step_s;
        let (shortest, longest) = crate::arm::params::limits::INTERNAL_STEP_S;
        let why = "must be between 1e-9 s and 1 s (limits::INTERNAL_STEP_S)";
        crate::arm::params::check(|| "integrator.internal_step_s".into(), h, h > 0.0, "must be > 0")?;
        crate::arm::params::check(|| "integrator.internal_step_s".into(), h, (shortest..=longest).contains(&h), why)
    }

    /// A simulator with the configured torque limits, and the configured sensors.
    pub fn build(&self) -> Result<(ArmSimulator, Sensors), ParamError> {
        self.validate()?;
        let mut sim = ArmSimulator::new(self.arm.clone(), self.integrator)?;
        sim.set_torque_limits(self.hardware.torque_limit_nm.clone())?;
        let sensors = Sensors::new(self.hardware.clone(), self.arm.dof())?;
        Ok((sim, sensors))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_config_round_trips_through_toml() {
        let c = ArmConfig::default();
        let back = ArmConfig::from_toml_str(&c.to_toml_string()).unwrap();
        assert_eq!(back, c);
    }

    #[test]
    fn unknown_key_and_bad_values_are_named() {
        let mut text = ArmConfig::default().to_toml_string();
        text = text.replacen("mass_kg = 2.0", "mass_kg = -2.0", 1);
        let e = ArmConfig::from_toml_str(&text).unwrap_err().to_string();
        assert!(e.contains("links[0].mass_kg = -2"), "{e}");
        let text = ArmConfig::default().to_toml_string().replacen("mass_kg", "mass", 1);
        let e = ArmConfig::from_toml_str(&text).unwrap_err().to_string();
        assert!(e.contains("unknown field `mass`"), "{e}");
    }
}
