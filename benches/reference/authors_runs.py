"""Decodes every run of the authors' published result files (their tensorboard tfevents, in the
history of `corgiTrax/stable-baselines3`), groups the runs into launch batches, marks the runs
their Figure 3 was drawn from, and compares the plotted runs with all runs of the same batches.

    python3 benches/reference/authors_runs.py --repo /path/to/stable-baselines3 \
        --out docs/results/authors-runs

`--repo` is a clone of the authors' repository or a bare git directory of it (nothing in it is
written). Nothing needs installing: the tfevents reader (TFRecord framing plus the few protobuf
fields of Event / Summary / TensorProto that scalars use) is below. Run time: about a minute on one
core (it reads about 500 MB of event files through one `git cat-file --batch`).

What it does:

1. Reads `git log --all` and collects every `events.out.tfevents.<unix time>.<host>.<pid>.<n>`
   file that any commit added or changed. One file name is one training process (a run); the
   same run was often copied into several result folders and committed several times while it
   grew, so the largest stored version of each name is decoded. Versions missing from the
   repository (files of 4 MiB and more may be absent from a snapshot) are listed.
2. For every run: paths, the commits that added it, host and launch time (from the file name),
   its scalar tags, steps covered, and at the task's horizon (Lunar Lander 150k steps, Reaching
   and Placing 100k):
   - `plotted_cum`: the value the authors' `accumulate_tensorboard.py`
     (`average_from_per_episode_rewards`) writes to the CSV their notebook plots: it recovers
     each block of 4 episodes from the logged 100-episode mean (`rollout/ep_rew_mean`, logged
     every 4 episodes), `b_n = v_n * len(buf) * scale - sum(buf)` with a 25-block buffer, and
     sums the blocks before the last logged step (scale 1; Reaching 0.1 on its reward-100 runs, 1
     on its reward-10 runs, so that Reaching values are always in units of reward 100 per
     success). This is the scale of the published values in algorithms.md section 2 (true sum /
     4, Reaching / 40); the notebook's `create_combined_data` multiplies it by 4 before drawing;
   - `sum_ep_rew_mean`: the plain sum of the logged 100-episode means (a smoothed variant);
   - `true_cum`: the sum of all finished episodes' returns, 4 x the sum of the recovered blocks;
   - `feedback_pct`: `train/feedback_percentage` (feedback given / steps) at the horizon;
   - `final_mean100`: the last logged 100-episode mean before the horizon;
   - `alpha0`: the oracle's starting alpha, `train/q_value_threshold - 1e-8 * step`.
3. Labels each run with a task (result folder; else the sign of the early returns, the expert
   critic's scale and the launch date), a method (DREF = `ActiveTamerRLSACOptim*`, EF-p% =
   `TamerRLSACOptim` with p its measured feedback rate, SAC, BC) and a batch: runs of one task and
   method whose launches follow each other by at most 10 minutes, under the same config commit
   (the latest commit of the method's pipeline, config, learner and expert files before the
   launch). Runs whose logs are identical (the same seed on the same code) are marked
   duplicates and counted once in the all-runs statistics.
4. Parses the notebooks `corl_graphs.ipynb` / `corl_graphs_2.ipynb` (every version) for the CSV
   files of each curve; the paper's curves are the cells titled as Figure 3's panels in the
   latest version at the repository root; EF at DREF's rate (not in the figure) is the
   `all_runs/Tamer<rate>/` folder's CSVs. Matches each CSV to the run(s) it was computed from (its
   step column is the run's `rollout/ep_rew_mean` step sequence, its values the rule above; some
   CSVs concatenate two event files of one folder); marks those runs plotted.
5. Writes `runs.csv`, `batches.csv`, `summary.csv`, `plotted_check.csv` and `summary.md` (tables:
   plotted vs all-runs means with standard errors, ratios, DREF's feedback, the constants each
   plotted batch ran with, read from the code at its config commit, and failure modes).
"""

from __future__ import annotations

import argparse
import ast
import csv
import io
import json
import math
import os
import re
import statistics
import struct
import subprocess
import sys
import time
import zipfile
from collections import Counter, defaultdict
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Iterable, Iterator

TASKS = ("lunar-lander", "reaching", "placing")
HORIZON = {"lunar-lander": 150_000, "reaching": 100_000, "placing": 100_000}
# accumulate_tensorboard.py's factor in `curr_rewards = i.value * len(rewards_buffer) * scale`
# for the CSVs the final notebook reads (checked below against every plotted CSV).
CSV_SCALE = {"lunar-lander": 1.0, "reaching": 0.1, "placing": 1.0}
FIGURE_TITLES = {"Lunar-Lander": "lunar-lander", "Reaching-Sim": "reaching", "Placing-Sim": "placing"}
RESULT_ROOTS = {"lunar_lander_results_all": "lunar-lander", "reaching_task_results_all": "reaching",
                "ballbasket_task_results_all": "placing"}
# algorithms.md section 2, "What the published runs show" (CSV scale, means of the plotted runs).
PUBLISHED = {
    "lunar-lander": {"DREF": 34.1e3, "EF-100": 29.1e3, "EF-50": 24.2e3, "EF-25": 18.7e3, "SAC": 17.6e3,
                     "EF-rate": -6.0e3, "fb": 6.3},
    "reaching": {"DREF": 11.4e3, "EF-100": 11.4e3, "EF-50": 10.4e3, "EF-25": 9.6e3, "SAC": 6.2e3,
                 "EF-rate": 10.2e3, "fb": 1.6},
    "placing": {"DREF": 43.3e3, "EF-100": 43.6e3, "EF-50": 23.4e3, "EF-25": 23.7e3, "SAC": 16.4e3,
                "EF-rate": 10.1e3, "fb": 8.4},
}
METHOD_ORDER = ("DREF", "EF-100", "EF-50", "EF-25", "EF-rate", "SAC", "BC")
EF_LEVELS = (100.0, 50.0, 30.0, 25.0, 20.0, 10.0, 8.4, 6.2, 5.0, 2.5, 2.0, 1.6, 1.0)
BATCH_GAP_S = 10 * 60  # default of --gap-minutes
NEIGHBOUR_S = 30 * 60  # a run without result folder or expert critic takes its neighbours' task
ROBOT_HOSTS = {"goddard-ws", "brainiac-ws"}

# Files whose latest commit before a launch is that batch's config commit, per task and method.
COMMON_FILES = ["stable_baselines3/common/buffers.py", "stable_baselines3/common/off_policy_algorithm.py",
                "stable_baselines3/sac/sac.py", "stable_baselines3/sac/policies.py"]
METHOD_FILES: dict[tuple[str, str], list[str]] = {
    ("lunar-lander", "DREF"): ["lunar_lander_pipeline_optim_active_tamer_rl.py",
                               "configs/lunar_lander/active_tamer_rl_sac.yaml",
                               "stable_baselines3/active_tamer/active_tamerRL_sac_optim.py",
                               "stable_baselines3/active_tamer/policies.py"],
    ("lunar-lander", "EF"): ["lunar_lander_pipeline_optim_tamer_rl.py", "configs/lunar_lander/tamer_rl_sac.yaml",
                             "stable_baselines3/active_tamer/tamerRL_sac_optim.py",
                             "stable_baselines3/active_tamer/policies.py"],
    ("lunar-lander", "SAC"): ["lunar_lander_pipeline_sac.py", "configs/lunar_lander/sac.yaml"],
    ("lunar-lander", "BC"): ["lunar_lander_pipeline_bc_tamer.py"],
    ("reaching", "DREF"): ["robosuite_pipeline_optim_active_tamer_rl.py", "configs/robosuite/active_tamer_rl_sac.yaml",
                           "stable_baselines3/active_tamer/active_tamerRL_sac_optim.py",
                           "stable_baselines3/active_tamer/policies.py"],
    ("reaching", "EF"): ["robosuite_pipeline_optim_tamer_rl.py", "configs/robosuite/tamer_rl_sac.yaml",
                         "stable_baselines3/active_tamer/tamerRL_sac_optim.py",
                         "stable_baselines3/active_tamer/policies.py"],
    ("reaching", "SAC"): ["robosuite_pipeline_sac_reaching.py|robosuite_pipeline_sac.py", "configs/robosuite/sac.yaml"],
    ("reaching", "BC"): ["robosuite_pipeline_bc_tamer.py", "configs/robosuite/tamer_sac_bc.yaml"],
    ("placing", "DREF"): ["robosuite_pipeline_optim_active_tamer_rl_ballbasket.py",
                          "configs/robosuite_ballbasket/active_tamer_rl_sac.yaml",
                          "stable_baselines3/active_tamer/active_tamerRL_sac_optim.py",
                          "stable_baselines3/active_tamer/policies.py"],
    ("placing", "EF"): ["robosuite_pipeline_optim_tamer_rl_ballbasket.py",
                        "configs/robosuite_ballbasket/tamer_rl_sac.yaml",
                        "stable_baselines3/active_tamer/tamerRL_sac_optim.py",
                        "stable_baselines3/active_tamer/policies.py"],
    ("placing", "SAC"): ["robosuite_pipeline_sac_ballbasket.py", "configs/robosuite_ballbasket/sac.yaml"],
    ("placing", "BC"): ["robosuite_pipeline_bc_tamer_ballbasket.py", "configs/robosuite_ballbasket/tamer_sac_bc.yaml"],
}
EXPERT_FILES = {"lunar-lander": "trained-models/LunarLanderContinuous-v2.zip",
                "reaching": "trained-models/RobosuiteReachingNew.zip", "placing": "trained-models/BallReaching.pt"}


