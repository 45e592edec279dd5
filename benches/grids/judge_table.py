#!/usr/bin/env python3
"""The table of `judge_equal_answers.sh`'s summaries, and the reading written before its runs.

Each `e<EF-100 step>-on-<DREF step>.json` is EF-100 normed's critic at that step judged on DREF
normed's policy at its step; DREF normed's own critic on the same steps is the committed
`w-<DREF step>-D-D.json` beside the README (the same 50 episodes from seed 1000, the same 8
actions around each step). The reading (docs/results/lunar-critic-judge/README.md, "At equal
answers"): Delta = rho(EF-100 normed at the same answer count) - rho(DREF normed's own) at
EF-100 8k on DREF 40k and EF-100 10k on DREF 80k; +0.05 or more at both: placement costs order;
within 0.05 at both: the count sets it; -0.05 or less at both: placement buys order.

    python3 benches/grids/judge_table.py OUT [COMMITTED]
"""

import json
import re
import sys
from pathlib import Path

MARGIN = 0.05
EQUAL_COUNT = [(8000, 40000), (10000, 80000)]


def nearest(steps: list[int], target: int) -> int:
    return min(steps, key=lambda s: abs(s - target))


def rho(path: Path) -> float:
    return json.loads(path.read_text())["judge"]["within_state_rank_correlation"]


def reading(deltas: list[float]) -> str:
    if all(d >= MARGIN for d in deltas):
        return "placement costs order per answer (Delta >= +0.05 at both)"
    if all(abs(d) < MARGIN for d in deltas):
        return "the count sets the order (|Delta| < 0.05 at both)"
    if all(d <= -MARGIN for d in deltas):
        return "placement buys order per answer (Delta <= -0.05 at both)"
    return "no reading (the two points disagree or fall between)"


def main() -> None:
    out = Path(sys.argv[1])
    committed = Path(sys.argv[2]) if len(sys.argv) > 2 else Path(__file__).resolve().parents[2] / "docs/results/lunar-critic-judge"
    judged: dict[tuple[int, int], Path] = {}
    for path in out.glob("e*-on-*.json"):
        m = re.fullmatch(r"e(\d+)-on-(\d+)\.json", path.name)
        if m:
            judged[(int(m[1]), int(m[2]))] = path
    own = {int(m[1]): p for p in committed.glob("w-*-D-D.json") if (m := re.fullmatch(r"w-(\d+)-D-D\.json", p.name))}
    print("| EF-100 normed's critic at (answers) | on DREF normed's steps at | rho | DREF normed's own | Delta |")
    print("|---:|---:|---:|---:|---:|")
    for (e, d), path in sorted(judged.items(), key=lambda kv: (kv[0][1], kv[0][0])):
        r = rho(path)
        mine = rho(own[d]) if d in own else float("nan")
        print(f"| {e:,} | {d:,} | {r:.3f} | {mine:.3f} | {r - mine:+.3f} |")
    early = sorted({e for e, _ in judged})
    drefs = sorted({d for _, d in judged})
    if not early or not drefs:
        return
    deltas = []
    for e_target, d_target in EQUAL_COUNT:
        e, d = nearest(early, e_target), nearest(drefs, d_target)
        if (e, d) not in judged or d not in own:
            print(f"equal-count point ({e_target}, {d_target}) not judged yet")
            return
        deltas.append(rho(judged[(e, d)]) - rho(own[d]))
    print("Delta at the equal-count points: " + ", ".join(f"{x:+.3f}" for x in deltas) + ": " + reading(deltas))


if __name__ == "__main__":
    main()
