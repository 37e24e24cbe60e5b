//! A closed loop of FMUs through the co-simulation master (`neurarm-cosim`): the default arm with
//! its base turned 90° (gravity in the plane), held at a target pose by the joint controller
//! (P(D) control) with the ideal gravity compensator feeding its `tau_comp` inputs. The three
//! FMUs are exported here from neurarm's models; the loop is also written as an SSP archive.
//!
//! Run: `cargo run --release --example run_system -- [output-folder]`

use std::f64::consts::FRAC_PI_2;
use std::path::PathBuf;

use neurarm::export::export_fmu;
use neurarm_cosim::{Algorithm, System, Value};
use neurarm_models::{FmuSpec, IdealCompensatorSpec, JointControllerSpec, ModelSpec, PlanarArmSpec};
use neurarm_physics::config::ArmConfig;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scratch = tempfile::tempdir()?;
    let dir = std::env::args_os().nth(1).map(PathBuf::from).unwrap_or_else(|| scratch.path().to_owned());
    std::fs::create_dir_all(&dir)?;
    let export = |id: &str, model: ModelSpec| -> Result<PathBuf, Box<dyn std::error::Error>> {
        let path = dir.join(format!("{id}.fmu"));
        export_fmu(&FmuSpec { identifier: id.into(), model }, &[], &path)?;
        Ok(path)
    };
    let config = ArmConfig::default();
    let hanging = vec![-FRAC_PI_2, 0.0, 0.0, 0.0];
    let arm = export("PlanarArm", ModelSpec::PlanarArm(PlanarArmSpec { config: config.clone(), q0: hanging, qd0: vec![0.0; 4] }))?;
    let ctl =
        export("JointController", ModelSpec::JointController(JointControllerSpec { joints: 4, kp: 50.0, kd: 2.0, use_sequence: false }))?;
    let gravity = IdealCompensatorSpec { arm: config.arm.with_base_angle(FRAC_PI_2), enable_friction: false, enable_gravity: true };
    let comp = export("GravityCompensator", ModelSpec::IdealCompensator(gravity))?;

    let target = [-0.8, 0.6, -0.4, 0.3];
    let mut system = System::new();
    system.add_fmu("arm", &arm)?.add_fmu("ctl", &ctl)?.add_fmu("comp", &comp)?;
    system.set("arm", "base_angle", Value::Real(FRAC_PI_2))?;
    for (i, q) in target.iter().enumerate() {
        system.set("ctl", &format!("q_ref_{}", i + 1), Value::Real(*q))?;
    }
    // The controller and the compensator see what the sensors measure.
    system.connect("arm.q_meas_*", "ctl.q_*")?.connect("arm.qd_meas_*", "ctl.qd_*")?.connect("ctl.tau_*", "arm.tau_*")?;
    system.connect("arm.q_meas_*", "comp.q_*")?.connect("arm.qd_meas_*", "comp.qd_*")?.connect("comp.tau_comp_*", "ctl.tau_comp_*")?;

    let record: Vec<String> = (1..=4).map(|i| format!("arm.q_{i}")).collect();
    let mut sim = system.clone().initialize(0.0, 1e-3, Algorithm::GaussSeidel, &record)?;
    let end = sim.run_until(5.0)?;
    if end != neurarm_cosim::RunEnd::Completed {
        return Err(format!("the run ended early: {end:?}").into());
    }
    println!("stepping order: {}", sim.step_order().join(" → "));
    let last = sim.rows().last().ok_or("nothing recorded")?;
    let errors: Vec<f64> = target.iter().zip(&last[1..]).map(|(t, q)| t - q).collect();
    println!("after {} s, q_ref − q [rad] = {:?}", last[0], errors.iter().map(|e| format!("{e:+.4}")).collect::<Vec<_>>());
    // What is left is friction against a P gain: at most the Coulomb level over kp (1.5/50 rad).
    if let Some(e) = errors.iter().find(|e| e.abs() > 0.05) {
        return Err(format!("the loop did not settle: an error of {e} rad").into());
    }
    let simulation = neurarm_cosim::SimulationSpec {
        start: 0.0,
        stop: 5.0,
        step: 1e-3,
        algorithm: Algorithm::GaussSeidel,
        record,
        record_every: 1,
        on_discard: neurarm_cosim::OnDiscard::Stop,
    };
    let ssp = dir.join("hold.ssp");
    neurarm_cosim::ssp::write_system(&system, &simulation, &ssp)?;
    println!("the loop as an SSP archive: {} (in a temporary folder unless you name one)", ssp.display());
    Ok(())
}
