//! One gradient step, in stable-baselines3's order (`SAC.train`), which the authors' DREF fork
//! follows, with the human critic between the critics and the actor (the authors' order):
//!
//! 1. policy sample at s: `a_pi`, `log_pi` (fresh noise);
//! 2. temperature: `ent_coef = exp(log_ent_coef)` *before* its step, then one Adam step on
//!    `-(log_ent_coef * (log_pi + target_entropy)).mean()`;
//! 3. target: `next_q_value = min_j Q_j_targ(s', a') - ent_coef log_pi'`,
//!    `y = r + (1 - terminated) gamma next_q_value`;
//! 4. critics (Eq. 4): `0.5 sum_j mse(Q_j(s, a), y)`, one Adam step over both;
//! 5. human critics (Eq. 3): `0.5 sum_j mse(H_j(s, a), H)` on the immediate H, no bootstrap;
//! 6. actor (Eq. 5) against the *updated* critics at `(s, a_pi)`;
//! 7. Polyak update of the Q targets (H has none).
//!
//! Each loss is a method that writes its gradient and returns its value, so the tests can
//! check each gradient by finite differences; [`Sac::gradient_step`] strings them together.
//!
//! On two threads the twins of each pair (Q1 and Q2, H1 and H2, the two targets) make their
//! passes side by side, one thread each (`kernels::side_by_side`), instead of splitting every
//! product between the threads; the results are the same bits as one after the other.

use crate::rl::kernels::side_by_side;
use crate::rl::loss::Regression;
use crate::rl::squashed_gaussian;
use crate::rl::{Mlp, MlpWorkspace};

use super::buffers::{TwinPicks, fill_critic_input};
use super::config::{ActorMix, CriticLoss};
use super::{HumanCritic, Sac, UpdateStats};

impl Sac {
    /// Steps 1 to 7 on the batch and noise already in `self.buffers`.
    pub(super) fn gradient_step(&mut self) -> UpdateStats {
        // 1. a_pi ~ pi(.|s), kept (with the actor's activations) for the actor loss.
        self.sample_policy_at_obs();

        // 2. Temperature. SB3 detaches alpha before the step: this update uses the old alpha.
        let ent_coef = self.log_ent_coef.exp();
        let (ent_coef_loss, ent_coef_grad) =
            temperature_loss(self.log_ent_coef, &self.buffers.log_pi, self.target_entropy);
        self.ent_coef_optimizer.step([(
            std::slice::from_mut(&mut self.log_ent_coef),
            std::slice::from_ref(&ent_coef_grad),
        )]);

        // 3. and 4. Soft Bellman residual (Eq. 4).
        self.compute_target_q_values(ent_coef);
        let critic_loss = self.critic_loss();
        self.critic_optimizer
            .step([self.q1.params_and_grads(), self.q2.params_and_grads()]);

        // 5. Human critic (Eq. 3); masked with no feedback in the batch, no step at all.
        let human_critic_loss = self.human_critic_loss();
        if let (Some(_), Some(hc)) = (human_critic_loss, &mut self.human_critic) {
            hc.optimizer
                .step([hc.h1.params_and_grads(), hc.h2.params_and_grads()]);
        }

        // 6. Actor (Eq. 5), through the updated, frozen critics.
        let actor_loss = self.actor_loss(ent_coef);
        self.actor_optimizer.step([self.actor.params_and_grads()]);

        // 7. Polyak averaging of the environment critics' targets.
        let tau = self.config.tau;
        let (q1_target, q2_target) = (&mut self.q1_target, &mut self.q2_target);
        let (q1, q2) = (&self.q1, &self.q2);
        side_by_side(
            || q1_target.soft_update_from(q1, tau),
            || q2_target.soft_update_from(q2, tau),
        );

        self.updates += 1;
        UpdateStats {
            critic_loss,
            actor_loss,
            human_critic_loss: human_critic_loss.unwrap_or(0.0),
            ent_coef,
            ent_coef_loss,
        }
    }

    /// Step 1: `a_pi = tanh(mu + std eps)` and `log_pi` at the batch's s.
    pub(super) fn sample_policy_at_obs(&mut self) {
        let b = &mut self.buffers;
        sample_policy(
            &self.actor,
            &mut b.actor_ws,
            &b.batch.obs,
            &b.noise_pi,
            &mut b.a_pi,
            &mut b.log_pi,
        );
    }

