"""Gymnasium's LunarLanderContinuous-v3 (Box2D) as the reference for our rapier2d port.

Prints one JSON object per policy with the same fields as `dualrep sim`, so the two can be
put side by side:

    pip install "gymnasium[box2d]"
    python3 benches/reference/gym_lunar_lander.py --episodes 100 --seed 0

`steps_per_second` times env.step alone (random actions drawn beforehand), one thread.
"""

import argparse
import json
import time

import gymnasium as gym
import numpy as np
from gymnasium.envs.box2d.lunar_lander import heuristic


def run(policy: str, episodes: int, seed: int) -> dict:
    env = gym.make("LunarLanderContinuous-v3")
    rng = np.random.default_rng(seed)
    returns, lengths, successes = [], [], 0
    step_seconds, steps = 0.0, 0
    for i in range(episodes):
        obs, _ = env.reset(seed=seed + i)
        total, length = 0.0, 0
        while True:
            if policy == "random":
                action = rng.uniform(-1.0, 1.0, size=2).astype(np.float32)
            else:
                action = heuristic(env.unwrapped, obs)
            t0 = time.perf_counter()
            obs, reward, terminated, truncated, _ = env.step(action)
            step_seconds += time.perf_counter() - t0
            total += float(reward)
            length += 1
            if terminated or truncated:
                # Gymnasium's "landed": the lander came to rest (+100 on the last step).
                successes += int(terminated and reward >= 100.0 - 1e-6 and not env.unwrapped.game_over)
                break
        steps += length
        returns.append(total)
        lengths.append(length)
    returns = np.array(returns)
    return {
        "task": "lunar-lander",
        "policy": policy,
        "implementation": "gymnasium-box2d",
        "episodes": episodes,
        "mean_return": float(returns.mean()),
        "std_return": float(returns.std()),
        "mean_length": float(np.mean(lengths)),
        "success_rate": successes / episodes,
        "steps_per_second": steps / step_seconds,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--episodes", type=int, default=100)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--policy", choices=["random", "heuristic", "both"], default="both")
    args = parser.parse_args()
    policies = ["random", "heuristic"] if args.policy == "both" else [args.policy]
    for policy in policies:
        print(json.dumps(run(policy, args.episodes, args.seed)))


if __name__ == "__main__":
    main()
