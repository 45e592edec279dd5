"""Read an .rrd file with the Python rerun-sdk and print what it holds as one JSON object.

Used by tests/recording.rs to check that the Rust recorder's files are readable by the Python
SDK of the same version (system.md, "Recording"), and what they contain:

    {"rerun_version": "0.36.3",
     "recordings": [{"application_id": ..., "recording_id": ...}],
     "timelines": ["episode", "step"],
     "entities": {"reward": {"rows": 300, "static_rows": 1, "timelines": ["episode", "step"],
                             "components": ["Scalars:scalars", ...],
                             "times": {"step": {"min": 0, "max": 299, "distinct": 300}, ...},
                             "scalars": [...], "texts": [...]}, ...}}

`rows` counts temporal rows, `static_rows` static ones. `scalars` (first scalar of each row) and
`texts` (TextLog text of each row) are in step order, for entities that have them.

Usage: python read_rrd.py FILE.rrd
"""

import json
import sys
from collections import defaultdict

import rerun
from rerun.experimental import RrdReader

# Rerun's own columns, not timelines a recorder chose.
BUILTIN_TIMELINES = {"log_time", "log_tick"}


def first_value(cell):
    """A component cell is a list (a batch); the tests log one value per row."""
    if isinstance(cell, list):
        return cell[0] if cell else None
    return cell


def main(path):
    reader = RrdReader(path)
    recordings = [
        {"application_id": r.application_id, "recording_id": r.recording_id} for r in reader.recordings()
    ]
    entities = defaultdict(
        lambda: {
            "rows": 0,
            "static_rows": 0,
            "timelines": set(),
            "components": set(),
            "times": defaultdict(list),
            "scalars": [],
            "texts": [],
        }
    )
    timelines = set()
    for chunk in reader.stream():
        path_ = chunk.entity_path.lstrip("/")
        if path_.startswith("__"):
            continue  # recording properties
        entity = entities[path_]
        batch = chunk.to_record_batch()
        names = [n for n in batch.schema.names if n != "rerun.controls.RowId"]
        chunk_timelines = [t for t in chunk.timeline_names if t not in BUILTIN_TIMELINES]
        components = [n for n in names if n not in chunk.timeline_names]
        entity["components"].update(components)
        if chunk.is_static:
            entity["static_rows"] += chunk.num_rows
            continue
        entity["rows"] += chunk.num_rows
        entity["timelines"].update(chunk_timelines)
        timelines.update(chunk_timelines)
        columns = {t: batch.column(t).cast("int64").to_pylist() for t in chunk_timelines}
        steps = columns.get("step", [None] * chunk.num_rows)
        for t, values in columns.items():
            entity["times"][t].extend(values)
        if "Scalars:scalars" in components:
            values = [first_value(v) for v in batch.column("Scalars:scalars").to_pylist()]
            entity["scalars"].extend(zip(steps, values))
        if "TextLog:text" in components:
            values = [first_value(v) for v in batch.column("TextLog:text").to_pylist()]
            entity["texts"].extend(zip(steps, values))

    out = {}
    for path_, e in sorted(entities.items()):
        out[path_] = {
            "rows": e["rows"],
            "static_rows": e["static_rows"],
            "timelines": sorted(e["timelines"]),
            "components": sorted(e["components"]),
            "times": {
                t: {"min": min(v), "max": max(v), "distinct": len(set(v))}
                for t, v in ((t, [x for x in v if x is not None]) for t, v in sorted(e["times"].items()))
                if v
            },
            # Stable sort: rows of one step keep their logging order.
            "scalars": [v for _, v in sorted(e["scalars"], key=lambda sv: sv[0] or 0)],
            "texts": [v for _, v in sorted(e["texts"], key=lambda sv: sv[0] or 0)],
        }
    json.dump(
        {
            "rerun_version": rerun.__version__,
            "recordings": recordings,
            "timelines": sorted(timelines),
            "entities": out,
        },
        sys.stdout,
    )
    print()


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit("usage: read_rrd.py FILE.rrd")
    main(sys.argv[1])
