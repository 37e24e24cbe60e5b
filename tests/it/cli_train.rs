//! `neurarm train` refuses what cannot make a useful net and says why; the weights file records
//! what the net is (kind, joint, units), and `export compensator` checks the nets against each
//! other by their file names. Every refusal leaves no output file.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use neurarm_nn::{NetKind, WeightsFile};

fn neurarm() -> Command {
    Command::cargo_bin("neurarm").unwrap()
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// `rows` friction-like pairs of one joint under the header `header`.
fn friction_pairs(header: &str, rows: usize, slope: f64) -> String {
    let mut csv = format!("{header}\n");
    for i in 0..rows {
        let v = -3.0 + 6.0 * i as f64 / (rows - 1) as f64;
        csv += &format!("{v},{}\n", 0.8 * (4.0 * v).tanh() + slope * v);
    }
    csv
}

/// Runs `train` and returns (success, stderr).
fn train(data: &Path, args: &[&str], output: &Path) -> (bool, String) {
    let o = neurarm().args(["train", "-d"]).arg(data).args(args).arg("-o").arg(output).output().unwrap();
    (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
}

/// Asserts that `train` fails with every text of `expected` and writes nothing.
fn refused(data: &Path, args: &[&str], expected: &[&str]) {
    let out = data.with_file_name("refused.json");
    let (ok, stderr) = train(data, args, &out);
    assert!(!ok, "accepted {args:?}: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    for e in expected {
        assert!(stderr.contains(e), "{args:?}: stderr {stderr:?} lacks {e:?}");
    }
    assert!(!out.exists(), "{args:?} left an output file");
}

#[test]
fn train_refuses_what_cannot_make_a_useful_net() {
    let dir = tempfile::tempdir().unwrap();
    let pairs = write(dir.path(), "pairs.csv", &friction_pairs("qd_1,tau_1", 40, 0.3));
    let few = write(dir.path(), "few.csv", &friction_pairs("qd_1,tau_1", 13, 0.3));
    let io = ["--inputs", "qd_1", "--targets", "tau_1"];
    let with = |extra: &[&'static str]| -> Vec<&'static str> { io.iter().copied().chain(extra.iter().copied()).collect() };

    // 13 pairs at 70/15/15 leave 2 for validation; the message gives the minimum.
    refused(&few, &io, &["13 samples give the", "at least 17 samples"]);
    // Without validation and test parts, 13 pairs are enough for the training part.
    let out = dir.path().join("all.json");
    let (ok, stderr) = train(&few, &with(&["--split", "1,0,0", "--hidden", "2"]), &out);
    assert!(ok, "{stderr}");
    refused(&few, &with(&["--split", "0.5,0.5,0.5"]), &["sum to 1", "0.5, 0.5, 0.5"]);
    refused(&pairs, &with(&["--split", "0.7,0.3"]), &["three fractions"]);
    refused(&pairs, &with(&["--split", "0.7,-0.1,0.4"]), &["must be >= 0"]);
    refused(&pairs, &with(&["--epochs", "0"]), &["epochs must be >= 1"]);
    refused(&pairs, &with(&["--max-fail", "0"]), &["max_fail must be >= 1"]);
    refused(&pairs, &with(&["--restarts", "0"]), &["restarts must be >= 1"]);
    refused(&pairs, &with(&["--hidden", "0"]), &["hidden must be 1 to 1000"]);
    refused(&pairs, &with(&["--hidden", "100000"]), &["hidden must be 1 to 1000"]);
    refused(&pairs, &with(&["--hidden", "18446744073709551615"]), &["hidden must be 1 to 1000"]);
    let constant = write(dir.path(), "constant.csv", &(0..40).fold("qd_1,tau_1\n".to_owned(), |s, i| s + &format!("0.5,{i}\n")));
    refused(&constant, &io, &["constant.csv", "input column 'qd_1' is constant (0.5 in all 40 rows)"]);
    refused(&pairs, &["--inputs", "qd_1", "--targets", "qd_1"], &["'qd_1' is named twice"]);

    // A net too large to factor, with three inputs and outputs.
    let mut wide = String::from("q_1,q_2,q_3,tau_gravity_1,tau_gravity_2,tau_gravity_3\n");
    for i in 0..40 {
        let q = [0.1 * i as f64, (0.37 * i as f64).sin(), (0.71 * i as f64).cos()];
        wide += &format!("{},{},{},{},{},{}\n", q[0], q[1], q[2], q[0].cos(), q[1].cos(), q[2].cos());
    }
    let wide = write(dir.path(), "wide.csv", &wide);
    let three = ["--inputs", "q_1,q_2,q_3", "--targets", "tau_gravity_1,tau_gravity_2,tau_gravity_3"];
    let mut big = three.to_vec();
    big.extend(["--hidden", "1000"]);
    refused(&wide, &big, &["more than 5000 weights"]);
}

#[test]
fn train_warns_on_a_time_series_and_records_kind_joint_and_units() {
    let dir = tempfile::tempdir().unwrap();
    // A recorded log: 1 kHz samples of a velocity that settles; consecutive rows nearly equal.
    let mut log = String::from("time [s],qd_2 [rad/s],tau_2 [N.m]\n");
    for k in 0..2000 {
        let t = k as f64 * 1e-3;
        let v = 2.0 * (1.0 - (-t / 0.3).exp());
        log += &format!("{t},{v},{}\n", 0.8 + 0.2 * v);
    }
    let log = write(dir.path(), "log.csv", &log);
    let out = dir.path().join("raw.json");
    let (ok, stderr) = train(&log, &["--inputs", "qd_2", "--targets", "tau_2", "--hidden", "2", "--epochs", "5"], &out);
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains("warning: ") && stderr.contains("look like a recorded time series") && stderr.contains("neurarm identify"),
        "{stderr}"
    );
    // Inferred from the input's name: the friction net of joint 2; units from the header.
    let w = WeightsFile::read(&out).unwrap();
    assert_eq!((w.kind, w.joint), (NetKind::Friction, Some(2)));
    assert_eq!((w.inputs[0].unit.as_str(), w.outputs[0].unit.as_str()), ("rad/s", "N.m"));
    assert!(stderr.contains("friction net of joint 2") && stderr.contains("RMS error train"), "no summary line: {stderr}");

    // Identified pairs (0.15 rad/s apart) draw no warning.
    let pairs = write(dir.path(), "pairs.csv", &friction_pairs("qd_1,tau_friction_1", 41, 0.3));
    let (ok, stderr) = train(&pairs, &["--inputs", "qd_1", "--targets", "tau_friction_1", "--hidden", "4"], &dir.path().join("p.json"));
    assert!(ok && !stderr.contains("warning"), "{stderr}");

    // The joint given must agree with the input's name; a net with no joint in its names
    // needs --joint to be a friction net.
    let v = write(dir.path(), "v.csv", &friction_pairs("v,tau", 41, 0.3));
    refused(&pairs, &["--inputs", "qd_1", "--targets", "tau_friction_1", "--joint", "2"], &["--joint 2", "velocity of joint 1"]);
    refused(&v, &["--inputs", "v", "--targets", "tau", "--kind", "friction"], &["give --joint J"]);
    refused(&v, &["--inputs", "v", "--targets", "tau", "--kind", "gravity", "--joint", "1"], &["--joint is for friction nets"]);
    refused(&v, &["--inputs", "v", "--targets", "tau", "--kind", "inertia"], &["unknown net kind 'inertia'"]);
    let (ok, stderr) = train(&v, &["--inputs", "v", "--targets", "tau", "--joint", "3", "--hidden", "3"], &dir.path().join("v.json"));
    assert!(ok, "{stderr}");
    let w = WeightsFile::read(&dir.path().join("v.json")).unwrap();
    assert_eq!((w.kind, w.joint, w.inputs[0].unit.as_str()), (NetKind::Friction, Some(3), ""));
    let (ok, stderr) = train(&v, &["--inputs", "v", "--targets", "tau", "--hidden", "3"], &dir.path().join("u.json"));
    assert!(ok, "{stderr}");
    assert_eq!(WeightsFile::read(&dir.path().join("u.json")).unwrap().kind, NetKind::Unspecified);
}

/// Trains the friction net of `joint` (pairs differing per joint) into `dir`.
fn friction_net(dir: &Path, joint: usize, header_unit: &str, slope: f64) -> PathBuf {
    let header = format!("qd_{joint}{header_unit},tau_friction_{joint}");
    let data = write(dir, &format!("f{joint}.csv"), &friction_pairs(&header, 30, slope));
    let out = dir.join(format!("friction_{joint}.json"));
    let target = format!("tau_friction_{joint}");
    let input = format!("qd_{joint}");
    let (ok, stderr) = train(&data, &["--inputs", &input, "--targets", &target, "--hidden", "3", "--epochs", "20"], &out);
    assert!(ok, "{stderr}");
    out
}

#[test]
fn export_compensator_checks_the_nets_against_each_other() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let f: Vec<PathBuf> = (1..=3).map(|j| friction_net(d, j, "", 0.1 * j as f64)).collect();
    let mut grid = String::from("q_1,q_2,tau_gravity_1,tau_gravity_2\n");
    for i in 0..6 {
        for j in 0..6 {
            let (a, b) = (i as f64 - 2.5, j as f64 - 2.5);
            grid += &format!("{a},{b},{},{}\n", 3.0 * a.cos() + (a + b).cos(), (a + b).cos());
        }
    }
    let grid = write(d, "gravity.csv", &grid);
    let gravity = d.join("gravity.json");
    let (ok, stderr) =
        train(&grid, &["--inputs", "q_1,q_2", "--targets", "tau_gravity_1,tau_gravity_2", "--hidden", "4", "--epochs", "20"], &gravity);
    assert!(ok, "{stderr}");
    assert_eq!(WeightsFile::read(&gravity).unwrap().kind, NetKind::Gravity);

    let fmu = d.join("Comp.fmu");
    let export = |friction: &[&PathBuf], gravity: Option<&PathBuf>| {
        let list = friction.iter().map(|p| p.display().to_string()).collect::<Vec<_>>().join(",");
        let mut cmd = neurarm();
        cmd.args(["export", "compensator"]);
        if !friction.is_empty() {
            cmd.arg("--friction").arg(list);
        }
        if let Some(g) = gravity {
            cmd.arg("--gravity").arg(g);
        }
        let o = cmd.arg("-o").arg(&fmu).output().unwrap();
        (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let refused = |friction: &[&PathBuf], gravity: Option<&PathBuf>, expected: &[&str]| {
        let (ok, stderr) = export(friction, gravity);
        assert!(!ok, "accepted: {stderr}");
        for e in expected {
            assert!(stderr.contains(e), "stderr {stderr:?} lacks {e:?}");
        }
        assert!(!fmu.exists(), "an FMU was written");
    };
    refused(&[&f[1], &f[0]], None, &["friction_2.json is the friction net of joint 2", "given as net 1 of 2", "joint order"]);
    refused(&[&f[0], &f[0]], None, &["friction_1.json and", "hold the same net"]);
    refused(&[&f[0], &gravity], None, &["gravity.json is a gravity net, given as the friction net of joint 2"]);
    refused(&[&f[0]], Some(&f[1]), &["friction_2.json is the friction net of joint 2, given as the gravity net"]);
    refused(&[&f[0], &f[1], &f[2]], Some(&gravity), &["3 friction nets but the gravity net", "is for 2 joints"]);
    // A net whose header said its input is in deg/s.
    let sub = d.join("deg");
    std::fs::create_dir(&sub).unwrap();
    let deg = friction_net(&sub, 2, " [deg/s]", 0.5);
    refused(&[&f[0], &deg], None, &["input 'qd_2' is in deg/s", "rad/s"]);

    let (ok, stderr) = export(&[&f[0], &f[1]], Some(&gravity));
    assert!(ok, "{stderr}");
    assert!(fmu.exists());
}