# ----------------------------------------------------------------------------------- git access

class Git:
    """Read-only access to a clone or bare git directory (no lazy fetches of absent objects)."""

    def __init__(self, repo: Path) -> None:
        self.env = dict(os.environ, GIT_NO_LAZY_FETCH="1", GIT_TERMINAL_PROMPT="0", LC_ALL="C")
        out = subprocess.run(["git", "-C", str(repo), "rev-parse", "--absolute-git-dir"], capture_output=True,
                             text=True, env=self.env)
        if out.returncode != 0:
            sys.exit(f"not a git repository: {repo}: {out.stderr.strip()}")
        self.git_dir = out.stdout.strip()

    def run(self, *args: str) -> str:
        out = subprocess.run(["git", "--git-dir", self.git_dir, *args], capture_output=True, env=self.env)
        if out.returncode != 0:
            raise RuntimeError(f"git {' '.join(args)}: {out.stderr.decode(errors='replace').strip()}")
        return out.stdout.decode("utf-8", errors="replace")

    def sizes(self, oids: Iterable[str]) -> dict[str, int]:
        """Object sizes; -1 where the object is not in the repository."""
        oids = list(oids)
        out = subprocess.run(["git", "--git-dir", self.git_dir, "cat-file", "--batch-check"],
                             input="\n".join(oids) + "\n", capture_output=True, text=True, env=self.env)
        sizes: dict[str, int] = {}
        for line in out.stdout.splitlines():
            parts = line.split()
            sizes[parts[0]] = int(parts[2]) if len(parts) == 3 and parts[1] != "missing" else -1
        return sizes

    def blobs(self, oids: list[str]) -> Iterator[tuple[str, bytes]]:
        """Contents of present blobs, streamed through one `git cat-file --batch`."""
        proc = subprocess.Popen(["git", "--git-dir", self.git_dir, "cat-file", "--batch"], stdin=subprocess.PIPE,
                                stdout=subprocess.PIPE, env=self.env)
        assert proc.stdin is not None and proc.stdout is not None
        try:
            for oid in oids:
                proc.stdin.write((oid + "\n").encode())
                proc.stdin.flush()
                header = proc.stdout.readline().split()
                if len(header) != 3:
                    continue
                data = proc.stdout.read(int(header[2]))
                proc.stdout.read(1)
                yield oid, data
        finally:
            proc.stdin.close()
            proc.wait()

    def file_at(self, commit: str, path: str) -> bytes | None:
        out = subprocess.run(["git", "--git-dir", self.git_dir, "cat-file", "blob", f"{commit}:{path}"],
                             capture_output=True, env=self.env)
        return out.stdout if out.returncode == 0 else None

    def text_at(self, commit: str, path: str) -> str | None:
        data = self.file_at(commit, path)
        return None if data is None else data.decode("utf-8", errors="replace")


@dataclass
class Commit:
    sha: str
    ctime: int
    subject: str
    changes: list[tuple[str, str, str, str]]  # (status, old blob, new blob, path)


def read_history(git: Git) -> list[Commit]:
    text = git.run("log", "--all", "--no-renames", "--raw", "--no-abbrev", "--format=%x00%H %ct %s")
    commits: list[Commit] = []
    for chunk in text.split("\x00")[1:]:
        lines = chunk.split("\n")
        sha, ctime, subject = (lines[0].split(" ", 2) + [""])[:3]
        changes = []
        for line in lines[1:]:
            if not line.startswith(":"):
                continue
            meta, path = line.split("\t", 1)
            fields = meta.split()
            changes.append((fields[4], fields[2], fields[3], path))
        commits.append(Commit(sha, int(ctime), subject, changes))
    commits.sort(key=lambda c: c.ctime)
    return commits


# ------------------------------------------------------------------------------ tfevents reader

def _varint(b: bytes, i: int) -> tuple[int, int]:
    result = shift = 0
    while True:
        c = b[i]
        i += 1
        result |= (c & 0x7F) << shift
        if c < 0x80:
            return result, i
        shift += 7


def _skip(b: bytes, i: int, wire: int) -> int:
    if wire == 0:
        return _varint(b, i)[1]
    if wire == 1:
        return i + 8
    if wire == 5:
        return i + 4
    if wire == 2:
        n, i = _varint(b, i)
        return i + n
    raise ValueError(f"protobuf wire type {wire}")


def _tensor_scalar(b: bytes) -> float | None:
    """A scalar TensorProto (TF2 summaries): dtype 1, float_val 5 / double_val 6 / tensor_content 4."""
    i, dtype, content, value = 0, 0, b"", None
    while i < len(b):
        key, i = _varint(b, i)
        num, wire = key >> 3, key & 7
        if num == 1 and wire == 0:
            dtype, i = _varint(b, i)
        elif num == 4 and wire == 2:
            n, i = _varint(b, i)
            content, i = b[i:i + n], i + n
        elif num == 5 and wire in (2, 5):
            if wire == 2:
                n, i = _varint(b, i)
            value = struct.unpack_from("<f", b, i)[0]
            i += 4 if wire == 5 else n
        elif num == 6 and wire == 2:
            n, i = _varint(b, i)
            value = struct.unpack_from("<d", b, i)[0]
            i += n
        else:
            i = _skip(b, i, wire)
    if value is None and content:
        if dtype == 1 and len(content) >= 4:
            value = struct.unpack_from("<f", content)[0]
        elif dtype == 2 and len(content) >= 8:
            value = struct.unpack_from("<d", content)[0]
    return value


def read_scalars(data: bytes) -> tuple[dict[str, list[tuple[int, float]]], int, bool]:
    """All scalar values of one tfevents file as {tag: [(step, value)]}, the record count, and
    whether the file ends in a partial record. TFRecord framing: u64 length, u32 crc, payload,
    u32 crc (the crcs are not checked). Event: 1 wall_time, 2 step, 5 summary; Summary: 1 value;
    Value: 1 tag, 2 simple_value, 8 tensor."""
    out: dict[bytes, list[tuple[int, float]]] = {}
    i, n, records = 0, len(data), 0
    while i + 12 <= n:
        (length,) = struct.unpack_from("<Q", data, i)
        j, end = i + 12, i + 12 + length
        if end + 4 > n:
            return {t.decode(): v for t, v in out.items()}, records, True
        records += 1
        step = 0
        values: list[tuple[bytes, float]] = []
        while j < end:
            key = data[j]
            j += 1
            if key == 0x10:
                step, j = _varint(data, j)
            elif key == 0x2A:
                m, j = _varint(data, j)
                summary_end = j + m
                while j < summary_end:
                    k2 = data[j]
                    j += 1
                    if k2 != 0x0A:
                        j = _skip(data, j, k2 & 7)
                        continue
                    m2, j = _varint(data, j)
                    value_end = j + m2
                    tag, val = b"", None
                    while j < value_end:
                        k3 = data[j]
                        j += 1
                        if k3 == 0x0A:
                            m3, j = _varint(data, j)
                            tag, j = data[j:j + m3], j + m3
                        elif k3 == 0x15:
                            val = struct.unpack_from("<f", data, j)[0]
                            j += 4
                        elif k3 == 0x42:
                            m3, j = _varint(data, j)
                            val, j = _tensor_scalar(data[j:j + m3]), j + m3
                        else:
                            j = _skip(data, j, k3 & 7)
                    if val is not None:
                        values.append((tag, val))
            else:
                j = _skip(data, j, key & 7)
        for tag, val in values:
            out.setdefault(tag, []).append((step, val))
        i = end + 4
    return {t.decode(): v for t, v in out.items()}, records, False


