//! The adaptive compensator: with adaptation off it is the NN compensator bit for bit; one
//! step of the law moves each torque by γ h s |φ|² (φ computed here from the weights file);
//! the projection bounds every torque's change; the leakage pulls the nets back; the adapted
//! weights are FMU state.

use neurarm_test_support::nets;

use nets::net_file;
use neurarm_fmi_export::instance::{Instance, Status};
use neurarm_models::*;
use neurarm_nn::WeightsFile;

struct Fixture {
    dir: tempfile::TempDir,
    friction: Vec<WeightsFile>,
}

fn fixture() -> Fixture {
    let dir = tempfile::tempdir().unwrap();
    let mut friction = Vec::new();
    for j in 1..=2 {
        let mut net = net_file(1, 5, 1);
        net.b2[0] += 0.1 * j as f64;
        std::fs::write(dir.path().join(format!("friction_{j}.json")), net.to_json()).unwrap();
        friction.push(net);
    }
    std::fs::write(dir.path().join("gravity.json"), net_file(2, 4, 2).to_json()).unwrap();
    Fixture { dir, friction }
}

fn instance(f: &Fixture, model: ModelSpec) -> Instance {
    let built = FmuSpec { identifier: "C".into(), model }.build_from(Some(f.dir.path())).unwrap();
    let guid = built.description().guid();
    let mut i = Instance::new("probe", &guid, built, Box::new(|_, _, m| eprintln!("{m}")), false).unwrap();
    assert_eq!(i.setup_experiment(None, 0.0, None), Status::Ok);
    assert_eq!(i.enter_initialization_mode(), Status::Ok);
    assert_eq!(i.exit_initialization_mode(), Status::Ok);
    i
}

fn adaptive(law: AdaptationLaw) -> ModelSpec {
    ModelSpec::AdaptiveCompensator(AdaptiveCompensatorSpec {
        joints: 2,
        friction: vec!["friction_1.json".into(), "friction_2.json".into()],
        gravity: Some("gravity.json".into()),
        enable_friction: true,
        enable_gravity: true,
        law,
    })
}

fn vr(i: &Instance, name: &str) -> u32 {
    i.description().variables.iter().find(|v| v.name == name).unwrap_or_else(|| panic!("no {name}")).value_reference
}

fn set(i: &mut Instance, names: &[&str], values: &[f64]) {
    let vrs: Vec<u32> = names.iter().map(|n| vr(i, n)).collect();
    assert_eq!(i.set_real(&vrs, values), Status::Ok);
}

fn get(i: &mut Instance, names: &[&str]) -> Vec<f64> {
    let vrs: Vec<u32> = names.iter().map(|n| vr(i, n)).collect();
    let mut out = vec![0.0; vrs.len()];
    assert_eq!(i.get_real(&vrs, &mut out), Status::Ok);
    out
}

const INPUTS: [&str; 4] = ["q_1", "q_2", "qd_1", "qd_2"];
const TORQUES: [&str; 6] = ["tau_friction_1", "tau_friction_2", "tau_gravity_1", "tau_gravity_2", "tau_comp_1", "tau_comp_2"];

#[test]
fn with_adaptation_off_it_is_the_nn_compensator_bit_for_bit() {
    let f = fixture();
    let mut a = instance(&f, adaptive(AdaptationLaw { adapt: false, ..AdaptationLaw::default() }));
    let mut n = instance(
        &f,
        ModelSpec::NnCompensator(NnCompensatorSpec {
            joints: 2,
            friction: vec!["friction_1.json".into(), "friction_2.json".into()],
            gravity: Some("gravity.json".into()),
            enable_friction: true,
            enable_gravity: true,
        }),
    );
    for k in 0..300 {
        let t = k as f64 * 1e-3;
        let x = [2.0 * (3.0 * t).sin(), -7.0 + 0.1 * k as f64, 1.5 * (5.0 * t).cos(), -0.8];
        set(&mut a, &INPUTS, &x);
        set(&mut n, &INPUTS, &x);
        set(&mut a, &["s_1", "s_2"], &[3.0, -2.0]);
        assert_eq!(a.do_step(t, 1e-3), Status::Ok);
        assert_eq!(n.do_step(t, 1e-3), Status::Ok);
        let (ya, yn) = (get(&mut a, &TORQUES), get(&mut n, &TORQUES));
        assert_eq!(ya.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), yn.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), "step {k}");
    }
}

