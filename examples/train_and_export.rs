//! From data to FMUs: export an arm, train a friction net per joint on a CSV of
//! (velocity, torque) pairs, and export the NN compensator that carries the nets.
//!
//! The pairs here come from the arm's own friction law, sampled and written as a CSV (the
//! shape of `neurarm paper`'s `data/friction_*.csv`); with pairs identified on your robot,
//! start from the CSV. Run: `cargo run --release --example train_and_export -- [output-folder]`

use std::path::PathBuf;

use nalgebra::DMatrix;
use neurarm::export::export_fmu;
use neurarm::table::{write_atomic, write_text_atomic, NumericTable};
use neurarm_models::{FmuSpec, ModelSpec, NnCompensatorSpec, PlanarArmSpec};
use neurarm_nn::{train, Signal, TrainSettings, WeightsFile};
use neurarm_physics::config::ArmConfig;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let scratch = tempfile::tempdir()?;
    let dir = std::env::args_os().nth(1).map(PathBuf::from).unwrap_or_else(|| scratch.path().to_owned());
    std::fs::create_dir_all(&dir)?;
    let config = ArmConfig::default();
    let n = config.arm.dof();

    // 1. The arm as an FMU.
    let arm = FmuSpec {
        identifier: "MyArm".into(),
        model: ModelSpec::PlanarArm(PlanarArmSpec { config: config.clone(), q0: vec![0.0; n], qd0: vec![0.0; n] }),
    };
    export_fmu(&arm, &[], &dir.join("MyArm.fmu"))?;

    let mut sources = Vec::new();
    for j in 0..n {
        // 2. A CSV of training pairs: velocities from −5 to 5 rad/s, away from the jump at 0.
        let csv = dir.join(format!("friction_{}.csv", j + 1));
        let rows =
            (0..=200).map(|k| -5.0 + 0.05 * k as f64).filter(|v: &f64| v.abs() > 0.02).map(|v| vec![v, config.arm.friction[j].torque(v)]);
        write_atomic(&csv, &["qd".into(), "tau".into()], rows)?;

        // 3. Read it back and train a 1-10-1 net by Levenberg–Marquardt.
        let table = NumericTable::read(&csv, &["qd", "tau"])?;
        let row = |name: &str| DMatrix::from_row_slice(1, table.rows(), table.column(name).expect("read as required"));
        let settings = TrainSettings { hidden: 10, restarts: 3, seed: j as u64 + 1, ..TrainSettings::default() };
        let trained = train(&row("qd"), &row("tau"), &settings, &mut |_| {})?;
        let signal = |name: &str, unit: &str| vec![Signal { name: format!("{name}_{}", j + 1), unit: unit.into() }];
        let weights = WeightsFile::new(&trained.net, signal("qd", "rad/s"), signal("tau_friction", "N.m"), settings, trained.report);
        let rms = (weights.report.train_mse).sqrt();
        println!("joint {}: {} pairs, {} epochs, training RMS error {rms:.2e} N·m", j + 1, table.rows(), weights.report.epochs);
        let path = dir.join(format!("friction_{}.json", j + 1));
        write_text_atomic(&path, &weights.to_json())?;
        sources.push((format!("friction_{}.json", j + 1), path));
    }

    // 4. The compensator FMU with the four nets inside.
    let model = NnCompensatorSpec {
        joints: n,
        friction: sources.iter().map(|(name, _)| name.clone()).collect(),
        gravity: None,
        enable_friction: true,
        enable_gravity: false,
    };
    let compensator = FmuSpec { identifier: "MyCompensator".into(), model: ModelSpec::NnCompensator(model) };
    export_fmu(&compensator, &sources, &dir.join("MyCompensator.fmu"))?;
    println!("wrote MyArm.fmu and MyCompensator.fmu to {} (a temporary folder unless you name one)", dir.display());
    Ok(())
}
