//! A C program, compiled with the `cc` crate's compiler, drives the FMU binary through dlopen
//! as a C tool chain would; then the same under valgrind's memcheck, leaving FMU states unfreed
//! at `fmi2FreeInstance` as a careless host does: no error, no leak.

use crate::common;

use std::path::PathBuf;
use std::process::Command;

use neurarm_models::FmuSpec;
use neurarm_physics::arm::ArmState;
use neurarm_physics::config::ArmConfig;

fn compile_host(dir: &std::path::Path) -> PathBuf {
    let triple = format!("{}-unknown-linux-gnu", std::env::consts::ARCH);
    let compiler = cc::Build::new().target(&triple).host(&triple).opt_level(1).cargo_metadata(false).warnings(true).get_compiler();
    let exe = dir.join("host");
    let source = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/c/host.c");
    let out =
        compiler.to_command().args(["-Wall", "-Werror", "-g", source, "-o"]).arg(&exe).arg("-ldl").output().expect("run the C compiler");
    assert!(out.status.success(), "C compile failed: {}", String::from_utf8_lossy(&out.stderr));
    exe
}

fn host_args(fmu: &common::Fmu, runs: u32, steps: u32) -> Vec<String> {
    vec![
        common::binary_path().display().to_string(),
        fmu.guid(),
        fmu.resource_uri(),
        runs.to_string(),
        steps.to_string(),
        fmu.vr("tau_1").to_string(),
        fmu.vr("q_1").to_string(),
    ]
}

#[test]
fn c_host_runs_the_fmu_and_matches_the_in_process_arm() {
    let fmu = common::Fmu::new(&FmuSpec::planar_arm("PlanarArm", ArmConfig::default()));
    let exe = compile_host(fmu.dir.path());
    let out = Command::new(&exe).args(host_args(&fmu, 2, 1000)).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let q1: f64 = String::from_utf8_lossy(&out.stdout).trim().parse().unwrap();

    let config = ArmConfig::default();
    let (mut sim, _) = config.build().unwrap();
    let mut state = ArmState::at_rest(vec![0.0; 4]);
    for _ in 0..1000 {
        sim.step(&mut state, &[2.5, 0.0, 0.0, 0.0], 1e-3).unwrap();
    }
    assert!(state.q[0] > 0.1, "the arm moved");
    assert_eq!(q1.to_bits(), state.q[0].to_bits(), "C host {q1} vs in-process {}", state.q[0]);
}

#[test]
fn valgrind_finds_no_error_and_no_leak() {
    let Ok(v) = Command::new("valgrind").arg("--version").output() else {
        panic!("valgrind is not installed: scripts/test installs it (Debian package valgrind)");
    };
    assert!(v.status.success());
    let fmu = common::Fmu::new(&FmuSpec::planar_arm("PlanarArm", ArmConfig::default()));
    let exe = compile_host(fmu.dir.path());
    let out = Command::new("valgrind")
        .args(["--tool=memcheck", "--error-exitcode=99", "--leak-check=full", "--errors-for-leak-kinds=definite,indirect"])
        .args(["--show-leak-kinds=definite,indirect", "-q"])
        .arg(&exe)
        .args(host_args(&fmu, 100, 1000))
        .arg("5")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "valgrind reported problems (exit {:?}):\n{stderr}", out.status.code());
    assert!(!stderr.contains("definitely lost"), "{stderr}");
}