# ---------------------------------------------------------------------------- the authors' rules

def block_sums(series: list[tuple[int, float]], horizon: int, scale: float) -> list[tuple[int, float, float]]:
    """accumulate_tensorboard.py's average_from_per_episode_rewards: for each logged 100-episode
    mean v_n (steps < horizon) the recovered block b_n = v_n * len(buf) * scale - sum(buf), buf
    the last <= 25 blocks (starting as [0]). Returns (step, CSV value = sum of the blocks before
    this one, b_n)."""
    buf: list[float] = [0.0]
    total = 0.0
    rows = []
    for step, value in series:
        if step >= horizon:
            break
        cur = value * len(buf) * scale
        if len(buf) == 25:
            buf.pop(0)
        cur -= sum(buf)
        rows.append((step, total, cur))
        total += cur
        buf.append(cur)
    return rows


def at_horizon(series: list[tuple[int, float]] | None, horizon: int) -> float | None:
    last = None
    for step, value in series or []:
        if step > horizon:
            break
        last = value
    return last


# ------------------------------------------------------------------------------------- the runs

EVENT_NAME = re.compile(r"^events\.out\.tfevents\.(\d+)\.(.+)\.(\d+)\.(\d+)(\.v2)?$")


@dataclass
class Run:
    name: str
    launch: int
    host: str
    derived: bool  # a TF2 `.v2` file written by the authors' averaging scripts, not a training run
    paths: set[str] = field(default_factory=set)
    versions: dict[str, int] = field(default_factory=dict)  # blob -> size (-1 absent)
    added_in: list[str] = field(default_factory=list)
    touched_in: list[str] = field(default_factory=list)
    tags: dict[str, list[tuple[int, float]]] = field(default_factory=dict)
    records: int = 0
    truncated_file: bool = False
    decoded_blob: str = ""
    task: str = ""
    task_from: str = ""
    algo: str = ""
    method: str = ""
    batch: str = ""
    plotted: list[str] = field(default_factory=list)
    metrics: dict[str, Any] = field(default_factory=dict)
    duplicate_of: str = ""  # an earlier run with identical logs (same seed, same code)

    @property
    def short_host(self) -> str:
        return self.host.split(".")[0]

    @property
    def launch_utc(self) -> str:
        return datetime.fromtimestamp(self.launch, timezone.utc).strftime("%Y-%m-%d %H:%M:%S")

    def primary_path(self) -> str:
        def rank(p: str) -> tuple[int, str]:
            q = strip_root(p)
            return (0 if "/all_runs/" in q else 1 if q.startswith("log_dir/") else 2, p)
        return sorted(self.paths, key=rank)[0]


def strip_root(path: str) -> str:
    return path[len("DREF_project_results/"):] if path.startswith("DREF_project_results/") else path


def collect_runs(commits: list[Commit]) -> dict[str, Run]:
    runs: dict[str, Run] = {}
    for commit in commits:
        for status, _old, new, path in commit.changes:
            base = path.rsplit("/", 1)[-1]
            m = EVENT_NAME.match(base)
            if not m:
                continue
            run = runs.get(base)
            if run is None:
                run = runs[base] = Run(base, int(m.group(1)), m.group(2), bool(m.group(5)))
            run.paths.add(path)
            if status != "D" and set(new) != {"0"}:
                run.versions.setdefault(new, 0)
                if commit.sha not in run.touched_in:
                    run.touched_in.append(commit.sha)
                if status == "A" and commit.sha not in run.added_in:
                    run.added_in.append(commit.sha)
    return runs


def decode_runs(git: Git, runs: dict[str, Run]) -> None:
    sizes = git.sizes({b for r in runs.values() for b in r.versions})
    wanted: dict[str, Run] = {}
    for run in runs.values():
        for blob in run.versions:
            run.versions[blob] = sizes.get(blob, -1)
        present = [b for b, s in run.versions.items() if s >= 0]
        if present:
            run.decoded_blob = max(present, key=lambda b: run.versions[b])
            wanted[run.decoded_blob] = run
    for blob, data in git.blobs(sorted(wanted, key=lambda b: wanted[b].name)):
        run = wanted[blob]
        run.tags, run.records, run.truncated_file = read_scalars(data)


# --------------------------------------------------------------------------------- labelling

def algo_of(run: Run) -> str:
    for path in sorted(run.paths, key=lambda p: (not strip_root(p).startswith("log_dir/"), p)):
        parts = strip_root(path).split("/")
        if len(parts) >= 2:
            parent = parts[-2]
            if parent in ("averaged", "averaged_results", "FINAL") and len(parts) >= 3:
                parent = parts[-3]
            return re.sub(r"_\d+$", "", parent)
    return ""


def ef_level(pct: float | None) -> str:
    if pct is None:
        return "EF-?"
    best = min(EF_LEVELS, key=lambda level: abs(level - pct) / level)
    return f"EF-{best:g}" if abs(best - pct) / best < 0.2 else f"EF-{pct:.1f}"


def label_runs(runs: dict[str, Run]) -> None:
    for run in runs.values():
        run.algo = algo_of(run)
        paths = [strip_root(p) for p in run.paths]
        er = run.tags.get("rollout/ep_rew_mean", [])
        tq = [v for _, v in run.tags.get("train/teacher_q_value", [])[:200]]
        robot = (run.short_host in ROBOT_HOSTS or any(re.search(r"robot|sawyer|Sawyer|realrobot", p) for p in paths))
        from_dir = {task for p in paths for root, task in RESULT_ROOTS.items() if p.startswith(root)}
        from_dir |= {"lunar-lander" for p in paths if p.startswith(("lunar_lander", "final_results", "old_final"))}
        from_dir |= {"reaching" for p in paths if p.startswith(("reaching", "tamer_results_reaching"))}
        from_dir |= {"placing" for p in paths if p.startswith("ballbasket")}
        negative = bool(er) and min(v for _, v in er) < -20
        if run.derived:
            run.task, run.task_from = "derived", "TF2 .v2 file written by the authors' averaging scripts"
        elif robot:
            run.task, run.task_from = "real-robot", "host or folder"
        elif len(from_dir) == 1 and (negative == (from_dir == {"lunar-lander"}) or not er):
            run.task, run.task_from = from_dir.pop(), "result folder"
        elif negative:
            run.task, run.task_from = "lunar-lander", "returns below -20"
        elif not er:
            run.task, run.task_from = "unknown", "no rollout/ep_rew_mean"
        elif tq and statistics.median(tq) > 30:
            run.task, run.task_from = "placing", "expert Q ~ 50-100 (BallReaching expert)"
        elif tq and statistics.median(tq) < 20:
            run.task, run.task_from = "reaching", "expert Q ~ 10 (Reaching expert)"
        elif run.launch < 1652659200:  # 2022-05-16: robosuite work starts ("Emptying for robosuite results")
            run.task, run.task_from = "lunar-lander", "launched before the robosuite work"
        elif run.launch < 1654391760:  # 2022-06-05 01:16 UTC: "Ball basket training" (db59408)
            run.task, run.task_from = "reaching", "robosuite run before the Placing task existed"
        else:
            run.task, run.task_from = "robosuite?", "Reaching or Placing (no result folder, no expert Q)"
        algo = run.algo
        fb = at_horizon(run.tags.get("train/feedback_percentage"), 10**9)
        if "Record" in algo or "Stop" in algo:
            run.method = "human/record"
        elif algo.startswith(("ActiveTamer", "RPEActiveTamer", "UCBActiveTamer", "StateReconstructionActive",
                              "SceneGraphChange")):
            run.method = "DREF"
        elif algo.startswith(("TamerRLSACOptim", "TamerRL", "Tamer")) and "BC" not in algo:
            run.method = ef_level(None if fb is None else 100 * fb)
        elif algo == "TamerSACBC" or algo.startswith(("BehaviorCloning", "BC")):
            run.method = "BC"
        elif algo == "SAC":
            run.method = "SAC"
        else:
            run.method = f"other:{algo}"


