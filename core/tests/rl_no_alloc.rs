//! The training loop allocates nothing of its own once the workspaces exist.
//!
//! The suite's counting global allocator (tests/main.rs) counts the allocations made during
//! SAC-like update steps, per thread, so the tests running beside these do not disturb the
//! count. On the portable kernel path every matrix product goes to matrixmultiply's `sgemm`,
//! which allocates (and frees) its packing buffer inside every call; that is the only
//! allocation allowed: exactly one per product, and nothing still live after. The fast paths
//! pack into per-thread scratch that the first update grows: after it, nothing at all.

use dualrep_core::rl::kernels::{self, KernelPath};
use dualrep_core::rl::{Adam, AdamConfig, Mlp, MlpWorkspace, mse_loss};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::support::counting_alloc;

use counting_alloc::count;

/// A critic, its Polyak target, an actor and their optimisers, as in a SAC update.
struct Sac {
    q: Mlp,
    q_target: Mlp,
    actor: Mlp,
    q_opt: Adam,
    actor_opt: Adam,
    q_ws: MlpWorkspace,
    actor_ws: MlpWorkspace,
    target: Vec<f32>,
}

impl Sac {
    fn new(obs_dim: usize, act_dim: usize, hidden: &[usize], batch: usize) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(0);
        let q = Mlp::new(obs_dim + act_dim, hidden, 1, &mut rng);
        let actor = Mlp::new(obs_dim, hidden, 2 * act_dim, &mut rng);
        let mut q_ws = q.workspace(batch);
        q_ws.input_mut().fill(0.3);
        let mut actor_ws = actor.workspace(batch);
        actor_ws.input_mut().fill(-0.2);
        Self {
            q_target: q.clone(),
            q_opt: Adam::new(AdamConfig::default(), &[q.params().len()]),
            actor_opt: Adam::new(AdamConfig::default(), &[actor.params().len()]),
            q,
            actor,
            q_ws,
            actor_ws,
            target: vec![1.0; batch],
        }
    }

    /// Critic regression, actor through the frozen critic, Polyak update.
    fn update(&mut self) {
        self.q.zero_grad();
        self.q.forward(&mut self.q_ws);
        let (q_sa, dq) = self.q_ws.output_and_grad_mut();
        mse_loss(q_sa.as_slice(), &self.target, dq.as_mut_slice());
        self.q.backward(&mut self.q_ws);
        self.q_opt.step([self.q.params_and_grads()]);

        self.actor.forward(&mut self.actor_ws);
        self.q.forward(&mut self.q_ws);
        self.q_ws.output_grad_mut().fill(-1.0);
        self.q.backward_input(&mut self.q_ws);
        let dl_da = self.q_ws.input_grad().as_slice()[0];
        self.actor_ws.output_grad_mut().fill(dl_da);
        self.actor.zero_grad();
        self.actor.backward(&mut self.actor_ws);
        self.actor_opt.step([self.actor.params_and_grads()]);

        self.q_target.soft_update_from(&self.q, 0.01);
    }
}

/// Matrix products of `forwards` forward passes, `param_backwards` backward passes that
/// accumulate parameter gradients (without the input gradient) and `input_backwards` passes that
/// compute the input gradient only: per layer, one product forward, one for dL/dW and one for
/// dL/dx, except that a parameter pass does not go below the first layer.
fn products(mlp: &Mlp, forwards: usize, param_backwards: usize, input_backwards: usize) -> usize {
    let layers = mlp.layers().len();
    forwards * layers + param_backwards * (2 * layers - 1) + input_backwards * layers
}

#[test]
fn rl_training_step_allocates_only_sgemm_packing_buffers_after_warm_up() {
    for path in KernelPath::ALL.into_iter().filter(|p| p.is_available()) {
        kernels::with_path(path, || allocations_of_update_steps(path));
    }
}

fn allocations_of_update_steps(path: KernelPath) {
    // A small network, and SAC's Reaching size at its batch.
    for (obs_dim, act_dim, hidden, batch) in [(3, 1, &[5, 4][..], 5), (8, 2, &[64, 64], 512)] {
        let mut sac = Sac::new(obs_dim, act_dim, hidden, batch);
        sac.update();
        // The critic: two forward passes, one parameter backward, one input backward. The
        // actor: one forward, one parameter backward. Three layers each.
        let per_update = products(&sac.q, 2, 1, 1) + products(&sac.actor, 1, 1, 0);
        assert_eq!(per_update, (6 + 5 + 3) + (3 + 5));
        let expected = match path {
            KernelPath::Portable => per_update,
            _ => 0,
        };
        for step in 0..5 {
            let (allocations, live) = count(|| sac.update());
            assert_eq!(
                allocations, expected,
                "{path} {hidden:?} update {step}: allocations beyond sgemm's"
            );
            assert_eq!(
                live, 0,
                "{hidden:?} update {step}: memory kept past the update"
            );
        }
    }
}
