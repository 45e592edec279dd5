//! Two independent jobs at once, one thread each: the twin critics of an update.
//!
//! Splitting every product of a critic over two threads costs two barriers per product and
//! leaves the narrow layers and the elementwise work on one thread; running the twin critics'
//! passes side by side keeps each thread on whole products with no barrier between them. The
//! results are the same bits either way: every product element is one chain over `k`, whatever
//! thread computes it and however many share the product.

use std::sync::Mutex;

use super::{current_path, threads_now, with_path, with_threads};

/// Run `a` and `b`: at once when this thread may use exactly two threads ([`threads_now`]),
/// each on one thread with this thread's kernel path, else `a` then `b` here, their products
/// split over this thread's threads as usual. With more than two a side would need a team of
/// its own inside the running one, so more threads keep splitting each product, as before
/// (a machine with many cores per run, such as `reproduce` with few jobs on 16 cores). Allocates
/// nothing once this thread's team has its helper (the first time).
pub fn side_by_side<A: Send, B: Send>(
    a: impl FnOnce() -> A + Send,
    b: impl FnOnce() -> B + Send,
) -> (A, B) {
    if threads_now() != 2 {
        return (a(), b());
    }
    let path = current_path();
    let (job_a, job_b) = (Mutex::new(Some(a)), Mutex::new(Some(b)));
    let (result_a, result_b) = (Mutex::new(None), Mutex::new(None));
    dualrep_kernels::team::run(2, &|part| {
        // One thread per side: a side's products must not ask for the team running them.
        with_path(path, || {
            with_threads(1, || {
                if part.index == 0 {
                    let job = job_a.lock().unwrap().take().expect("side a runs once");
                    *result_a.lock().unwrap() = Some(job());
                } else {
                    let job = job_b.lock().unwrap().take().expect("side b runs once");
                    *result_b.lock().unwrap() = Some(job());
                }
            })
        })
    });
    (finished(result_a), finished(result_b))
}

fn finished<T>(result: Mutex<Option<T>>) -> T {
    result
        .into_inner()
        .unwrap()
        .expect("the team ran both sides")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_threads_run_the_sides_at_once_with_the_callers_path_one_thread_each() {
        for threads in [1, 2, 3] {
            with_threads(threads, || {
                let path = current_path();
                let side = || (current_path(), threads_now(), std::thread::current().id());
                let (a, b) = side_by_side(side, side);
                assert_eq!((a.0, b.0), (path, path), "{threads} threads");
                if threads == 2 {
                    assert_eq!((a.1, b.1), (1, 1), "two threads: one each");
                    assert_ne!(a.2, b.2, "two threads: side by side");
                } else {
                    assert_eq!((a.1, b.1), (threads, threads), "{threads}: products split");
                    assert_eq!(a.2, b.2, "{threads} threads: one after the other");
                }
                assert_eq!(threads_now(), threads, "restored");
            });
        }
    }
}