    /// Step 3: `y = r + (1 - terminated) gamma (min_j Q_j_targ(s', a') - ent_coef log_pi')`
    /// with `a' ~ pi(.|s')`. Termination masks the bootstrap; a truncated transition is stored
    /// as not terminated, so it bootstraps.
    pub(super) fn compute_target_q_values(&mut self, ent_coef: f32) {
        let b = &mut self.buffers;
        sample_policy(
            &self.actor,
            &mut b.next_actor_ws,
            &b.batch.next_obs,
            &b.noise_next,
            &mut b.next_actions,
            &mut b.next_log_pi,
        );
        let (next_obs, next_actions) = (&b.batch.next_obs, &b.next_actions);
        let target_forward = |q_target: &Mlp, ws: &mut MlpWorkspace| {
            fill_critic_input(ws, next_obs, next_actions);
            q_target.forward(ws);
        };
        let (q1_ws, q2_ws) = (&mut b.q1_ws, &mut b.q2_ws);
        side_by_side(
            || target_forward(&self.q1_target, q1_ws),
            || target_forward(&self.q2_target, q2_ws),
        );
        let gamma = self.config.gamma;
        let (q1_next, q2_next) = (b.q1_ws.output().as_slice(), b.q2_ws.output().as_slice());
        for (i, y) in b.target_q_values.iter_mut().enumerate() {
            let next_q_value = q1_next[i].min(q2_next[i]) - ent_coef * b.next_log_pi[i];
            // Torch's evaluation order: r + ((1 - done) * gamma) * next_q_value.
            *y = b.batch.rewards[i] + (1.0 - b.batch.dones[i]) * gamma * next_q_value;
        }
    }

    /// Step 4 (Eq. 4): `0.5 sum_j mse(Q_j(s, a), y)` (with `critic_loss = huber`, the Huber
    /// loss in place of mse); overwrites both critics' gradients.
    pub(super) fn critic_loss(&mut self) -> f32 {
        let b = &mut self.buffers;
        let (batch, target) = (&b.batch, &b.target_q_values);
        let regression = match self.config.critic_loss {
            CriticLoss::Mse => Regression::Mse,
            CriticLoss::Huber => Regression::Huber,
        };
        let loss = |q: &mut Mlp, ws: &mut MlpWorkspace| {
            fill_critic_input(ws, &batch.obs, &batch.actions);
            regress(q, ws, target, regression)
        };
        let (q1_ws, q2_ws) = (&mut b.q1_ws, &mut b.q2_ws);
        let (q1, q2) = (&mut self.q1, &mut self.q2);
        let losses = side_by_side(|| loss(q1, q1_ws), || loss(q2, q2_ws));
        sum_of_halves(losses)
    }

    /// Step 5 (Eq. 3): `0.5 sum_j mse(H_j(s, a), H)` on the immediate feedback, over every row
    /// (H = 0 included, as the authors do) or, with `mask`, over the rows with H != 0 only, plus
    /// `anchor` times the other rows' mean squared H (their pull towards 0); with
    /// `answer_replay`, over the critic's own batch of answered transitions.
    /// `None` without a human critic, or masked and unanchored with no feedback in the batch
    /// (with `answer_replay`, which needs the plain mask: while no transition has an answer).
    pub(super) fn human_critic_loss(&mut self) -> Option<f32> {
        let (hc, [h1_ws, h2_ws]) = match (&mut self.human_critic, &mut self.buffers.h_ws) {
            (Some(hc), Some(ws)) => (hc, ws),
            _ => return None,
        };
        let batch = self
            .buffers
            .answer_batch
            .as_ref()
            .unwrap_or(&self.buffers.batch);
        // Masked: the anchor's weight (0 for the plain mask); unmasked: None.
        let mask = self
            .config
            .human_critic
            .as_ref()
            .filter(|c| c.mask)
            .map(|c| c.anchor);
        let regression = mask.map_or(Regression::Mse, Regression::AnchoredMse);
        if mask == Some(0.0) && batch.human.iter().all(|&h| h == 0.0) {
            return None;
        }
        let HumanCritic { h1, h2, .. } = hc;
        let loss = |h: &mut Mlp, ws: &mut MlpWorkspace| {
            fill_critic_input(ws, &batch.obs, &batch.actions);
            regress(h, ws, &batch.human, regression)
        };
        let losses = side_by_side(|| loss(h1, h1_ws), || loss(h2, h2_ws));
        Some(sum_of_halves(losses))
    }

