//! `neurarm simulate` end to end: good input gives the library's trajectory to the bit; bad
//! input gives an error naming file, line and column, and leaves no output file behind.
//! `neurarm random-arm` gives one valid arm per seed and joint count, and refuses a count
//! beyond 2 to 8.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use neurarm::simulate::{simulate, TorqueInput};
use neurarm::table::NumericTable;
use neurarm_physics::arm::ArmState;
use neurarm_physics::config::ArmConfig;

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn good_csv() -> String {
    let mut s = String::from("time,tau_1,tau_2,tau_3,tau_4\n");
    for k in 0..=200 {
        let t = k as f64 * 1e-3;
        s += &format!("{t},{},{},{},0.4\n", 3.0 * (5.0 * t).sin(), -2.0, 1.0);
    }
    s
}

fn neurarm() -> Command {
    Command::cargo_bin("neurarm").unwrap()
}

/// Runs simulate on `csv` and returns stderr, asserting failure and that no output appeared.
fn fails_with(csv: &str, expected: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "tau.csv", csv);
    let out = dir.path().join("traj.csv");
    let assert = neurarm().args(["simulate", "-t"]).arg(&input).arg("-o").arg(&out).assert().failure();
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
    for e in expected {
        assert!(stderr.contains(e), "stderr {stderr:?} lacks {e:?}");
    }
    assert!(stderr.contains("tau.csv"), "the file is not named: {stderr}");
    assert!(!out.exists(), "output file left behind");
    let leftovers: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(leftovers.len(), 1, "stray files: {leftovers:?}");
}

#[test]
fn simulate_writes_the_library_trajectory_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "tau.csv", &good_csv());
    let out = dir.path().join("traj.csv");
    neurarm()
        .args(["simulate", "-t"])
        .arg(&input)
        .args(["--q0", "0.1,-0.2,0.3,0.4", "--qd0", "0,1,0,-1", "-o"])
        .arg(&out)
        .assert()
        .success();
    let written = NumericTable::read(&out, &["time", "q_1", "qd_4", "x", "y", "tau_1"]).unwrap();
    let config = ArmConfig::default();
    let initial = ArmState { q: vec![0.1, -0.2, 0.3, 0.4], qd: vec![0.0, 1.0, 0.0, -1.0] };
    let want = simulate(&config, &initial, &TorqueInput::read_csv(&input, 4).unwrap()).unwrap();
    assert_eq!(written.names, want.names);
    assert_eq!(written.rows(), 201);
    for (r, row) in want.rows.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            assert_eq!(written.columns[c][r].to_bits(), v.to_bits(), "row {r} column {}", want.names[c]);
        }
    }
    assert_eq!(written.column("q_1").unwrap()[0], 0.1);
    assert_ne!(written.column("q_1").unwrap()[200], 0.1);
}

#[test]
fn missing_column_is_named() {
    fails_with("time,tau_1,tau_2,tau_4\n0,1,1,1\n", &["line 1", "missing column 'tau_3'"]);
}

#[test]
fn text_in_a_number_is_located() {
    fails_with("time,tau_1,tau_2,tau_3,tau_4\n0,1,1,1,1\n0.001,1,abc,1,1\n", &["line 3", "column 3 (tau_2)", "'abc' is not a number"]);
}

#[test]
fn nan_is_located() {
    fails_with(
        "time,tau_1,tau_2,tau_3,tau_4\n0,1,1,1,1\n0.001,1,1,1,1\n0.002,1,1,NaN,1\n",
        &["line 4", "column 4 (tau_3)", "not a finite number"],
    );
}

#[test]
fn non_monotonic_time_is_located() {
    fails_with("time,tau_1,tau_2,tau_3,tau_4\n0,1,1,1,1\n0.002,1,1,1,1\n0.001,1,1,1,1\n", &["line 4", "column 1 (time)", "must increase"]);
    fails_with("time,tau_1,tau_2,tau_3,tau_4\n0,1,1,1,1\n0,1,1,1,1\n", &["line 3", "column 1 (time)"]);
}

#[test]
fn ragged_row_and_empty_file_are_reported() {
    fails_with("time,tau_1,tau_2,tau_3,tau_4\n0,1,1,1,1\n0.001,1,1\n", &["line 3", "3 fields where the header has 5"]);
    fails_with("time,tau_1,tau_2,tau_3,tau_4\n", &["no data rows"]);
    fails_with("", &["empty"]);
}

#[test]
fn failed_run_keeps_an_existing_output_file() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "tau.csv", "time,tau_1,tau_2,tau_3,tau_4\n0,1,1,1,x\n");
    let out = write(dir.path(), "traj.csv", "precious\n");
    neurarm().args(["simulate", "-t"]).arg(&input).arg("-o").arg(&out).assert().failure();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "precious\n");
}

