//! Writes the committed seed corpora under `fuzz/corpus/<target>/`: serialized states and
//! spec files of every fixture, the example arm configurations, the fixtures' weights files,
//! a system file and CSV tables. Run from `fuzz/` after a change of the formats:
//! `cargo +nightly run --example write_seeds`.

use std::io::Write;
use std::path::Path;

use neurarm_fuzz::*;

fn put(target: &str, name: &str, bytes: &[u8]) {
    let dir = Path::new("corpus").join(target);
    std::fs::create_dir_all(&dir).expect("make the corpus folder");
    std::fs::write(dir.join(name), bytes).expect("write a seed");
}

fn main() {
    for (i, fixture) in fixtures().iter().enumerate() {
        for (k, state) in fixture.states.iter().enumerate() {
            // Model, then how (0: as saved; 2: into an initialized instance), then the bytes.
            for how in [0u8, 2] {
                put("fmu_state", &format!("{}-{k}-{how}", fixture.name), &[&[i as u8, how][..], state].concat());
            }
        }
    }
    for (name, spec, files) in specs() {
        put("resources", name, spec.to_toml().as_bytes());
        if let Some((_, gravity)) = files.iter().find(|(n, _)| n == "gravity.json") {
            // The compensator's gravity net given as the extra file `fuzz.json`.
            let text = spec.to_toml().replace("gravity.json", "fuzz.json");
            put("resources", &format!("{name}-extra"), &[text.as_bytes(), b"\0", gravity.as_bytes()].concat());
        }
    }
    let root = Path::new("..");
    put("arm_config", "default", neurarm_physics::config::ArmConfig::default().to_toml_string().as_bytes());
    for example in ["examples/arms/arm3.toml", "examples/arms/arm6.toml", "examples/robot/real3.toml"] {
        let text = std::fs::read(root.join(example)).expect("an example configuration");
        put("arm_config", Path::new(example).file_stem().unwrap().to_str().unwrap(), &text);
    }
    for (name, file) in compensator_nets() {
        put("weights_file", &name, file.to_json().as_bytes());
    }
    put(
        "system_file",
        "loop",
        br#"[[fmu]]
name = "arm"
path = "PlanarArm.fmu"
parameters = { q0_1 = 0.3, use_sequence = true, noise_seed = 4 }

[[fmu]]
name = "ctl"
path = "JointController.fmu"

[[connection]]
from = "arm.q_meas_*"
to = "ctl.q_*"

[[connection]]
from = "ctl.tau_*"
to = "arm.tau_*"

[simulation]
start = 0.5
stop = 15.0
step = 0.001
algorithm = "jacobi"
record = ["arm.q_1", "ctl.q_target_1"]
record_every = 10
"#,
    );
    let torques = std::fs::read(root.join("examples/torque_steps.csv")).expect("the example torques");
    let short: Vec<u8> = torques.split(|&b| b == b'\n').take(40).collect::<Vec<_>>().join(&b'\n');
    put("csv_table", "torques", &[&[2u8][..], &short].concat());
    put("csv_table", "units", b"\0time [s],qd_1 [rad/s], tau_1 [N.m]\n0,0.5,1e-3\n0.001,-0.25,2\n");
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    gz.write_all(&short).expect("compress");
    put("csv_table", "torques-gz", &[&[3u8][..], &gz.finish().expect("compress")].concat());
    // Two models (the same one, or two) at their phases, then a few moves of the host.
    let n = fixtures().len() as u8;
    for a in 0..n {
        for b in [a, (a + 1) % n] {
            put("foreign_state", &format!("{a}-{b}"), &[a, b, 2 + 3 * 2, 0, 0, 0, 2, 0, 0, 0, 3, 0, 1, 4, 0, 1, 2, 0, 0, 3]);
        }
    }
}
