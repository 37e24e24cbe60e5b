//! Inputs the CLI reads that parse but are no usable data (issue 14's fuzzing findings, each
//! failing before its fix): an endless device as a table or a configuration, a weights file
//! that overflows, outputs that are not finite, configuration values beyond physical limits.
//! Each run fails with a message naming the file and the value, and writes nothing.

use std::ffi::OsStr;
use std::path::{Path, PathBuf};

use assert_cmd::Command;
use neurarm_nn::{MinMaxScaling, Mlp, Signal, StopReason, TrainReport, TrainSettings, WeightsFile};

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Runs `neurarm args…`, expects failure with every one of `expected` in stderr.
fn fails_with(args: &[&dyn AsRef<OsStr>], expected: &[&str]) {
    let args: Vec<&OsStr> = args.iter().map(|a| a.as_ref()).collect();
    let o = Command::cargo_bin("neurarm").unwrap().args(&args).timeout(std::time::Duration::from_secs(120)).output().unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "succeeded: {args:?}");
    for e in expected {
        assert!(stderr.contains(e), "{e:?} not in {stderr:?}");
    }
}

/// A one-input net y = lw·tanh(iw·x̃ + b1) + b2 on x scaled from [min, max].
fn net_file(dir: &Path, iw: f64, lw: f64, scaling: (f64, f64)) -> PathBuf {
    let net = Mlp {
        iw: nalgebra::DMatrix::from_element(1, 1, iw),
        b1: nalgebra::DVector::from_element(1, 0.1),
        lw: nalgebra::DMatrix::from_element(1, 1, lw),
        b2: nalgebra::DVector::from_element(1, 0.0),
        input_scaling: MinMaxScaling { min: vec![scaling.0], max: vec![scaling.1] },
        output_scaling: MinMaxScaling { min: vec![-1.0], max: vec![1.0] },
    };
    let signal = |name: &str| vec![Signal { name: name.into(), unit: String::new() }];
    let report = TrainReport {
        epochs: 1,
        best_epoch: 1,
        stop_reason: StopReason::Epochs,
        restart: 0,
        train_mse: 0.0,
        validation_mse: None,
        test_mse: None,
        counts: [10, 0, 0],
    };
    let file = WeightsFile::new(&net, signal("x"), signal("y"), TrainSettings::default(), report);
    write(dir, "net.json", &file.to_json())
}

#[test]
fn eval_refuses_an_endless_device_without_allocating_it() {
    // /dev/zero aborted `eval` on a 4 GiB allocation: there is no newline in it.
    let dir = tempfile::tempdir().unwrap();
    let net = net_file(dir.path(), 0.5, 0.7, (-1.0, 1.0));
    let out = dir.path().join("out.csv");
    fails_with(
        &[&"eval", &"-n", &net, &"-d", &"/dev/zero", &"-o", &out],
        &["/dev/zero", "line 1 is longer than 1 MiB: this is not a CSV table"],
    );
    assert!(!out.exists());
}

#[test]
fn eval_refuses_weights_no_trained_net_has_and_outputs_that_are_not_finite() {
    let dir = tempfile::tempdir().unwrap();
    let data = write(dir.path(), "x.csv", "x\n0.5\n-0.25\n1e10\n");
    let out = dir.path().join("out.csv");
    // A weight of 1.8e308 wrote -inf with exit 0.
    let big = net_file(dir.path(), 0.5, 1.7e308, (-1.0, 1.0));
    fails_with(&[&"eval", &"-n", &big, &"-d", &data, &"-o", &out], &["net.json", "a weight or bias is 1.7e308: beyond ±1e8"]);
    assert!(!out.exists());
    // A net within the limits whose input scaling spans 1e-300: an input outside it gives
    // 0·∞ in the first layer (1e10 on line 4), NaN out; refused with the line, nothing written.
    let narrow = net_file(dir.path(), 0.0, 0.7, (0.0, 1e-300));
    fails_with(
        &[&"eval", &"-n", &narrow, &"-d", &data, &"-o", &out],
        &["x.csv, line 4: the net's output 'y' is NaN", "nothing was written"],
    );
    assert!(!out.exists());
}

#[test]
fn configurations_beyond_physical_limits_and_endless_files_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let default = String::from_utf8(Command::cargo_bin("neurarm").unwrap().arg("default-config").output().unwrap().stdout).unwrap();
    // qd_noise_std_rad_s = 1.8e308 made `simulate` write inf.
    let noisy = write(dir.path(), "noisy.toml", &default.replacen("qd_noise_std_rad_s = 0.0", "qd_noise_std_rad_s = 1.7e308", 1));
    let torques = write(dir.path(), "tau.csv", "time,tau_1,tau_2,tau_3,tau_4\n0,1,0,0,0\n0.001,1,0,0,0\n");
    let out = dir.path().join("traj.csv");
    fails_with(
        &[&"simulate", &"-c", &noisy, &"-t", &torques, &"-o", &out],
        &["noisy.toml: qd_noise_std_rad_s = 1.7e308 is invalid: must be at most 1e5 rad/s"],
    );
    fails_with(&[&"simulate", &"-c", &"/dev/zero", &"-t", &torques, &"-o", &out], &["/dev/zero", "larger than 4 MiB"]);
    fails_with(&[&"simulate", &"/dev/zero", &"-o", &out], &["reading /dev/zero", "larger than 4 MiB"]);
    assert!(!out.exists());
}
