//! The system file (TOML) and the one piece of `modelDescription.xml` the `fmi` crate does
//! not keep: whether an output's `dependencies` attribute is absent (depends on every input)
//! or empty (depends on none).

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::{Algorithm, Value};

/// A system: FMUs, connections, and how to simulate it.
///
/// ```toml
/// [[fmu]]
/// name = "arm"
/// path = "PlanarArm.fmu"          # relative to the system file
/// parameters = { q0_1 = 0.3 }
///
/// [[connection]]
/// from = "arm.q_*"                # '*' matches the same text on both sides
/// to = "controller.q_*"
///
/// [simulation]
/// stop = 10.0
/// step = 0.001
/// record = ["arm.x", "arm.y"]
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SystemSpec {
    /// The units, in declaration order.
    pub fmu: Vec<FmuEntry>,
    /// Output → input connections.
    #[serde(default)]
    pub connection: Vec<ConnectionSpec>,
    /// Time span, step, algorithm, recording.
    pub simulation: SimulationSpec,
}

/// One FMU of a system.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FmuEntry {
    /// Unit name (instance name), used in connections as `name.variable`.
    pub name: String,
    /// Path of the `.fmu`, relative to the system file.
    pub path: String,
    /// Parameters (and unconnected inputs) to set before initialisation.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub parameters: BTreeMap<String, Value>,
}

/// A connection from an output to an input.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConnectionSpec {
    /// "unit.output".
    pub from: String,
    /// "unit.input".
    pub to: String,
}

/// How to simulate.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationSpec {
    /// Start time [s].
    #[serde(default)]
    pub start: f64,
    /// Stop time [s].
    pub stop: f64,
    /// Communication step [s].
    pub step: f64,
    /// Stepping algorithm.
    #[serde(default)]
    pub algorithm: Algorithm,
    /// Variables to record ("unit.variable").
    #[serde(default)]
    pub record: Vec<String>,
    /// Record every k-th communication point.
    #[serde(default = "one")]
    pub record_every: u64,
}

fn one() -> u64 {
    1
}

impl SystemSpec {
    /// Parses a system file's text; `origin` names it in messages.
    pub fn from_toml(text: &str, origin: &str) -> Result<Self, String> {
        let spec: Self = toml::from_str(text).map_err(|e| format!("{origin}: {}", e.to_string().trim_end()))?;
        let s = &spec.simulation;
        if !(s.step > 0.0 && s.step.is_finite()) || !(s.stop >= s.start) || !s.start.is_finite() || !s.stop.is_finite() {
            return Err(format!("{origin}: [simulation] needs a positive step and stop ≥ start (got start {}, stop {}, step {})", s.start, s.stop, s.step));
        }
        Ok(spec)
    }

    /// The system file's text; [`SystemSpec::from_toml`] reads it back unchanged (reals
    /// are written in their shortest exact form).
    pub fn to_toml(&self) -> Result<String, String> {
        toml::to_string(self).map_err(|e| format!("writing the system file: {e}"))
    }
}

/// Per output in `ModelStructure/Outputs`: its dependencies as 1-based variable indices, or
/// `None` when the attribute is absent (the output may depend on every input).
pub fn output_dependencies(xml: &str) -> Result<Vec<Option<Vec<u32>>>, String> {
    use quick_xml::events::Event;
    let mut reader = quick_xml::Reader::from_str(xml);
    let mut in_outputs = false;
    let mut found = Vec::new();
    loop {
        match reader.read_event().map_err(|e| e.to_string())? {
            Event::Start(e) if e.name().as_ref() == b"Outputs" => in_outputs = true,
            Event::End(e) if e.name().as_ref() == b"Outputs" => in_outputs = false,
            Event::Start(e) | Event::Empty(e) if in_outputs && e.name().as_ref() == b"Unknown" => {
                let mut deps = None;
                for a in e.attributes() {
                    let a = a.map_err(|e| e.to_string())?;
                    if a.key.as_ref() == b"dependencies" {
                        let text = a.unescape_value().map_err(|e| e.to_string())?;
                        let list = text
                            .split_whitespace()
                            .map(|t| t.parse::<u32>().map_err(|_| format!("dependencies: '{t}' is not an index")))
                            .collect::<Result<Vec<_>, _>>()?;
                        deps = Some(list);
                    }
                }
                found.push(deps);
            }
            Event::Eof => break,
            _ => {}
        }
    }
    Ok(found)
}
