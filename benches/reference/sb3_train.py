"""stable-baselines3's SAC end to end on Gymnasium's `LunarLanderContinuous-v3`: environment steps
per second of `model.learn` (env, replay, one gradient step per environment step), with our Lunar
Lander configuration (`sb3_lunar_lander.py` lists it side by side with `dualrep train`'s), the
peer of `dualrep bench train --task lunar-lander`.

    bash benches/reference/compare_speed.sh        # ours and the peers in one run, with ratios
    python3 benches/reference/sb3_train.py --steps 2000    # one JSON object (pins: compare_speed.sh)

One CPU thread unless `--threads` (`torch.set_num_threads`).
"""

from __future__ import annotations

import argparse
import json
import time
from importlib.metadata import version

import gymnasium as gym
import torch
from stable_baselines3 import SAC

from sb3_lunar_lander import CONFIG


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    torch.set_num_threads(args.threads)

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
    start = time.perf_counter()
    model.learn(total_timesteps=args.steps)
    seconds = time.perf_counter() - start
    print(
        json.dumps(
            {
                "framework": f"stable-baselines3 {version('stable-baselines3')}, torch {torch.__version__}",
                "task": "lunar-lander",
                "method": "sac",
                "steps": args.steps,
                "threads": torch.get_num_threads(),
                "seconds": seconds,
                "env_steps_per_second": args.steps / seconds,
                "updates": model._n_updates,
            }
        )
    )


if __name__ == "__main__":
    main()
