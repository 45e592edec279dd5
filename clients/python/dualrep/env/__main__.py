"""``python -m dualrep.env --gym ID --predicates MODULE:FUNC --port P``: serve a Gymnasium env
(or ``--make MODULE:FUNC``, a function that returns your env) to dualrep."""

from __future__ import annotations

import argparse
import importlib
import json
import sys
from typing import Any, List, Optional

from .server import serve


def load(spec: str) -> Any:
    """The object ``MODULE:NAME`` names (the current directory is importable)."""
    module, sep, name = spec.partition(":")
    if not sep or not module or not name:
        raise SystemExit(f"{spec!r}: expected MODULE:NAME, e.g. mypredicates:pendulum")
    if "" not in sys.path:
        sys.path.insert(0, "")
    try:
        target: Any = importlib.import_module(module)
    except ImportError as e:
        raise SystemExit(f"{spec}: cannot import {module}: {e}") from None
    for part in name.split("."):
        try:
            target = getattr(target, part)
        except AttributeError:
            raise SystemExit(f"{spec}: {module} has no {name}") from None
    return target


def main(argv: Optional[List[str]] = None) -> None:
    p = argparse.ArgumentParser(prog="python -m dualrep.env", description=__doc__)
    source = p.add_mutually_exclusive_group(required=True)
    source.add_argument("--gym", metavar="ID", help="a Gymnasium env id (e.g. Pendulum-v1)")
    source.add_argument("--make", metavar="MODULE:FUNC", help="a function that returns a new env")
    p.add_argument("--predicates", metavar="MODULE:FUNC", help="the scene graph's predicate function")
    p.add_argument("--features", metavar="MODULE:FUNC", help="DRPL's feature function")
    p.add_argument("--success", metavar="MODULE:FUNC", help="whether an episode's last step succeeded")
    p.add_argument("--host", default="127.0.0.1", help="address to listen on [127.0.0.1]")
    p.add_argument("--port", type=int, default=5555, help="port (0: any free one, printed) [5555]")
    p.add_argument("--id", help="the env id dualrep shows [the Gymnasium id]")
    p.add_argument("--control-hz", type=float, help="steps per second of the env's clock [its render_fps]")
    p.add_argument("--max-episode-steps", type=int, help="episode limit [the Gymnasium spec's]")
    p.add_argument("--gym-kwargs", default="{}", help="JSON keyword arguments for gymnasium.make")
    p.add_argument("--no-render", action="store_true", help="never send frames")
    args = p.parse_args(argv)
    env: Any = args.gym if args.gym else load(args.make)
    serve(
        env,
        host=args.host,
        port=args.port,
        predicates=load(args.predicates) if args.predicates else None,
        features=load(args.features) if args.features else None,
        success=load(args.success) if args.success else None,
        env_id=args.id,
        control_hz=args.control_hz,
        max_episode_steps=args.max_episode_steps,
        render=not args.no_render,
        gym_kwargs=json.loads(args.gym_kwargs),
    )


if __name__ == "__main__":
    main()
