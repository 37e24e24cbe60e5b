//! A global allocator that counts the allocations (and reallocations) made on a thread while it
//! watches, for the tests that a step or a training epoch allocates nothing. Counting per
//! thread keeps tests that run beside each other in one binary out of each other's counts. A
//! test binary gets this allocator by calling any function here.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

struct Counting;

thread_local! {
    static WATCHING: Cell<bool> = const { Cell::new(false) };
    static COUNT: Cell<usize> = const { Cell::new(0) };
}

// SAFETY: every call is passed on unchanged to the system allocator, which upholds the
// GlobalAlloc contract; counting touches only a thread-local integer and allocates nothing.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if WATCHING.with(Cell::get) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        // SAFETY: the caller upholds GlobalAlloc's contract for these arguments; they are passed on as given.
        unsafe { System.alloc(layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if WATCHING.with(Cell::get) {
            COUNT.with(|c| c.set(c.get() + 1));
        }
        // SAFETY: the caller upholds GlobalAlloc's contract for these arguments; they are passed on as given.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: the caller upholds GlobalAlloc's contract for these arguments; they are passed on as given.
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Starts counting this thread's allocations from 0.
pub fn start() {
    COUNT.with(|c| c.set(0));
    WATCHING.with(|w| w.set(true));
}

/// Stops counting; the allocations since [`start`].
pub fn stop() -> usize {
    WATCHING.with(|w| w.set(false));
    COUNT.with(Cell::get)
}

/// The allocations `f` makes on this thread.
pub fn allocations_during(f: impl FnOnce()) -> usize {
    start();
    f();
    stop()
}
