//! Neural networks for SAC and the human critic: small MLPs on nalgebra with a hand-written
//! backward pass and Adam. No IO, no autograd: each network knows its own gradient, proven by
//! finite differences and by PyTorch's numbers (`tests/rl_gradients.rs`).
//!
//! ## Map
//!
//! - [`linear`]: [`Linear`], where one layer's weight and bias sit in the flat parameter vector.
//! - [`layer_norm`]: a hidden layer's optional layer norm (fused with its ReLU) and its backward
//!   pass; where its gain and bias sit.
//! - [`mlp`]: [`Mlp`]: PyTorch's initialisation, forward, backward (parameter
//!   and/or input gradients), parameters as one flat slice, Polyak averaging, tensor names for
//!   checkpoints. Its module doc explains the memory layout.
//! - [`workspace`]: [`MlpWorkspace`], every activation and gradient buffer of one batch size,
//!   so that a training step allocates nothing of its own.
//! - [`kernels`]: every layer's products, on the portable path (matrixmultiply's `sgemm`, the
//!   same bits everywhere) or our own AVX-512 / AVX2 kernels chosen at run time, on one or more
//!   threads.
//! - [`adam`]: [`Adam`] with PyTorch's defaults and arithmetic.
//! - [`loss`]: [`mse_loss`] and the critics' other losses, with their gradients.
//! - [`squashed_gaussian`]: SAC's tanh-squashed Gaussian policy head: sampling, log-prob
//!   with the tanh correction, and its gradient.
//! - [`replay`]: the preallocated replay buffer, `(s, a, r, H, s', terminated)` per row, and
//!   its bytes for a run's checkpoint.
//! - [`rng_state`]: a generator's state as data, for checkpoints.
//! - [`sac`]: [`sac::Sac`], SAC with DREF's human critic, built from all of the above.
//!
//! ## Allocation
//!
//! After the workspaces exist, forward, backward, [`mse_loss`] and [`Adam::step`] allocate
//! nothing themselves, and on the fast kernel paths nothing at all. On the portable path one
//! allocation per matrix product remains, not ours: matrixmultiply's `sgemm` allocates and
//! frees its packing buffer inside every call (it has no API to pass one in).
//! `tests/rl_no_alloc.rs` pins this down on every path this CPU runs.
//!
//! ## How SAC uses it
//!
//! A twin critic is two [`Mlp`]s under one [`Adam`]; an actor is one [`Mlp`] whose
//! `2 * dim(A)` outputs are the mean and log-std heads (one `Linear` with both heads' rows is the
//! same function and the same initialisation as two heads on the last hidden layer). The actor
//! loss reaches the actor through the frozen critic's input gradient:
//!
//! ```
//! use dualrep_core::rl::{Adam, AdamConfig, Mlp, mse_loss};
//! use rand::SeedableRng;
//!
//! let (obs_dim, act_dim, batch) = (8, 2, 32);
//! let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0);
//! let mut q1 = Mlp::new(obs_dim + act_dim, &[64, 64], 1, &mut rng);
//! let mut q2 = Mlp::new(obs_dim + act_dim, &[64, 64], 1, &mut rng);
//! let mut q1_target = q1.clone();
//! let mut actor = Mlp::new(obs_dim, &[64, 64], 2 * act_dim, &mut rng);
//! let mut critic_opt = Adam::new(AdamConfig::with_lr(7.5e-4), &[q1.params().len(), q2.params().len()]);
//! let mut actor_opt = Adam::new(AdamConfig::with_lr(7.5e-4), &[actor.params().len()]);
//! // Made once, reused every update. Each column of an input is one sample: [s; a] for a critic.
//! let mut q_ws = q1.workspace(batch);
//! let mut actor_ws = actor.workspace(batch);
//!
//! // Critic step (Eq. 4): y = r + gamma (1 - terminated) (min_j Q_j_target(s', a') - alpha log pi),
//! // from forward passes of the target critics; here a stand-in.
//! let y = vec![0.5f32; batch];
//! q1.zero_grad();
//! q2.zero_grad();
//! for q in [&mut q1, &mut q2] {
//!     q_ws.input_mut().fill(0.1); // [s; a] of the sampled batch
//!     q.forward(&mut q_ws);
//!     let (q_sa, dq) = q_ws.output_and_grad_mut();
//!     mse_loss(q_sa.as_slice(), &y, dq.as_mut_slice());
//!     *dq *= 0.5; // SB3: 0.5 * sum_j mse(Q_j(s, a), y)
//!     q.backward(&mut q_ws); // this critic's backward before the other's forward
//! }
//! critic_opt.step([q1.params_and_grads(), q2.params_and_grads()]);
//!
//! // Actor step (Eq. 5): a~ = tanh(mu + sigma eps) from actor_ws.output(), then the frozen critic.
//! actor_ws.input_mut().fill(0.1); // s
//! actor.forward(&mut actor_ws);
//! q_ws.input_mut().fill(0.1); // [s; a~]
//! q1.forward(&mut q_ws);
//! q_ws.output_grad_mut().fill(-1.0 / batch as f32); // d(-mean Q) / dQ
//! q1.backward_input(&mut q_ws); // q1's own gradients stay untouched
//! let dl_da = q_ws.input_grad().rows(obs_dim, act_dim); // then through tanh and the heads:
//! assert_eq!(dl_da.shape(), (act_dim, batch));
//! actor_ws.output_grad_mut().fill(0.0); // dL/d(mu, log_std), chained from dl_da
//! actor.zero_grad();
//! actor.backward(&mut actor_ws);
//! actor_opt.step([actor.params_and_grads()]);
//!
//! q1_target.soft_update_from(&q1, 0.01); // Polyak, tau = 0.01
//! ```
//!
//! With `min_j Q_j` in the actor loss, give each critic its own workspace for that pass: both
//! forward passes must be kept until the backward passes.

pub mod adam;
pub mod kernels;
pub mod layer_norm;
pub mod linear;
pub mod loss;
pub mod mlp;
pub mod replay;
pub mod rng_state;
pub mod sac;
pub mod squashed_gaussian;
pub mod workspace;

pub use adam::{Adam, AdamConfig};
pub use linear::Linear;
pub use loss::mse_loss;
pub use mlp::{Mlp, ParamTensor};
pub use sac::{
    ActorMix, CheckpointError, CriticLoss, HumanCriticConfig, Sac, SacConfig, UpdateStats,
};
pub use workspace::MlpWorkspace;
