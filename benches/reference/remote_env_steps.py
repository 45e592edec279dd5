"""Env steps through dualrep's env protocol against in-process, in one run on this machine:
our rapier2d Lunar Lander in-process (`dualrep bench env`); Gymnasium's Box2D
LunarLanderContinuous-v3 in-process (a Python loop) and served by `python -m dualrep.env`; and
an env that does nothing served the same way (what the protocol itself costs per step: a
localhost round trip, JSON on both sides, the server's loop). Each is timed as a loop of random
actions, steps and resets, in wall-clock time and in CPU time (client and server together), the
latter being what a shared machine's load does not change. Prints one JSON object.

Run with the venv's Python (Gymnasium with Box2D and this repository's clients/python):
    python benches/reference/remote_env_steps.py --dualrep target/release/dualrep --steps 50000
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Dict, List, Tuple

HERE = Path(__file__).resolve().parent
TICK = os.sysconf("SC_CLK_TCK")


def proc_cpu(pid: int) -> float:
    """User plus system CPU seconds of a running process (Linux /proc)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICK


def children_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def serve(args: List[str], cwd: Path) -> Tuple[subprocess.Popen, str]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "dualrep.env", "--port", "0", "--no-render", *args],
        cwd=cwd,
        stdout=subprocess.PIPE,
        text=True,
    )
    line = proc.stdout.readline() if proc.stdout else ""
    match = re.search(r"tcp://[0-9.]+:[0-9]+", line)
    if not match:
        proc.kill()
        raise SystemExit(f"the env server did not start: {line!r}")
    return proc, match.group(0)


def bench(dualrep: str, steps: int, *flags: str) -> Tuple[Dict[str, Any], float]:
    """`dualrep bench env ...`: its JSON and the CPU seconds it used."""
    before = children_cpu()
    out = subprocess.run(
        [dualrep, "bench", "env", "--task", "lunar-lander", "--steps", str(steps), *flags],
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout), children_cpu() - before


def gymnasium_in_process(steps: int) -> Dict[str, float]:
    import gymnasium as gym
    import numpy as np

    env = gym.make("LunarLanderContinuous-v3")
    rng = np.random.default_rng(7)
    episodes = 0
    env.reset(seed=episodes)
    wall, cpu = time.perf_counter(), time.process_time()
    for _ in range(steps):
        action = rng.uniform(-1.0, 1.0, size=2).astype(np.float32)
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            episodes += 1
            env.reset(seed=episodes)
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    return {"wall_us_per_step": wall * 1e6 / steps, "cpu_us_per_step": cpu * 1e6 / steps}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--dualrep", default="target/release/dualrep")
    p.add_argument("--steps", type=int, default=50_000)
    args = p.parse_args()
    n = args.steps
    result: Dict[str, Any] = {"steps": n, "cpu": os.uname().machine}

    ours, cpu = bench(args.dualrep, n)
    timing = ours["in_process"]
    result["rapier_in_process"] = {
        "wall_us_per_step": timing["microseconds_per_step"],
        # The process's whole CPU time (start-up included) over the steps.
        "cpu_us_per_step": cpu * 1e6 / n,
    }
    result["gymnasium_in_process"] = gymnasium_in_process(n)
    for name, server_args, cwd in [
        ("gymnasium_remote", ["--gym", "LunarLanderContinuous-v3"], Path.cwd()),
        ("null_remote", ["--make", "null_env:NullEnv", "--id", "null", "--max-episode-steps", "1000"], HERE),
    ]:
        proc, url = serve(server_args, cwd)
        try:
            server_before = proc_cpu(proc.pid)
            flag = "--env-url" if name == "gymnasium_remote" else "--null-url"
            report, client_cpu = bench(args.dualrep, n, "--skip-in-process", flag, url)
            server_cpu = proc_cpu(proc.pid) - server_before
        finally:
            proc.terminate()
            proc.wait()
        timing = report["remote" if name == "gymnasium_remote" else "null_remote"]
        result[name] = {
            "wall_us_per_step": timing["microseconds_per_step"],
            "cpu_us_per_step": (client_cpu + server_cpu) * 1e6 / n,
            "client_cpu_us_per_step": client_cpu * 1e6 / n,
            "server_cpu_us_per_step": server_cpu * 1e6 / n,
        }
    for kind in ("wall", "cpu"):
        key = f"{kind}_us_per_step"
        result[f"rapier_over_remote_{kind}"] = result["gymnasium_remote"][key] / result["rapier_in_process"][key]
        result[f"protocol_{kind}_us_per_step"] = result["null_remote"][key]
    print(json.dumps(result))


if __name__ == "__main__":
    main()
