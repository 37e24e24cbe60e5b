//! The committed `modelDescription/*.xml` files are what the code generates (nobody edits
//! them by hand). To accept a deliberate change of a model's interface, run
//! `NEURARM_UPDATE_MODEL_DESCRIPTIONS=1 cargo test --test model_description` and commit.

use std::path::Path;

use neurarm::config::ArmConfig;
use neurarm::fmi2::description::Causality;
use neurarm::models::FmuSpec;

fn check(name: &str, spec: FmuSpec) {
    let xml = spec.description().unwrap().to_xml();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("modelDescription").join(format!("{name}.xml"));
    if std::env::var_os("NEURARM_UPDATE_MODEL_DESCRIPTIONS").is_some() {
        std::fs::write(&path, &xml).unwrap();
    }
    let committed = std::fs::read_to_string(&path).unwrap_or_default();
    assert!(
        committed == xml,
        "{} differs from the generated model description; if the change is intended, run \
         NEURARM_UPDATE_MODEL_DESCRIPTIONS=1 cargo test --test model_description",
        path.display()
    );
}

#[test]
fn planar_arm_model_description_has_not_drifted() {
    check("PlanarArm", FmuSpec::planar_arm("PlanarArm", ArmConfig::default()));
}

#[test]
fn model_structure_indices_are_one_based_positions_of_outputs() {
    let d = FmuSpec::planar_arm("PlanarArm", ArmConfig::default()).description().unwrap();
    let xml = d.to_xml();
    let outputs: Vec<usize> = d.variables.iter().enumerate().filter(|(_, v)| v.causality == Causality::Output).map(|(i, _)| i + 1).collect();
    assert_eq!(outputs.len(), 4 + 4 + 4 + 8);
    // Read the Outputs section back and compare with the table.
    let start = xml.find("<Outputs>").unwrap();
    let end = xml.find("</Outputs>").unwrap();
    let indices: Vec<usize> = xml[start..end]
        .split("index=\"")
        .skip(1)
        .map(|s| s[..s.find('"').unwrap()].parse().unwrap())
        .collect();
    assert_eq!(indices, outputs);
    assert_eq!(d.variables[outputs[0] - 1].name, "q_1");
    // The arm has no direct feedthrough: torques act through the state.
    assert!(xml[start..end].contains("dependencies=\"\""));
    assert!(!xml.contains("canHandleMultipleSetPerTimeInstant"));
    assert!(xml.contains("canNotUseMemoryManagementFunctions=\"true\""));
}

#[test]
fn guid_changes_with_any_start_value() {
    let a = FmuSpec::planar_arm("PlanarArm", ArmConfig::default()).description().unwrap().guid();
    let mut c = ArmConfig::default();
    c.arm.links[2].mass_kg += 1e-9;
    let b = FmuSpec::planar_arm("PlanarArm", c).description().unwrap().guid();
    assert_ne!(a, b);
    assert_eq!(a, FmuSpec::planar_arm("PlanarArm", ArmConfig::default()).description().unwrap().guid());
}