#[test]
fn bad_config_and_initial_state_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "tau.csv", &good_csv());
    let out = dir.path().join("traj.csv");
    let bad = ArmConfig::default().to_toml_string().replacen("length_m = 0.25", "length_m = 0.0", 1);
    let config = write(dir.path(), "arm.toml", &bad);
    let a = neurarm().args(["simulate", "-t"]).arg(&input).arg("-c").arg(&config).arg("-o").arg(&out).assert().failure();
    let stderr = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(stderr.contains("arm.toml") && stderr.contains("links[0].length_m"), "{stderr}");
    let a = neurarm().args(["simulate", "-t"]).arg(&input).args(["--q0", "1,2", "-o"]).arg(&out).assert().failure();
    let stderr = String::from_utf8_lossy(&a.get_output().stderr).to_string();
    assert!(stderr.contains("--q0 has 2 values, the arm has 4 joints"), "{stderr}");
    assert!(!out.exists());
}

#[test]
fn three_joint_config_simulates() {
    let dir = tempfile::tempdir().unwrap();
    let mut config = ArmConfig::default();
    config.arm.links.truncate(3);
    config.arm.friction.truncate(3);
    let cfg = write(dir.path(), "arm3.toml", &config.to_toml_string());
    let input = write(dir.path(), "tau.csv", "time,tau_1,tau_2,tau_3\n0,2,0,0\n0.5,0,0,0\n1,0,0,0\n");
    let out = dir.path().join("traj.csv");
    neurarm().args(["simulate", "-t"]).arg(&input).arg("-c").arg(&cfg).arg("-o").arg(&out).assert().success();
    let t = NumericTable::read(&out, &["q_3", "qd_3"]).unwrap();
    assert!(t.column("q_4").is_none());
    assert!(t.column("q_1").unwrap()[2] > 0.0);
}

/// Runs `neurarm export arm -c CONFIG -o OUT` and returns (success, stderr, out exists).
fn export_with(config_text: &str) -> (bool, String, bool) {
    let dir = tempfile::tempdir().unwrap();
    let cfg = write(dir.path(), "my_arm.toml", config_text);
    let out = dir.path().join("MyArm.fmu");
    let o = neurarm().args(["export", "arm", "-c"]).arg(&cfg).arg("-o").arg(&out).output().unwrap();
    let left: Vec<_> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert!(o.status.success() || left.len() == 1, "stray files after a failed export: {left:?}");
    (o.status.success(), String::from_utf8_lossy(&o.stderr).into_owned(), out.exists())
}

#[test]
fn export_arm_rejects_invalid_configs_clearly() {
    let good = ArmConfig::default().to_toml_string();
    let (ok, stderr, exists) = export_with(&good.replacen("mass_kg = 1.6", "mass_kg = -1.6", 1));
    assert!(!ok && !exists && stderr.contains("my_arm.toml") && stderr.contains("links[1].mass_kg = -1.6"), "{stderr}");

    let mut none = ArmConfig::default();
    none.arm.links.clear();
    none.arm.friction.clear();
    let (ok, stderr, exists) = export_with(&none.to_toml_string());
    assert!(!ok && !exists && stderr.contains("at least one joint"), "{stderr}");

    let (ok, stderr, exists) = export_with(&good.replacen("[arm]", "[arm]\nwheels = 4", 1));
    assert!(!ok && !exists && stderr.contains("unknown field `wheels`"), "{stderr}");

    let (ok, stderr, exists) = export_with(&good.replacen("internal_step_s = 0.00025", "internal_step_s = 0.0", 1));
    assert!(!ok && !exists && stderr.contains("internal_step_s"), "{stderr}");
}

#[test]
fn export_arm_names_the_fmu_after_its_file_and_checks_the_name() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("MyArm.fmu");
    let o = neurarm().args(["export", "arm", "-o"]).arg(&out).output().unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("MyArm"));
    assert!(std::fs::metadata(&out).unwrap().len() > 10_000);
    let bad = dir.path().join("my-arm.fmu");
    let o = neurarm().args(["export", "arm", "-o"]).arg(&bad).output().unwrap();
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("model identifier 'my-arm'"));
    assert!(!bad.exists());
}

