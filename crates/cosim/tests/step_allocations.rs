//! A communication step of the master allocates nothing once the run is under way, whatever
//! the units' FMI versions and the types their connections carry (Real, Boolean, enumeration),
//! with nothing recorded. The FMUs allocate through their own libraries' allocators; the
//! counting allocator here sees the master's allocations only.
//! Needs the test FMUs' library: `cargo build --release -p neurarm-test-fmus` (scripts/test does).

use std::alloc::{GlobalAlloc, Layout, System as SystemAllocator};
use std::sync::atomic::{AtomicUsize, Ordering};

use neurarm_cosim::{Algorithm, FmiVersion, System};
use neurarm_test_fmus::{fmu3_in, fmu_in, TestModel};

struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

// SAFETY: every call is passed on unchanged to the system allocator, which upholds the
// GlobalAlloc contract; counting touches only a thread-local integer and allocates nothing.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: the caller upholds GlobalAlloc's contract for these arguments; they are passed on as given.
        unsafe { SystemAllocator.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller upholds GlobalAlloc's contract for these arguments; they are passed on as given.
        unsafe { SystemAllocator.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        // SAFETY: the caller upholds GlobalAlloc's contract for these arguments; they are passed on as given.
        unsafe { SystemAllocator.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn a_step_allocates_nothing_after_warm_up() {
    let dir = tempfile::tempdir().unwrap();
    let fmu = |model, version| match version {
        FmiVersion::V2 => fmu_in(dir.path(), model),
        FmiVersion::V3 => fmu3_in(dir.path(), model),
    };
    for (v1, v2) in [(FmiVersion::V2, FmiVersion::V2), (FmiVersion::V3, FmiVersion::V3), (FmiVersion::V3, FmiVersion::V2)] {
        for algorithm in [Algorithm::GaussSeidel, Algorithm::Jacobi] {
            let mut s = System::new();
            s.add_fmu("m1", &fmu(TestModel::Modes, v1).unwrap()).unwrap();
            s.add_fmu("m2", &fmu(TestModel::Modes, v2).unwrap()).unwrap();
            s.add_fmu("split", &fmu(TestModel::Split, v2).unwrap()).unwrap();
            s.connect("m1.active", "m2.follow").unwrap().connect("m1.y", "split.u1").unwrap();
            let mut sim = s.initialize(0.0, 0.01, algorithm, &[]).unwrap();
            for _ in 0..10 {
                sim.step().unwrap();
            }
            let before = ALLOCATIONS.load(Ordering::Relaxed);
            for _ in 0..200 {
                sim.step().unwrap();
            }
            let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;
            assert_eq!(allocations, 0, "{v1:?} → {v2:?}, {algorithm:?}: {allocations} allocations in 200 steps");
        }
    }
}
