//! Where the commands write (`-o`, see `neurarm::output`): a file is replaced whole, a symbolic
//! link is written through and stays a link, `-` is standard output, a device or FIFO is
//! streamed; side files go beside files only. A simulation that turns NaN fails and writes
//! nothing. Numbers are written in the shortest round-trip form, also by the master's
//! recordings. Needs the FMU binary for the export and system tests (scripts/test builds it).

use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};

use assert_cmd::Command;

fn neurarm() -> Command {
    Command::cargo_bin("neurarm").unwrap()
}

fn repo(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn torque_csv() -> String {
    let mut s = String::from("time,tau_1,tau_2,tau_3,tau_4\n");
    for k in 0..=50 {
        let t = k as f64 * 1e-3;
        s += &format!("{t},{},-2,1,0.4\n", 3.0 * (5.0 * t).sin());
    }
    s
}

fn stderr_of(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// The trajectory `simulate` writes to a plain new file, as bytes (the reference for the other
/// destinations).
fn trajectory_in_a_file(dir: &Path, input: &Path) -> Vec<u8> {
    let plain = dir.join("plain.csv");
    neurarm().args(["simulate", "-t"]).arg(input).arg("-o").arg(&plain).assert().success();
    let bytes = std::fs::read(&plain).unwrap();
    std::fs::remove_file(&plain).unwrap();
    assert!(bytes.len() > 1000 && bytes.starts_with(b"time,q_1,"));
    bytes
}

/// Names in `dir`, sorted: to see that no temporary file was left.
fn names_in(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

#[test]
fn a_symbolic_link_is_written_through_and_stays_a_link() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let input = write(d, "tau.csv", &torque_csv());
    let want = trajectory_in_a_file(d, &input);
    std::fs::create_dir(d.join("data")).unwrap();
    let target = write(&d.join("data"), "real.csv", "old content\n");
    std::os::unix::fs::symlink("data/real.csv", d.join("link.csv")).unwrap();
    neurarm().args(["simulate", "-t"]).arg(&input).arg("-o").arg(d.join("link.csv")).assert().success();
    assert!(std::fs::symlink_metadata(d.join("link.csv")).unwrap().file_type().is_symlink(), "the link was replaced");
    assert_eq!(std::fs::read_link(d.join("link.csv")).unwrap(), Path::new("data/real.csv"));
    assert_eq!(std::fs::read(&target).unwrap(), want);
    assert_eq!(names_in(&d.join("data")), ["real.csv"]);
    assert_eq!(names_in(d), ["data", "link.csv", "tau.csv"]);

    // A chain of links, the last one dangling: the file it names is created.
    std::os::unix::fs::symlink(d.join("data/new.csv"), d.join("to_new")).unwrap();
    std::os::unix::fs::symlink("to_new", d.join("chain.csv")).unwrap();
    neurarm().args(["simulate", "-t"]).arg(&input).arg("-o").arg(d.join("chain.csv")).assert().success();
    assert!(std::fs::symlink_metadata(d.join("chain.csv")).unwrap().file_type().is_symlink());
    assert_eq!(std::fs::read(d.join("data/new.csv")).unwrap(), want);

    // A failed run leaves the target as it was.
    let bad = write(d, "bad.csv", "time,tau_1,tau_2,tau_3,tau_4\n0,1,1,1,x\n");
    neurarm().args(["simulate", "-t"]).arg(&bad).arg("-o").arg(d.join("link.csv")).assert().failure();
    assert_eq!(std::fs::read(&target).unwrap(), want);

    // A loop of links is refused by name.
    std::os::unix::fs::symlink("loop_b", d.join("loop_a")).unwrap();
    std::os::unix::fs::symlink("loop_a", d.join("loop_b")).unwrap();
    let o = neurarm().args(["simulate", "-t"]).arg(&input).arg("-o").arg(d.join("loop_a")).output().unwrap();
    assert!(!o.status.success() && stderr_of(&o).contains("loop_a"), "{}", stderr_of(&o));
}

/// Runs `simulate` into a FIFO in `d` read by another thread; returns what the reader got, or
/// `None` when the program did not open the FIFO (it replaced it, or failed) within a minute.
fn simulate_into_a_fifo(d: &Path, input: &Path) -> (std::process::Output, Option<Vec<u8>>) {
    let fifo = d.join("pipe.csv");
    assert!(std::process::Command::new("mkfifo").arg(&fifo).status().unwrap().success());
    let (sender, received) = std::sync::mpsc::channel();
    {
        let fifo = fifo.clone();
        std::thread::spawn(move || sender.send(std::fs::read(fifo).unwrap()));
    }
    let o = neurarm().args(["simulate", "-t"]).arg(input).arg("-o").arg(&fifo).output().unwrap();
    if !o.status.success() {
        // Let the reader go.
        drop(std::fs::OpenOptions::new().write(true).open(&fifo));
    }
    // A writer that replaced the FIFO instead of opening it would leave the reader waiting.
    let got = received.recv_timeout(std::time::Duration::from_secs(60)).ok();
    let still_a_fifo = std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo();
    std::fs::remove_file(&fifo).unwrap();
    (o, got.filter(|_| still_a_fifo))
}

#[test]
fn a_fifo_is_streamed_to_its_reader() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let input = write(d, "tau.csv", &torque_csv());
    let want = trajectory_in_a_file(d, &input);
    let (o, got) = simulate_into_a_fifo(d, &input);
    assert!(o.status.success(), "{}", stderr_of(&o));
    assert_eq!(got.expect("the FIFO was not opened and read"), want);
    assert_eq!(names_in(d), ["tau.csv"]);
}

#[test]
fn dash_writes_to_standard_output() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let input = write(d, "tau.csv", &torque_csv());
    let want = trajectory_in_a_file(d, &input);
    let o = neurarm().current_dir(d).args(["simulate", "-t"]).arg(&input).args(["-o", "-"]).output().unwrap();
    assert!(o.status.success(), "{}", stderr_of(&o));
    assert_eq!(o.stdout, want);
    assert!(stderr_of(&o).contains("to standard output"));

    // default-config: standard output by default, or a file.
    let o = neurarm().current_dir(d).args(["default-config"]).output().unwrap();
    let toml = String::from_utf8(o.stdout.clone()).unwrap();
    assert!(toml.contains("[arm]") && toml.contains("length_m"));
    neurarm().current_dir(d).args(["default-config", "-o", "arm.toml"]).assert().success();
    assert_eq!(std::fs::read_to_string(d.join("arm.toml")).unwrap(), toml);

    // eval and train: CSV and JSON on standard output.
    let mut pairs = String::from("qd_1,tau_friction_1\n");
    for k in 0..60 {
        let v = -3.0 + 0.1 * k as f64;
        pairs += &format!("{v},{}\n", 0.8 * v + 1.2 * (v / 0.05).tanh());
    }
    let pairs = write(d, "pairs.csv", &pairs);
    let o = neurarm()
        .current_dir(d)
        .args(["train", "-d", "pairs.csv", "--inputs", "qd_1", "--targets", "tau_friction_1", "--hidden", "4", "--epochs", "20", "-o", "-"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr_of(&o));
    let net = d.join("net.json");
    std::fs::write(&net, &o.stdout).unwrap();
    assert!(neurarm_nn::WeightsFile::read(&net).is_ok(), "the JSON on standard output is a weights file");
    let o = neurarm().current_dir(d).args(["eval", "-n", "net.json", "-d"]).arg(&pairs).args(["-o", "-"]).output().unwrap();
    assert!(o.status.success(), "{}", stderr_of(&o));
    let text = String::from_utf8(o.stdout.clone()).unwrap();
    assert!(text.starts_with("qd_1,tau_friction_1\n") && text.lines().count() == 61, "{text}");

    // plan: the CSV on standard output, the instructions on the terminal, no file.
    let o = neurarm().current_dir(d).args(["plan", "friction", "--joints", "1", "-o", "-"]).output().unwrap();
    assert!(o.status.success(), "{}", stderr_of(&o));
    assert!(String::from_utf8(o.stdout.clone()).unwrap().starts_with("time [s],segment,joint,"));
    assert!(stderr_of(&o).contains("Friction plan for"), "the instructions are shown: {}", stderr_of(&o));
    assert_eq!(names_in(d), ["arm.toml", "net.json", "pairs.csv", "tau.csv"]);

    // identify: the pairs on standard output, no .json of verdicts (and no file called "-").
    let o = neurarm()
        .current_dir(d)
        .args(["identify", "friction", "--joint", "1", "--log"])
        .arg(repo("examples/robot/friction_log.csv.gz"))
        .args(["-o", "-"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr_of(&o));
    let text = String::from_utf8(o.stdout.clone()).unwrap();
    assert!(text.starts_with("qd_1 [rad/s],tau_friction_1 [N.m],samples\n") && text.lines().count() > 10, "{text}");
    assert!(stderr_of(&o).contains("no .json of verdicts"));
    assert_eq!(names_in(d), ["arm.toml", "net.json", "pairs.csv", "tau.csv"]);
}

#[test]
fn binary_and_folder_outputs_refuse_dash_and_say_why() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for args in
        [&["export", "arm", "-o", "-"][..], &["export", "controller", "joint", "-o", "-"], &["export", "compensator", "--ideal", "-o", "-"]]
    {
        let o = neurarm().current_dir(d).args(args).output().unwrap();
        assert!(!o.status.success() && o.stdout.is_empty(), "{args:?}");
        assert!(stderr_of(&o).contains("an FMU is a binary archive"), "{args:?}: {}", stderr_of(&o));
    }
    let o = neurarm().current_dir(d).args(["compensator", "--friction-log", "log.csv", "-o", "-"]).output().unwrap();
    assert!(!o.status.success() && stderr_of(&o).contains("an FMU is a binary archive"), "{}", stderr_of(&o));
    // To a device there is no folder beside the FMU for the intermediate files.
    let o = neurarm().current_dir(d).args(["compensator", "--friction-log", "log.csv", "-o", "/dev/null"]).output().unwrap();
    assert!(!o.status.success() && stderr_of(&o).contains("give --work"), "{}", stderr_of(&o));
    let o = neurarm().current_dir(d).args(["paper", "--quick", "-o", "-"]).output().unwrap();
    assert!(!o.status.success() && stderr_of(&o).contains("not '-'"), "{}", stderr_of(&o));
    assert!(names_in(d).is_empty(), "{:?}", names_in(d));
}

#[test]
fn devices_are_written_directly() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let input = write(d, "tau.csv", &torque_csv());
    // The machine's devices are at stake (as root, a program that renames over its output would
    // replace /dev/null): try a FIFO of our own first.
    let (_, got) = simulate_into_a_fifo(d, &input);
    assert!(got.is_some(), "the program does not stream to a FIFO: not trying it on /dev/null");
    neurarm().args(["simulate", "-t"]).arg(&input).args(["-o", "/dev/null"]).assert().success();
    neurarm().current_dir(d).args(["export", "arm", "-o", "/dev/null"]).assert().success();
    neurarm().current_dir(d).args(["plan", "gravity", "--grid", "2", "-o", "/dev/null"]).assert().success();
    assert!(Path::new("/dev/null").metadata().unwrap().file_type().is_char_device(), "/dev/null is still a device");
    assert_eq!(names_in(d), ["tau.csv"]);

    // /dev/stdout with standard output redirected to a file: the file gets the trajectory, and
    // nothing is renamed over it (the process's descriptor would keep writing to a lost file).
    let want = trajectory_in_a_file(d, &input);
    let captured = d.join("captured.csv");
    let file = std::fs::File::create(&captured).unwrap();
    let o = std::process::Command::new(assert_cmd::cargo::cargo_bin("neurarm"))
        .args(["simulate", "-t"])
        .arg(&input)
        .args(["-o", "/dev/stdout"])
        .stdout(file)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr_of(&o));
    assert_eq!(std::fs::read(&captured).unwrap(), want);
    // An FMU streamed through a pipe is the same archive a file gets.
    let o = neurarm().current_dir(d).args(["export", "arm", "--name", "Arm", "-o", "/dev/stdout"]).output().unwrap();
    assert!(o.status.success(), "{}", stderr_of(&o));
    neurarm().current_dir(d).args(["export", "arm", "--name", "Arm", "-o", "Arm.fmu"]).assert().success();
    assert_eq!(o.stdout, std::fs::read(d.join("Arm.fmu")).unwrap());
}