#[test]
fn train_and_eval_round_trip_and_report_bad_data() {
    let dir = tempfile::tempdir().unwrap();
    let mut csv = String::from("qd_1,tau_1\n");
    for i in 0..=100 {
        let v = -5.0 + 0.1 * i as f64;
        csv += &format!("{v},{}\n", 1.2 * (3.0 * v).tanh() + 0.5 * v);
    }
    let data = write(dir.path(), "pairs.csv", &csv);
    let net = dir.path().join("net.json");
    let o = neurarm()
        .args(["train", "-d"])
        .arg(&data)
        .args(["--inputs", "qd_1", "--targets", "tau_1", "--hidden", "6", "-o"])
        .arg(&net)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let weights = neurarm_nn::WeightsFile::read(&net).unwrap();
    assert_eq!(weights.inputs[0].unit, "rad/s");
    assert_eq!(weights.outputs[0].unit, "N.m");
    // eval writes the library's forward pass.
    let out = dir.path().join("eval.csv");
    neurarm().args(["eval", "-n"]).arg(&net).arg("-d").arg(&data).arg("-o").arg(&out).assert().success();
    let table = NumericTable::read(&out, &["qd_1", "tau_1"]).unwrap();
    let mlp = weights.network().unwrap();
    for r in 0..table.rows() {
        let y = mlp.evaluate(&[table.column("qd_1").unwrap()[r]])[0];
        assert_eq!(y.to_bits(), table.column("tau_1").unwrap()[r].to_bits());
    }

    // Nielsen's damping, recorded in the file; an unknown rule is refused.
    let nielsen = dir.path().join("nielsen.json");
    neurarm()
        .args(["train", "-d"])
        .arg(&data)
        .args(["--inputs", "qd_1", "--targets", "tau_1", "--damping", "nielsen", "-o"])
        .arg(&nielsen)
        .assert()
        .success();
    let w = neurarm_nn::WeightsFile::read(&nielsen).unwrap();
    assert_eq!(w.training.damping, neurarm_nn::lm::Damping::Nielsen);
    assert!(w.report.train_mse < 1e-3, "Nielsen's rule trains: MSE {}", w.report.train_mse);
    let o = neurarm()
        .args(["train", "-d"])
        .arg(&data)
        .args(["--inputs", "qd_1", "--targets", "tau_1", "--damping", "fast", "-o"])
        .arg(dir.path().join("f.json"))
        .output()
        .unwrap();
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("use trainlm or nielsen"));

    // Bad data: missing column, text in a number; nothing written.
    let bad = write(dir.path(), "bad.csv", "qd_1,tau_1\n0.1,0.2\n0.2,x\n");
    let out2 = dir.path().join("net2.json");
    let o = neurarm().args(["train", "-d"]).arg(&bad).args(["--inputs", "qd_1", "--targets", "tau_1", "-o"]).arg(&out2).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && stderr.contains("bad.csv, line 3, column 2 (tau_1): 'x' is not a number"), "{stderr}");
    let o = neurarm().args(["train", "-d"]).arg(&data).args(["--inputs", "qd_2", "--targets", "tau_1", "-o"]).arg(&out2).output().unwrap();
    assert!(String::from_utf8_lossy(&o.stderr).contains("missing column 'qd_2'"));
    assert!(!out2.exists());
    let o = neurarm().args(["eval", "-n"]).arg(&data).arg("-d").arg(&data).arg("-o").arg(&out2).output().unwrap();
    assert!(!o.status.success() && String::from_utf8_lossy(&o.stderr).contains("pairs.csv"));
    assert!(!out2.exists());
}

#[test]
fn written_files_are_readable_by_others() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let input = write(dir.path(), "tau.csv", &good_csv());
    let out = dir.path().join("traj.csv");
    neurarm().args(["simulate", "-t"]).arg(&input).arg("-o").arg(&out).assert().success();
    let fmu = dir.path().join("Arm.fmu");
    neurarm().args(["export", "arm", "-o"]).arg(&fmu).assert().success();
    // What a plain create would give: 0644 less the process umask (Linux reports it here).
    let status = std::fs::read_to_string("/proc/self/status").unwrap();
    let umask = status.lines().find_map(|l| l.strip_prefix("Umask:")).map(|u| u32::from_str_radix(u.trim(), 8).unwrap()).unwrap_or(0o022);
    for f in [out, fmu] {
        assert_eq!(std::fs::metadata(&f).unwrap().permissions().mode() & 0o777, 0o644 & !umask, "{}", f.display());
    }
}

/// `neurarm paper` with `args` in a fresh folder: asserts failure, that stderr has every one of
/// `expected`, and that no output folder (or staging folder) was left.
fn paper_fails_with(args: &[&str], files: &[(&str, String)], expected: &[&str]) {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in files {
        write(dir.path(), name, text);
    }
    let assert = neurarm().current_dir(dir.path()).arg("paper").args(args).args(["-o", "run"]).assert().failure();
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
    for e in expected {
        assert!(stderr.contains(e), "stderr {stderr:?} lacks {e:?}");
    }
    let left: Vec<String> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert!(left.iter().all(|n| files.iter().any(|(f, _)| f == n)), "left behind: {left:?}");
}

