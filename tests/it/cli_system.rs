//! `neurarm simulate system.toml` with FMUs that are not neurarm's (the test FMUs of
//! `neurarm-test-fmus`): a unit that ends the run by discarding a step, strings and
//! enumerations in the CSV, a stop time that is not a whole number of steps, and Ctrl-C.
//! Needs the built binaries (scripts/test builds the workspace first).

use std::path::{Path, PathBuf};
use std::process::Stdio;

use assert_cmd::Command;
use neurarm_test_fmus::{fmu_in, TestModel};

fn neurarm() -> Command {
    Command::cargo_bin("neurarm").expect("the neurarm binary is built")
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// The CSV's lines split into fields (no quoted commas in the fields checked this way).
fn rows(path: &Path) -> Vec<Vec<String>> {
    std::fs::read_to_string(path).unwrap().lines().map(|l| l.split(',').map(str::to_owned).collect()).collect()
}

fn counter_system(dir: &Path, stop: f64, step: f64, extra: &str) -> PathBuf {
    fmu_in(dir, TestModel::Counter).unwrap();
    let text = format!(
        "[[fmu]]\nname = \"counter\"\npath = \"Counter.fmu\"\n\n[simulation]\nstop = {stop:?}\nstep = {step:?}\nrecord = [\"counter.count\", \"counter.t_last\"]\n{extra}"
    );
    write(dir, "counter.toml", &text)
}

#[test]
fn a_unit_that_discards_ends_the_run_with_a_notice_and_exit_0_unless_told_otherwise() {
    let dir = tempfile::tempdir().unwrap();
    let system = counter_system(dir.path(), 10.0, 0.1, "");
    let out = dir.path().join("out.csv");
    let assert = neurarm().arg("simulate").arg(&system).arg("-o").arg(&out).assert().success();
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).into_owned();
    assert!(stderr.contains("notice: unit 'counter' discarded the step from t = 8.8") && stderr.contains("asks to end"), "{stderr}");
    let table = rows(&out);
    assert_eq!(table[0], ["time", "counter.count", "counter.t_last"]);
    assert_eq!(table.len(), 1 + 89, "rows 0, 0.1, …, 8.8");
    let last = table.last().unwrap();
    assert_eq!((last[1].as_str(), last[2].parse::<f64>().unwrap()), ("88", 8.8), "{last:?}");

    // --on-discard error (or on_discard = "error" in the file) fails, keeping the rows.
    let out2 = dir.path().join("out2.csv");
    let assert = neurarm().arg("simulate").arg(&system).args(["--on-discard", "error", "-o"]).arg(&out2).assert().failure();
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).into_owned();
    assert!(stderr.contains("FMU 'counter' at t = 8.8") && stderr.contains("asks to end the simulation"), "{stderr}");
    assert!(stderr.contains("the 89 rows recorded before the failure"), "{stderr}");
    assert_eq!(rows(&out2).len(), 90);
    let strict = counter_system(dir.path(), 10.0, 0.1, "on_discard = \"error\"\n");
    neurarm().arg("simulate").arg(&strict).arg("-o").arg(dir.path().join("out3.csv")).assert().failure();
    neurarm().arg("simulate").arg(&system).args(["--on-discard", "maybe", "-o"]).arg(&out2).assert().failure();
}

#[test]
fn the_last_row_is_at_the_stop_time() {
    let dir = tempfile::tempdir().unwrap();
    let system = counter_system(dir.path(), 1.0, 0.3, "");
    let out = dir.path().join("out.csv");
    neurarm().arg("simulate").arg(&system).arg("-o").arg(&out).assert().success();
    let times: Vec<f64> = rows(&out)[1..].iter().map(|r| r[0].parse().unwrap()).collect();
    assert_eq!(times.len(), 5);
    assert!((times[3] - 0.9).abs() < 1e-12 && times[4] == 1.0, "{times:?}");
}

#[test]
fn strings_and_enumerations_are_written_as_text_and_integers() {
    let dir = tempfile::tempdir().unwrap();
    fmu_in(dir.path(), TestModel::Modes).unwrap();
    let system = write(
        dir.path(),
        "modes.toml",
        r#"[[fmu]]
name = "m"
path = "Modes.fmu"
parameters = { shape = "ramp", label = "say \"hi\", then" }

[simulation]
stop = 0.5
step = 0.25
record = ["m.y", "m.active", "m.status", "m.steps"]
"#,
    );
    let out = dir.path().join("out.csv");
    neurarm().arg("simulate").arg(&system).arg("-o").arg(&out).assert().success();
    let text = std::fs::read_to_string(&out).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "time,m.y,m.active,m.status,m.steps");
    assert_eq!(lines[1], r#"0,0,3,"say ""hi"", then:ramp",0"#);
    assert_eq!(lines[3], r#"0.5,0.5,3,"say ""hi"", then:ramp",2"#);
    // An unknown item is refused by name before anything runs.
    let bad = write(dir.path(), "bad.toml", &std::fs::read_to_string(&system).unwrap().replace("\"ramp\"", "\"zigzag\""));
    let assert = neurarm().arg("simulate").arg(&bad).arg("-o").arg(dir.path().join("bad.csv")).assert().failure();
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).into_owned();
    assert!(stderr.contains("'m'") && stderr.contains("'shape'") && stderr.contains("not an item of type Shape"), "{stderr}");
    assert!(!dir.path().join("bad.csv").exists());
}