/// |φ|² of a friction net at velocity v, from the weights file: Σ tanh(iw·x̃ + b1)² + 1.
fn phi_squared(net: &WeightsFile, v: f64) -> f64 {
    let (min, max) = (net.input_scaling.min[0], net.input_scaling.max[0]);
    let x = 2.0 * (v - min) / (max - min) - 1.0;
    net.iw.iter().zip(&net.b1).map(|(w, b)| (w[0] * x + b).tanh().powi(2)).sum::<f64>() + 1.0
}

#[test]
fn one_step_of_the_law_moves_the_torque_by_gain_step_signal_and_the_regressor_norm() {
    let f = fixture();
    let law = AdaptationLaw { leakage: 0.0, bound_friction: 1e3, gain_friction: 4.0, ..AdaptationLaw::default() };
    let mut a = instance(&f, adaptive(law));
    set(&mut a, &INPUTS, &[0.2, -0.4, 0.7, -1.3]);
    let before = get(&mut a, &["tau_friction_1", "tau_friction_2"]);
    set(&mut a, &["s_1", "s_2"], &[0.5, -0.25]);
    let h = 2e-3;
    assert_eq!(a.do_step(0.0, h), Status::Ok);
    let after = get(&mut a, &["tau_friction_1", "tau_friction_2"]);
    for (j, (v, s)) in [(0.7, 0.5), (-1.3, -0.25)].into_iter().enumerate() {
        let expected = 4.0 * h * s * phi_squared(&f.friction[j], v);
        let moved = after[j] - before[j];
        assert!((moved - expected).abs() < 1e-12 * (1.0 + expected.abs()), "joint {}: {moved} vs {expected}", j + 1);
    }
}

#[test]
fn no_torque_moves_further_than_the_bound_whatever_the_signal() {
    let f = fixture();
    let law = AdaptationLaw { gain_friction: 1e4, gain_gravity: 1e4, bound_friction: 0.3, bound_gravity: 0.2, ..AdaptationLaw::default() };
    let mut a = instance(&f, adaptive(law));
    let mut off = instance(&f, adaptive(AdaptationLaw { adapt: false, ..law }));
    for k in 0..500 {
        let t = k as f64 * 1e-3;
        let x = [3.0 * (2.0 * t).sin(), (7.0 * t).cos(), 2.5 * (3.0 * t).sin(), -2.0 * (1.3 * t).cos()];
        set(&mut a, &INPUTS, &x);
        set(&mut a, &["s_1", "s_2"], &[50.0 * (11.0 * t).sin(), -80.0]);
        assert_eq!(a.do_step(t, 1e-3), Status::Ok);
    }
    let reach = get(&mut a, &["adapted_friction_1", "adapted_friction_2", "adapted_gravity_1", "adapted_gravity_2"]);
    assert!(reach[0] > 0.29 && reach[0] <= 0.3 + 1e-12 && reach[3] > 0.19 && reach[3] <= 0.2 + 1e-12, "{reach:?}");
    // Probe both at many inputs (no learning signal, so probing changes nothing).
    set(&mut a, &["s_1", "s_2"], &[0.0, 0.0]);
    for k in 0..200 {
        let x = [-4.0 + 0.04 * k as f64, 3.0 - 0.03 * k as f64, -5.0 + 0.05 * k as f64, 4.0 - 0.04 * k as f64];
        set(&mut a, &INPUTS, &x);
        set(&mut off, &INPUTS, &x);
        let (ya, yo) = (get(&mut a, &TORQUES), get(&mut off, &TORQUES));
        for j in 0..2 {
            assert!((ya[j] - yo[j]).abs() <= 0.3 + 1e-12, "friction {j} at {x:?}: {} vs {}", ya[j], yo[j]);
            assert!((ya[2 + j] - yo[2 + j]).abs() <= 0.2 + 1e-12, "gravity {j} at {x:?}");
        }
    }
}

