"""PyTorch's speed at the update `dualrep bench sac` times: DREF's SAC gradient step (twin
critics, twin human critics with the authors' mix, automatic temperature, Polyak), in
stable-baselines3's order, on one CPU thread unless `--threads`, on batches drawn from random
transitions.

    pip install torch==2.15.0   # CPU is enough
    python3 benches/reference/torch_sac_update.py                      # Lunar Lander's sizes
    python3 benches/reference/torch_sac_update.py --hidden 256,256 --batch 256

Prints one JSON object with `updates_per_second` (1 / the median time of an update, as `dualrep
bench sac` reports it: robust to other processes on a shared machine) and
`mean_updates_per_second`. Sizes default to Lunar Lander's
(obs 8, act 2, hidden [400, 300], batch 512). Each update samples its batch by index from a
replay of 100,000 random transitions, as the Rust benchmark does.
"""

import argparse
import copy
import json
import statistics
import time

import torch
import torch.nn.functional as F

LR, TAU, GAMMA, LAMBDA = 7.3e-4, 0.01, 0.99, 9.0


def mlp(sizes):
    layers = []
    for i, (a, b) in enumerate(zip(sizes, sizes[1:])):
        layers.append(torch.nn.Linear(a, b))
        if i < len(sizes) - 2:
            layers.append(torch.nn.ReLU())
    return torch.nn.Sequential(*layers)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--obs", type=int, default=8)
    parser.add_argument("--act", type=int, default=2)
    parser.add_argument("--hidden", default="400,300")
    parser.add_argument("--batch", type=int, default=512)
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    torch.manual_seed(0)
    obs_dim, act_dim, batch = args.obs, args.act, args.batch
    hidden = [int(h) for h in args.hidden.split(",")]

    actor = mlp([obs_dim, *hidden, 2 * act_dim])
    q1, q2, h1, h2 = (mlp([obs_dim + act_dim, *hidden, 1]) for _ in range(4))
    q1_target, q2_target = copy.deepcopy(q1), copy.deepcopy(q2)
    for p in [*q1_target.parameters(), *q2_target.parameters()]:
        p.requires_grad_(False)
    log_ent_coef = torch.zeros(1, requires_grad=True)
    target_entropy = -float(act_dim)
    actor_optimizer = torch.optim.Adam(actor.parameters(), lr=LR)
    critic_optimizer = torch.optim.Adam([*q1.parameters(), *q2.parameters()], lr=LR)
    human_optimizer = torch.optim.Adam([*h1.parameters(), *h2.parameters()], lr=LR)
    ent_coef_optimizer = torch.optim.Adam([log_ent_coef], lr=LR)
    w_q, w_h = 1.0 / (1.0 + LAMBDA), LAMBDA / (1.0 + LAMBDA)

    n = 100_000
    replay = {
        "obs": torch.rand(n, obs_dim) * 2 - 1,
        "actions": torch.rand(n, act_dim) * 2 - 1,
        "rewards": torch.rand(n, 1) * 2 - 1,
        "human": torch.randint(-1, 2, (n, 1)).float(),
        "next_obs": torch.rand(n, obs_dim) * 2 - 1,
        "dones": (torch.rand(n, 1) < 0.01).float(),
    }

    def action_log_prob(observations):
        out = actor(observations)
        mean, log_std = out[:, :act_dim], torch.clamp(out[:, act_dim:], -20, 2)
        std = log_std.exp()
        gaussian_actions = mean + std * torch.randn_like(mean)
        log_prob = torch.distributions.Normal(mean, std).log_prob(gaussian_actions).sum(dim=1)
        actions = torch.tanh(gaussian_actions)
        log_prob -= torch.sum(torch.log(1 - actions**2 + 1e-6), dim=1)
        return actions, log_prob.reshape(-1, 1)

    def update():
        idx = torch.randint(0, n, (batch,))
        obs, actions, rewards = replay["obs"][idx], replay["actions"][idx], replay["rewards"][idx]
        human, next_obs, dones = replay["human"][idx], replay["next_obs"][idx], replay["dones"][idx]

        actions_pi, log_prob = action_log_prob(obs)
        ent_coef = torch.exp(log_ent_coef.detach())
        ent_coef_loss = -(log_ent_coef * (log_prob + target_entropy).detach()).mean()
        ent_coef_optimizer.zero_grad()
        ent_coef_loss.backward()
        ent_coef_optimizer.step()

        with torch.no_grad():
            next_actions, next_log_prob = action_log_prob(next_obs)
            x_next = torch.cat([next_obs, next_actions], dim=1)
            next_q_values = torch.min(q1_target(x_next), q2_target(x_next))
            next_q_values = next_q_values - ent_coef * next_log_prob
            target_q_values = rewards + (1 - dones) * GAMMA * next_q_values

        x = torch.cat([obs, actions], dim=1)
        critic_loss = 0.5 * (F.mse_loss(q1(x), target_q_values) + F.mse_loss(q2(x), target_q_values))
        critic_optimizer.zero_grad()
        critic_loss.backward()
        critic_optimizer.step()

        human_loss = 0.5 * (F.mse_loss(h1(x), human) + F.mse_loss(h2(x), human))
        human_optimizer.zero_grad()
        human_loss.backward()
        human_optimizer.step()

        x_pi = torch.cat([obs, actions_pi], dim=1)
        mixed = torch.cat([w_q * q1(x_pi) + w_h * h1(x_pi), w_q * q2(x_pi) + w_h * h2(x_pi)], dim=1)
        min_mixed, _ = torch.min(mixed, dim=1, keepdim=True)
        actor_loss = (ent_coef * log_prob - min_mixed).mean()
        actor_optimizer.zero_grad()
        actor_loss.backward()
        actor_optimizer.step()

        with torch.no_grad():
            for online, target in ((q1, q1_target), (q2, q2_target)):
                torch._foreach_mul_(list(target.parameters()), 1 - TAU)
                torch._foreach_add_(list(target.parameters()), list(online.parameters()), alpha=TAU)

    for _ in range(3):
        update()
    start, times = time.perf_counter(), []
    while time.perf_counter() - start < args.seconds:
        t = time.perf_counter()
        update()
        times.append(time.perf_counter() - t)
    elapsed = time.perf_counter() - start
    count = len(times)
    print(
        json.dumps(
            {
                "framework": f"torch {torch.__version__}",
                "threads": torch.get_num_threads(),
                "obs_dim": obs_dim,
                "act_dim": act_dim,
                "hidden": hidden,
                "batch": batch,
                "updates": count,
                "updates_per_second": 1.0 / statistics.median(times),
                "mean_updates_per_second": count / elapsed,
            }
        )
    )


if __name__ == "__main__":
    main()