def resolve_unknown_robosuite(runs: dict[str, Run]) -> None:
    """A Reaching/Placing run without result folder or expert critic takes the task of the runs of
    its method launched within 30 minutes of it, if those agree."""
    known = [r for r in runs.values() if r.task in ("reaching", "placing")]
    for run in runs.values():
        if run.task != "robosuite?":
            continue
        near = {r.task for r in known if r.method == run.method and abs(r.launch - run.launch) <= NEIGHBOUR_S}
        if len(near) == 1:
            run.task, run.task_from = near.pop(), "a same-method run launched within 30 min"


# ----------------------------------------------------------------------------- per-run metrics

def compute_metrics(run: Run) -> None:
    m: dict[str, Any] = {}
    er = run.tags.get("rollout/ep_rew_mean", [])
    all_steps = [s for series in run.tags.values() for s, _ in series]
    m["last_step"] = max(all_steps) if all_steps else 0
    m["logs"] = len(er)
    if run.task in HORIZON:
        horizon = HORIZON[run.task]
        # Reaching ran with reward_scale 10 until 2022-06-09 (0a94b0d), then 100 (a success pays the
        # scale); the authors' CSVs use factor 1 on the first and 0.1 on the second. Reaching values
        # here are in units of reward 100 per success, whichever scale the run had.
        m["reward_unit"] = reward_unit(run.task, er)
        norm = 100.0 / m["reward_unit"] if run.task == "reaching" else 1.0
        rows = block_sums(er, horizon, CSV_SCALE[run.task] * norm)
        unit = block_sums(er, horizon + 1, norm)
        m["horizon"] = horizon
        m["complete"] = bool(er) and er[-1][0] >= 0.95 * horizon
        m["plotted_cum"] = rows[-1][1] if rows else None
        m["sum_ep_rew_mean"] = sum(v * norm for s, v in er if s < horizon) if er else None
        m["true_cum"] = 4 * sum(b for _, _, b in unit) if unit else None
        fb = at_horizon(run.tags.get("train/feedback_percentage"), horizon)
        m["feedback_pct"] = None if fb is None else 100 * fb
        m["final_mean100"] = at_horizon(er, horizon)
        lens = [v for s, v in run.tags.get("rollout/ep_len_mean", []) if s <= horizon]
        m["final_len100"] = lens[-1] if lens else None
        m["min_len100"] = min(lens) if lens else None
        q = run.tags.get("train/q_value_threshold", [])
        alphas = [v - 1e-8 * s for s, v in q[:20]]
        m["alpha0"] = statistics.median(alphas) if alphas else None
        m["flags"] = failure_flags(run.task, run.method, m)
    run.metrics = m


def reward_unit(task: str, er: list[tuple[int, float]]) -> float:
    """Reward of one Reaching success in this run (its reward_scale): 10 or 100."""
    if task == "placing":
        return 100.0  # reward_scale=100 in every Placing pipeline
    if task != "reaching" or not er:
        return 1.0
    top = max(v for _, v in er)
    return 10.0 if 0 < top <= 10.0001 else 100.0


def failure_flags(task: str, method: str, m: dict[str, Any]) -> list[str]:
    flags = []
    fb, final, length = m.get("feedback_pct"), m.get("final_mean100"), m.get("final_len100")
    if not m.get("complete"):
        flags.append("incomplete")
    if method == "DREF" and fb is not None:
        if fb >= 90:
            flags.append("asks every step")
        elif task == "lunar-lander" and fb < 3.5:
            flags.append("asks <3.5%")
    if task == "placing" and length is not None and length <= 12 and (final or 0) <= 5:
        flags.append("~9-step episodes, ~0 reward")
    if task == "lunar-lander" and final is not None and final < 0:
        flags.append("final 100-ep mean < 0")
    if task in ("reaching", "placing") and final is not None and final < 0.2 * m.get("reward_unit", 100.0):
        flags.append("final 100-ep mean < 20% of a success")
    return flags


def mark_duplicates(runs: dict[str, Run]) -> None:
    """Runs of one task and method whose first 60 logged 100-episode means (steps and values)
    are identical: the authors' seeds were fixed in the config unless `--seed` was passed, and a
    seed on the same code and machine type repeats its run exactly."""
    first_seen: dict[tuple[Any, ...], Run] = {}
    for run in sorted(runs.values(), key=lambda r: (r.launch, r.name)):
        er = run.tags.get("rollout/ep_rew_mean", [])
        if run.derived or len(er) < 20:
            continue
        key = (run.task, run.method, tuple((s, round(v, 4)) for s, v in er[:60]))
        if key in first_seen:
            run.duplicate_of = first_seen[key].name
            run.metrics.setdefault("flags", []).append("duplicate of " + first_seen[key].name[20:])
        else:
            first_seen[key] = run


def distinct(runs: list[Run]) -> list[Run]:
    """One run of each group of identical runs (see mark_duplicates), in the given order."""
    seen: set[str] = set()
    kept = []
    for run in runs:
        key = run.duplicate_of or run.name
        if key not in seen:
            seen.add(key)
            kept.append(run)
    return kept


# ----------------------------------------------------------------------------------- batching

class ConfigHistory:
    """Commits touching each (task, method) file set, for the commit in force at a launch."""

    def __init__(self, commits: list[Commit]) -> None:
        self.commits = commits
        self.cache: dict[tuple[str, str], list[Commit]] = {}

    def files(self, task: str, family: str) -> list[str]:
        listed = [alt for entry in METHOD_FILES.get((task, family), []) for alt in entry.split("|")]
        return listed + COMMON_FILES + [EXPERT_FILES[task]]

    def touching(self, task: str, family: str) -> list[Commit]:
        key = (task, family)
        if key not in self.cache:
            files = set(self.files(task, family))
            self.cache[key] = [c for c in self.commits if any(p in files for _, _, _, p in c.changes)]
        return self.cache[key]

    def around(self, task: str, family: str, t: int) -> tuple[Commit | None, Commit | None]:
        before = after = None
        for c in self.touching(task, family):
            if c.ctime <= t:
                before = c
            elif after is None:
                after = c
        return before, after


def family(method: str) -> str:
    return "EF" if method.startswith("EF") else method


@dataclass
class Batch:
    bid: str
    task: str
    method: str
    algo: str
    runs: list[Run]
    commit: Commit | None
    next_commit: Commit | None


def make_batches(runs: dict[str, Run], history: ConfigHistory, gap: int = BATCH_GAP_S) -> list[Batch]:
    groups: dict[tuple[str, str, str], list[Run]] = defaultdict(list)
    for run in runs.values():
        if run.task in HORIZON and run.method in ("DREF", "SAC", "BC") or run.task in HORIZON and run.method.startswith("EF-"):
            groups[(run.task, run.method, run.algo)].append(run)
    batches: list[Batch] = []
    for (task, method, algo), members in groups.items():
        members.sort(key=lambda r: r.launch)
        current: list[Run] = []
        current_commit: Commit | None = None
        for run in members:
            commit, _ = history.around(task, family(method), run.launch)
            if current and (run.launch - current[-1].launch > gap or commit is not current_commit):
                batches.append(Batch("", task, method, algo, current, current_commit, None))
                current = []
            if not current:
                current_commit = commit
            current.append(run)
        if current:
            batches.append(Batch("", task, method, algo, current, current_commit, None))
    batches.sort(key=lambda b: (TASKS.index(b.task), method_rank(b.method), b.runs[0].launch))
    counters: Counter[tuple[str, str]] = Counter()
    short = {"lunar-lander": "LL", "reaching": "R", "placing": "P"}
    for batch in batches:
        counters[(batch.task, batch.method)] += 1
        first = datetime.fromtimestamp(batch.runs[0].launch, timezone.utc).strftime("%m%d-%H%M")
        batch.bid = f"{short[batch.task]}-{batch.method}-{first}"
        _, batch.next_commit = history.around(batch.task, family(batch.method), batch.runs[0].launch)
        for run in batch.runs:
            run.batch = batch.bid
    return batches


