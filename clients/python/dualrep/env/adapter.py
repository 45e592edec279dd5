"""What dualrep needs of an environment, read from a Gymnasium env or from any object with
``reset(seed=...)`` and ``step(action)`` in Gymnasium's form: its Box spaces, control rate,
episode limit, and observations as flat lists of floats."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple

#: A predicate function: ``(obs, action, info) -> {name: bool}`` (or the names that hold);
#: ``action`` is None after a reset. Declare names and labels with :func:`predicates`.
PredicateFn = Callable[[Any, Any, Mapping[str, Any]], Any]
#: DRPL features: ``(obs, action, info) -> sequence of floats``, declared with :func:`features`.
FeatureFn = Callable[[Any, Any, Mapping[str, Any]], Sequence[float]]
#: Whether an episode's last step achieved the task: ``(obs, reward, terminated, truncated,
#: info) -> bool``.
SuccessFn = Callable[[Any, float, bool, bool, Mapping[str, Any]], bool]


def predicates(**labels: str) -> Callable[[PredicateFn], PredicateFn]:
    """Declare a predicate function's predicates, in bit order: ``name="label people read"``.

    >>> @predicates(upright="pendulum upright", fast="spinning fast")
    ... def pendulum(obs, action, info):
    ...     return {"upright": obs[0] > 0.9, "fast": abs(obs[2]) > 4.0}
    """

    def declare(fn: PredicateFn) -> PredicateFn:
        fn.labels = dict(labels)  # type: ignore[attr-defined]
        return fn

    return declare


def features(*names: str) -> Callable[[FeatureFn], FeatureFn]:
    """Declare a feature function's feature names, in order."""

    def declare(fn: FeatureFn) -> FeatureFn:
        fn.names = list(names)  # type: ignore[attr-defined]
        return fn

    return declare


def flat(values: Any) -> List[float]:
    """A flat list of floats from an array, a sequence (nested or not) or a number."""
    if hasattr(values, "ravel"):
        return [float(v) for v in values.ravel().tolist()]
    if isinstance(values, (int, float)):
        return [float(values)]
    out: List[float] = []
    for v in values:
        if isinstance(v, (list, tuple)) or hasattr(v, "ravel"):
            out.extend(flat(v))
        else:
            out.append(float(v))
    return out


def _bound(v: float) -> Optional[float]:
    return float(v) if math.isfinite(v) else None


@dataclass
class Space:
    """A Box space as the protocol writes it."""

    shape: List[int]
    low: List[float]
    high: List[float]
    dtype: Any = None

    def message(self) -> Dict[str, Any]:
        return {
            "shape": self.shape,
            "low": [_bound(v) for v in self.low],
            "high": [_bound(v) for v in self.high],
        }


def box_of(space: Any, what: str) -> Space:
    """A Gymnasium ``Box`` (or anything with ``shape``, ``low`` and ``high``) as a :class:`Space`."""
    if not all(hasattr(space, a) for a in ("shape", "low", "high")):
        raise TypeError(
            f"{what} is {type(space).__name__}: dualrep takes Box spaces (shape, low, high); "
            "wrap a Discrete or Dict space into a Box first"
        )
    shape = [int(d) for d in space.shape]
    size = 1
    for d in shape:
        size *= d
    low, high = flat(space.low), flat(space.high)
    if len(low) == 1 and size > 1:
        low = low * size
    if len(high) == 1 and size > 1:
        high = high * size
    return Space(shape, low, high, getattr(space, "dtype", None))


@dataclass
class Declared:
    """Everything the env's ``hello`` says besides its spaces."""

    id: str
    control_hz: float
    max_episode_steps: int
    render: bool
    deterministic: bool
    predicates: List[Tuple[str, str]] = field(default_factory=list)
    features: List[str] = field(default_factory=list)


def describe(
    env: Any,
    *,
    env_id: Optional[str],
    control_hz: Optional[float],
    max_episode_steps: Optional[int],
    predicate_fn: Optional[PredicateFn],
    feature_fn: Optional[FeatureFn],
    deterministic: Optional[bool],
) -> Tuple[Space, Space, Declared]:
    """Read an env's spaces and defaults; the keyword arguments override what it says."""
    obs_space = box_of(env.observation_space, "observation_space")
    act_space = box_of(env.action_space, "action_space")
    spec = getattr(env, "spec", None)
    metadata = getattr(env, "metadata", None) or {}
    name = env_id or getattr(spec, "id", None) or type(getattr(env, "unwrapped", env)).__name__
    limit = max_episode_steps or getattr(spec, "max_episode_steps", None)
    if not limit:
        raise ValueError(
            f"{name} has no episode limit: give max_episode_steps (dualrep checkpoints between episodes)"
        )
    rate = control_hz or metadata.get("render_fps") or 20
    gym_env = spec is not None and hasattr(env, "unwrapped")
    can_render = getattr(env, "render_mode", None) in ("rgb_array", None) and hasattr(env, "render")
    if gym_env and getattr(env, "render_mode", None) != "rgb_array":
        can_render = False
    labels = getattr(predicate_fn, "labels", None) if predicate_fn is not None else None
    if predicate_fn is not None and not labels:
        raise ValueError("declare the predicate function's predicates with @predicates(name='label', ...)")
    names = getattr(feature_fn, "names", None) if feature_fn is not None else None
    if feature_fn is not None and not names:
        raise ValueError("declare the feature function's names with @features('name', ...)")
    declared = Declared(
        id=str(name),
        control_hz=float(rate),
        max_episode_steps=int(limit),
        render=bool(can_render),
        # A registered Gymnasium env replays from its seed; any other says so itself.
        deterministic=gym_env if deterministic is None else deterministic,
        predicates=list((labels or {}).items()),
        features=list(names or []),
    )
    return obs_space, act_space, declared


def holding(predicate_fn: Optional[PredicateFn], declared: Declared, obs: Any, action: Any, info: Mapping[str, Any]) -> List[str]:
    """The names of the declared predicates that hold."""
    if predicate_fn is None:
        return []
    result = predicate_fn(obs, action, info)
    known = {name for name, _ in declared.predicates}
    if isinstance(result, Mapping):
        names = [str(k) for k, v in result.items() if v]
    else:
        names = [str(k) for k in result]
    unknown = [n for n in names if n not in known]
    if unknown:
        raise ValueError(f"predicate function returned undeclared predicates {unknown}")
    return names
