"""An env whose steps do nothing, for timing the env protocol alone:
``python -m dualrep.env --make null_env:NullEnv`` run from this folder."""

from __future__ import annotations

from typing import Any, Dict, List, Optional, Tuple


class _Box:
    def __init__(self, n: int, bound: float) -> None:
        self.shape = (n,)
        self.low = [-bound] * n
        self.high = [bound] * n


class NullEnv:
    """Lunar Lander's sizes (8 observations, 2 actions); episodes of 1000 steps."""

    observation_space = _Box(8, 10.0)
    action_space = _Box(2, 1.0)
    spec = None
    metadata = {"render_fps": 50}

    def __init__(self) -> None:
        self.t = 0
        self.obs: List[float] = [0.0] * 8

    def reset(self, seed: Optional[int] = None) -> Tuple[List[float], Dict[str, Any]]:
        self.t = 0
        return self.obs, {}

    def step(self, action: Any) -> Tuple[List[float], float, bool, bool, Dict[str, Any]]:
        self.t += 1
        return self.obs, 0.0, False, self.t >= 1000, {}
