//! The crate's one thread pool and what runs on it: [`ParallelFor`] (numbered tasks, on any
//! thread, in any order), [`Serial`] (all on the calling thread), [`Pool`] (worker threads that
//! live for a scope, see [`Pool::scoped`]) and [`SharedSlice`] (one slice that tasks write in
//! disjoint parts).
//!
//! The trainer's tasks write disjoint parts of its buffers and its sums are added in a fixed
//! order, so how tasks are spread over threads never changes a result.

use std::marker::PhantomData;
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Condvar, Mutex, MutexGuard, TryLockError};

/// Runs numbered tasks, possibly on several threads. The trainer and its linear algebra hand
/// out tasks that write disjoint parts of one buffer, so how they are spread over threads
/// never changes a result.
pub trait ParallelFor: Sync {
    /// Calls `task(i)` once for every i in 0..tasks, in any order and on any thread, and
    /// returns when all calls have returned.
    fn run(&self, tasks: usize, task: &(dyn Fn(usize) + Sync));
}

/// Runs every task on the calling thread, in order.
pub struct Serial;

impl ParallelFor for Serial {
    fn run(&self, tasks: usize, task: &(dyn Fn(usize) + Sync)) {
        for i in 0..tasks {
            task(i);
        }
    }
}

/// A mutable slice that tasks on several threads write in parts no two tasks share.
#[derive(Clone, Copy)]
pub struct SharedSlice<'a> {
    ptr: *mut f64,
    len: usize,
    _borrow: PhantomData<&'a mut [f64]>,
}

// SAFETY: a SharedSlice is only a &mut [f64] whose parts are handed out by `part`, whose
// callers promise that no two live parts overlap.
unsafe impl Send for SharedSlice<'_> {}
// SAFETY: as for Send: threads that share it touch disjoint parts only (`part`, `view`).
unsafe impl Sync for SharedSlice<'_> {}

impl<'a> SharedSlice<'a> {
    /// Shares `slice` for the lifetime of the borrow.
    pub fn new(slice: &'a mut [f64]) -> Self {
        Self { ptr: slice.as_mut_ptr(), len: slice.len(), _borrow: PhantomData }
    }

    /// Elements `start..start + len`.
    ///
    /// # Safety
    /// No other live reference (from this or another call) may overlap the range.
    #[allow(clippy::mut_from_ref)]
    pub unsafe fn part(&self, start: usize, len: usize) -> &'a mut [f64] {
        assert!(start <= self.len && len <= self.len - start, "part {start}+{len} of {}", self.len);
        // SAFETY: in bounds (checked), and the caller guarantees exclusivity.
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(start), len) }
    }

    /// Elements `start..start + len`, read only.
    ///
    /// # Safety
    /// No live mutable part may overlap the range.
    pub unsafe fn view(&self, start: usize, len: usize) -> &'a [f64] {
        assert!(start <= self.len && len <= self.len - start, "view {start}+{len} of {}", self.len);
        // SAFETY: in bounds (checked), and the caller guarantees nobody writes it meanwhile.
        unsafe { std::slice::from_raw_parts(self.ptr.add(start), len) }
    }

    /// The raw pointer to element 0, for GEMM calls whose operands are parts no task writes.
    pub fn as_ptr(&self) -> *mut f64 {
        self.ptr
    }
}

/// The number of threads training uses by default: `NEURARM_THREADS` if set to a positive
/// number, otherwise the machine's available parallelism. Results do not depend on it.
pub fn default_threads() -> usize {
    std::env::var("NEURARM_THREADS")
        .ok()
        .and_then(|v| v.parse().ok())
        .filter(|&t: &usize| t > 0)
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()))
}

/// The task of a [`ParallelFor::run`] call.
type Task<'a> = dyn Fn(usize) + Sync + 'a;

/// A job in flight: the caller's task with its lifetime erased (see [`Pool::run`]).
#[derive(Clone, Copy)]
struct Job {
    task: *const Task<'static>,
    tasks: usize,
}

// SAFETY: the task is Sync, and the pointer is only followed while `run` keeps it alive.
unsafe impl Send for Job {}

struct State {
    generation: u64,
    job: Option<Job>,
    /// Workers that took the current job and have not yet left it.
    busy: usize,
    shutdown: bool,
}