    /// Step 6 (Eq. 5) at `(s, a_pi)` from step 1, writing the actor's gradient:
    ///
    /// - plain SAC: `mean(ent_coef log_pi - min_j Q_j)`;
    /// - [`ActorMix::Authors`]: `mean(ent_coef log_pi - min_j (w_q Q_j + w_h H_j))`,
    ///   `w_q = 1 / (1 + lambda)`, `w_h = lambda / (1 + lambda)` (their `0.1 Q + 0.9 H`);
    /// - [`ActorMix::Paper`]: `mean(ent_coef log_pi - (min_j Q_j + lambda min_j H_j))`;
    /// - [`ActorMix::Answered`]: the authors' mix with `w_h` times `unanswered` (0 by default,
    ///   or what the run's gate set) on the rows whose stored H is 0 (no answer), unless the
    ///   heads of H agree there within `agree_within`; with `unread_to_q`, `w_q = 1 - w_h`.
    ///
    /// The critics are frozen: each passes dL/d a_pi back through `backward_input` only. Then
    /// `squashed_gaussian::backward` adds the path through `log_pi` and takes both to
    /// `[mu; log_std]`, and the actor's own backward pass.
    pub(super) fn actor_loss(&mut self, ent_coef: f32) -> f32 {
        let configured = self
            .config
            .human_critic
            .as_ref()
            .map_or(0.0, |c| c.unanswered);
        let unanswered = self.unanswered_override.unwrap_or(configured);
        let b = &mut self.buffers;
        let n = b.log_pi.len();
        let inv_n = 1.0 / n as f32;
        let (obs, a_pi) = (&b.batch.obs, &b.a_pi);
        let forward = |net: &Mlp, ws: &mut MlpWorkspace| {
            fill_critic_input(ws, obs, a_pi);
            net.forward(ws);
        };
        let mut human = match (&self.human_critic, &mut b.h_ws, &self.config.human_critic) {
            (Some(hc), Some([h1_ws, h2_ws]), Some(config)) => Some((hc, h1_ws, h2_ws, config)),
            _ => None,
        };
        // Each side: one twin of each pair.
        let (q1_ws, q2_ws) = (&mut b.q1_ws, &mut b.q2_ws);
        let h_sides = human
            .as_mut()
            .map(|(hc, h1_ws, h2_ws, _)| ((&hc.h1, &mut **h1_ws), (&hc.h2, &mut **h2_ws)));
        let (h1_side, h2_side) = h_sides.unzip();
        side_by_side(
            || {
                forward(&self.q1, q1_ws);
                if let Some((h1, ws)) = h1_side {
                    forward(h1, ws);
                }
            },
            || {
                forward(&self.q2, q2_ws);
                if let Some((h2, ws)) = h2_side {
                    forward(h2, ws);
                }
            },
        );

        // Per sample: the value the actor maximises, and dL/d(critic output) per critic
        // (torch.min sends the gradient to the first minimum).
        let mut objective_sum = 0.0f64;
        b.picks_q.clear();
        b.picks_h.clear();
        match &mut human {
            None => {
                for i in 0..n {
                    let (q1, q2) = (b.q1_ws.output()[i], b.q2_ws.output()[i]);
                    let min_qf_pi = q1.min(q2);
                    objective_sum += f64::from(ent_coef * b.log_pi[i] - min_qf_pi);
                    b.q1_ws.output_grad_mut()[i] = if q1 <= q2 { -inv_n } else { 0.0 };
                    b.q2_ws.output_grad_mut()[i] = if q1 <= q2 { 0.0 } else { -inv_n };
                    b.picks_q.push(i, q1 <= q2);
                }
            }
            Some((_, h1_ws, h2_ws, config)) => {
                let lambda = config.lambda;
                for i in 0..n {
                    let q = [b.q1_ws.output()[i], b.q2_ws.output()[i]];
                    let h = [h1_ws.output()[i], h2_ws.output()[i]];
                    // (dL/dQ_1, dL/dQ_2, dL/dH_1, dL/dH_2) per sample, times n.
                    let (value, dq, dh) = match config.mix {
                        ActorMix::Authors | ActorMix::Answered => {
                            // The authors' head-wise mix: min_j(0.1 Q_j + 0.9 H_j) at lambda = 9;
                            // `Answered` keeps `unanswered` of H's weight (by default none) on a
                            // row nobody answered, unless its heads agree within `agree_within`
                            // (H is constrained there, not extrapolated).
                            let agree = config.agree_within > 0.0
                                && (h[0] - h[1]).abs() <= config.agree_within;
                            let answered =
                                config.mix == ActorMix::Authors || b.batch.human[i] != 0.0 || agree;
                            let read = if answered { 1.0 } else { unanswered };
                            let (w_q, w_h) = mix_weights(lambda, read, config.unread_to_q);
                            let mixed = [w_q * q[0] + w_h * h[0], w_q * q[1] + w_h * h[1]];
                            let first = mixed[0] <= mixed[1];
                            let j = if first { [1.0, 0.0] } else { [0.0, 1.0] };
                            b.picks_q.push(i, first);
                            b.picks_h.push(i, first);
                            (
                                mixed[0].min(mixed[1]),
                                j.map(|s| s * w_q),
                                j.map(|s| s * w_h),
                            )
                        }
                        ActorMix::Paper => {
                            // Eq. 5 as printed: min_j Q_j + lambda min_j H_j.
                            let jq = if q[0] <= q[1] { [1.0, 0.0] } else { [0.0, 1.0] };
                            let jh = if h[0] <= h[1] { [1.0, 0.0] } else { [0.0, 1.0] };
                            b.picks_q.push(i, q[0] <= q[1]);
                            b.picks_h.push(i, h[0] <= h[1]);
                            let value = q[0].min(q[1]) + lambda * h[0].min(h[1]);
                            (value, jq, jh.map(|s| s * lambda))
                        }
                    };
                    objective_sum += f64::from(ent_coef * b.log_pi[i] - value);
                    b.q1_ws.output_grad_mut()[i] = -dq[0] * inv_n;
                    b.q2_ws.output_grad_mut()[i] = -dq[1] * inv_n;
                    h1_ws.output_grad_mut()[i] = -dh[0] * inv_n;
                    h2_ws.output_grad_mut()[i] = -dh[1] * inv_n;
                }
            }
        }

        // dL/d a_pi: the sum over the frozen critics of their input gradient's action rows,
        // each through the samples whose min picked it (the rest of its gradient is zero).
        // Added in a fixed order (q1, q2, h1, h2).
        b.dl_da.fill(0.0);
        add_twins_action_grad(
            [&self.q1, &self.q2],
            [&mut b.q1_ws, &mut b.q2_ws],
            &b.picks_q,
            &mut b.picked_ws,
            &mut b.dl_da,
        );
        if let Some((hc, h1_ws, h2_ws, _)) = human {
            add_twins_action_grad(
                [&hc.h1, &hc.h2],
                [h1_ws, h2_ws],
                &b.picks_h,
                &mut b.picked_ws,
                &mut b.dl_da,
            );
        }

        // Through tanh and the Gaussian to [mu; log_std]; dL/d log_pi = ent_coef / n.
        let act_dim = self.act_dim;
        let (head, dl_dhead) = b.actor_ws.output_and_grad_mut();
        let columns = head
            .as_slice()
            .chunks_exact(2 * act_dim)
            .zip(dl_dhead.as_mut_slice().chunks_exact_mut(2 * act_dim));
        for (i, (head, dl_dhead)) in columns.enumerate() {
            let k = i * act_dim..(i + 1) * act_dim;
            squashed_gaussian::backward(
                head,
                &b.noise_pi[k.clone()],
                &b.a_pi[k.clone()],
                &b.dl_da[k],
                ent_coef * inv_n,
                dl_dhead,
            );
        }
        self.actor.zero_grad();
        self.actor.backward(&mut b.actor_ws);
        (objective_sum / n as f64) as f32
    }
}

