//! A team of threads that share out one product: the calling thread plus parked helpers, kept
//! per calling thread and reused, so that handing out a job allocates nothing.
//!
//! A job is a `Fn(&Part)` that every member runs with its own index; members meet at
//! [`Part::barrier`] when one phase's output is the next one's input (packing, then the
//! product). A helper spins a little after each job, since the next product of an update comes
//! within microseconds, and then parks until woken.

use std::cell::RefCell;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::thread::{self, JoinHandle, Thread};
use std::time::{Duration, Instant};

/// One member's view of a job: which share is its own, and the team's barrier.
pub struct Part<'a> {
    pub index: usize,
    pub count: usize,
    barrier: Option<&'a SpinBarrier>,
}

impl Part<'_> {
    /// Wait until every member of the job got here.
    pub fn barrier(&self) {
        if let Some(b) = self.barrier {
            b.wait();
        }
    }

    /// This member's share of `0..n` in contiguous chunks of `grain` (the last may be short).
    pub fn share(&self, n: usize, grain: usize) -> std::ops::Range<usize> {
        let chunks = n.div_ceil(grain.max(1));
        let (lo, hi) = (
            chunks * self.index / self.count,
            chunks * (self.index + 1) / self.count,
        );
        (lo * grain).min(n)..(hi * grain).min(n)
    }
}

