//! `Sac::update` allocates nothing of its own: with the suite's counting global allocator (per-thread
//! counters), the only allocations during updates are, on the portable kernel path,
//! matrixmultiply's packing buffers, one per matrix product, all freed again, and on the
//! fast paths none at all, on one thread or two (see `rl_no_alloc.rs` for the same on bare MLPs).
//! The per-thread counters do not see a helper thread (on two threads one twin of each pair
//! runs on one), so the fast paths are also counted over the whole process, in a child process
//! that runs that one test alone.

use std::process::Command;

use dualrep_core::rl::kernels::{self, KernelPath};
use dualrep_core::rl::replay::{ReplayBuffer, Transition};
use dualrep_core::rl::sac::{HumanCriticConfig, Sac, SacConfig};
use dualrep_core::sim::Task;

use crate::support::counting_alloc;

use counting_alloc::{count, count_all_threads};

/// Set in the child process that [`fast_paths_allocate_nothing_on_any_thread`] starts.
const ALONE: &str = "DUALREP_TEST_ALONE_IN_PROCESS";

/// Matrix products of one gradient step with `layers` linear layers per network, fewest and
/// most: forward passes `layers` each, a backward pass with parameter gradients
/// `2 layers - 1`, an input-gradient-only pass `layers`. In the actor loss each sample's
/// gradient goes back through one head of each twin pair only, so a head that no sample
/// picked makes no pass at all: one pass per pair when all pick the same head, two otherwise.
fn products_per_step(layers: usize, human: bool) -> (usize, usize) {
    let (forward, backward, backward_input) = (layers, 2 * layers - 1, layers);
    let twins = if human { 4 } else { 2 };
    let rest = forward // actor at s
        + forward + 2 * forward // actor at s', both target critics
        + 2 * (forward + backward) // critics
        + if human { 2 * (forward + backward) } else { 0 } // human critics
        + twins * forward // critics in the actor loss
        + backward; // actor
    (
        rest + twins / 2 * backward_input,
        rest + twins * backward_input,
    )
}

#[test]
fn updates_allocate_only_sgemm_packing_buffers() {
    for path in KernelPath::ALL.into_iter().filter(|p| p.is_available()) {
        // The counters are per thread, and on two threads one twin of each pair runs on a
        // helper: one thread sees every network's work, two the side-by-side hand-over.
        let threads: &[usize] = if path == KernelPath::Portable {
            &[1]
        } else {
            &[1, 2]
        };
        for &threads in threads {
            kernels::with_path(path, || {
                kernels::with_threads(threads, || allocations_of_updates(path, |f| count(f)));
            });
        }
    }
}

/// The fast paths on one thread and two, counting every thread's allocations: this test binary
/// again, running only [`fast_paths_counted_over_the_process`], so that no other test's threads
/// add to the count.
#[test]
fn fast_paths_allocate_nothing_on_any_thread() {
    let out = Command::new(std::env::current_exe().unwrap())
        .args([
            "--exact",
            "sac_no_alloc::fast_paths_counted_over_the_process",
            "--ignored",
            "--test-threads",
            "1",
            "--nocapture",
        ])
        .env(ALONE, "1")
        .output()
        .unwrap();
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "child failed:\n{text}");
    assert!(text.contains("1 passed"), "the child ran no test:\n{text}");
}

#[test]
#[ignore = "run alone in a child process by fast_paths_allocate_nothing_on_any_thread"]
fn fast_paths_counted_over_the_process() {
    assert!(
        std::env::var_os(ALONE).is_some(),
        "counts every thread of the process: run by fast_paths_allocate_nothing_on_any_thread"
    );
    for path in KernelPath::ALL.into_iter().filter(|p| p.is_available()) {
        if path == KernelPath::Portable {
            continue;
        }
        for threads in [1, 2] {
            kernels::with_path(path, || {
                kernels::with_threads(threads, || {
                    allocations_of_updates(path, fewest_over_the_process)
                });
            });
        }
    }
}

/// The process-wide count of the fewest allocations in three windows of the same work. An
/// update allocates the same every time, so a window of 0 proves it allocates nothing; another
/// thread of the test harness can allocate during any one window (libtest's main thread records
/// the running test just after starting it, and on a machine loaded enough it gets there late),
/// so one window alone can fail a correct update.
fn fewest_over_the_process(f: &mut dyn FnMut()) -> (usize, isize) {
    (0..3)
        .map(|_| count_all_threads(&mut *f))
        .min_by_key(|&(allocations, _)| allocations)
        .expect("three windows")
}

/// Checks the allocations `count` sees during two updates, after a first.
fn allocations_of_updates(path: KernelPath, count: impl Fn(&mut dyn FnMut()) -> (usize, isize)) {
    for human in [false, true] {
        let mut config = SacConfig::for_task(Task::Reaching);
        config.hidden = vec![16, 8];
        config.batch_size = 32;
        config.gradient_steps = 3;
        config.human_critic = human.then(|| HumanCriticConfig {
            mask: true,
            ..HumanCriticConfig::default()
        });
        let mut sac = Sac::new(4, 2, config, 0);
        let mut replay = ReplayBuffer::new(100, 4, 2);
        for i in 0..100 {
            let x = i as f32 / 100.0;
            replay.push(Transition {
                obs: &[x, -x, 0.5, 1.0],
                action: &[x, 0.0],
                reward: x,
                human: [1.0, -1.0][i % 2],
                next_obs: &[x, x, 0.5, 1.0],
                terminated: i % 10 == 0,
            });
        }
        sac.update(&replay).unwrap(); // first use
        let (allocations, live) = count(&mut || {
            sac.update(&replay).unwrap();
            sac.update(&replay).unwrap();
        });
        let (fewest, most) = match path {
            KernelPath::Portable => {
                let (fewest, most) = products_per_step(3, human);
                (2 * 3 * fewest, 2 * 3 * most)
            }
            _ => (0, 0),
        };
        assert!(
            (fewest..=most).contains(&allocations),
            "{path}, human critic {human}: {allocations} allocations, not {fewest}..={most}"
        );
        assert_eq!(live, 0, "nothing kept");
    }
}