/// Step 2: SB3's `-(log_ent_coef * (log_pi + target_entropy).detach()).mean()` and its gradient
/// with respect to `log_ent_coef`.
pub(super) fn temperature_loss(
    log_ent_coef: f32,
    log_pi: &[f32],
    target_entropy: f32,
) -> (f32, f32) {
    let sum: f64 = log_pi.iter().map(|&l| f64::from(l + target_entropy)).sum();
    let mean = (sum / log_pi.len() as f64) as f32;
    (-(log_ent_coef * mean), -mean)
}

/// Actor forward pass on `obs` and one tanh-Gaussian sample per row with the given noise.
fn sample_policy(
    actor: &Mlp,
    ws: &mut MlpWorkspace,
    obs: &[f32],
    noise: &[f32],
    actions: &mut [f32],
    log_pi: &mut [f32],
) {
    ws.input_mut().as_mut_slice().copy_from_slice(obs);
    actor.forward(ws);
    let act_dim = noise.len() / log_pi.len();
    let heads = ws.output().as_slice().chunks_exact(2 * act_dim);
    let rows = noise
        .chunks_exact(act_dim)
        .zip(actions.chunks_exact_mut(act_dim));
    for ((head, (eps, action)), log_prob) in heads.zip(rows).zip(log_pi.iter_mut()) {
        *log_prob = squashed_gaussian::sample(head, eps, action);
    }
}

/// SB3's `0.5 * sum_j` of the twins' losses, `j` in order.
fn sum_of_halves((first, second): (f32, f32)) -> f32 {
    let mut sum = 0.0;
    sum += 0.5 * first;
    sum += 0.5 * second;
    sum
}