#[test]
fn side_files_go_beside_the_name_given() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("plans")).unwrap();
    std::os::unix::fs::symlink("plans/friction_v2.csv", d.join("friction.csv")).unwrap();
    neurarm().current_dir(d).args(["plan", "friction", "--joints", "1", "-o", "friction.csv"]).assert().success();
    assert!(std::fs::symlink_metadata(d.join("friction.csv")).unwrap().file_type().is_symlink());
    assert!(std::fs::read_to_string(d.join("plans/friction_v2.csv")).unwrap().starts_with("time [s],"));
    assert!(std::fs::read_to_string(d.join("friction.txt")).unwrap().contains("Friction plan for"));
}

#[test]
fn a_simulation_that_turns_nan_fails_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // 1e9 N·m on the first joint for one 1 ms step: the state is NaN at the last row.
    let input = write(d, "tau.csv", "time,tau_1,tau_2,tau_3,tau_4\n0,0,0,0,0\n0.001,1e9,0,0,0\n0.002,0,0,0,0\n");
    let out = d.join("traj.csv");
    let o = neurarm().args(["simulate", "-t"]).arg(&input).arg("-o").arg(&out).output().unwrap();
    let stderr = stderr_of(&o);
    assert!(!o.status.success(), "{stderr}");
    for part in
        ["joint ", "became NaN", "from t = 0.001 s to 0.002 s", "1000000000, 0, 0, 0", "4 RK4 sub-steps of 0.00025 s", "internal_step_s"]
    {
        assert!(stderr.contains(part), "{stderr:?} lacks {part:?}");
    }
    assert!(!out.exists());
    assert_eq!(names_in(d), ["tau.csv"]);
    // Nor does anything reach standard output.
    let o = neurarm().args(["simulate", "-t"]).arg(&input).args(["-o", "-"]).output().unwrap();
    assert!(!o.status.success() && o.stdout.is_empty());
    // Which joint: the state of the in-process simulation says.
    let config = neurarm_physics::config::ArmConfig::default();
    let (mut sim, _) = config.build().unwrap();
    let mut state = neurarm_physics::arm::ArmState::at_rest(vec![0.0; 4]);
    sim.step(&mut state, &[0.0; 4], 1e-3).unwrap();
    sim.step(&mut state, &[1e9, 0.0, 0.0, 0.0], 1e-3).unwrap();
    let first = (0..4).find(|&i| !state.q[i].is_finite() || !state.qd[i].is_finite()).expect("the state turned non-finite");
    let what = if state.q[first].is_finite() { "velocity" } else { "angle" };
    let o = neurarm().args(["simulate", "-t"]).arg(&input).arg("-o").arg(&out).output().unwrap();
    assert!(stderr_of(&o).contains(&format!("joint {}'s {what} became", first + 1)), "{}", stderr_of(&o));
}

