//! The committed `modelDescription/*.xml` files (FMI 2.0) and `*.fmi3.xml` (the FMI 3.0 twins)
//! are what the code generates (nobody edits them by hand). To accept a deliberate change of a model's interface, run
//! `NEURARM_UPDATE_MODEL_DESCRIPTIONS=1 cargo test --test model_description` and commit.

use std::path::Path;

use neurarm_fmi_export::description::Causality;
use neurarm_models::FmuSpec;
use neurarm_physics::config::ArmConfig;

fn check(name: &str, spec: FmuSpec) {
    let description = spec.description().unwrap();
    compare(&format!("{name}.xml"), &description.to_xml());
    compare(&format!("{name}.fmi3.xml"), &neurarm_fmi_export::fmi3::description::to_xml(&description));
}

fn compare(file: &str, xml: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("modelDescription").join(file);
    if std::env::var_os("NEURARM_UPDATE_MODEL_DESCRIPTIONS").is_some() {
        std::fs::write(&path, xml).unwrap();
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
    let outputs: Vec<usize> =
        d.variables.iter().enumerate().filter(|(_, v)| v.causality == Causality::Output).map(|(i, _)| i + 1).collect();
    assert_eq!(outputs.len(), 4 + 4 + 4 + 8);
    // Read the Outputs section back and compare with the table.
    let start = xml.find("<Outputs>").unwrap();
    let end = xml.find("</Outputs>").unwrap();
    let indices: Vec<usize> = xml[start..end].split("index=\"").skip(1).map(|s| s[..s.find('"').unwrap()].parse().unwrap()).collect();
    assert_eq!(indices, outputs);
    assert_eq!(d.variables[outputs[0] - 1].name, "q_1");
    // The arm has no direct feedthrough: torques act through the state.
    assert!(xml[start..end].contains("dependencies=\"\""));
    assert!(!xml.contains("canHandleMultipleSetPerTimeInstant"));
    assert!(xml.contains("canNotUseMemoryManagementFunctions=\"true\""));
}

#[test]
fn fmi3_value_references_are_positions_and_unique() {
    let d = FmuSpec::planar_arm("PlanarArm", ArmConfig::default()).description().unwrap();
    let xml = neurarm_fmi_export::fmi3::description::to_xml(&d);
    let start = xml.find("<ModelVariables>").unwrap();
    let end = xml.find("</ModelVariables>").unwrap();
    let vrs: Vec<u32> = xml[start..end].split("valueReference=\"").skip(1).map(|s| s[..s.find('"').unwrap()].parse().unwrap()).collect();
    assert_eq!(vrs, (0..d.variables.len() as u32).collect::<Vec<_>>());
    // The Integer noise_seed shares FMI 2.0 value reference 0 with time; in FMI 3.0 they differ.
    let seed = d.variables.iter().position(|v| v.name == "noise_seed").unwrap();
    assert_eq!(d.variables[seed].value_reference, 0);
    assert!(xml.contains(&format!("<Int32 name=\"noise_seed\" valueReference=\"{seed}\"")));
    let structure = &xml[xml.find("<ModelStructure>").unwrap()..];
    let outputs: Vec<usize> = d.variables.iter().enumerate().filter(|(_, v)| v.causality == Causality::Output).map(|(i, _)| i).collect();
    let listed: Vec<usize> =
        structure.split("<Output valueReference=\"").skip(1).map(|s| s[..s.find('"').unwrap()].parse().unwrap()).collect();
    assert_eq!(listed, outputs);
    assert!(xml.contains(&format!("instantiationToken=\"{}\"", d.guid())));
    assert!(!xml.contains("canNotUseMemoryManagementFunctions"), "not an FMI 3.0 attribute");
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

/// Fixed, formula-made weights (no training, so the file is the same on every machine).
fn fixed_weights(n_in: usize, hidden: usize, n_out: usize, names: (&str, &str)) -> neurarm_nn::WeightsFile {
    use nalgebra::{DMatrix, DVector};
    use neurarm_nn::{MinMaxScaling, Mlp, Signal, TrainReport, TrainSettings, WeightsFile};
    // Exact binary fractions: the same bits on every machine, whatever its libm.
    let f = |a: usize, b: usize, c: f64| ((a * 7 + b * 3) % 11) as f64 / 8.0 - 0.625 + c;
    let net = Mlp {
        iw: DMatrix::from_fn(hidden, n_in, |j, i| f(j, i, 0.125)),
        b1: DVector::from_fn(hidden, |j, _| f(j, 0, 0.25)),
        lw: DMatrix::from_fn(n_out, hidden, |k, j| f(k, j, 0.375)),
        b2: DVector::from_fn(n_out, |k, _| f(k, 0, 0.5)),
        input_scaling: MinMaxScaling { min: vec![-5.0; n_in], max: vec![5.0; n_in] },
        output_scaling: MinMaxScaling { min: vec![-2.0; n_out], max: vec![2.0; n_out] },
    };
    let sig = |p: &str, u: &str, n: usize| (1..=n).map(|i| Signal { name: format!("{p}_{i}"), unit: u.into() }).collect();
    let report = TrainReport {
        epochs: 0,
        best_epoch: 0,
        stop_reason: neurarm_nn::StopReason::Epochs,
        restart: 0,
        train_mse: 0.0,
        validation_mse: None,
        test_mse: None,
        counts: [0, 0, 0],
    };
    let input_unit = if names.0 == "qd" { "rad/s" } else { "rad" };
    WeightsFile::new(&net, sig(names.0, input_unit, n_in), sig(names.1, "N.m", n_out), TrainSettings::default(), report)
}

/// The friction net of `joint`: the fixed weights, shifted by a binary fraction per joint (the
/// compensator refuses one net given for two joints), named and marked for that joint.
fn fixed_friction(joint: usize) -> neurarm_nn::WeightsFile {
    let mut file = fixed_weights(1, 3, 1, ("qd", "tau_friction")).friction_of_joint(joint);
    file.b2[0] += 0.125 * joint as f64;
    file.inputs[0].name = format!("qd_{joint}");
    file.outputs[0].name = format!("tau_friction_{joint}");
    file
}

#[test]
fn nn_compensator_model_description_has_not_drifted() {
    use neurarm_models::{ModelSpec, NnCompensatorSpec};
    let dir = tempfile::tempdir().unwrap();
    let mut friction = Vec::new();
    for j in 1..=4 {
        let name = format!("friction_{j}.json");
        std::fs::write(dir.path().join(&name), fixed_friction(j).to_json()).unwrap();
        friction.push(name);
    }
    std::fs::write(dir.path().join("gravity.json"), fixed_weights(4, 5, 4, ("q", "tau_gravity")).gravity().to_json()).unwrap();
    let spec = FmuSpec {
        identifier: "NnCompensator".into(),
        model: ModelSpec::NnCompensator(NnCompensatorSpec {
            joints: 4,
            friction,
            gravity: Some("gravity.json".into()),
            enable_friction: true,
            enable_gravity: true,
        }),
    };
    let model = spec.build_from(Some(dir.path())).unwrap();
    compare("NnCompensator.xml", &model.description().to_xml());
    compare("NnCompensator.fmi3.xml", &neurarm_fmi_export::fmi3::description::to_xml(model.description()));
}

/// A friction net whose input is encoded as angles is refused by name; a periodic gravity net
/// is taken, and its first layer is checked against the encoded inputs.
#[test]
fn nn_compensator_checks_the_encodings_of_its_nets() {
    use neurarm_models::{ModelSpec, NnCompensatorSpec};
    use neurarm_nn::InputEncoding;
    let dir = tempfile::tempdir().unwrap();
    let build = |friction: &neurarm_nn::WeightsFile, gravity: &neurarm_nn::WeightsFile| {
        std::fs::write(dir.path().join("friction_1.json"), friction.to_json()).unwrap();
        std::fs::write(dir.path().join("friction_2.json"), fixed_friction(2).to_json()).unwrap();
        std::fs::write(dir.path().join("gravity.json"), gravity.to_json()).unwrap();
        let spec = FmuSpec {
            identifier: "NnCompensator".into(),
            model: ModelSpec::NnCompensator(NnCompensatorSpec {
                joints: 2,
                friction: vec!["friction_1.json".into(), "friction_2.json".into()],
                gravity: Some("gravity.json".into()),
                enable_friction: true,
                enable_gravity: true,
            }),
        };
        spec.build_from(Some(dir.path())).map(|_| ()).map_err(|e| e.to_string())
    };
    let friction = fixed_friction(1);
    let periodic_gravity = fixed_weights(4, 5, 2, ("q", "tau"));
    let periodic_gravity = neurarm_nn::WeightsFile {
        inputs: periodic_gravity.inputs[..2].to_vec(),
        ..periodic_gravity.with_encoding(InputEncoding::LinkAngles)
    };
    build(&friction, &periodic_gravity).unwrap();
    let two = fixed_weights(2, 3, 1, ("qd", "tau"));
    let angle_friction =
        neurarm_nn::WeightsFile { inputs: two.inputs[..1].to_vec(), ..two.clone().with_encoding(InputEncoding::JointAngles) };
    let e = build(&angle_friction, &periodic_gravity).unwrap_err();
    assert!(e.contains("friction net of joint 1") && e.contains("joint_angles"), "{e}");
    let raw_shaped = fixed_weights(2, 5, 2, ("q", "tau")).with_encoding(InputEncoding::LinkAngles);
    let e = build(&friction, &raw_shaped).unwrap_err();
    assert!(e.contains("iw row 0 has 2 values, expected 4"), "{e}");
    // The resources are checked as `export compensator` checks its files, named by file.
    let e = build(&fixed_friction(2), &periodic_gravity).unwrap_err();
    assert!(e.contains("friction_1.json is the friction net of joint 2"), "{e}");
    let e = build(&friction, &fixed_friction(1)).unwrap_err();
    assert!(e.contains("gravity.json is the friction net of joint 1, given as the gravity net"), "{e}");
}
