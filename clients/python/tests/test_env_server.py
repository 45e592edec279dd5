"""The env server over real sockets: a user class, a Gymnasium env, a shared robot-like env,
and the command line, driven by a client that speaks the protocol as dualrep does."""

from __future__ import annotations

import re
import socket
import subprocess
import sys
import threading
from typing import Any, Dict, Optional, Tuple

import numpy as np
import pytest

from dualrep.env import EnvServer, features, predicates
from dualrep.env.protocol import read_message, write_message


class Line:
    """A one-dimensional toy env in Gymnasium's form: move a point to the right edge."""

    class Box:
        def __init__(self, low: float, high: float, shape: Tuple[int, ...]) -> None:
            self.low, self.high, self.shape = np.full(shape, low), np.full(shape, high), shape
            self.dtype = np.float32

    observation_space = Box(-1.0, 1.0, (1,))
    action_space = Box(-0.5, 0.5, (1,))

    def __init__(self) -> None:
        self.x = 0.0

    def reset(self, seed: Optional[int] = None) -> Tuple[np.ndarray, Dict[str, Any]]:
        self.x = ((seed or 0) % 7) / 10.0
        return np.array([self.x]), {}

    def step(self, action: np.ndarray) -> Tuple[np.ndarray, float, bool, bool, Dict[str, Any]]:
        self.x = float(np.clip(self.x + float(action[0]), -1.0, 1.0))
        done = self.x >= 1.0
        return np.array([self.x]), self.x, done, False, {"is_success": done}


@predicates(right="point right of centre", at_edge="point at the right edge")
def line_scene(obs: Any, action: Any, info: Any) -> Dict[str, bool]:
    return {"right": obs[0] > 0.0, "at_edge": obs[0] >= 1.0}


@features("x", "x_squared")
def line_features(obs: Any, action: Any, info: Any) -> list:
    return [float(obs[0]), float(obs[0]) ** 2]


class Conn:
    """dualrep's side of one connection."""

    def __init__(self, url: str) -> None:
        host, port = url[len("tcp://") :].rsplit(":", 1)
        self.sock = socket.create_connection((host, int(port)), timeout=10)
        self.rfile = self.sock.makefile("rb")
        self.wfile = self.sock.makefile("wb")

    def call(self, message: Dict[str, Any]) -> Tuple[Dict[str, Any], Optional[bytes]]:
        write_message(self.wfile, message)
        reply = read_message(self.rfile)
        assert reply is not None, "the env closed the connection"
        frame = reply.get("frame")
        data = self.rfile.read(frame["bytes"]) if frame else None
        return reply, data

    def close(self) -> None:
        self.sock.close()


def test_a_user_class_is_described_reset_and_stepped_with_its_predicates_and_features() -> None:
    with EnvServer(Line, predicates=line_scene, features=line_features, max_episode_steps=50, control_hz=10, quiet=True) as server:
        c = Conn(server.url)
        hello, _ = c.call({"type": "hello", "protocol": 1})
        env = hello["env"]
        assert env["id"] == "Line"
        assert env["action_space"] == {"shape": [1], "low": [-0.5], "high": [0.5]}
        assert env["predicates"] == [
            {"name": "right", "label": "point right of centre"},
            {"name": "at_edge", "label": "point at the right edge"},
        ]
        assert env["features"] == ["x", "x_squared"]
        assert (env["control_hz"], env["max_episode_steps"], env["deterministic"]) == (10.0, 50, False)
        reset, _ = c.call({"type": "reset", "seed": 3})
        assert reset["obs"] == [pytest.approx(0.3)] and reset["holding"] == ["right"]
        steps = 0
        while True:
            step, _ = c.call({"type": "step", "action": [0.5]})
            steps += 1
            assert step["features"] == [pytest.approx(step["obs"][0]), pytest.approx(step["obs"][0] ** 2)]
            if step["terminated"]:
                break
        assert steps == 2 and step["holding"] == ["right", "at_edge"] and step["success"] is True
        # The episode is over: another step is an error, and the connection stays usable.
        error, _ = c.call({"type": "step", "action": [0.1]})
        assert error["type"] == "error" and "reset" in error["message"]
        error, _ = c.call({"type": "reset", "seed": 1})
        assert error["type"] == "reset"
        error, _ = c.call({"type": "step", "action": [0.1, 0.2]})
        assert error["type"] == "error" and "1 numbers" in error["message"]
        error, _ = c.call({"type": "jump"})
        assert error["type"] == "error" and "jump" in error["message"]
        bye, _ = c.call({"type": "close"})
        assert bye == {"type": "close"}
        c.close()


