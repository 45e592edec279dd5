"""Episodes of the authors' own Placing environment (`BallBasket`, their robosuite fork
`misoshiruseijin/robosuite`) under a fixed behaviour policy: how long episodes last, how they end
and how many succeed. The peer of `dualrep sim --task placing --policy random`, measured to ask
whether the authors' task gives a learner more chance successes than ours (docs/results/
fig3-as-run/placing-sac/README.md).

    bash benches/reference/run_authors_placing_env.sh /path/to/misoshiruseijin-robosuite 200 0 uniform

Policies: `uniform` (every action component uniform in [-1, 1], as `dualrep sim --policy
random`), `closed` (the same moves with the gripper always commanded closed: how often the ball is
lost without an "open" command), `sb3` (stable-baselines3's SAC with the authors' Placing config,
`placing_standin.AUTHORS_SAC`, learning for `--steps` steps; the time limit terminal, as run). The environment is made exactly as the authors' Placing
pipelines made it (`robosuite_pipeline_*_ballbasket.py`: Sawyer, OSC_POSITION, 20 Hz,
reward_scale 100, prehensile=False). Steps count the agent's steps (the 50 random reset moves
happen inside the authors' `reset`).

One deviation, printed with the result: MuJoCo 2.3.7 with PyPI robosuite 1.4.1's Sawyer meshes
reports the robot's link0 touching its own base at rest, so the authors' "arm collision" check
would end every episode after one step (their logged episodes last 65-250 steps); contacts
between two of the robot's own geoms are not counted.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import sys
import time
from typing import Any, Callable

import numpy as np


def make_env(fork_overlay: str) -> Any:
    sys.path.insert(0, fork_overlay)
    import robosuite as suite  # the overlay's robosuite: the fork's sources, PyPI's assets
    from robosuite import load_controller_config

    return suite.make(
        env_name="BallBasket",
        robots="Sawyer",
        controller_configs=load_controller_config(default_controller="OSC_POSITION"),
        has_renderer=False,
        has_offscreen_renderer=False,
        render_camera="agentview",
        ignore_done=False,
        use_camera_obs=False,
        control_freq=20,
        reward_scale=100,
        hard_reset=False,
        prehensile=False,
    )


def ignore_self_contacts(env: Any) -> None:
    """The deviation of the module doc: a robot-only contact is not an arm collision."""
    robot_model = env.robots[0].robot_model
    robot_geoms = set(robot_model.contact_geoms)
    original: Callable[..., bool] = env.check_contact

    def check_contact(geoms_1: Any, geoms_2: Any = None) -> bool:
        if geoms_1 is robot_model and geoms_2 is None:
            for contact in env.sim.data.contact[: env.sim.data.ncon]:
                g1 = env.sim.model.geom_id2name(contact.geom1)
                g2 = env.sim.model.geom_id2name(contact.geom2)
                if (g1 in robot_geoms) != (g2 in robot_geoms):
                    return True
            return False
        return original(geoms_1, geoms_2)

    env.check_contact = check_contact


def action(policy: str) -> np.ndarray:
    # numpy's global generator, which the authors' reset also draws from: one seed, one stream.
    a = np.random.uniform(-1.0, 1.0, 4)
    if policy == "closed":
        a[3] = 1.0
    return a


def end_reason(printed: io.StringIO, reward: float) -> str:
    """How an episode ended: the last line the authors' environment printed ("ball dropped",
    "gripper collision: hoop", "arm collision"), "success" when it paid, "time limit" when it
    printed nothing."""
    if reward > 0:
        return "success"
    lines = printed.getvalue().strip().splitlines()
    return lines[-1] if lines else "time limit"


def episode(env: Any, policy: str) -> tuple[str, int, list[float]]:
    """(how it ended, agent steps, gripper position at the start). The authors' environment prints
    its reason for ending ("ball dropped", "gripper collision: hoop", "arm collision", "success");
    a run to the horizon prints nothing."""
    printed = io.StringIO()
    with contextlib.redirect_stdout(printed):
        obs = env.reset()
        start = [float(v) for v in obs["eef_xyz_gripper"][:3]]
        steps, total = 0, 0.0
        while True:
            _, reward, done, _ = env.step(action(policy))
            steps += 1
            total += reward
            if done:
                break
    return end_reason(printed, total), steps, start


def sb3_run(env: Any, seed: int, steps: int) -> dict[str, Any]:
    import gymnasium as gym
    import torch
    from gymnasium import spaces
    from stable_baselines3 import SAC

    from placing_standin import AUTHORS_SAC, summarize

    class Wrapped(gym.Env):  # type: ignore[misc]
        def __init__(self) -> None:
            self.observation_space = spaces.Box(-np.inf, np.inf, (4,), np.float32)
            self.action_space = spaces.Box(-1.0, 1.0, (4,), np.float32)
            self.ends: list[tuple[int, str]] = []
            self.t = 0

        def reset(self, seed: int | None = None, options: Any = None) -> tuple[np.ndarray, dict]:
            with contextlib.redirect_stdout(io.StringIO()):
                obs = env.reset()
            self.t = 0
            return obs["eef_xyz_gripper"].astype(np.float32), {}

        def step(self, a: np.ndarray) -> tuple[np.ndarray, float, bool, bool, dict]:
            printed = io.StringIO()
            with contextlib.redirect_stdout(printed):
                obs, reward, done, _ = env.step(np.array(a, dtype=np.float64))
            self.t += 1
            if done:
                self.ends.append((self.t, end_reason(printed, reward)))
            return obs["eef_xyz_gripper"].astype(np.float32), float(reward), bool(done), False, {}

    torch.set_num_threads(1)
    wrapped = Wrapped()
    model = SAC("MlpPolicy", wrapped, seed=seed, device="cpu", verbose=0, **AUTHORS_SAC)
    t0 = time.time()
    model.learn(total_timesteps=steps)
    return summarize(wrapped.ends, steps) | {"seconds": round(time.time() - t0)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--overlay", required=True, help="folder holding the overlay's robosuite/")
    parser.add_argument("--episodes", type=int, default=200)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--policy", choices=["uniform", "closed", "sb3"], default="uniform")
    parser.add_argument("--steps", type=int, default=15000, help="sb3: steps to learn for")
    args = parser.parse_args()
    if args.policy == "sb3":
        # torch before robosuite: importing torch's compiler after numba's LLVM crashes (SIGSEGV).
        import torch._dynamo  # noqa: F401
    np.random.seed(args.seed)
    env = make_env(args.overlay)
    ignore_self_contacts(env)
    header = {
        "env": "authors' BallBasket (misoshiruseijin/robosuite), robosuite 1.4.1 assets, mujoco 2.3.7",
        "deviation": "contacts between two of the robot's own geoms are not arm collisions",
        "policy": args.policy,
        "seed": args.seed,
    }
    if args.policy == "sb3":
        print(json.dumps(header | sb3_run(env, args.seed, args.steps)))
        return
    ends: dict[str, int] = {}
    lengths: list[int] = []
    starts: list[list[float]] = []
    t0 = time.time()
    for n in range(args.episodes):
        end, steps, start = episode(env, args.policy)
        ends[end] = ends.get(end, 0) + 1
        lengths.append(steps)
        starts.append(start)
        if (n + 1) % 20 == 0:
            print(f"{n + 1} episodes: {ends}, mean length {np.mean(lengths):.1f}", file=sys.stderr)
    s = np.array(starts)
    print(json.dumps(header | {
        "episodes": args.episodes,
        "ends": ends,
        "successes": ends.get("success", 0),
        "mean_length": round(float(np.mean(lengths)), 1),
        "start_mean": [round(float(v), 3) for v in s.mean(0)],
        "start_sd": [round(float(v), 3) for v in s.std(0)],
        "seconds": round(time.time() - t0),
    }))


if __name__ == "__main__":
    main()