def method_rank(method: str) -> tuple[int, float]:
    if method == "DREF":
        return (0, 0.0)
    if method.startswith("EF-"):
        try:
            return (1, -float(method[3:]))
        except ValueError:
            return (1, 0.0)
    return (2 if method == "SAC" else 3, 0.0)


# ---------------------------------------------------------------------------- notebooks, CSVs

@dataclass
class Curve:
    task: str
    label: str  # as in the notebook, e.g. "DREF-8.4%"
    method: str  # DREF, EF-100, ..., SAC
    kind: str  # "paper" (a Figure 3 cell of the final notebook) or "folder" (EF at DREF's rate)
    notebook: str
    commit: str
    cell: int
    csvs: list[str]
    at_root: bool = True  # the notebook sits at the repository root, where its CSV paths point


def notebook_curves(git: Git, commits: list[Commit]) -> tuple[list[Curve], str]:
    names = ("corl_graphs.ipynb", "corl_graphs_2.ipynb")
    versions = [(c, p) for c in commits for _, _, new, p in c.changes
                if p.rsplit("/", 1)[-1] in names and set(new) != {"0"}]
    found: list[Curve] = []
    for commit, path in versions:
        text = git.text_at(commit.sha, path)
        if not text:
            continue
        try:
            cells = json.loads(text)["cells"]
        except (ValueError, KeyError):
            continue
        for index, cell in enumerate(cells):
            if cell.get("cell_type") != "code":
                continue
            source = "".join(cell.get("source", []))
            source = "\n".join(line for line in source.splitlines() if not line.lstrip().startswith(("%", "!")))
            try:
                tree = ast.parse(source)
            except SyntaxError:
                continue
            title = None
            for node in ast.walk(tree):
                if (isinstance(node, ast.Call) and getattr(node.func, "attr", "") == "set_title" and node.args
                        and isinstance(node.args[0], ast.Constant)):
                    title = node.args[0].value
            for node in tree.body:
                if not (isinstance(node, ast.Assign) and any(getattr(t, "id", "") == "experiments" for t in node.targets)):
                    continue
                try:
                    experiments = ast.literal_eval(node.value)
                except ValueError:
                    continue
                by_cat: dict[str, list[str]] = defaultdict(list)
                for exp in experiments:
                    if (isinstance(exp, dict) and "csv" in exp and "cat" in exp
                            and not str(exp["csv"]).endswith("_feedback.csv")):
                        by_cat[str(exp["cat"])].append(str(exp["csv"]))
                for label, csvs in by_cat.items():
                    roots = {RESULT_ROOTS.get(c.split("/")[0]) for c in csvs}
                    if len(roots) != 1 or None in roots or not all("/all_runs/" in c for c in csvs):
                        continue
                    task = roots.pop()
                    kind = "paper" if FIGURE_TITLES.get(title or "") == task else "notebook"
                    found.append(Curve(task, label, curve_method(label), kind, path, commit.sha, index, csvs))
                    found[-1].at_root = "/" not in path
    if not found:
        return [], ""
    # The paper's curves: the Figure 3 cells (titled as the paper's panels) of the latest version.
    final_commit = max((c for c in found if c.kind == "paper"),
                       key=lambda c: (c.at_root, commit_time(commits, c.commit))).commit
    paper = [c for c in found if c.kind == "paper" and c.commit == final_commit]
    curves = list(paper)
    # EF at DREF's measured rate is not in the paper's figure: its runs are the CSVs of the
    # `all_runs/Tamer<rate>/` folder at the same commit (some notebook versions plot 3 or 5 of
    # them, or only their feedback curves).
    tree = git.run("ls-tree", "-r", "--name-only", final_commit).splitlines()
    roots = {task: root for root, task in RESULT_ROOTS.items()}
    for task in TASKS:
        dref = [c for c in paper if c.task == task and c.method == "DREF"]
        rate = re.search(r"([\d.]+)%", dref[0].label).group(1) if dref else None
        folder = f"{roots[task]}/all_runs/Tamer{rate}/"
        csvs = sorted((p for p in tree if p.startswith(folder) and re.search(r"_\d+\.csv$", p)),
                      key=lambda p: int(re.search(r"_(\d+)\.csv$", p).group(1)))
        if rate and csvs:
            curves.append(Curve(task, f"EF-{rate}%", "EF-rate", "folder", folder, final_commit, -1, csvs))
    return curves, final_commit


def curve_method(label: str) -> str:
    label = label.replace(" ", "")
    if label.startswith("DREF"):
        return "DREF"
    m = re.match(r"EF-([\d.]+)%", label)
    if m:
        return f"EF-{float(m.group(1)):g}"
    return label


def commit_time(commits: list[Commit], sha: str) -> int:
    for c in commits:
        if c.sha == sha:
            return c.ctime
    return 0


def read_csv_rows(data: bytes) -> list[tuple[int, float]]:
    rows = []
    for row in list(csv.reader(io.StringIO(data.decode("utf-8", errors="replace"))))[1:]:
        if len(row) >= 2:
            rows.append((int(float(row[0])), float(row[1])))
    return rows


@dataclass
class CsvMatch:
    csv_path: str
    rows: int
    final: float | None
    runs: list[str]  # event files whose logs make up the CSV, longest segment first
    how: str  # exact / prefix / concatenation / none
    scale: float | None


def match_csv(csv_path: str, rows: list[tuple[int, float]], task: str,
              index: dict[tuple[int, ...], list[Run]]) -> CsvMatch:
    """Finds the event file(s) whose `rollout/ep_rew_mean` steps make up the CSV's step column (in
    order; EventAccumulator concatenates the files of one folder) and checks the CSV's values
    against block_sums over their concatenated logs."""
    final = rows[-1][1] if rows else None
    steps = [s for s, _ in rows]
    segments: list[tuple[Run, int]] = []
    i = 0
    folder = csv_path[:-4] + "/"
    while i < len(steps):
        key = tuple(steps[i:i + 2])
        best: tuple[int, int, Run] | None = None
        stubs = [r for r in index.get((steps[i],), []) if any(strip_root(p).startswith(folder) for p in r.paths)]
        for run in index.get(key, []) + stubs:
            rs = [s for s, _ in run.tags["rollout/ep_rew_mean"]]
            k = 0
            while i + k < len(steps) and k < len(rs) and rs[k] == steps[i + k]:
                k += 1
            in_folder = any(strip_root(p).startswith(folder) for p in run.paths)
            if k < 3 and not in_folder:
                continue
            cand = (k, int(in_folder), run)
            if best is None or cand[:2] > best[:2]:
                best = cand
        if best is None or best[0] == 0:
            return CsvMatch(csv_path, len(rows), final, [r.name for r, _ in segments], "none", None)
        segments.append((best[2], best[0]))
        i += best[0]
    series: list[tuple[int, float]] = []
    for run, k in segments:
        series.extend(run.tags["rollout/ep_rew_mean"][:k])
    for scale in (CSV_SCALE[task], 1.0, 4.0, 0.1):
        est = block_sums(series, 10**9, scale)
        if len(est) == len(rows) and all(abs(a[1] - b[1]) <= 1e-3 * max(1.0, abs(b[1])) for a, b in zip(est, rows)):
            break
    else:
        scale = None
    names = [r.name for r, _ in sorted(segments, key=lambda s: -s[1])]
    full = len(segments) == 1 and segments[0][1] == len([s for s, _ in segments[0][0].tags["rollout/ep_rew_mean"]
                                                         if s < HORIZON[task]])
    how = "exact" if full else "prefix" if len(segments) == 1 else "concatenation"
    return CsvMatch(csv_path, len(rows), final, names, how if scale is not None else how + " (values differ)", scale)


# ---------------------------------------------------------------------------- config readings

def class_source(text: str, name: str) -> str:
    m = re.search(rf"^class {re.escape(name)}\b.*?(?=^class |^def |\Z)", text, re.S | re.M)
    return m.group(0) if m else ""


def first(pattern: str, text: str | None, flags: int = 0) -> str:
    if not text:
        return "?"
    m = re.search(pattern, text, flags)
    return m.group(1).strip() if m else "?"


def yaml_value(text: str | None, key: str) -> str:
    if not text:
        return "?"
    values = re.findall(rf"^{re.escape(key)}:\s*([^#\n]+)", text, re.M)
    return values[-1].strip().strip('"') if values else "?"


