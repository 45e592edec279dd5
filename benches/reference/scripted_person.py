"""The scripted-person check of DREF for people (docs/dref.md): a human DREF session on Reaching,
served by `dualrep serve` at its default 20 Hz, answered over the trainer websocket by a script
that judges as a person would: +1 when the action moves the gripper toward the goal, -1 when it
moves it away. It reports how often the rule asked (queries per minute of the session at 20 Hz,
the share of steps, the longest run of consecutive asked steps) and whether the robot ended
solved (successes in its last 10 episodes).

    python3 benches/reference/scripted_person.py --binary target/release/dualrep \
        --method dref --steps 6000 --seed 0 --out docs/results/scripted-person/dref-seed0

Needs the `dualrep` Python package (clients/python) in the interpreter that runs it. The server
runs in a fresh data folder on a free loopback port and is stopped at the end.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import socket
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any, Dict, List, Mapping

from dualrep.client import Client
from dualrep.trainer import Trainer

PACE_HZ = 20.0


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def toward_goal(query: Mapping[str, Any]) -> int:
    """+1 if the action points from the gripper toward the goal's centre, else -1: what a
    person watching the clip's last frame would say about where the robot is heading."""
    frame = query["clip"]["frames"][-1]
    x, y = frame["gripper"]["position"][:2]
    gx0, gy0, gx1, gy1 = query["clip"]["geometry"]["goal"]
    to_goal = ((gx0 + gx1) / 2 - x, (gy0 + gy1) / 2 - y)
    ax, ay = query["action"][:2]
    return 1 if ax * to_goal[0] + ay * to_goal[1] > 0 else -1


def longest_run(steps: List[int]) -> int:
    """The longest stretch of consecutive step numbers."""
    best, run, previous = 0, 0, None
    for s in sorted(steps):
        run = run + 1 if previous is not None and s == previous + 1 else 1
        best, previous = max(best, run), s
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--binary", default="target/release/dualrep")
    parser.add_argument("--task", default="reaching")
    parser.add_argument("--method", default="dref")
    parser.add_argument("--steps", type=int, default=6000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                        help="a session setting (JSON value where it parses), e.g. max_queries_per_minute=20")
    args = parser.parse_args()
    params: Dict[str, Any] = {}
    for kv in args.param:
        key, _, text = kv.partition("=")
        try:
            params[key] = json.loads(text)
        except json.JSONDecodeError:
            params[key] = text

    port, token = free_port(), "scripted-person"
    data = tempfile.mkdtemp(prefix="dualrep-person-")
    server = subprocess.Popen(
        [args.binary, "serve", "--addr", f"127.0.0.1:{port}", "--data-dir", data,
         "--token", token, "--max-sessions", "1"],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
    )
    try:
        client = Client(f"http://127.0.0.1:{port}", token=token)
        for _ in range(100):
            try:
                client.tasks()
                break
            except OSError:
                time.sleep(0.1)
        launched = client.launch(args.method, task=args.task, trainer="human",
                                 steps=args.steps, seed=args.seed, params=params)
        asked: List[int] = []
        toward = {1: 0, -1: 0}

        def judge(query: Mapping[str, Any]) -> int:
            asked.append(int(query["step"]))
            h = toward_goal(query)
            toward[h] += 1
            return h

        started = time.monotonic()
        result = Trainer.for_session(client, launched).run(judge, timeout=120.0)
        wall = time.monotonic() - started
        session = client.wait(launched["id"])
        episodes = client.episodes(launched["id"])
    finally:
        server.terminate()
        server.wait(timeout=30)

    last = episodes[-10:]
    minutes = args.steps / PACE_HZ / 60.0
    summary: Dict[str, Any] = {
        "task": args.task,
        "method": args.method,
        "seed": args.seed,
        "params": params,
        "steps": args.steps,
        "status": session["status"],
        "ended_as": result.status,
        "queries": len(asked),
        "acknowledged": len(result.answered),
        "share_of_steps": len(asked) / args.steps,
        "queries_per_minute_at_20hz": len(asked) / minutes,
        "longest_flood": longest_run(asked),
        "answers_plus_one": toward[1],
        "answers_minus_one": toward[-1],
        "episodes": len(episodes),
        "successes_in_last_10": sum(1 for e in last if e["outcome"] == "success"),
        "cumulative_return": episodes[-1]["cumulative_return"] if episodes else 0.0,
        "pacing": session.get("latest", {}).get("pacing"),
        "wall_seconds": round(wall, 1),
    }
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    (args.out / "asked_steps.json").write_text(json.dumps(asked) + "\n")
    print(json.dumps(summary))
    if not math.isfinite(summary["queries_per_minute_at_20hz"]):
        raise SystemExit("no steps")


if __name__ == "__main__":
    main()