#[test]
fn ctrl_c_ends_the_run_cleanly_with_the_rows_so_far() {
    let dir = tempfile::tempdir().unwrap();
    let system = counter_system(dir.path(), 1e9, 1e-3, "record_every = 100\n");
    let system_text = std::fs::read_to_string(&system)
        .unwrap()
        .replace("path = \"Counter.fmu\"", "path = \"Counter.fmu\"\nparameters = { stop_at = 1e12 }");
    std::fs::write(&system, system_text).unwrap();
    let out = dir.path().join("out.csv");
    let binary = assert_cmd::cargo::cargo_bin("neurarm");
    let child = std::process::Command::new(binary).arg("simulate").arg(&system).arg("-o").arg(&out).stderr(Stdio::piped()).spawn().unwrap();
    std::thread::sleep(std::time::Duration::from_millis(1500));
    let killed = std::process::Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(killed.success());
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted at t = ") && stderr.contains("rows so far"), "{stderr}");
    let table = rows(&out);
    assert!(table.len() > 2, "rows were written: {}", table.len());
    let last = table.last().unwrap();
    let (t, count): (f64, f64) = (last[0].parse().unwrap(), last[1].parse().unwrap());
    assert!(t > 0.0 && (count - t / 1e-3).abs() < 0.5, "a whole last row: {last:?}");
}

#[test]
fn a_reader_that_stops_early_ends_the_run_quietly() {
    use std::io::{BufRead, BufReader};
    let dir = tempfile::tempdir().unwrap();
    // 200 001 rows: far more than a pipe holds, so writing meets the closed pipe.
    let system = counter_system(dir.path(), 200.0, 1e-3, "");
    let binary = assert_cmd::cargo::cargo_bin("neurarm");
    let mut child = std::process::Command::new(binary)
        .arg("simulate")
        .arg(&system)
        .args(["-o", "-"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap()).read_line(&mut first).unwrap();
    assert_eq!(first, "time,counter.count,counter.t_last\n");
    // The reader is dropped here, as `head -1` ends.
    let output = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("error"), "{stderr}");
}

#[test]
fn fmi3_units_write_the_same_csv_as_their_fmi2_twins() {
    let dir = tempfile::tempdir().unwrap();
    // Each system once with FMI 2.0 FMUs and once with their FMI 3.0 twins: Real values with
    // fractions (a Float64 column is a Real one), integers, enumerations and strings, a
    // discard, a last short step, and a connection from one version to the other.
    let systems = [
        ("Counter", "[simulation]\nstop = 10.0\nstep = 0.1\nrecord = [\"a.count\", \"a.t_last\"]\n"),
        ("Modes", "[simulation]\nstop = 1.0\nstep = 0.3\nrecord = [\"a.y\", \"a.active\", \"a.status\", \"a.steps\"]\n"),
        ("Hold", "[simulation]\nstop = 1.0\nstep = 0.125\nrecord = [\"a.y\", \"b.y\"]\n"),
    ];
    for (model, simulation) in systems {
        let m = TestModel::named(model).unwrap();
        fmu_in(dir.path(), m).unwrap();
        neurarm_test_fmus::fmu3_in(dir.path(), m).unwrap();
        let mut csv = Vec::new();
        for (va, vb) in [("fmu", "fmu"), ("fmi3.fmu", "fmi3.fmu"), ("fmi3.fmu", "fmu")] {
            let mut text = format!("[[fmu]]\nname = \"a\"\npath = \"{model}.{va}\"\n\n");
            if model == "Hold" {
                // Hold's output fed back through a second Hold of the other version.
                text += &format!("[[fmu]]\nname = \"b\"\npath = \"{model}.{vb}\"\nparameters = {{ y = 0.25 }}\n\n");
                text += "[[connection]]\nfrom = \"b.y\"\nto = \"a.u\"\n[[connection]]\nfrom = \"a.y\"\nto = \"b.u\"\n\n";
            }
            let system = write(dir.path(), &format!("{model}-{va}-{vb}.toml"), &(text + simulation));
            let out = dir.path().join(format!("{model}-{va}-{vb}.csv"));
            neurarm().arg("simulate").arg(&system).arg("-o").arg(&out).assert().success();
            csv.push(std::fs::read_to_string(&out).unwrap());
        }
        assert!(csv[0].lines().count() > 3 && csv[0].contains('.'), "{model}: {}", csv[0]);
        assert_eq!(csv[1], csv[0], "{model}: FMI 3.0 against FMI 2.0");
        assert_eq!(csv[2], csv[0], "{model}: mixed against FMI 2.0");
    }
}
