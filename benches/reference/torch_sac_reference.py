"""Reference values for `core/src/rl/sac/tests/torch_reference.rs`, computed with PyTorch.

Two full SAC updates in stable-baselines3's order (`SAC.train`, which the authors' DREF fork
uses) on tiny networks with fixed weights, a fixed batch and fixed policy noise, for four
learners: plain SAC, DREF with the authors' head-wise mix (lambda = 9, every row), DREF with
the paper's Eq. 5 mix (lambda = 2, `human_critic_mask`), and plain SAC whose critics fit their
targets with `F.huber_loss` (delta 1; `critic_loss = "huber"`) on rewards three times the
formula's, so that the targets fall on both sides of the loss's seam. Prints Rust constants to
paste beside the test.

    pip install torch==2.15.0   # CPU is enough
    python3 benches/reference/torch_sac_reference.py

Formulas (k the flat index, i the row; each computed in float64 and rounded to float32):
    parameter[k] of network n = 0.5 * sin(1.3 k + 0.1 + 0.7 n)
        (n: actor 0, q1 1, q2 2, h1 3, h2 4; parameters in `named_parameters()` order,
        each row-major; targets start as copies)
    obs[k]        = cos(0.5 k)            (batch-major (5, 3))
    next_obs[k]   = cos(0.5 k + 0.3)
    actions[k]    = 0.9 sin(0.7 k + 0.2)  (batch-major (5, 2))
    noise_pi[k]   = 1.2 sin(0.9 k + 0.4)  (the policy noise at s)
    noise_next[k] = cos(0.8 k + 0.1)      (the policy noise at s')
    reward[i]     = sin(1.1 i + 0.5)
    human         = [1, 0, -1, 0, 1]
    terminated    = [0, 1, 0, 0, 0]
The same batch and noise are used by both updates.

Printed per learner: the five losses of each update (critic, human critic, actor, ent_coef,
ent_coef_loss), a fingerprint `sum_k p[k] cos(0.37 k)` (float64) of each network after the
updates (actor, q1, q2, q1_target, q2_target, h1, h2; 0 where absent) and log_ent_coef, and a
few of the actor's parameters.
"""

import copy
import math

import numpy as np
import torch
import torch.nn.functional as F

OBS, ACT, HIDDEN, BATCH = 3, 2, [6, 5], 5
LR, TAU, GAMMA, INIT_ENT_COEF, TARGET_ENTROPY = 0.01, 0.05, 0.99, 0.5, -2.0
ACTOR_PROBE = [0, 17, 40, 75]
LEARNERS = [
    # name, human critic (lambda, mix, mask) or None, the critics' loss
    ("SAC", None, "mse"),
    ("AUTHORS", (9.0, "authors", False), "mse"),
    ("PAPER", (2.0, "paper", True), "mse"),
    ("HUBER", None, "huber"),
]
# The Huber learner's rewards are this times the formula's.
HUBER_REWARD_FACTOR = 3.0


class Mlp(torch.nn.Module):
    def __init__(self, sizes):
        super().__init__()
        self.layers = torch.nn.ModuleList(torch.nn.Linear(a, b) for a, b in zip(sizes, sizes[1:]))

    def forward(self, x):
        for layer in self.layers[:-1]:
            x = torch.relu(layer(x))
        return self.layers[-1](x)


def formula(n, f):
    return torch.tensor([f(k) for k in range(n)], dtype=torch.float64).float()


def f32(value):
    """The shortest literal that reads back as the same f32 (what clippy asks for)."""
    return str(np.float32(value))


def rust_array(name, values):
    values = [float(v) for v in values]
    body = ", ".join(f32(v) for v in values)
    return f"const {name}: [f32; {len(values)}] = [{body}];"


def make_mlp(sizes, n):
    mlp = Mlp(sizes)
    total = sum(p.numel() for p in mlp.parameters())
    flat = formula(total, lambda k: 0.5 * math.sin(1.3 * k + 0.1 + 0.7 * n))
    with torch.no_grad():
        offset = 0
        for p in mlp.parameters():
            p.copy_(flat[offset : offset + p.numel()].view_as(p))
            offset += p.numel()
    return mlp


def flat(mlp):
    return torch.cat([p.detach().reshape(-1) for p in mlp.parameters()])


def fingerprint(mlp):
    if mlp is None:
        return 0.0
    p = flat(mlp).double()
    return float((p * torch.cos(0.37 * torch.arange(p.numel(), dtype=torch.float64))).sum())