def expert_action_space(git: Git, commit: str, path: str) -> str:
    data = git.file_at(commit, path)
    if data is None:
        return "absent from this snapshot"
    try:
        meta = json.loads(zipfile.ZipFile(io.BytesIO(data)).read("data"))
        space = meta["action_space"]
        return f"low {space.get('low')} high {space.get('high')}"
    except (KeyError, ValueError, zipfile.BadZipFile):
        return "unreadable"


def read_constants(git: Git, task: str, method: str, commit: Commit | None) -> dict[str, str]:
    """The constants a batch ran with, read from the code at its config commit."""
    if commit is None:
        return {}
    sha = commit.sha
    fam = family(method)
    files = METHOD_FILES.get((task, fam), [])
    out: dict[str, str] = {}
    pipeline = None
    for candidate in (files[0].split("|") if files else []):
        pipeline = pipeline or git.text_at(sha, candidate)
    config = git.text_at(sha, files[1]) if len(files) > 1 else None
    if fam in ("DREF", "EF"):
        learner = git.text_at(sha, files[2]) if len(files) > 2 else None
        out["oracle alpha0 (learner default)"] = first(r"q_val_threshold:\s*float\s*=\s*([0-9.]+)", learner)
        passed = first(r"q_val_threshold\s*=\s*([^,\n)]+)", pipeline)
        if passed != "?":
            out["oracle alpha0 (pipeline)"] = passed
        out["alpha step"] = first(r"self\.q_val_threshold\s*\+=\s*([0-9.eE-]+)", learner)
        out["oracle's critic judges"] = first(
            r"student_q_val\s*=\s*self\.trained_model\.critic\.forward\(\s*th\.from_numpy\([^\n]*\n\s*th\.from_numpy\((\w+)\)",
            learner)
        out["expert"] = yaml_value(config, "trained_model")
        if out["expert"] not in ("?", ""):
            out["expert action space"] = expert_action_space(git, sha, out["expert"])
    if fam == "EF":
        out["percent_feedback (config file; `--feedback` overrides)"] = yaml_value(config, "percent_feedback")
    if fam == "DREF" and pipeline:
        graph_class = first(r"scene_graph\s*=\s*(\w+)\(", pipeline)
        body = class_source(pipeline, graph_class)
        out["scene graph class"] = graph_class
        out["k (rank <=)"] = first(r"getUCBRank\(\)\s*<=\s*([^\n]+)", body)
        out["c"] = first(r"\+\s*([0-9.]+)\s*\*\s*math\.sqrt", body)
        preds = re.findall(r"self\.(\w+)\(self\.agent", first(r"def getCurrGraph.*?(\[.*?\])", body, re.S))
        out["graph bits"] = f"{len(preds)}: " + ", ".join(preds) if preds else "?"
        out["graph reads"] = first(r"self\.agent\['location'\]\s*=\s*(\{[^\n]*\})", body)
        action = first(r"self\.agent\['action'\]\s*=\s*(\{[^\n]*\})", body)
        if action != "?":
            out["engine predicates read"] = action
        for name in ("above", "below"):
            rule = first(rf"def {name}\(self, obj_a\):\s*return ([^\n]+)", body)
            if rule != "?":
                out[f"{name}()"] = rule
        learner = git.text_at(sha, files[2]) if len(files) > 2 else None
        out["graph evaluated on"] = first(r"self\.scene_graph\.updateGraph\((\w+)", learner)
        tail = learner.split("self.scene_graph.updateGraph", 1)[-1] if learner else None
        out["query on"] = first(r"if \(\s*(?:#[^\n]*\n\s*)*(\w+)", tail, re.S)
    if task in ("reaching", "placing") and pipeline:
        out["reward_scale"] = first(r"reward_scale\s*=\s*([0-9.]+)", pipeline)
        out["obs keys"] = first(r"keys\s*=\s*(\[[^\]]*\])", pipeline)
        out["env_name"] = first(r"\"env_name\":\s*\"(\w+)\"", pipeline)
    if task == "lunar-lander" and pipeline:
        out["env"] = first(r"gym\.make\(\"([^\"]+)\"", pipeline)
    out["steps (config)"] = yaml_value(config, "steps")
    return out


# ------------------------------------------------------------------------------------- stats

def mean_se(values: list[float]) -> tuple[float | None, float | None, int]:
    values = [v for v in values if v is not None and not math.isnan(v)]
    if not values:
        return None, None, 0
    mean = sum(values) / len(values)
    se = statistics.stdev(values) / math.sqrt(len(values)) if len(values) > 1 else None
    return mean, se, len(values)


def ratio(a: tuple[float | None, float | None, int], b: tuple[float | None, float | None, int]) -> tuple[float | None, float | None]:
    if a[0] is None or b[0] in (None, 0):
        return None, None
    r = a[0] / b[0]
    if a[1] is None or b[1] is None or a[0] == 0:
        return r, None
    return r, abs(r) * math.sqrt((a[1] / a[0]) ** 2 + (b[1] / b[0]) ** 2)


def fmt(value: float | None, digits: int = 1, kilo: bool = False) -> str:
    if value is None:
        return ""
    if kilo:
        return f"{value / 1000:.{digits}f}k"
    return f"{value:.{digits}f}"


def pm(mean: float | None, se: float | None, digits: int = 1, kilo: bool = False) -> str:
    if mean is None:
        return "-"
    return fmt(mean, digits, kilo) + ("" if se is None else " ± " + fmt(se, digits, kilo))


# ------------------------------------------------------------------------------------- output