fn arm_with_joints(n: usize) -> String {
    let mut c = ArmConfig::default();
    c.arm.links = (0..n).map(|i| c.arm.links[i % 4].clone()).collect();
    c.arm.friction = (0..n).map(|i| c.arm.friction[i % 4]).collect();
    c.to_toml_string()
}

#[test]
fn paper_refuses_arms_it_cannot_run_and_says_why() {
    paper_fails_with(&["-c", "one.toml"], &[("one.toml", arm_with_joints(1))], &["one.toml", "1 joint", "2 to 8"]);
    paper_fails_with(&["-c", "nine.toml"], &[("nine.toml", arm_with_joints(9))], &["nine.toml", "9 joints", "2 to 8"]);
    paper_fails_with(&["--real", "real3.toml"], &[("real3.toml", arm_with_joints(3))], &["real3.toml", "3 joints", "has 4"]);
    paper_fails_with(&["--scale", "3"], &[], &["reach", "1.000 m"]);
    paper_fails_with(&["--centre", "0.45"], &[], &["--centre takes two numbers"]);
    paper_fails_with(&["--intent-horizon", "-0.01"], &[], &["--intent-horizon", "outside 0 to 1 s"]);
    paper_fails_with(&["--intent-horizon", "soon"], &[], &["--intent-horizon", "not a number"]);
    paper_fails_with(&["--friction-max-speed", "0.1"], &[], &["--friction-max-speed", "outside 0.5 to 50 rad/s"]);
    paper_fails_with(&["--friction-max-speed", "NaN"], &[], &["--friction-max-speed", "outside 0.5 to 50 rad/s"]);
    paper_fails_with(&["--joint-gains", "50"], &[], &["--joint-gains takes two numbers"]);
    paper_fails_with(&["--tracking-gains", "1000"], &[], &["--tracking-gains takes kp,kd or kp,kd,null_damping", "got 1"]);
    paper_fails_with(&["--tracking-gains", "1000,160,20,1"], &[], &["--tracking-gains takes", "got 4"]);
    paper_fails_with(&["--tracking-gains", "1000,160,-1"], &[], &["--tracking-gains", "null-space damping must be >= 0"]);
    paper_fails_with(&["-c", "broken.toml"], &[("broken.toml", "[arm]\ngravity_m_s2 = 9.81\n".into())], &["broken.toml"]);
}

#[test]
fn paper_with_unstable_gains_fails_and_keeps_the_earlier_run() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    neurarm().args(["paper", "--quick", "-o"]).arg(&out).assert().success();
    let before = std::fs::read(out.join("results.json")).unwrap();
    let assert = neurarm().args(["paper", "--quick", "--joint-gains", "1e6,1e3", "-o"]).arg(&out).assert().failure();
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).to_string();
    assert!(stderr.contains("loop joint_") && stderr.contains("--joint-gains") && stderr.contains("no run was written"), "{stderr}");
    assert_eq!(std::fs::read(out.join("results.json")).unwrap(), before, "the earlier run was replaced");
    let left: Vec<String> = std::fs::read_dir(dir.path()).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    assert_eq!(left, ["run"], "staging folders left behind");
    // A folder that is not a run is not replaced.
    let other = dir.path().join("other");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("notes.txt"), "mine").unwrap();
    let assert = neurarm().args(["paper", "--quick", "-o"]).arg(&other).assert().failure();
    assert!(String::from_utf8_lossy(&assert.get_output().stderr).contains("not the folder of an earlier run"));
    assert_eq!(std::fs::read_to_string(other.join("notes.txt")).unwrap(), "mine");
}