/// Every cell of `text` (a CSV with a header) against `rows`, bit for bit.
fn assert_cells_are(text: &str, rows: &[Vec<f64>]) {
    let body: Vec<&str> = text.lines().skip(1).collect();
    assert_eq!(body.len(), rows.len());
    for (line, row) in body.iter().zip(rows) {
        let cells: Vec<&str> = line.split(',').collect();
        assert_eq!(cells.len(), row.len());
        for (cell, v) in cells.iter().zip(row) {
            assert_eq!(cell.parse::<f64>().unwrap().to_bits(), v.to_bits(), "{cell} for {v:e}");
            assert!(cell.len() <= 24, "{cell} is not the shortest form");
        }
    }
}

#[test]
fn the_masters_recordings_are_written_in_the_shortest_round_trip_form() {
    use neurarm_models::{FmuSpec, GainSpec, IntegratorSpec, ModelSpec};
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (identifier, model) in
        [("Integrator", ModelSpec::Integrator(IntegratorSpec { y0: 0.0 })), ("Gain", ModelSpec::Gain(GainSpec { k: 1.0 }))]
    {
        neurarm::export::export_fmu(&FmuSpec { identifier: identifier.into(), model }, &[], &d.join(format!("{identifier}.fmu"))).unwrap();
    }
    // Two loops y' = k y: one decaying from a subnormal through the smallest subnormal to 0 (and
    // -0 out of its gain), one growing to near the largest double.
    let system = "\
[[fmu]]\nname = \"small\"\npath = \"Integrator.fmu\"\nparameters = { y0 = 1e-310 }\n\
[[fmu]]\nname = \"shrink\"\npath = \"Gain.fmu\"\nparameters = { k = -8.0 }\n\
[[fmu]]\nname = \"large\"\npath = \"Integrator.fmu\"\nparameters = { y0 = 1e300 }\n\
[[fmu]]\nname = \"grow\"\npath = \"Gain.fmu\"\nparameters = { k = 2.0 }\n\
[[connection]]\nfrom = \"small.y\"\nto = \"shrink.u\"\n[[connection]]\nfrom = \"shrink.y\"\nto = \"small.u\"\n\
[[connection]]\nfrom = \"large.y\"\nto = \"grow.u\"\n[[connection]]\nfrom = \"grow.y\"\nto = \"large.u\"\n\
[simulation]\nstop = 10.0\nstep = 0.1\nrecord = [\"small.y\", \"shrink.y\", \"large.y\"]\n";
    let system_path = write(d, "system.toml", system);
    let out = d.join("run.csv");
    let o = neurarm().args(["simulate"]).arg(&system_path).arg("-o").arg(&out).output().unwrap();
    assert!(o.status.success(), "{}", stderr_of(&o));
    let spec = neurarm_cosim::SystemSpec::from_toml(system, "system.toml").unwrap();
    let outcome = neurarm_cosim::run(&spec, d, None).unwrap();
    assert!(outcome.error.is_none());
    let text = std::fs::read_to_string(&out).unwrap();
    assert_cells_are(&text, &outcome.rows);
    // The extremes are there: subnormals, the smallest one, -0, and values near 1e308.
    let all: Vec<f64> = outcome.rows.iter().flatten().copied().collect();
    assert!(all.iter().any(|v| v.is_subnormal()) && all.contains(&5e-324));
    assert!(all.iter().any(|v| *v == 0.0 && v.is_sign_negative()));
    assert!(all.iter().any(|v| *v > 1e307));
    assert!(text.contains("1e-310") && text.contains("5e-324") && text.contains(",-0,"), "{text}");
}