#[test]
fn the_leakage_pulls_the_nets_back_to_the_offline_ones() {
    let f = fixture();
    let law = AdaptationLaw { leakage: 2.0, bound_friction: 1e3, bound_gravity: 1e3, ..AdaptationLaw::default() };
    let mut a = instance(&f, adaptive(law));
    set(&mut a, &INPUTS, &[0.3, 0.1, 0.9, -0.4]);
    set(&mut a, &["s_1", "s_2"], &[1.0, 1.0]);
    for k in 0..100 {
        assert_eq!(a.do_step(k as f64 * 1e-3, 1e-3), Status::Ok);
    }
    let learned = get(&mut a, &["adapted_friction_1"])[0];
    set(&mut a, &["s_1", "s_2"], &[0.0, 0.0]);
    for k in 100..1100 {
        assert_eq!(a.do_step(k as f64 * 1e-3, 1e-3), Status::Ok);
    }
    let left = get(&mut a, &["adapted_friction_1"])[0];
    // Without a signal the distance shrinks by (1 − σh) each step: e^(−2) after 1 s.
    let expected = learned * (1.0f64 - 2e-3).powi(1000);
    assert!(learned > 0.0 && (left - expected).abs() < 1e-9 * learned, "{learned} → {left}, expected {expected}");
}

#[test]
fn the_adapted_weights_are_fmu_state() {
    let f = fixture();
    let mut a = instance(&f, adaptive(AdaptationLaw::default()));
    let run = |a: &mut Instance, from: usize, to: usize| -> Vec<f64> {
        for k in from..to {
            let t = k as f64 * 1e-3;
            set(a, &INPUTS, &[(3.0 * t).sin(), 0.5, 1.2 * (2.0 * t).cos(), -0.7]);
            set(a, &["s_1", "s_2"], &[(5.0 * t).sin(), 0.3]);
            assert_eq!(a.do_step(t, 1e-3), Status::Ok);
        }
        get(a, &TORQUES)
    };
    run(&mut a, 0, 200);
    let saved = a.get_state().unwrap();
    let bytes = a.serialize(&saved).unwrap();
    let first = run(&mut a, 200, 400);
    assert_eq!(a.set_state(&saved), Status::Ok);
    assert_eq!(run(&mut a, 200, 400), first, "restored, the learning goes on the same way");
    let mut other = instance(&f, adaptive(AdaptationLaw::default()));
    let restored = other.deserialize(&bytes).unwrap();
    assert_eq!(other.set_state(&restored), Status::Ok);
    assert_eq!(run(&mut other, 200, 400), first, "and in another instance, from the serialized state");
    assert_eq!(a.reset(), Status::Ok);
}

