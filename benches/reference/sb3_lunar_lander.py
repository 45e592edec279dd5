"""stable-baselines3's SAC on Gymnasium's `LunarLanderContinuous-v3` with our Lunar Lander
configuration (algorithms.md section 1), written in our `dualrep train` format so that the two
sit side by side: `OUT/metrics.csv` (a row per finished episode) and `OUT/summary.json`.

    bash benches/reference/run_sb3_lunar_lander.sh 0 1 2     # venv, packages, three seeds
    python3 benches/reference/sb3_lunar_lander.py --steps 20000 --seed 0 --out runs/sb3-0

Configuration, as `dualrep train --task lunar-lander --method sac` runs it:

| ours                                   | stable-baselines3                                  |
|----------------------------------------|----------------------------------------------------|
| hidden [400, 300] ReLU, actor + twin Q | policy_kwargs net_arch [400, 300] (ReLU default)   |
| Adam lr 7.3e-4 (actor, critics, alpha) | learning_rate 7.3e-4 (one rate for all three)      |
| batch 512, buffer 1e6                  | batch_size 512, buffer_size 1_000_000              |
| tau 0.01, gamma 0.99                   | tau 0.01, gamma 0.99                               |
| learning starts 0, 1 update per step   | learning_starts 0, train_freq 1, gradient_steps 1  |
| temperature auto, initial 1.0          | ent_coef "auto_1.0", target_entropy "auto" (-2)    |
| truncation at 1000 steps bootstraps    | SB3 >= 2 handles `truncated` the same way          |

One CPU thread (`torch.set_num_threads(1)`), as our learner runs on one.

An episode's outcome: `time_limit` when Gymnasium truncates it, `success` when it terminates with
the lander at rest (the env's last reward then includes its +100, which a crash's -100 or a
flight out of the world never does: the last reward is above 50), else `failure`.
"""

from __future__ import annotations

import argparse
import csv
import json
import time
from importlib.metadata import version
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3 import SAC
from stable_baselines3.common.callbacks import BaseCallback

CONFIG: dict[str, Any] = {
    "hidden": [400, 300],
    "learning_rate": 7.3e-4,
    "batch_size": 512,
    "buffer_size": 1_000_000,
    "tau": 0.01,
    "gamma": 0.99,
    "learning_starts": 0,
    "train_freq": 1,
    "gradient_steps": 1,
    "ent_coef": "auto_1.0",
    "target_entropy": "auto",
}


class EpisodeLog(BaseCallback):
    """Writes a `metrics.csv` row at the end of every episode."""

    def __init__(self, path: Path) -> None:
        super().__init__()
        self.file = path.open("w", newline="")
        self.csv = csv.writer(self.file)
        self.csv.writerow(["step", "episode", "return", "length", "outcome", "cumulative_return"])
        self.episode_return = 0.0
        self.length = 0
        self.cumulative = 0.0
        self.episodes: list[float] = []

    def _on_step(self) -> bool:
        reward = float(self.locals["rewards"][0])
        self.episode_return += reward
        self.length += 1
        if bool(self.locals["dones"][0]):
            info = self.locals["infos"][0]
            truncated = bool(info.get("TimeLimit.truncated", False))
            if truncated:
                outcome = "time_limit"
            elif reward > 50.0:
                outcome = "success"
            else:
                outcome = "failure"
            self.cumulative += self.episode_return
            self.episodes.append(self.episode_return)
            self.csv.writerow(
                [
                    self.num_timesteps,
                    len(self.episodes) - 1,
                    self.episode_return,
                    self.length,
                    outcome,
                    self.cumulative,
                ]
            )
            self.file.flush()
            self.episode_return = 0.0
            self.length = 0
        return True

    def close(self) -> None:
        self.file.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=20_000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, required=True)
    args = parser.parse_args()
    torch.set_num_threads(1)
    args.out.mkdir(parents=True, exist_ok=True)

    env = gym.make("LunarLanderContinuous-v3")
    model = SAC(
        "MlpPolicy",
        env,
        learning_rate=CONFIG["learning_rate"],
        buffer_size=CONFIG["buffer_size"],
        learning_starts=CONFIG["learning_starts"],
        batch_size=CONFIG["batch_size"],
        tau=CONFIG["tau"],
        gamma=CONFIG["gamma"],
        train_freq=CONFIG["train_freq"],
        gradient_steps=CONFIG["gradient_steps"],
        ent_coef=CONFIG["ent_coef"],
        target_entropy=CONFIG["target_entropy"],
        policy_kwargs={"net_arch": CONFIG["hidden"]},
        seed=args.seed,
        device="cpu",
        verbose=0,
    )
    log = EpisodeLog(args.out / "metrics.csv")
    start = time.perf_counter()
    model.learn(total_timesteps=args.steps, callback=log)
    wall = time.perf_counter() - start
    log.close()

    last = log.episodes[-10:]
    summary = {
        "task": "lunar-lander",
        "env": "gymnasium LunarLanderContinuous-v3 (Box2D)",
        "method": "sb3-sac",
        "seed": args.seed,
        "steps": args.steps,
        "episodes": len(log.episodes),
        "cumulative_return": log.cumulative,
        "final_mean_return": float(np.mean(last)) if last else 0.0,
        "wall_seconds": wall,
        "updates_per_second": model._n_updates / wall,
        "config": CONFIG,
        "versions": {p: version(p) for p in ["stable-baselines3", "gymnasium", "torch", "box2d"]},
    }
    (args.out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    print(json.dumps({k: summary[k] for k in ["seed", "episodes", "cumulative_return", "wall_seconds"]}))


if __name__ == "__main__":
    main()