/// Spin iterations (≈ 0.1–0.3 ms) before a waiting thread sleeps: the gaps between an
/// epoch's parallel parts are shorter than that, and a sleeping thread takes tens of µs
/// to wake. After the first [`SPIN_HARD`] a spinning thread yields its core at every
/// iteration, so that on a machine busy with other work it does not hold up the thread
/// it waits for.
const SPIN: u32 = 1 << 14;
const SPIN_HARD: u32 = 1 << 11;

#[inline]
fn pause(spins: u32) {
    if spins < SPIN_HARD {
        std::hint::spin_loop();
    } else {
        std::thread::yield_now();
    }
}

/// Worker threads that run the tasks of [`ParallelFor::run`] calls for as long as a scope lasts
/// ([`Pool::scoped`]), spinning briefly and then sleeping between calls, since spawning threads
/// for every part of an epoch costs too much (docs/decisions/0010-worker-pool.md). A pool of
/// `threads` threads has `threads − 1` workers plus the caller; tasks are taken in increasing
/// order, each by the first thread free. One job runs at a time: a [`ParallelFor::run`] called
/// while another is in flight (by one of its tasks, or by another thread) runs its own tasks on
/// its calling thread.
pub struct Pool {
    /// Held by the caller whose job is in flight.
    caller: Mutex<()>,
    state: Mutex<State>,
    wake: Condvar,
    idle: Condvar,
    /// Mirrors of `state.generation` and `state.busy` for spinning without the lock.
    generation: AtomicU64,
    busy: AtomicUsize,
    next: AtomicUsize,
    workers: usize,
}

impl Pool {
    /// A pool for `threads` threads in all: the caller and `threads − 1` workers, each of
    /// which must call [`Pool::serve`] until [`Pool::shutdown`] ([`Pool::scoped`] does both).
    pub fn new(threads: usize) -> Self {
        Self {
            caller: Mutex::new(()),
            state: Mutex::new(State { generation: 0, job: None, busy: 0, shutdown: false }),
            wake: Condvar::new(),
            idle: Condvar::new(),
            generation: AtomicU64::new(0),
            busy: AtomicUsize::new(0),
            next: AtomicUsize::new(0),
            workers: threads.max(1) - 1,
        }
    }

    /// Number of worker threads (the caller of [`ParallelFor::run`] not counted).
    pub fn workers(&self) -> usize {
        self.workers
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    fn claim(&self, task: &Task<'_>, tasks: usize) {
        loop {
            let i = self.next.fetch_add(1, Ordering::Relaxed);
            if i >= tasks {
                break;
            }
            task(i);
        }
    }

    /// A worker's loop: runs tasks of every job until [`Pool::shutdown`].
    pub fn serve(&self) {
        let mut seen = 0;
        loop {
            let mut spins = 0;
            while self.generation.load(Ordering::Acquire) == seen && spins < SPIN {
                pause(spins);
                spins += 1;
            }
            let job = {
                let mut st = self.lock();
                while st.generation == seen && !st.shutdown {
                    st = self.wake.wait(st).unwrap_or_else(|e| e.into_inner());
                }
                if st.shutdown {
                    return;
                }
                seen = st.generation;
                let Some(job) = st.job else { continue };
                st.busy += 1;
                self.busy.store(st.busy, Ordering::Release);
                job
            };
            let _leave = Leave(self);
            // SAFETY: `run` withdraws the job only after this worker has left it.
            self.claim(unsafe { &*job.task }, job.tasks);
        }
    }

    /// Ends every worker's [`Pool::serve`].
    pub fn shutdown(&self) {
        self.lock().shutdown = true;
        self.wake.notify_all();
    }

    /// Runs `f` with a pool of `threads` threads in all (0 counts as 1): the calling thread
    /// and `threads − 1` workers that serve it until `f` returns (or panics), then end.
    pub fn scoped<R>(threads: usize, f: impl FnOnce(&Pool) -> R) -> R {
        let pool = Pool::new(threads);
        std::thread::scope(|scope| {
            for _ in 0..pool.workers() {
                scope.spawn(|| pool.serve());
            }
            // Stops the workers however `f` ends, so that the scope can join them.
            struct Stop<'a>(&'a Pool);
            impl Drop for Stop<'_> {
                fn drop(&mut self) {
                    self.0.shutdown();
                }
            }
            let _stop = Stop(&pool);
            f(&pool)
        })
    }
}

