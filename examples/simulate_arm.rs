//! Simulate the default 4-link arm with its base turned 90° (gravity in the plane) and its
//! default Coulomb + viscous friction, under sinusoidal joint torques, for 5 s at a 1 ms step.
//!
//! Run: `cargo run --release --example simulate_arm -- [output.csv]`

use std::time::Instant;

use neurarm::table::write_atomic;
use neurarm_physics::arm::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let output = std::env::args().nth(1).unwrap_or_else(|| "arm_example.csv".into());
    let params = ArmParams::default_four_link().with_base_angle(std::f64::consts::FRAC_PI_2);
    let mut sim = ArmSimulator::new(params.clone(), IntegratorSettings::default())?;
    let mut state = ArmState::at_rest(vec![0.3, -0.5, 0.7, -0.2]);
    // Scratch space of the dynamics, made once: the loop below allocates nothing for them.
    let (mut data, mut g) = (ArmData::new(&params), vec![0.0; 4]);

    let dt = 1e-3;
    let amplitude = [4.0, 3.0, 1.5, 0.6]; // N·m, above each joint's Coulomb level
    let mut names = vec!["time".to_string()];
    for p in ["q", "qd", "tau"] {
        names.extend((1..=4).map(|i| format!("{p}_{i}")));
    }
    names.extend(["x", "y"].map(String::from));
    let mut rows = Vec::new();
    let started = Instant::now();
    for k in 0..5000 {
        let t = k as f64 * dt;
        // Gravity compensation plus a sinusoid per joint, each at its own frequency.
        gravity_torques_into(&params, &mut data, &state.q, &mut g);
        let tau: Vec<f64> = (0..4).map(|i| g[i] + amplitude[i] * (t * (1.0 + i as f64)).sin()).collect();
        let x = end_effector_position(&params, &state.q);
        let mut row = vec![t];
        row.extend(state.q.iter().chain(&state.qd).chain(&tau));
        row.extend([x[0], x[1]]);
        rows.push(row);
        sim.step(&mut state, &tau, dt)?;
    }
    let elapsed = started.elapsed().as_secs_f64();
    write_atomic(output.as_ref(), &names, rows.into_iter())?;

    let x = end_effector_position(&params, &state.q);
    println!("simulated 5 s of the default arm in {:.1} ms ({:.0}x real time)", elapsed * 1e3, 5.0 / elapsed);
    println!("final q  [rad]   = {:?}", state.q.iter().map(|v| format!("{v:.4}")).collect::<Vec<_>>());
    println!("final qd [rad/s] = {:?}", state.qd.iter().map(|v| format!("{v:.4}")).collect::<Vec<_>>());
    println!("end effector [m] = ({:.4}, {:.4})", x[0], x[1]);
    println!("trajectory written to {output}");
    Ok(())
}