/// Run `job` on `threads` threads of this thread's team (the caller is member 0). Public for
/// element-wise work outside the products (the optimiser's step) that shares the same threads.
pub fn run(threads: usize, job: &(dyn Fn(&Part<'_>) + Sync)) {
    if threads <= 1 {
        return job(&Part {
            index: 0,
            count: 1,
            barrier: None,
        });
    }
    TEAM.with(|team| {
        let mut team = team.borrow_mut();
        let team = team.get_or_insert_with(Team::default);
        team.grow(threads - 1);
        team.run(threads, job);
    });
}

thread_local! {
    static TEAM: RefCell<Option<Team>> = const { RefCell::new(None) };
}

/// A sense-reversing spin barrier for the members of one job.
struct SpinBarrier {
    members: AtomicUsize,
    arrived: AtomicUsize,
    generation: AtomicUsize,
}

impl SpinBarrier {
    fn wait(&self) {
        let generation = self.generation.load(Ordering::Acquire);
        if self.arrived.fetch_add(1, Ordering::AcqRel) + 1 == self.members.load(Ordering::Relaxed) {
            self.arrived.store(0, Ordering::Relaxed);
            self.generation.fetch_add(1, Ordering::Release);
        } else {
            let mut spin = Backoff::default();
            while self.generation.load(Ordering::Acquire) == generation {
                spin.snooze();
            }
        }
    }
}

struct Shared {
    /// Counts jobs handed out; a helper runs a job when it sees this change.
    epoch: AtomicU64,
    /// The current job, written by the caller before `epoch` is bumped (Release) and read by
    /// helpers after they see the bump (Acquire).
    job: std::sync::Mutex<Option<JobSlot>>,
    members: AtomicUsize,
    /// Helpers of the current job that have not finished it.
    pending: AtomicUsize,
    panicked: AtomicBool,
    stop: AtomicBool,
    barrier: SpinBarrier,
}

/// What a helper needs to run its part: the job and where the caller's `&dyn Fn` lives.
#[derive(Clone, Copy)]
struct JobSlot {
    job: *const (dyn Fn(&Part<'_>) + Sync),
}

// SAFETY: the pointer is only dereferenced while the caller, who owns the closure, waits in
// `Team::run` for every helper to finish; the closure is `Sync`.
unsafe impl Send for JobSlot {}

#[derive(Default)]
struct Team {
    shared: Option<Arc<Shared>>,
    helpers: Vec<(JoinHandle<()>, Thread)>,
}

impl Team {
    fn shared(&mut self) -> &Arc<Shared> {
        self.shared.get_or_insert_with(|| {
            Arc::new(Shared {
                epoch: AtomicU64::new(0),
                job: std::sync::Mutex::new(None),
                members: AtomicUsize::new(1),
                pending: AtomicUsize::new(0),
                panicked: AtomicBool::new(false),
                stop: AtomicBool::new(false),
                barrier: SpinBarrier {
                    members: AtomicUsize::new(1),
                    arrived: AtomicUsize::new(0),
                    generation: AtomicUsize::new(0),
                },
            })
        })
    }

    /// Spawn helpers until there are `n`.
    fn grow(&mut self, n: usize) {
        while self.helpers.len() < n {
            let shared = Arc::clone(self.shared());
            let index = self.helpers.len() + 1;
            let handle = thread::Builder::new()
                .name(format!("dualrep-kernels-{index}"))
                .spawn(move || helper(&shared, index))
                .expect("spawning a kernel thread");
            let thread = handle.thread().clone();
            self.helpers.push((handle, thread));
        }
    }

    fn run(&mut self, members: usize, job: &(dyn Fn(&Part<'_>) + Sync)) {
        let shared = Arc::clone(self.shared());
        // SAFETY (lifetime erasure): helpers dereference this only until they decrement
        // `pending`, and this function does not return before `pending` is back to 0.
        let erased: *const (dyn Fn(&Part<'_>) + Sync) = unsafe { std::mem::transmute(job) };
        *shared.job.lock().unwrap_or_else(|e| e.into_inner()) = Some(JobSlot { job: erased });
        shared.members.store(members, Ordering::Relaxed);
        shared.barrier.members.store(members, Ordering::Relaxed);
        shared.pending.store(members - 1, Ordering::Relaxed);
        shared.epoch.fetch_add(1, Ordering::Release);
        for (_, thread) in &self.helpers[..members - 1] {
            thread.unpark();
        }
        let mine = catch_unwind(AssertUnwindSafe(|| {
            job(&Part {
                index: 0,
                count: members,
                barrier: Some(&shared.barrier),
            })
        }));
        let mut spin = Backoff::default();
        while shared.pending.load(Ordering::Acquire) != 0 {
            spin.snooze();
        }
        if let Err(panic) = mine {
            std::panic::resume_unwind(panic);
        }
        assert!(
            !shared.panicked.swap(false, Ordering::Relaxed),
            "a kernel thread panicked"
        );
    }
}

impl Drop for Team {
    fn drop(&mut self) {
        if let Some(shared) = &self.shared {
            shared.stop.store(true, Ordering::Release);
            shared.epoch.fetch_add(1, Ordering::Release);
        }
        for (handle, thread) in self.helpers.drain(..) {
            thread.unpark();
            let _ = handle.join();
        }
    }
}

/// How long a helper spins for the next job before it parks.
const SPIN_BEFORE_PARK: Duration = Duration::from_micros(300);

fn helper(shared: &Shared, index: usize) {
    let mut seen = 0u64;
    loop {
        let started = Instant::now();
        let mut spin = Backoff::default();
        let epoch = loop {
            let epoch = shared.epoch.load(Ordering::Acquire);
            if epoch != seen {
                break epoch;
            }
            if started.elapsed() < SPIN_BEFORE_PARK {
                spin.snooze();
            } else {
                // A bump between the load above and this park leaves an unpark token, so the
                // park returns at once.
                thread::park();
            }
        };
        seen = epoch;
        if shared.stop.load(Ordering::Acquire) {
            return;
        }
        if index >= shared.members.load(Ordering::Relaxed) {
            continue;
        }
        let slot = shared
            .job
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .expect("a job is set before the epoch moves");
        let part = Part {
            index,
            count: shared.members.load(Ordering::Relaxed),
            barrier: Some(&shared.barrier),
        };
        // SAFETY: the caller waits for `pending` to reach 0 before its closure goes away.
        let ok = catch_unwind(AssertUnwindSafe(|| unsafe { (*slot.job)(&part) }));
        if ok.is_err() {
            shared.panicked.store(true, Ordering::Relaxed);
        }
        shared.pending.fetch_sub(1, Ordering::Release);
    }
}

/// Spin with a pause hint, then yield the core to whoever else wants it.
#[derive(Default)]
struct Backoff(u32);

impl Backoff {
    fn snooze(&mut self) {
        if self.0 < 2000 {
            std::hint::spin_loop();
            self.0 += 1;
        } else {
            thread::yield_now();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::AtomicUsize;

    #[test]
    fn every_member_runs_its_share_once_and_barriers_order_phases() {
        for threads in [1, 2, 3] {
            let hits: Vec<AtomicUsize> = (0..100).map(|_| AtomicUsize::new(0)).collect();
            let phase_one = AtomicUsize::new(0);
            run(threads, &|part: &Part<'_>| {
                for i in part.share(100, 7) {
                    hits[i].fetch_add(1, Ordering::Relaxed);
                }
                phase_one.fetch_add(1, Ordering::AcqRel);
                part.barrier();
                assert_eq!(phase_one.load(Ordering::Acquire), part.count);
            });
            assert!(hits.iter().all(|h| h.load(Ordering::Relaxed) == 1));
        }
    }

    #[test]
    fn a_panic_in_a_helper_reaches_the_caller() {
        let result = catch_unwind(|| {
            run(2, &|part: &Part<'_>| {
                if part.index == 1 {
                    panic!("boom");
                }
            });
        });
        assert!(result.is_err());
        // The team still works afterwards.
        let count = AtomicUsize::new(0);
        run(2, &|_: &Part<'_>| {
            count.fetch_add(1, Ordering::Relaxed);
        });
        assert_eq!(count.load(Ordering::Relaxed), 2);
    }
}