/// Marks a worker as having left its job (also when a task panics).
struct Leave<'a>(&'a Pool);

impl Drop for Leave<'_> {
    fn drop(&mut self) {
        let mut st = self.0.lock();
        st.busy -= 1;
        self.0.busy.store(st.busy, Ordering::Release);
        if st.busy == 0 {
            self.0.idle.notify_all();
        }
    }
}

/// Withdraws the caller's job once no worker is in it (also when a task panics).
struct Withdraw<'a>(&'a Pool);

impl Drop for Withdraw<'_> {
    fn drop(&mut self) {
        let mut spins = 0;
        while self.0.busy.load(Ordering::Acquire) > 0 && spins < SPIN {
            pause(spins);
            spins += 1;
        }
        let mut st = self.0.lock();
        while st.busy > 0 {
            st = self.0.idle.wait(st).unwrap_or_else(|e| e.into_inner());
        }
        st.job = None;
    }
}

impl ParallelFor for Pool {
    fn run(&self, tasks: usize, task: &(dyn Fn(usize) + Sync)) {
        if self.workers == 0 || tasks < 2 {
            (0..tasks).for_each(task);
            return;
        }
        // The job in flight and its task counter are the pool's alone: a second caller would
        // reset the counter under the first one's tasks.
        let _caller = match self.caller.try_lock() {
            Ok(guard) => guard,
            Err(TryLockError::Poisoned(poisoned)) => poisoned.into_inner(),
            Err(TryLockError::WouldBlock) => {
                (0..tasks).for_each(task);
                return;
            }
        };
        let task: *const Task<'_> = task;
        // SAFETY: only the lifetime is erased. Workers take the job under the lock and are
        // counted in `busy`; `Withdraw` removes it under the lock once `busy` is 0, before
        // this function returns or unwinds, so no worker follows the pointer after the
        // borrow ends.
        let task = unsafe { std::mem::transmute::<*const Task<'_>, *const Task<'static>>(task) };
        {
            let mut st = self.lock();
            self.next.store(0, Ordering::Relaxed);
            st.job = Some(Job { task, tasks });
            st.generation += 1;
            self.generation.store(st.generation, Ordering::Release);
        }
        self.wake.notify_all();
        let _withdraw = Withdraw(self);
        // SAFETY: the pointer was made from a reference alive for this whole call.
        self.claim(unsafe { &*task }, tasks);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every task of `tasks` runs once: counts per task.
    fn counts(par: &dyn ParallelFor, tasks: usize) -> Vec<usize> {
        let hits: Vec<AtomicUsize> = (0..tasks).map(|_| AtomicUsize::new(0)).collect();
        par.run(tasks, &|i| {
            hits[i].fetch_add(1, Ordering::Relaxed);
        });
        hits.into_iter().map(AtomicUsize::into_inner).collect()
    }

    #[test]
    fn every_task_runs_once_also_when_tasks_and_threads_call_the_pool_again() {
        Pool::scoped(3, |pool| {
            assert_eq!(pool.workers(), 2);
            assert_eq!(counts(pool, 1000), vec![1; 1000]);
            // A task that runs a job of its own on the same pool, and two threads at once.
            let inner: Vec<AtomicUsize> = (0..50).map(|_| AtomicUsize::new(0)).collect();
            pool.run(50, &|i| {
                assert_eq!(counts(pool, 7), vec![1; 7]);
                inner[i].fetch_add(1, Ordering::Relaxed);
            });
            assert!(inner.iter().all(|c| c.load(Ordering::Relaxed) == 1));
            std::thread::scope(|s| {
                let other = s.spawn(|| (0..200).all(|_| counts(pool, 64) == vec![1; 64]));
                assert!((0..200).all(|_| counts(pool, 64) == vec![1; 64]));
                assert!(other.join().unwrap());
            });
        });
        assert_eq!(counts(&Serial, 5), vec![1; 5]);
    }
}