def write_outputs(out: Path, git: Git, runs: dict[str, Run], batches: list[Batch], curves: list[Curve],
                  matches: dict[tuple[str, str], list[CsvMatch]], final_nb: str, commits: list[Commit]) -> None:
    out.mkdir(parents=True, exist_ok=True)
    by_batch = {b.bid: b for b in batches}
    short = lambda sha: sha[:7] if sha else ""  # noqa: E731

    # runs.csv: every run (training processes; the derived .v2 files are listed too).
    with (out / "runs.csv").open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["task", "method", "batch", "plotted", "path", "event_file", "host", "launch_utc", "config_commit",
                    "algo_dir", "task_from", "first_added_commit", "commits_with_file", "versions", "versions_absent",
                    "tags", "last_step", "complete", "duplicate_of", "reward_unit", "plotted_cum", "sum_ep_rew_mean",
                    "true_cum", "feedback_pct", "final_mean100", "final_len100", "alpha0", "flags"])
        for run in sorted(runs.values(), key=lambda r: (r.task, r.method, r.launch, r.name)):
            m = run.metrics
            batch = by_batch.get(run.batch)
            w.writerow([run.task, run.method, run.batch, "; ".join(run.plotted) or "no", strip_root(run.primary_path()),
                        run.name, run.short_host, run.launch_utc, short(batch.commit.sha) if batch and batch.commit else "",
                        run.algo, run.task_from, short(run.added_in[0]) if run.added_in else "", len(run.touched_in),
                        len(run.versions), sum(1 for s in run.versions.values() if s < 0),
                        len(run.tags), m.get("last_step", 0), "yes" if m.get("complete") else "no", run.duplicate_of,
                        fmt(m.get("reward_unit"), 0), fmt(m.get("plotted_cum"), 2), fmt(m.get("sum_ep_rew_mean"), 2), fmt(m.get("true_cum"), 1),
                        fmt(m.get("feedback_pct"), 3), fmt(m.get("final_mean100"), 2), fmt(m.get("final_len100"), 1),
                        fmt(m.get("alpha0"), 5), "; ".join(m.get("flags", []))])

    # batches.csv
    with (out / "batches.csv").open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["batch", "task", "method", "algo_dir", "hosts", "first_launch_utc", "last_launch_utc", "runs",
                    "complete_distinct", "plotted", "config_commit", "config_commit_utc", "config_subject", "next_commit",
                    "next_commit_minutes_after_first_launch", "mean_plotted_cum_complete", "mean_feedback_pct",
                    "alpha0_logged"])
        for b in batches:
            complete = distinct([r for r in b.runs if r.metrics.get("complete")])
            alphas = [r.metrics["alpha0"] for r in b.runs if r.metrics.get("alpha0") is not None]
            w.writerow([b.bid, b.task, b.method, b.algo, " ".join(sorted({r.short_host for r in b.runs})),
                        b.runs[0].launch_utc, b.runs[-1].launch_utc, len(b.runs), len(complete),
                        sum(1 for r in b.runs if any(p.startswith("paper") for p in r.plotted)),
                        short(b.commit.sha) if b.commit else "",
                        utc(b.commit.ctime) if b.commit else "", b.commit.subject if b.commit else "",
                        short(b.next_commit.sha) if b.next_commit else "",
                        f"{(b.next_commit.ctime - b.runs[0].launch) / 60:.0f}" if b.next_commit else "",
                        fmt(mean_se([r.metrics.get("plotted_cum") for r in complete])[0], 1),
                        fmt(mean_se([r.metrics.get("feedback_pct") for r in complete])[0], 2),
                        fmt(statistics.median(alphas), 5) if alphas else ""])

    # plotted_check.csv: every plotted CSV, its run(s), the CSV's final value and ours.
    with (out / "plotted_check.csv").open("w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["task", "curve", "kind", "notebook", "notebook_commit", "csv", "csv_rows", "csv_final",
                    "match", "csv_scale", "runs", "run_plotted_cum"])
        for curve in curves:
            for cm in matches[(curve.task, curve.label + "|" + curve.kind)]:
                primary = runs.get(cm.runs[0]) if cm.runs else None
                w.writerow([curve.task, curve.label, curve.kind, curve.notebook, short(curve.commit), cm.csv_path,
                            cm.rows, fmt(cm.final, 2), cm.how, "" if cm.scale is None else f"{cm.scale:g}",
                            " + ".join(cm.runs), fmt(primary.metrics.get("plotted_cum"), 2) if primary else ""])

    # summary.csv and summary.md
    lines: list[str] = []
    lines.append("# The authors' runs decoded: plotted vs all runs of the same batches\n")
    lines.append(f"Generated by `benches/reference/authors_runs.py` from the history of "
                 f"`corgiTrax/stable-baselines3` ({len(commits)} commits, newest "
                 f"{short(commits[-1].sha)} of {utc(commits[-1].ctime)[:10]}). Paper figure: "
                 f"`corl_graphs.ipynb` at {short(final_nb)}. Values at the horizon (Lunar Lander 150k steps, "
                 f"Reaching and Placing 100k). `plotted` = the value the authors' CSV holds at its last row "
                 f"(their `accumulate_tensorboard.py` rule; the scale of algorithms.md's published numbers; "
                 f"the figure draws 4 x this); `true` = the sum of every finished episode's return (Reaching "
                 f"in units of reward 100 per success, whatever the run's reward_scale); mean ± "
                 f"standard error over runs. All-runs means are over the runs of the batches that hold a plotted "
                 f"run and reached the horizon, runs with identical logs (a seed run twice) counted once.\n")
    n_train = sum(1 for r in runs.values() if not r.derived)
    absent = [r for r in runs.values() if any(s < 0 for s in r.versions.values())]
    lines.append(f"Event files: {len(runs)} names ({n_train} training processes, "
                 f"{len(runs) - n_train} `.v2` files written by the authors' averaging scripts); by task: "
                 + ", ".join(f"{t} {n}" for t, n in Counter(r.task for r in runs.values()).most_common()) + ". "
                 + (f"Versions absent from the snapshot (files of 4 MiB and more): "
                    + ", ".join(f"`{r.name}` ({sum(1 for s in r.versions.values() if s < 0)} of "
                                f"{len(r.versions)} versions; the largest present one is decoded)" for r in absent)
                    if absent else "No version is absent.") + "\n")

    summary_rows: list[dict[str, Any]] = []
    lines.append("## Plotted vs all runs, per task and curve\n")
    lines.append("| task | curve | plotted runs | published | plotted (CSVs) | plotted (our rule, own logs) | "
                 "batches: runs (complete, distinct) | all runs | true, plotted | true, all runs | feedback %, plotted | "
                 "feedback %, all runs |")
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|")
    stats: dict[tuple[str, str], dict[str, Any]] = {}
    for task in TASKS:
        for curve in sorted((c for c in curves if c.task == task), key=lambda c: METHOD_ORDER.index(c.method)
                            if c.method in METHOD_ORDER else 99):
            key = (task, curve.method)
            cms = matches[(task, curve.label + "|" + curve.kind)]
            plotted_runs = [runs[cm.runs[0]] for cm in cms if cm.runs]
            batch_ids = sorted({r.batch for r in plotted_runs if r.batch})
            members = [r for bid in batch_ids for r in by_batch[bid].runs]
            complete = distinct([r for r in members if r.metrics.get("complete")])
            csv_final = mean_se([cm.final for cm in cms])
            own = mean_se([r.metrics.get("plotted_cum") for r in plotted_runs])
            allr = mean_se([r.metrics.get("plotted_cum") for r in complete])
            true_p = mean_se([r.metrics.get("true_cum") for r in plotted_runs])
            true_a = mean_se([r.metrics.get("true_cum") for r in complete])
            fb_p = mean_se([r.metrics.get("feedback_pct") for r in plotted_runs])
            fb_a = mean_se([r.metrics.get("feedback_pct") for r in complete])
            published = PUBLISHED[task].get(curve.method)
            batch_desc = ", ".join(
                f"{bid} {len(by_batch[bid].runs)} "
                f"({len(distinct([r for r in by_batch[bid].runs if r.metrics.get('complete')]))})"
                for bid in batch_ids)
            show_fb = curve.method in ("DREF", "EF-rate")
            lines.append(f"| {task} | {curve.label}{'' if curve.kind == 'paper' else ' (all_runs folder, not in the figure)'} | "
                         f"{len(plotted_runs)} | {fmt(published, 1, True)} | {pm(*csv_final[:2], 1, True)} | "
                         f"{pm(*own[:2], 1, True)} | {batch_desc} | {pm(*allr[:2], 1, True)} (n={allr[2]}) | "
                         f"{pm(*true_p[:2], 1, True)} | {pm(*true_a[:2], 1, True)} | "
                         f"{pm(*fb_p[:2], 2) if show_fb else ''} | {pm(*fb_a[:2], 2) if show_fb else ''} |")
            stats[key] = {"plotted": csv_final, "own": own, "all": allr, "fb_p": fb_p, "fb_a": fb_a,
                          "true_p": true_p, "true_a": true_a}
            summary_rows.append({
                "task": task, "curve": curve.label, "method": curve.method, "kind": curve.kind,
                "published": published, "n_plotted": len(plotted_runs), "plotted_mean": csv_final[0],
                "plotted_se": csv_final[1], "plotted_own_logs_mean": own[0],
                "batches": " ".join(batch_ids), "batch_runs": len(members), "all_runs_complete": allr[2],
                "all_runs_mean": allr[0], "all_runs_se": allr[1], "true_plotted_mean": true_p[0],
                "true_all_mean": true_a[0], "true_all_se": true_a[1], "feedback_plotted_mean": fb_p[0],
                "feedback_plotted_se": fb_p[1], "feedback_all_mean": fb_a[0], "feedback_all_se": fb_a[1]})
    lines.append("")
    lines.append("## Ratios to EF-100 (plotted vs all runs of the batches)\n")
    lines.append("| task | DREF / EF-100, published | plotted | all runs | SAC / EF-100, published | plotted | all runs | "
                 "EF at DREF's rate / EF-100, published | plotted | all runs | DREF feedback %, published | plotted | all runs |")
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for task in TASKS:
        s = lambda m, k: stats.get((task, m), {}).get(k, (None, None, 0))  # noqa: E731
        pub = PUBLISHED[task]
        cells = [task]
        for m in ("DREF", "SAC", "EF-rate"):
            rp = ratio(s(m, "plotted"), s("EF-100", "plotted"))
            ra = ratio(s(m, "all"), s("EF-100", "all"))
            cells += [f"{pub[m] / pub['EF-100']:.2f}", pm(*rp, 2), pm(*ra, 2)]
            summary_rows.append({"task": task, "curve": f"{m} / EF-100", "method": "ratio",
                                 "published": pub[m] / pub["EF-100"], "plotted_mean": rp[0], "plotted_se": rp[1],
                                 "all_runs_mean": ra[0], "all_runs_se": ra[1]})
        cells += [f"{pub['fb']:.1f}", pm(*s("DREF", "fb_p")[:2], 2), pm(*s("DREF", "fb_a")[:2], 2)]
        lines.append("| " + " | ".join(cells) + " |")
    lines.append("")

    with (out / "summary.csv").open("w", newline="") as f:
        keys = ["task", "curve", "method", "kind", "published", "n_plotted", "plotted_mean", "plotted_se",
                "plotted_own_logs_mean", "batches", "batch_runs", "all_runs_complete", "all_runs_mean", "all_runs_se",
                "true_plotted_mean", "true_all_mean", "true_all_se", "feedback_plotted_mean", "feedback_plotted_se",
                "feedback_all_mean", "feedback_all_se"]
        w = csv.DictWriter(f, fieldnames=keys)
        w.writeheader()
        for row in summary_rows:
            w.writerow({k: (f"{v:.4g}" if isinstance(v, float) else v) for k, v in row.items() if k in keys})

    # Per plotted batch: its runs, and the constants at its config commit.
    lines.append("## The batches that hold plotted runs\n")
    lines.append("Config commit: the latest commit of the method's pipeline, config, learner, expert and SAC/buffer "
                 "files before the batch's first launch; `next` is the first such commit after it (a commit minutes "
                 "after a launch may hold the code the batch ran with uncommitted). Constants are read from the "
                 "code at the config commit; `alpha0 logged` is `train/q_value_threshold - 1e-8 * step`.\n")
    plotted_batches = [b for b in batches if any(r.plotted for r in b.runs)]
    for b in plotted_batches:
        hosts = " ".join(sorted({r.short_host for r in b.runs}))
        lines.append(f"### {b.bid}: {b.task} {b.method}, {len(b.runs)} runs ({hosts}), "
                     f"{b.runs[0].launch_utc} to {b.runs[-1].launch_utc[11:]} UTC\n")
        if b.commit:
            after = (f"; next {short(b.next_commit.sha)} {utc(b.next_commit.ctime)} "
                     f"({(b.next_commit.ctime - b.runs[0].launch) / 60:+.0f} min) \"{b.next_commit.subject}\""
                     if b.next_commit else "")
            lines.append(f"Config commit {short(b.commit.sha)} {utc(b.commit.ctime)} "
                         f"({(b.commit.ctime - b.runs[0].launch) / 60:+.0f} min) \"{b.commit.subject}\"{after}.\n")
        consts = read_constants(git, b.task, b.method, b.commit)
        alphas = [r.metrics["alpha0"] for r in b.runs if r.metrics.get("alpha0") is not None]
        if alphas:
            consts["alpha0 logged (median over runs)"] = f"{statistics.median(alphas):.5f}"
        if consts:
            lines.append("| constant | at the config commit |")
            lines.append("|---|---|")
            for k, v in consts.items():
                lines.append(f"| {k} | `{v}` |")
            if b.next_commit and b.commit:
                later = read_constants(git, b.task, b.method, b.next_commit)
                changed = {k: v for k, v in later.items() if consts.get(k) != v and not k.startswith("alpha0 logged")}
                if changed:
                    lines.append("| **changed at next** | " + "; ".join(f"{k} -> `{v}`" for k, v in changed.items())
                                 + " |")
            lines.append("")
        lines.append("| run | host | launch UTC | plotted | steps | plotted cum | true cum | final 100-ep mean | "
                     "feedback % | alpha0 | flags |")
        lines.append("|---|---|---|---|---|---|---|---|---|---|---|")
        for r in b.runs:
            m = r.metrics
            lines.append(f"| `{r.name[len('events.out.tfevents.'):]}` | {r.short_host} | {r.launch_utc[5:]} | "
                         f"{'; '.join(r.plotted) or 'no'} | {m.get('last_step')} | {fmt(m.get('plotted_cum'), 0)} | "
                         f"{fmt(m.get('true_cum'), 0)} | {fmt(m.get('final_mean100'), 1)} | "
                         f"{fmt(m.get('feedback_pct'), 2)} | {fmt(m.get('alpha0'), 4)} | "
                         f"{'; '.join(m.get('flags', []))} |")
        lines.append("")

    # How each plotted CSV was matched.
    lines.append("## Plotted CSVs and the runs they were computed from\n")
    lines.append("| task | curve | CSV | rows | CSV final | match | run(s) |")
    lines.append("|---|---|---|---|---|---|---|")
    for curve in curves:
        for cm in matches[(curve.task, curve.label + "|" + curve.kind)]:
            lines.append(f"| {curve.task} | {curve.label} | `{cm.csv_path.split('/all_runs/')[1]}` | {cm.rows} | "
                         f"{fmt(cm.final, 1)} | {cm.how} | "
                         + " + ".join(f"`{n[len('events.out.tfevents.'):]}`" for n in cm.runs) + " |")
    lines.append("")

    # Failure modes of DREF over every complete DREF run of the three tasks.
    lines.append("## DREF runs by outcome (every complete DREF run, plotted batches or not)\n")
    lines.append("| task | batch | runs | plotted | flags (runs) |")
    lines.append("|---|---|---|---|---|")
    for b in batches:
        if b.method != "DREF":
            continue
        complete = distinct([r for r in b.runs if r.metrics.get("complete")])
        if not complete:
            continue
        flags = Counter(f for r in complete for f in r.metrics.get("flags", []))
        lines.append(f"| {b.task} | {b.bid} | {len(complete)} | {sum(1 for r in b.runs if r.plotted)} | "
                     + ", ".join(f"{k} ({v})" for k, v in flags.most_common()) + " |")
    lines.append("")
    (out / "summary.md").write_text("\n".join(lines))


