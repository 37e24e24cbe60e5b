//! FMUs with the same binary share one loaded copy. Alone in its test program, so that no
//! other test's FMUs are mapped into the process while it counts.
//! Needs the test FMUs' library: `cargo build --release -p neurarm-test-fmus` (scripts/test does).

use neurarm_cosim::{Algorithm, RunEnd, System, Value};
use neurarm_test_fmus::{fmu_in, TestModel};

/// FMUs with the same binary share one loaded copy (the test FMUs are one library renamed):
/// the process maps one file of the units' unpacked archives, not three.
#[cfg(target_os = "linux")]
#[test]
fn identical_binaries_are_loaded_once() {
    let dir = tempfile::tempdir().unwrap();
    let split = fmu_in(dir.path(), TestModel::Split).unwrap();
    let counter = fmu_in(dir.path(), TestModel::Counter).unwrap();
    let mut s = System::new();
    s.add_fmu("a", &split).unwrap().add_fmu("b", &split).unwrap().add_fmu("c", &counter).unwrap();
    s.set("a", "u1", Value::Real(1.0)).unwrap().set("b", "k", Value::Real(3.0)).unwrap();
    s.connect("a.y1", "b.u1").unwrap();
    let mut sim = s.initialize(0.0, 0.5, Algorithm::GaussSeidel, &["b.y1".to_owned(), "c.count".to_owned()]).unwrap();
    assert_eq!(sim.run_until(1.0).unwrap(), RunEnd::Completed);
    assert_eq!(sim.rows().last().unwrap()[1..], [6.0, 2.0], "instances of the shared library keep their own parameters and state");
    let maps = std::fs::read_to_string("/proc/self/maps").unwrap();
    let mut mapped: Vec<&str> = maps
        .lines()
        .filter_map(|l| l.split_whitespace().nth(5))
        .filter(|p| p.contains("/neurarm-cosim-") && p.contains("/binaries/"))
        .collect();
    mapped.sort_unstable();
    mapped.dedup();
    assert_eq!(mapped.len(), 1, "{mapped:?}");
}
