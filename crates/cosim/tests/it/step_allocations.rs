//! A communication step of the master allocates nothing once the run is under way, whatever
//! the units' FMI versions and the types their connections carry (Real, Boolean, enumeration),
//! with nothing recorded or recording into room reserved ahead. The FMUs allocate through their
//! own libraries' allocators; the
//! counting allocator sees the master's allocations only, on the stepping thread.
//! Needs the test FMUs' library: `cargo build --release -p neurarm-test-fmus` (scripts/test does).

use neurarm_cosim::{Algorithm, FmiVersion, System};
use neurarm_test_fmus::{fmu3_in, fmu_in, TestModel};
use neurarm_test_support::allocations;

#[test]
fn a_step_allocates_nothing_after_warm_up() {
    assert!(allocations::allocations_during(|| drop(std::hint::black_box(Box::new(1)))) >= 1, "the counter must see allocations");
    let dir = tempfile::tempdir().unwrap();
    let fmu = |model, version| match version {
        FmiVersion::V2 => fmu_in(dir.path(), model),
        FmiVersion::V3 => fmu3_in(dir.path(), model),
    };
    for (v1, v2) in [(FmiVersion::V2, FmiVersion::V2), (FmiVersion::V3, FmiVersion::V3), (FmiVersion::V3, FmiVersion::V2)] {
        for algorithm in [Algorithm::GaussSeidel, Algorithm::Jacobi] {
            let system = || {
                let mut s = System::new();
                s.add_fmu("m1", &fmu(TestModel::Modes, v1).unwrap()).unwrap();
                s.add_fmu("m2", &fmu(TestModel::Modes, v2).unwrap()).unwrap();
                s.add_fmu("split", &fmu(TestModel::Split, v2).unwrap()).unwrap();
                s.connect("m1.active", "m2.follow").unwrap().connect("m1.y", "split.u1").unwrap();
                s
            };
            for record in [&[][..], &["m1.y".to_owned(), "m2.active".to_owned(), "split.y1".to_owned()][..]] {
                let mut sim = system().initialize(0.0, 0.01, algorithm, record).unwrap();
                for _ in 0..10 {
                    sim.step().unwrap();
                }
                let before = sim.rows().len();
                sim.reserve_steps(200);
                let allocations = allocations::allocations_during(|| {
                    for _ in 0..200 {
                        sim.step().unwrap();
                    }
                });
                let what = format!("{v1:?} → {v2:?}, {algorithm:?}, recording {record:?}");
                assert_eq!(allocations, 0, "{what}: {allocations} allocations in 200 steps");
                if !record.is_empty() {
                    assert_eq!(sim.rows().len(), before + 200, "{what}: a row per step");
                    assert_eq!(sim.rows().last().unwrap().len(), 4, "{what}: time and three variables");
                }
            }
        }
    }
}
