"""How fast a random policy meets Lunar Lander's abstract states, on Gymnasium's own Box2D env.

DREF's rule (k = 60) asks on every step until more than 61 abstract states have feedback, so
the step at which a run has met 62 states bounds how long it asks on every step. This prints,
per action distribution and per choice of side-engine bits (ours test a1, the authors' code
a0; tasks.md), that step and the number of states met in the first `--steps` steps:

    pip install "gymnasium[box2d]"
    python3 benches/reference/lunar_lander_state_discovery.py --seeds 5 --steps 5000

"uniform" draws each action component from U(-1, 1); "tanh-normal" from tanh(N(0, 1)), the
action of an untrained squashed-Gaussian SAC actor (mean near 0, standard deviation near 1).
"""

import argparse
import json

import gymnasium as gym
import numpy as np

FLAG_X = 0.28
FLAG_TOP_Y = 0.235
UPRIGHT_ANGLE = 0.5


def abstract_state(next_obs: np.ndarray, action: np.ndarray, side_on_a0: bool) -> tuple:
    """The task's 10 predicates (tasks.md) on the next observation and the action."""
    x, y, angle = float(next_obs[0]), float(next_obs[1]), float(next_obs[4])
    side = float(action[0] if side_on_a0 else action[1])
    return (
        x < -FLAG_X,
        x < FLAG_X,
        x < 0.0,
        y > FLAG_TOP_Y,
        y > FLAG_TOP_Y,
        y > 0.0,
        abs(angle) < UPRIGHT_ANGLE,
        float(action[0]) > 0.0,
        side < -0.5,
        side > 0.5,
    )


def discover(distribution: str, side_on_a0: bool, seed: int, steps: int, k: int) -> dict:
    env = gym.make("LunarLanderContinuous-v3")
    rng = np.random.default_rng(seed)
    env.reset(seed=seed)
    seen: set = set()
    first_past_k: int | None = None
    for t in range(1, steps + 1):
        if distribution == "uniform":
            action = rng.uniform(-1.0, 1.0, 2)
        else:
            action = np.tanh(rng.normal(0.0, 1.0, 2))
        next_obs, _, terminated, truncated, _ = env.step(action.astype(np.float32))
        seen.add(abstract_state(next_obs, action, side_on_a0))
        if first_past_k is None and len(seen) > k + 1:
            first_past_k = t
        if terminated or truncated:
            env.reset()
    return {"step_past_k_plus_1": first_past_k, "states": len(seen)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=5)
    parser.add_argument("--steps", type=int, default=5000)
    parser.add_argument("--k", type=int, default=60, help="the query rule's k (Lunar Lander: 60)")
    args = parser.parse_args()
    for distribution in ("uniform", "tanh-normal"):
        for side_on_a0 in (False, True):
            runs = [
                discover(distribution, side_on_a0, seed, args.steps, args.k)
                for seed in range(args.seeds)
            ]
            print(json.dumps({
                "actions": distribution,
                "side_engine_bits": "a0 (authors)" if side_on_a0 else "a1 (ours)",
                "steps": args.steps,
                "runs": runs,
            }))


if __name__ == "__main__":
    main()
