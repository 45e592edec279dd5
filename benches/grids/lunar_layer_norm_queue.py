#!/usr/bin/env python3
"""The queue `local_runs.sh` runs for the normed learner's grid since the fifty-fifth stop: the
probe, then the rows (lunar-layer-norm-rows.jobs), each seed's cut-at-60k branches
(lunar-layer-norm-branches.jobs) right after its EF-100 normed line, so that a branch starts
once its seed's pair has run past 60k; then, since the sixtieth stop, DREF normed until 60k on
the seeds with no branch (lunar-layer-norm-until-60k.jobs) before SAC alone normed.

    python3 benches/grids/lunar_layer_norm_queue.py > /work/grid/ln-queue.jobs
"""

from __future__ import annotations

import re
import sys
from pathlib import Path

GRIDS = Path(__file__).resolve().parent


def queue() -> str:
    rows = (GRIDS / "lunar-layer-norm-rows.jobs").read_text().splitlines(keepends=True)
    branches = [
        line
        for line in (GRIDS / "lunar-layer-norm-branches.jobs").read_text().splitlines(keepends=True)
        if line.strip() and not line.startswith("#")
    ]
    until_60k = (GRIDS / "lunar-layer-norm-until-60k.jobs").read_text()
    out = [(GRIDS / "lunar-layer-norm-probe.jobs").read_text()]
    for line in rows:
        if until_60k and re.match(r"\S*/lunar-lander/sac/seed\d+ ", line):
            out.append(until_60k)
            until_60k = ""
        out.append(line)
        ef100 = re.match(r"\S*/lunar-lander/ef-100/seed(\d+) ", line)
        if ef100:
            out += [b for b in branches if re.search(rf"-until-60k/seed{ef100.group(1)} ", b)]
    return "".join(out)


if __name__ == "__main__":
    sys.stdout.write(queue())