#[test]
fn paper_measures_gravity_at_sampled_poses_over_the_whole_turn() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    // Through a symbolic link: the folder it points to gets the run, and the link stays.
    std::os::unix::fs::symlink("run_folder", &out).unwrap();
    let arm = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/arms/arm3.toml");
    neurarm()
        .args(["paper", "--quick", "--gravity-poses", "120", "--gravity-study", "60", "-c"])
        .arg(&arm)
        .arg("-o")
        .arg(&out)
        .assert()
        .success();
    assert!(std::fs::symlink_metadata(&out).unwrap().file_type().is_symlink());
    assert!(dir.path().join("run_folder/results.json").is_file());
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    assert_eq!(json["gravity"]["design"]["kind"].as_str(), Some("sampled"));
    assert_eq!(json["gravity"]["pairs"].as_u64(), Some(120));
    let pairs = NumericTable::read(&out.join("data/gravity_pairs.csv"), &["q_1", "q_2", "q_3"]).unwrap();
    for name in ["q_1", "q_2", "q_3"] {
        let q = pairs.column(name).unwrap();
        assert!(q.iter().all(|&a| (0.0..2.0 * std::f64::consts::PI).contains(&a)), "{name} wrapped into the turn");
        // Poses over the whole turn, not only the grid's span [0, 2π·2/3).
        assert!(q.iter().any(|&a| a > 2.0 * std::f64::consts::PI * 5.0 / 6.0), "{name} reaches the last sixth of the turn");
    }
    assert_eq!(json["gravity"]["encoding"].as_str(), Some("link_angles"));
    // The study: the 3³ grid and sampled 25, 50, 60 poses, three encodings each, over the whole turn.
    let points = json["gravity"]["study"]["points"].as_array().unwrap();
    assert_eq!(points.len(), 4 * 3);
    assert!(points.iter().all(|p| p["rms_share"].as_array().unwrap().len() == 3));
    assert!(out.join("gravity_study.png").is_file() && out.join("data/gravity_study.csv").is_file());
    let e = neurarm().args(["paper", "--gravity-poses", "3", "-o"]).arg(dir.path().join("x")).assert().failure();
    assert!(String::from_utf8_lossy(&e.get_output().stderr).contains("--gravity-poses"));
    // A design too large to measure is refused before anything runs, naming the way out.
    let six = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/arms/arm6.toml");
    let e = neurarm().args(["paper", "--gravity-grid", "7", "-c"]).arg(&six).arg("-o").arg(dir.path().join("y")).assert().failure();
    let stderr = String::from_utf8_lossy(&e.get_output().stderr).into_owned();
    assert!(stderr.contains("117649 poses") && stderr.contains("--gravity-poses"), "{stderr}");
    assert!(!dir.path().join("y").exists());
    let e = neurarm().args(["paper", "--gravity-inputs", "polar", "-o"]).arg(dir.path().join("z")).assert().failure();
    let stderr = String::from_utf8_lossy(&e.get_output().stderr).into_owned();
    assert!(stderr.contains("raw, joint_angles, link_angles"), "{stderr}");
}

/// `neurarm random-arm --seed SEED --joints JOINTS` to standard output: its TOML, asserting success.
fn random_arm(seed: &str, joints: &str) -> String {
    let o = neurarm().args(["random-arm", "--seed", seed, "--joints", joints]).output().unwrap();
    assert!(o.status.success(), "random-arm --seed {seed} --joints {joints}: {}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout).unwrap()
}

#[test]
fn random_arm_is_repeatable_valid_and_refuses_joint_counts_beyond_2_to_8() {
    let text = random_arm("7", "4");
    assert_eq!(random_arm("7", "4"), text, "the same seed and joint count gave another arm");
    ArmConfig::from_toml_str(&text).unwrap_or_else(|e| panic!("not a valid arm: {e}\n{text}"));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("arm.toml");
    neurarm().args(["random-arm", "--seed", "7", "--joints", "4", "-o"]).arg(&out).assert().success();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), text, "-o FILE differs from standard output");
    for joints in ["1", "9"] {
        let bad = dir.path().join("bad.toml");
        let e = neurarm().args(["random-arm", "--seed", "7", "--joints", joints, "-o"]).arg(&bad).assert().failure();
        let stderr = String::from_utf8_lossy(&e.get_output().stderr).into_owned();
        assert!(stderr.contains("--joints") && stderr.contains("2..=8"), "--joints {joints}: {stderr}");
        assert!(!bad.exists(), "--joints {joints} left a file");
    }
}

#[test]
fn random_arm_follows_its_seed_and_joint_count() {
    for joints in 2..=8 {
        let (a, b) = (random_arm("1", &joints.to_string()), random_arm("2", &joints.to_string()));
        assert_ne!(a, b, "seeds 1 and 2 gave the same {joints}-joint arm");
        for text in [&a, &b] {
            let table: toml::Table = toml::from_str(text).unwrap_or_else(|e| panic!("not TOML: {e}\n{text}"));
            let links = table["arm"]["links"].as_array().map_or(0, Vec::len);
            assert_eq!(links, joints, "a {joints}-joint arm with {links} links:\n{text}");
            ArmConfig::from_toml_str(text).unwrap_or_else(|e| panic!("not a valid arm: {e}\n{text}"));
        }
    }
}
