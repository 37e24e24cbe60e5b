//! `neurarm export controller task-space|joint` and `export compensator --ideal` for arms of
//! any joint count: the FMUs have the ports the paper's loops connect, and a 3- and a 6-joint
//! arm track the reference through the master with them; bad input is refused by name and
//! leaves no file.

use std::io::Read;
use std::path::{Path, PathBuf};

use assert_cmd::Command;
use neurarm_cosim::{Algorithm, System, Value};
use neurarm_physics::arm::{end_effector_position, JointFriction, LinkParams};
use neurarm_physics::config::ArmConfig;
use neurarm_physics::control::{scaled_reference, ReferencePlacement};

fn neurarm() -> Command {
    Command::cargo_bin("neurarm").unwrap()
}

/// An arm of `n` joints of `length` each (masses falling outwards), default friction per joint.
fn arm_config(n: usize, length: f64) -> ArmConfig {
    let mut c = ArmConfig::default();
    c.arm.links = (0..n).map(|i| LinkParams::uniform_rod(length, 2.0 - 1.4 * i as f64 / n as f64)).collect();
    c.arm.friction = (0..n).map(|i| JointFriction::default_for_joint(i.min(3))).collect();
    c
}

fn write_config(dir: &Path, name: &str, config: &ArmConfig) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, config.to_toml_string()).unwrap();
    p
}

/// The names of the FMU's variables, from its modelDescription.xml.
fn variable_names(fmu: &Path) -> Vec<String> {
    let mut zip = zip::ZipArchive::new(std::fs::File::open(fmu).unwrap()).unwrap();
    let mut xml = String::new();
    zip.by_name("modelDescription.xml").unwrap().read_to_string(&mut xml).unwrap();
    xml.split("<ScalarVariable name=\"").skip(1).map(|s| s[..s.find('"').unwrap()].to_owned()).collect()
}

fn export(dir: &Path, args: &[&str], name: &str) -> PathBuf {
    let out = dir.join(name);
    neurarm().arg("export").args(args).arg("-o").arg(&out).assert().success();
    out
}

/// Exports arm, task-space controller and ideal friction compensator for `config` and runs the
/// loop for 2 s, with the compensator's torques added or not; returns the RMS distance of the
/// end effector from the reference [m].
fn tracking_error(dir: &Path, config: &ArmConfig, compensated: bool) -> f64 {
    let placement = ReferencePlacement::for_arm(&config.arm);
    let rows = tracking_rows(dir, config, compensated, [false; 3]);
    // Independently of the controller: the reference from its formula, the end effector from
    // the recorded angles.
    let squares: f64 = rows
        .iter()
        .map(|row| {
            let x_ref = scaled_reference(row[0], placement.centre, placement.scale).0;
            (x_ref - end_effector_position(&config.arm, &row[1..])).norm_squared()
        })
        .sum();
    (squares / rows.len() as f64).sqrt()
}