def run(human, critic_loss_kind):
    actor = make_mlp([OBS, *HIDDEN, 2 * ACT], 0)
    q1, q2 = make_mlp([OBS + ACT, *HIDDEN, 1], 1), make_mlp([OBS + ACT, *HIDDEN, 1], 2)
    q1_target, q2_target = copy.deepcopy(q1), copy.deepcopy(q2)
    h1 = h2 = None
    if human is not None:
        h1, h2 = make_mlp([OBS + ACT, *HIDDEN, 1], 3), make_mlp([OBS + ACT, *HIDDEN, 1], 4)
    log_ent_coef = torch.log(torch.ones(1) * INIT_ENT_COEF).requires_grad_(True)
    actor_optimizer = torch.optim.Adam(actor.parameters(), lr=LR)
    critic_optimizer = torch.optim.Adam([*q1.parameters(), *q2.parameters()], lr=LR)
    ent_coef_optimizer = torch.optim.Adam([log_ent_coef], lr=LR)
    if human is not None:
        human_optimizer = torch.optim.Adam([*h1.parameters(), *h2.parameters()], lr=LR)

    obs = formula(BATCH * OBS, lambda k: math.cos(0.5 * k)).view(BATCH, OBS)
    next_obs = formula(BATCH * OBS, lambda k: math.cos(0.5 * k + 0.3)).view(BATCH, OBS)
    actions = formula(BATCH * ACT, lambda k: 0.9 * math.sin(0.7 * k + 0.2)).view(BATCH, ACT)
    noise_pi = formula(BATCH * ACT, lambda k: 1.2 * math.sin(0.9 * k + 0.4)).view(BATCH, ACT)
    noise_next = formula(BATCH * ACT, lambda k: math.cos(0.8 * k + 0.1)).view(BATCH, ACT)
    rewards = formula(BATCH, lambda i: math.sin(1.1 * i + 0.5)).view(BATCH, 1)
    if critic_loss_kind == "huber":
        rewards = rewards * HUBER_REWARD_FACTOR
    regress = F.huber_loss if critic_loss_kind == "huber" else F.mse_loss
    human_feedback = torch.tensor([1.0, 0.0, -1.0, 0.0, 1.0]).view(BATCH, 1)
    dones = torch.tensor([0.0, 1.0, 0.0, 0.0, 0.0]).view(BATCH, 1)

    def action_log_prob(observations, noise):
        # SB3's SquashedDiagGaussianDistribution with the noise of rsample given.
        out = actor(observations)
        mean, log_std = out[:, :ACT], torch.clamp(out[:, ACT:], -20, 2)
        std = log_std.exp()
        gaussian_actions = mean + std * noise
        log_prob = torch.distributions.Normal(mean, std).log_prob(gaussian_actions).sum(dim=1)
        squashed = torch.tanh(gaussian_actions)
        log_prob -= torch.sum(torch.log(1 - squashed**2 + 1e-6), dim=1)
        return squashed, log_prob

    losses = []
    for _ in range(2):
        actions_pi, log_prob = action_log_prob(obs, noise_pi)
        log_prob = log_prob.reshape(-1, 1)
        ent_coef = torch.exp(log_ent_coef.detach())
        ent_coef_loss = -(log_ent_coef * (log_prob + TARGET_ENTROPY).detach()).mean()
        ent_coef_optimizer.zero_grad()
        ent_coef_loss.backward()
        ent_coef_optimizer.step()

        with torch.no_grad():
            next_actions, next_log_prob = action_log_prob(next_obs, noise_next)
            x_next = torch.cat([next_obs, next_actions], dim=1)
            next_q_values = torch.cat([q1_target(x_next), q2_target(x_next)], dim=1)
            next_q_values, _ = torch.min(next_q_values, dim=1, keepdim=True)
            next_q_values = next_q_values - ent_coef * next_log_prob.reshape(-1, 1)
            target_q_values = rewards + (1 - dones) * GAMMA * next_q_values

        x = torch.cat([obs, actions], dim=1)
        critic_loss = 0.5 * sum(regress(q(x), target_q_values) for q in (q1, q2))
        critic_optimizer.zero_grad()
        critic_loss.backward()
        critic_optimizer.step()

        human_loss = torch.zeros(())
        if human is not None:
            lam, mix, mask = human
            rows = (human_feedback != 0).reshape(-1) if mask else torch.ones(BATCH, dtype=torch.bool)
            human_loss = 0.5 * sum(F.mse_loss(h(x)[rows], human_feedback[rows]) for h in (h1, h2))
            human_optimizer.zero_grad()
            human_loss.backward()
            human_optimizer.step()

        x_pi = torch.cat([obs, actions_pi], dim=1)
        if human is None:
            q_values_pi = torch.cat([q1(x_pi), q2(x_pi)], dim=1)
            value, _ = torch.min(q_values_pi, dim=1, keepdim=True)
        elif mix == "authors":
            w_q = float(np.float32(1.0) / np.float32(1.0 + lam))
            w_h = float(np.float32(lam) / np.float32(1.0 + lam))
            mixed = torch.cat([w_q * q1(x_pi) + w_h * h1(x_pi), w_q * q2(x_pi) + w_h * h2(x_pi)], dim=1)
            value, _ = torch.min(mixed, dim=1, keepdim=True)
        else:
            min_q, _ = torch.min(torch.cat([q1(x_pi), q2(x_pi)], dim=1), dim=1, keepdim=True)
            min_h, _ = torch.min(torch.cat([h1(x_pi), h2(x_pi)], dim=1), dim=1, keepdim=True)
            value = min_q + lam * min_h
        actor_loss = (ent_coef * log_prob - value).mean()
        actor_optimizer.zero_grad()
        actor_loss.backward()
        actor_optimizer.step()

        with torch.no_grad():
            for online, target in ((q1, q1_target), (q2, q2_target)):
                for p, t in zip(online.parameters(), target.parameters()):
                    t.mul_(1 - TAU)
                    t.add_(p, alpha=TAU)

        losses.append(
            [critic_loss.item(), human_loss.item(), actor_loss.item(), ent_coef.item(), ent_coef_loss.item()]
        )

    nets = [actor, q1, q2, q1_target, q2_target, h1, h2]
    prints = [fingerprint(n) for n in nets] + [log_ent_coef.item()]
    return losses, prints, flat(actor)[ACTOR_PROBE]


def main():
    torch.set_default_dtype(torch.float32)
    print(f"// torch {torch.__version__}, benches/reference/torch_sac_reference.py")
    for name, human, critic_loss_kind in LEARNERS:
        losses, prints, probe = run(human, critic_loss_kind)
        for step, row in enumerate(losses):
            print(rust_array(f"{name}_LOSSES_{step}", row))
        print(rust_array(f"{name}_FINGERPRINTS", prints))
        print(rust_array(f"{name}_ACTOR_PROBE", probe))
    print(f"// ACTOR_PROBE = {ACTOR_PROBE}")


if __name__ == "__main__":
    main()