/// `regression`'s loss of `net(input)` against `target`, scaled by 0.5 in the gradient (SB3's
/// `0.5 * sum_j` over twins): zero the net's gradient, forward, backward. Returns the unscaled
/// loss.
pub(super) fn regress(
    net: &mut Mlp,
    ws: &mut MlpWorkspace,
    target: &[f32],
    regression: Regression,
) -> f32 {
    net.zero_grad();
    net.forward(ws);
    let (prediction, grad) = ws.output_and_grad_mut();
    let loss = regression.loss(prediction.as_slice(), target, grad.as_mut_slice());
    for g in grad.as_mut_slice().iter_mut() {
        *g *= 0.5;
    }
    net.backward(ws);
    loss
}

/// `dl_da += ` the action rows of a twin pair's input gradients through the samples each head
/// picked: the twins pass back side by side, then add in order (first, second), so the sums
/// do not depend on which finished first.
fn add_twins_action_grad(
    [first, second]: [&Mlp; 2],
    [first_ws, second_ws]: [&mut MlpWorkspace; 2],
    picks: &TwinPicks,
    [first_sub, second_sub]: &mut [MlpWorkspace; 2],
    dl_da: &mut [f32],
) {
    let (first_picked, second_picked) = (picks.head(0), picks.head(1));
    side_by_side(
        || pass_back_picked(first, first_ws, first_picked, first_sub),
        || pass_back_picked(second, second_ws, second_picked, second_sub),
    );
    add_picked_action_grad(first_ws, first_picked, first_sub, dl_da);
    add_picked_action_grad(second_ws, second_picked, second_sub, dl_da);
}

/// A frozen critic's input gradient at the samples `picked` only (after its forward pass, with
/// dL/d output in `ws`, zero at every other sample): in `ws` when every sample picked it, else
/// in `sub`, each sample with the bits the whole batch's pass gives it. The other samples'
/// gradient is an exact zero, so skipping them changes nothing but the time: half of the actor
/// loss's backward work, since each sample's min picks one head of two.
fn pass_back_picked(net: &Mlp, ws: &mut MlpWorkspace, picked: &[usize], sub: &mut MlpWorkspace) {
    if picked.len() == ws.batch() {
        net.backward_input(ws);
    } else if !picked.is_empty() {
        net.backward_input_columns(ws, picked, sub);
    }
}

/// `dl_da += ` the action rows of what [`pass_back_picked`] computed for the same `picked`.
fn add_picked_action_grad(
    ws: &MlpWorkspace,
    picked: &[usize],
    sub: &MlpWorkspace,
    dl_da: &mut [f32],
) {
    if picked.len() == ws.batch() {
        add_action_grad(ws, dl_da);
        return;
    }
    if picked.is_empty() {
        return;
    }
    let n_in = ws.input().nrows();
    let act_dim = dl_da.len() / ws.batch();
    let input_grad = sub.input_grad().as_slice().chunks_exact(n_in);
    for (column, &i) in input_grad.zip(picked) {
        let d = &mut dl_da[i * act_dim..(i + 1) * act_dim];
        for (d, g) in d.iter_mut().zip(&column[n_in - act_dim..]) {
            *d += g;
        }
    }
}

/// `dl_da += ` the action rows of a critic's input gradient (`[s; a]` per column).
fn add_action_grad(ws: &MlpWorkspace, dl_da: &mut [f32]) {
    let input_grad = ws.input_grad().as_slice();
    let n_in = ws.input().nrows();
    let act_dim = dl_da.len() / ws.batch();
    let obs_dim = n_in - act_dim;
    for (column, d) in input_grad
        .chunks_exact(n_in)
        .zip(dl_da.chunks_exact_mut(act_dim))
    {
        for (d, g) in d.iter_mut().zip(&column[obs_dim..]) {
            *d += g;
        }
    }
}

/// The authors' weights on Q and H (`1 / (1 + lambda)`, `lambda / (1 + lambda)`) for a row whose
/// H is read at share `read` of its weight; with `unread_to_q` the unread share goes to Q, so the
/// two sum to 1. At `read = 1` both forms are the authors' weights to the bit.
pub(super) fn mix_weights(lambda: f32, read: f32, unread_to_q: bool) -> (f32, f32) {
    // In this order the weights are the ones runs before `unread_to_q` computed, bit for bit.
    let w_q = 1.0 / (1.0 + lambda);
    let w_h = read * lambda / (1.0 + lambda);
    let unread = lambda / (1.0 + lambda) - w_h;
    (if unread_to_q { w_q + unread } else { w_q }, w_h)
}