def utc(t: int) -> str:
    return datetime.fromtimestamp(t, timezone.utc).strftime("%Y-%m-%d %H:%M")


# --------------------------------------------------------------------------------------- main

def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repo", type=Path, required=True,
                        help="a clone or bare git directory of corgiTrax/stable-baselines3")
    parser.add_argument("--out", type=Path, required=True, help="folder for runs.csv, batches.csv, summary.*")
    parser.add_argument("--gap-minutes", type=float, default=BATCH_GAP_S / 60,
                        help="largest gap between consecutive launches of one batch (default 10)")
    args = parser.parse_args()
    t0 = time.time()
    git = Git(args.repo)
    commits = read_history(git)
    runs = collect_runs(commits)
    print(f"{len(commits)} commits, {len(runs)} event files", file=sys.stderr)
    decode_runs(git, runs)
    print(f"decoded in {time.time() - t0:.0f} s", file=sys.stderr)
    label_runs(runs)
    resolve_unknown_robosuite(runs)
    for run in runs.values():
        compute_metrics(run)
    mark_duplicates(runs)
    history = ConfigHistory(commits)
    batches = make_batches(runs, history, int(args.gap_minutes * 60))

    curves, final_nb = notebook_curves(git, commits)
    index: dict[tuple[int, ...], list[Run]] = defaultdict(list)
    for run in runs.values():
        er = run.tags.get("rollout/ep_rew_mean", [])
        if er and not run.derived:
            index[(er[0][0],)].append(run)
            if len(er) >= 2:
                index[(er[0][0], er[1][0])].append(run)
    matches: dict[tuple[str, str], list[CsvMatch]] = {}
    for curve in curves:
        found = []
        for n, path in enumerate(curve.csvs, 1):
            data = git.file_at(curve.commit, path)
            if data is None:  # the final reorganisation (cc1b460) moved the results under DREF_project_results/
                data = git.file_at(curve.commit, "DREF_project_results/" + path)
            if data is None:
                found.append(CsvMatch(path, 0, None, [], "CSV absent", None))
                continue
            cm = match_csv(path, read_csv_rows(data), curve.task, index)
            found.append(cm)
            tag = f"{'paper' if curve.kind == 'paper' else 'folder'} {curve.label} run {n}"
            for name in cm.runs:
                if tag not in runs[name].plotted:
                    runs[name].plotted.append(tag)
        matches[(curve.task, curve.label + "|" + curve.kind)] = found
    write_outputs(args.out, git, runs, batches, curves, matches, final_nb, commits)
    print(f"wrote {args.out} in {time.time() - t0:.0f} s", file=sys.stderr)


if __name__ == "__main__":
    main()
