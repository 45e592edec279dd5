"""A kinematic stand-in of our Placing (tasks.md's authors' variant) in Python, so that
stable-baselines3's SAC, the authors' own learner, can be run on our task's rules: the home start
and its 50 small reset moves, 1.2 cm per full action, the safety gate (workspace and no-entry box,
probe 0.07 * a), the gripper's integrated command (0.01 per step, the ball released at c <= 0.88),
+100 for a release over the opening above the ring, 0 and the end for a release elsewhere or a
touch of the hoop (a ball-sized sphere around the gripper point), and the time limit stored as
terminal, as run. No ball physics: nothing here needs it (a success is decided at the release).

    python3 benches/reference/placing_standin.py random --hoop box --episodes 2000
    python3 benches/reference/placing_standin.py sb3 --hoop box --seed 0 --steps 20000

`--hoop box` is our hoop (a hollow box with an opening in its top); `none` lets nothing touch it,
as in the authors' MuJoCo scene, where 200 random episodes never touched their thin ring, overhang
and pole (authors_placing_env.py). Calibration against the real env: 2,000 random episodes of the
stand-in last 92.3 steps and succeed 0.1 %; `dualrep sim --task placing --policy random
--episodes 200` gives 95.1 steps and 0 successes. `sb3` uses the authors' Placing SAC config
(`configs/robosuite/sac.yaml`, which their `robosuite_pipeline_sac_ballbasket.py` read in the
batches of 2022-06-05): learning rate 7.5e-4, batch 512, tau 0.01, gamma 0.99, learning_starts
0, one update a step, net_arch [128, 128], entropy coefficient "auto"; one CPU thread.
"""

from __future__ import annotations

import argparse
import json
import time
from typing import Any

import numpy as np

GRIPPER_RADIUS = 0.025
STEP = 0.012
LOOKAHEAD = 0.07
HOME = (-0.315, 0.0, 1.0)
RESET_STEPS = 50
HORIZON = 1000
RELEASE_AT = 0.88
# Where the authors' gripper starts after their reset (200 resets of authors_placing_env.py: mean and
# s.d. per axis); ours starts at HOME and moves about 0.2 cm in its reset.
AUTHORS_START = (-0.313, 0.0, 1.015)
AUTHORS_START_SD = (0.014, 0.013, 0.009)
Box3 = tuple[tuple[float, float], tuple[float, float], tuple[float, float]]
WORKSPACE: Box3 = ((-0.6, 0.2), (-0.3, 0.3), (0.80, 1.65))
NO_ENTRY: Box3 = ((-0.17, 0.2), (-0.16, 0.16), (0.80, 1.03))


def box_hoop() -> list[Box3]:
    """Our hoop (core/src/sim/placing/hoop.rs): four walls and four top plates framing the opening."""
    top = (0.99, 1.0)
    walls = (0.75, 0.99)
    return [
        ((-0.25, -0.24), (-0.15, 0.15), walls), ((0.24, 0.25), (-0.15, 0.15), walls),
        ((-0.24, 0.24), (-0.15, -0.14), walls), ((-0.24, 0.24), (0.14, 0.15), walls),
        ((-0.25, 0.25), (-0.15, -0.1), top), ((-0.25, 0.25), (0.1, 0.15), top),
        ((-0.25, -0.1), (-0.1, 0.1), top), ((0.1, 0.25), (-0.1, 0.1), top),
    ]


HOOPS: dict[str, list[Box3]] = {"box": box_hoop(), "none": []}

# The authors' Placing SAC (their configs/robosuite/sac.yaml and the pipeline's net_arch).
AUTHORS_SAC: dict[str, Any] = {
    "learning_rate": 0.00075, "buffer_size": 1_000_000, "learning_starts": 0, "batch_size": 512,
    "tau": 0.01, "gamma": 0.99, "train_freq": 1, "gradient_steps": 1,
    "policy_kwargs": {"net_arch": [128, 128]},
}


def inside(p: np.ndarray, region: Box3) -> bool:
    return all(lo < v < hi for v, (lo, hi) in zip(p, region))


def gate_allows(probe: np.ndarray) -> bool:
    return inside(probe, WORKSPACE) and not inside(probe, NO_ENTRY)


def touching(p: np.ndarray, hoop: list[Box3]) -> bool:
    for (x0, x1), (y0, y1), (z0, z1) in hoop:
        dx = max(x0 - p[0], 0.0, p[0] - x1)
        dy = max(y0 - p[1], 0.0, p[1] - y1)
        dz = max(z0 - p[2], 0.0, p[2] - z1)
        if dx * dx + dy * dy + dz * dz < GRIPPER_RADIUS**2:
            return True
    return False