/// The recorded rows (time, arm angles) of the loop of [`tracking_error`], with arm,
/// controller and compensator exported as FMI 3.0 where `fmi3` says so.
fn tracking_rows(dir: &Path, config: &ArmConfig, compensated: bool, fmi3: [bool; 3]) -> Vec<Vec<f64>> {
    let n = config.arm.dof();
    let cfg = write_config(dir, "arm.toml", config);
    let cfg = cfg.to_str().unwrap();
    let version = |three: bool| if three { ["--fmi", "3"] } else { ["--fmi", "2"] };
    let arm = export(dir, &[&version(fmi3[0])[..], &["arm", "-c", cfg]].concat(), "Arm.fmu");
    let ctl = export(dir, &[&version(fmi3[1])[..], &["controller", "task-space", "-c", cfg]].concat(), "Ctl.fmu");
    let comp = export(dir, &[&version(fmi3[2])[..], &["compensator", "--ideal", "--friction", "-c", cfg]].concat(), "Comp.fmu");
    for (fmu, must, must_not, three) in
        [(&arm, "tau_", "q_ref_", fmi3[0]), (&ctl, "tau_comp_", "q_ref_", fmi3[1]), (&comp, "tau_friction_", "tau_", fmi3[2])]
    {
        if three {
            continue;
        }
        let names = variable_names(fmu);
        assert!(names.contains(&format!("{must}{n}")) && !names.contains(&format!("{must}{}", n + 1)), "{fmu:?}: {names:?}");
        assert!(!names.contains(&format!("{must_not}1")), "{fmu:?}");
    }
    // The arm starts where the controller's angle inputs start: on the curve, at rest.
    let placement = ReferencePlacement::for_arm(&config.arm);
    let start = neurarm::experiments::tracking_start(&config.arm, &placement).unwrap();
    let mut s = System::new();
    s.add_fmu("arm", &arm).unwrap().add_fmu("ctl", &ctl).unwrap().add_fmu("comp", &comp).unwrap();
    for i in 0..n {
        s.set("arm", &format!("q0_{}", i + 1), Value::Real(start.q[i])).unwrap();
        s.set("arm", &format!("qd0_{}", i + 1), Value::Real(start.qd[i])).unwrap();
    }
    s.connect("arm.q_meas_*", "ctl.q_*").unwrap().connect("arm.qd_meas_*", "ctl.qd_*").unwrap().connect("ctl.tau_*", "arm.tau_*").unwrap();
    s.connect("arm.q_meas_*", "comp.q_*").unwrap().connect("arm.qd_meas_*", "comp.qd_*").unwrap();
    if compensated {
        s.connect("comp.tau_comp_*", "ctl.tau_comp_*").unwrap();
    }
    let record: Vec<String> = (1..=n).map(|i| format!("arm.q_{i}")).collect();
    let mut sim = s.initialize(0.0, 1e-3, Algorithm::GaussSeidel, &record).unwrap();
    assert_eq!(sim.run_until(2.0).unwrap(), neurarm_cosim::RunEnd::Completed);
    sim.take_rows()
}

#[test]
fn the_loop_gives_the_same_rows_with_fmi3_units_mixed_in() {
    // The FMI 3.0 twins run the same model code: a loop of any mix of versions must give the
    // very same numbers as the FMI 2.0 loop (the master passes f64 both ways).
    let dir = tempfile::tempdir().unwrap();
    let config = arm_config(3, 0.3);
    let reference = tracking_rows(dir.path(), &config, true, [false; 3]);
    assert_eq!(reference.len(), 2001);
    for mix in [[true, false, true], [false, true, false], [true; 3]] {
        let rows = tracking_rows(dir.path(), &config, true, mix);
        assert_eq!(rows, reference, "FMI 3.0 where {mix:?}");
    }
}

#[test]
fn three_and_six_joint_arms_track_with_exported_controllers() {
    for (n, length) in [(3, 0.3), (6, 0.2)] {
        let dir = tempfile::tempdir().unwrap();
        let perfect = tracking_error(dir.path(), &arm_config(n, length), true);
        let none = tracking_error(dir.path(), &arm_config(n, length), false);
        // Perfect friction compensation and a perfect model leave the sampling's error (the
        // default arm's Table 1 run: 0.5 mm RMS); without compensation friction shows.
        assert!(perfect < 1e-3, "{n} joints: RMS tracking error {perfect} m with perfect compensation");
        eprintln!("{n} joints: RMS tracking error {:.3} mm compensated, {:.3} mm not", perfect * 1e3, none * 1e3);
        assert!(none > 3.0 * perfect, "{n} joints: RMS {none} m uncompensated against {perfect} m compensated");
    }
}