#[test]
fn the_adapted_nets_are_written_at_terminate_and_make_the_same_nn_compensator() {
    let f = fixture();
    let mut a = instance(&f, adaptive(AdaptationLaw::default()));
    for k in 0..300 {
        let t = k as f64 * 1e-3;
        set(&mut a, &INPUTS, &[(3.0 * t).sin(), 0.5, 1.2 * (2.0 * t).cos(), -0.7]);
        set(&mut a, &["s_1", "s_2"], &[(5.0 * t).sin(), 0.3]);
        assert_eq!(a.do_step(t, 1e-3), Status::Ok);
    }
    let out = tempfile::tempdir().unwrap();
    let folder = out.path().join("adapted");
    let vr_folder = vr(&a, "nets_folder");
    assert_eq!(a.set_string(&[vr_folder], &[folder.display().to_string()]), Status::Ok);
    let probe = [0.4, -1.1, 0.8, -0.3];
    set(&mut a, &INPUTS, &probe);
    let adapted = get(&mut a, &TORQUES);
    assert_eq!(a.terminate(), Status::Ok);
    let mut names: Vec<String> = std::fs::read_dir(&folder).unwrap().map(|e| e.unwrap().file_name().into_string().unwrap()).collect();
    names.sort();
    assert_eq!(names, ["friction_1.json", "friction_2.json", "gravity.json"], "and no partial file left");
    let built = FmuSpec {
        identifier: "N".into(),
        model: ModelSpec::NnCompensator(NnCompensatorSpec {
            joints: 2,
            friction: vec!["friction_1.json".into(), "friction_2.json".into()],
            gravity: Some("gravity.json".into()),
            enable_friction: true,
            enable_gravity: true,
        }),
    }
    .build_from(Some(&folder))
    .unwrap();
    let guid = built.description().guid();
    let mut nn = Instance::new("n", &guid, built, Box::new(|_, _, m| eprintln!("{m}")), false).unwrap();
    assert_eq!(nn.setup_experiment(None, 0.0, None), Status::Ok);
    assert_eq!(nn.enter_initialization_mode(), Status::Ok);
    assert_eq!(nn.exit_initialization_mode(), Status::Ok);
    set(&mut nn, &INPUTS, &probe);
    assert_eq!(get(&mut nn, &TORQUES), adapted, "the written nets are the adapted ones, exactly");
    let mut off = instance(&f, adaptive(AdaptationLaw { adapt: false, ..AdaptationLaw::default() }));
    set(&mut off, &INPUTS, &probe);
    let offline = get(&mut off, &TORQUES);
    assert_ne!(offline, adapted, "and they did adapt");
}

/// At a measured speed of exactly 0 the friction torque is 0, as the law's: the nets have no
/// training sample there (found on arms of the random family, issue 24: a net's value at rest,
/// up to 5 % of the Coulomb level, acted as a bias on every stuck joint and made NN/perfect up
/// to 4). Just off rest the net's own value is given; a friction row does not adapt at rest.
#[test]
fn at_rest_the_friction_torque_is_zero_and_does_not_adapt() {
    let f = fixture();
    let nn = ModelSpec::NnCompensator(NnCompensatorSpec {
        joints: 2,
        friction: vec!["friction_1.json".into(), "friction_2.json".into()],
        gravity: None,
        enable_friction: true,
        enable_gravity: false,
    });
    let mut n = instance(&f, nn);
    set(&mut n, &INPUTS, &[0.3, -0.2, 0.0, 0.0]);
    assert_eq!(get(&mut n, &["tau_friction_1", "tau_friction_2"]), vec![0.0, 0.0]);
    for v in [1e-9, -1e-9, 0.5] {
        set(&mut n, &INPUTS, &[0.3, -0.2, v, v]);
        let torque = get(&mut n, &["tau_friction_1"])[0];
        let net = f.friction[0].network().unwrap().evaluate(&[v])[0];
        assert_eq!(torque, net, "v = {v}");
        assert_ne!(torque, 0.0, "the test net is not 0 near rest");
    }
    let mut a = instance(&f, adaptive(AdaptationLaw::default()));
    set(&mut a, &INPUTS, &[0.3, -0.2, 0.0, 0.4]);
    let before = get(&mut a, &["tau_friction_1", "tau_friction_2"]);
    set(&mut a, &["s_1", "s_2"], &[3.0, -2.0]);
    assert_eq!(a.do_step(0.0, 1e-3), Status::Ok);
    set(&mut a, &INPUTS, &[0.3, -0.2, 1e-3, 0.4]);
    let moved = get(&mut a, &["tau_friction_1"])[0];
    let mut fresh = instance(&f, adaptive(AdaptationLaw::default()));
    set(&mut fresh, &INPUTS, &[0.3, -0.2, 1e-3, 0.4]);
    assert_eq!(moved, get(&mut fresh, &["tau_friction_1"])[0], "joint 1 at rest learned nothing");
    assert_eq!(before[0], 0.0);
}
