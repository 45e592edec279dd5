//! `Sac::update` allocates nothing of its own: with the suite's counting global allocator (per-thread
//! counters), the only allocations during updates are, on the portable kernel path,
//! matrixmultiply's packing buffers, one per matrix product, all freed again, and on the
//! fast paths none at all, on one thread or two (see `rl_no_alloc.rs` for the same on bare MLPs).

use dualrep::rl::kernels::{self, KernelPath};
use dualrep::rl::replay::{ReplayBuffer, Transition};
use dualrep::rl::sac::{HumanCriticConfig, Sac, SacConfig};
use dualrep::sim::Task;

use crate::support::counting_alloc;

use counting_alloc::count;

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
                kernels::with_threads(threads, || allocations_of_updates(path));
            });
        }
    }
}

fn allocations_of_updates(path: KernelPath) {
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
        let (allocations, live) = count(|| {
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