#[test]
fn joint_controller_and_ideal_compensator_take_their_size_and_parts() {
    let dir = tempfile::tempdir().unwrap();
    let cfg = write_config(dir.path(), "arm5.toml", &arm_config(5, 0.2));
    let cfg = cfg.to_str().unwrap();
    let joint = export(dir.path(), &["controller", "joint", "-c", cfg, "--kp", "80", "--sequence"], "J.fmu");
    let names = variable_names(&joint);
    for v in ["q_5", "qd_5", "tau_comp_5", "q_ref_5", "qd_ref_5", "tau_5", "q_target_5", "kp_5", "kd_5", "use_sequence"] {
        assert!(names.iter().any(|n| n == v), "{v} missing: {names:?}");
    }
    let joint7 = export(dir.path(), &["controller", "joint", "--joints", "7"], "J7.fmu");
    assert!(variable_names(&joint7).contains(&"tau_7".to_owned()));
    // The ideal compensator's switches start as asked: only gravity here.
    let comp = export(dir.path(), &["compensator", "--ideal", "--gravity", "-c", cfg], "G.fmu");
    let mut zip = zip::ZipArchive::new(std::fs::File::open(&comp).unwrap()).unwrap();
    let mut xml = String::new();
    zip.by_name("modelDescription.xml").unwrap().read_to_string(&mut xml).unwrap();
    let start_of = |name: &str| {
        let at = xml.find(&format!("name=\"{name}\"")).unwrap();
        let tail = &xml[at..];
        let s = tail.find("start=\"").unwrap() + 7;
        tail[s..s + tail[s..].find('"').unwrap()].to_owned()
    };
    assert_eq!((start_of("enable_friction").as_str(), start_of("enable_gravity").as_str()), ("false", "true"));
}

#[test]
fn bad_exports_say_why_and_write_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let one = write_config(dir.path(), "one.toml", &arm_config(1, 0.5));
    let out = dir.path().join("X.fmu");
    let refused = |args: &[&str], expected: &[&str]| {
        let o = neurarm().arg("export").args(args).arg("-o").arg(&out).output().unwrap();
        let stderr = String::from_utf8_lossy(&o.stderr).to_string();
        assert!(!o.status.success(), "{args:?} was accepted");
        for e in expected {
            assert!(stderr.contains(e), "{args:?}: {stderr:?} lacks {e:?}");
        }
        assert!(!out.exists(), "{args:?} left a file");
    };
    refused(&["controller", "task-space", "-c", one.to_str().unwrap()], &["at least 2 joints", "has 1"]);
    refused(&["controller", "task-space", "--centre", "0.9,0.5"], &["reach of", "it has 1.000 m"]);
    refused(&["controller", "task-space", "--centre", "0.1"], &["--centre takes two numbers"]);
    refused(&["controller", "task-space", "--scale", "0"], &["scale must be > 0"]);
    refused(&["compensator", "--ideal", "--friction", "f.json"], &["--ideal takes no weights files"]);
    refused(&["compensator", "--friction"], &["give --friction nets"]);
    refused(&["controller", "joint", "--joints", "0"], &["at least one joint"]);
    // A lopsided arm (first link longer than the rest) has a hole in its workspace: the curve
    // placed by the reach alone cuts into it and is refused; by default it is fitted into the
    // ring the arm reaches, and the export goes through.
    let mut lopsided = arm_config(2, 0.5);
    lopsided.arm.links[1] = LinkParams::uniform_rod(0.1, 0.5);
    let lop = write_config(dir.path(), "lop.toml", &lopsided);
    let by_reach = ["controller", "task-space", "-c", lop.to_str().unwrap(), "--centre", "0.27,0.06", "--scale", "0.6"];
    refused(&by_reach, &["cannot reach within 0.400 m"]);
    let fitted =
        neurarm().arg("export").args(["controller", "task-space", "-c", lop.to_str().unwrap()]).arg("-o").arg(&out).output().unwrap();
    assert!(fitted.status.success(), "{}", String::from_utf8_lossy(&fitted.stderr));
    assert!(out.is_file());
}
