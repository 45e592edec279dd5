"""Ready-made scene graphs (predicate functions) and success rules for Gymnasium's continuous
classic-control envs and Lunar Lander: ``--predicates dualrep.scenes:pendulum``."""

from __future__ import annotations

from typing import Any, Dict, Mapping

from .env.adapter import predicates


@predicates(
    upright="pendulum upright",
    right_side="pendulum on the right",
    fast="spinning fast",
    clockwise="pushing clockwise",
)
def pendulum(obs: Any, action: Any, info: Mapping[str, Any]) -> Dict[str, bool]:
    """Pendulum-v1: obs = (cos theta, sin theta, angular velocity)."""
    return {
        "upright": obs[0] > 0.9,
        "right_side": obs[1] < 0.0,
        "fast": abs(obs[2]) > 4.0,
        "clockwise": action is not None and float(action[0]) < 0.0,
    }


@predicates(
    right_of_valley="car right of the valley floor",
    moving_right="car moving right",
    near_goal="car near the flag",
    pushing_right="pushing right",
)
def mountain_car(obs: Any, action: Any, info: Mapping[str, Any]) -> Dict[str, bool]:
    """MountainCarContinuous-v0: obs = (position, velocity); the flag is at 0.45."""
    return {
        "right_of_valley": obs[0] > -0.52,
        "moving_right": obs[1] > 0.0,
        "near_goal": obs[0] > 0.3,
        "pushing_right": action is not None and float(action[0]) > 0.0,
    }


def mountain_car_success(obs: Any, reward: float, terminated: bool, truncated: bool, info: Mapping[str, Any]) -> bool:
    """The car reached the flag."""
    return bool(terminated)


def lunar_lander_success(obs: Any, reward: float, terminated: bool, truncated: bool, info: Mapping[str, Any]) -> bool:
    """Gymnasium's Lunar Lander pays exactly +100 on the step it comes to rest (and -100 on a
    crash): resting ends the episode as a success."""
    return bool(terminated) and reward == 100.0