def test_a_gymnasium_env_sends_png_frames_only_when_asked(pendulum_env: EnvServer) -> None:
    c = Conn(pendulum_env.url)
    hello, _ = c.call({"type": "hello", "protocol": 1})
    env = hello["env"]
    assert env["id"] == "Pendulum-v1" and env["render"] and env["deterministic"]
    assert env["max_episode_steps"] == 200
    assert [p["name"] for p in env["predicates"]] == ["upright", "right_side", "fast", "clockwise"]
    first, _ = c.call({"type": "reset", "seed": 5, "render": False})
    plain, frame = c.call({"type": "step", "action": [-1.0]})
    assert frame is None and "frame" not in plain
    assert "clockwise" in plain["holding"]
    drawn, frame = c.call({"type": "step", "action": [2.0], "render": True})
    assert drawn["frame"]["format"] == "png" and (drawn["frame"]["width"], drawn["frame"]["height"]) == (500, 500)
    assert frame is not None and frame.startswith(b"\x89PNG") and len(frame) == drawn["frame"]["bytes"]
    # Same seed, same actions, same observations: the env is deterministic, as it says.
    again, _ = c.call({"type": "reset", "seed": 5})
    assert again["obs"] == first["obs"]
    wrong, _ = c.call({"type": "hello", "protocol": 99})
    assert wrong["type"] == "error" and "protocol 1" in wrong["message"]
    c.close()


def test_one_shared_env_serves_one_connection_at_a_time() -> None:
    shared = Line()
    with EnvServer(shared, max_episode_steps=20, quiet=True) as server:
        first = Conn(server.url)
        first.call({"type": "hello", "protocol": 1})
        first.call({"type": "reset", "seed": 0})
        second = Conn(server.url)
        answered = threading.Event()

        def second_hello() -> None:
            second.call({"type": "hello", "protocol": 1})
            answered.set()

        t = threading.Thread(target=second_hello)
        t.start()
        assert not answered.wait(0.5), "the second connection waits for the first"
        first.call({"type": "close"})
        first.close()
        assert answered.wait(5), "and goes on once the first is done"
        t.join()
        second.close()


def test_a_discrete_space_is_refused_with_the_reason() -> None:
    import gymnasium as gym

    class Discrete:
        observation_space = gym.spaces.Box(-1, 1, (2,))
        action_space = gym.spaces.Discrete(3)

        def reset(self, seed: Optional[int] = None) -> Any:
            return np.zeros(2), {}

        def step(self, action: Any) -> Any:
            return np.zeros(2), 0.0, False, False, {}

    with pytest.raises(TypeError, match="Box spaces"):
        EnvServer(Discrete(), max_episode_steps=10, quiet=True)


def test_the_command_line_serves_a_gymnasium_env_on_the_port_it_prints() -> None:
    proc = subprocess.Popen(
        [sys.executable, "-m", "dualrep.env", "--gym", "MountainCarContinuous-v0", "--predicates", "dualrep.scenes:mountain_car", "--success", "dualrep.scenes:mountain_car_success", "--port", "0"],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        line = proc.stdout.readline() if proc.stdout else ""
        match = re.search(r"serving MountainCarContinuous-v0 on (tcp://[0-9.]+:[0-9]+)", line)
        assert match, line
        c = Conn(match.group(1))
        hello, _ = c.call({"type": "hello", "protocol": 1})
        assert hello["env"]["max_episode_steps"] == 999
        c.call({"type": "reset", "seed": 0})
        step, _ = c.call({"type": "step", "action": [1.0]})
        assert "pushing_right" in step["holding"]
        c.close()
    finally:
        proc.terminate()
        proc.wait(10)
    bad = subprocess.run([sys.executable, "-m", "dualrep.env", "--gym", "Pendulum-v1", "--predicates", "nowhere:x"], capture_output=True, text=True)
    assert bad.returncode != 0 and "cannot import nowhere" in bad.stderr