class Placing:
    """One episode at a time; `step` returns (how it ended or None, reward)."""

    def __init__(self, hoop: str, seed: int, release_at: float = RELEASE_AT, start: str = "home") -> None:
        self.hoop = HOOPS[hoop]
        self.release_at = release_at
        self.start = start
        self.rng = np.random.default_rng(seed)
        self.p = np.array(HOME)
        self.c, self.g, self.t = 1.0, 1.0, RESET_STEPS

    def reset(self) -> np.ndarray:
        # A reset whose random moves touch the hoop is redrawn, as in ours.
        while True:
            p = np.array(HOME) if self.start == "home" else self.rng.normal(AUTHORS_START, AUTHORS_START_SD)
            for _ in range(RESET_STEPS):
                a = self.rng.uniform(-0.05, 0.05, 3)
                if gate_allows(p + LOOKAHEAD * a):
                    p = p + STEP * a
                if touching(p, self.hoop):
                    break
            else:
                break
        self.p, self.c, self.g, self.t = p, 1.0, 1.0, RESET_STEPS
        return self.observation()

    def observation(self) -> np.ndarray:
        return np.array([*self.p, self.g], dtype=np.float32)

    def step(self, action: np.ndarray) -> tuple[str | None, float]:
        a = np.clip(np.asarray(action, dtype=np.float64), -1.0, 1.0)
        if gate_allows(self.p + LOOKAHEAD * a[:3]):
            self.p = self.p + STEP * a[:3]
        self.c = min(1.0, max(-1.0, self.c + 0.01 * np.sign(a[3])))
        self.g = -1.0 if a[3] < 0 else 1.0
        self.t += 1
        if touching(self.p, self.hoop):
            return "touch", 0.0
        if self.c <= self.release_at + 1e-9:
            over = abs(self.p[0]) < 0.1 and abs(self.p[1]) < 0.1 and self.p[2] > 1.0
            return ("success", 100.0) if over else ("drop", 0.0)
        if self.t >= HORIZON:
            return "time limit", 0.0
        return None, 0.0


def random_episodes(hoop: str, episodes: int, seed: int, release_at: float, start: str) -> dict[str, Any]:
    env = Placing(hoop, seed, release_at, start)
    ends: dict[str, int] = {}
    lengths = []
    for _ in range(episodes):
        env.reset()
        steps = 0
        while True:
            end, _ = env.step(env.rng.uniform(-1.0, 1.0, 4))
            steps += 1
            if end:
                break
        ends[end] = ends.get(end, 0) + 1
        lengths.append(steps)
    return {"policy": "uniform", "hoop": hoop, "release_at": release_at, "start": start, "seed": seed,
            "episodes": episodes, "ends": ends,
            "mean_length": round(float(np.mean(lengths)), 1)}


def sb3_run(hoop: str, seed: int, steps: int, release_at: float, start: str) -> dict[str, Any]:
    import gymnasium as gym
    import torch
    from gymnasium import spaces
    from stable_baselines3 import SAC

    class Env(gym.Env):  # type: ignore[misc]
        def __init__(self) -> None:
            self.inner = Placing(hoop, seed, release_at, start)
            self.observation_space = spaces.Box(-np.inf, np.inf, (4,), np.float32)
            self.action_space = spaces.Box(-1.0, 1.0, (4,), np.float32)
            self.ends: list[tuple[int, str]] = []

        def reset(self, seed: int | None = None, options: Any = None) -> tuple[np.ndarray, dict]:
            return self.inner.reset(), {}

        def step(self, action: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
            end, reward = self.inner.step(action)
            if end:
                self.ends.append((self.inner.t - RESET_STEPS, end))
            # As run: the time limit is terminal (no truncation flag).
            return self.inner.observation(), reward, end is not None, False, {}

    torch.set_num_threads(1)
    env = Env()
    model = SAC("MlpPolicy", env, seed=seed, device="cpu", verbose=0, **AUTHORS_SAC)
    t0 = time.time()
    model.learn(total_timesteps=steps)
    return summarize(env.ends, steps) | {"learner": "stable-baselines3 SAC, authors' Placing config",
                                        "hoop": hoop, "release_at": release_at, "start": start, "seed": seed,
                                        "seconds": round(time.time() - t0)}


def summarize(ends: list[tuple[int, str]], steps: int) -> dict[str, Any]:
    """Episode ends in order as (length, how): counts, successes' steps, 5k-step bins."""
    rows, at = [], 0
    for length, end in ends:
        at += length
        rows.append((at, end))
    kinds = sorted({e for _, e in rows})
    return {
        "steps": steps,
        "episodes": len(rows),
        "successes": sum(e == "success" for _, e in rows),
        "success_steps": [s for s, e in rows if e == "success"],
        "first100": {k: sum(1 for _, e in rows[:100] if e == k) for k in kinds},
        "by5k": [[b, {k: sum(1 for s, e in rows if b <= s < b + 5000 and e == k) for k in kinds}]
                 for b in range(0, steps, 5000)],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("mode", choices=["random", "sb3"])
    parser.add_argument("--hoop", choices=sorted(HOOPS), default="box")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--episodes", type=int, default=2000)
    parser.add_argument("--steps", type=int, default=20000)
    parser.add_argument("--release-at", type=float, default=RELEASE_AT,
                        help="the ball drops once c <= this (0.88: twelve net opens; 0.92: eight)")
    parser.add_argument("--start", choices=["home", "authors"], default="home",
                        help="home: ours; authors: a normal draw around where the authors' reset leaves it")
    args = parser.parse_args()
    if args.mode == "random":
        print(json.dumps(random_episodes(args.hoop, args.episodes, args.seed, args.release_at, args.start)))
    else:
        print(json.dumps(sb3_run(args.hoop, args.seed, args.steps, args.release_at, args.start)))


if __name__ == "__main__":
    main()
