"""Serve an environment to dualrep over its env protocol (docs/env-protocol.md).

One connection is one episode stream: dualrep sends ``hello``, then ``reset`` and ``step``
requests, and the server answers each, in order. Given a factory (a Gymnasium id, or a
callable that makes an env), every connection gets an env of its own; given one env object (a
robot), connections take turns on it, one at a time.
"""

from __future__ import annotations

import socket
import socketserver
import sys
import threading
import traceback
from typing import Any, Callable, Dict, Mapping, Optional, Tuple, Union

from .adapter import (
    Declared,
    FeatureFn,
    PredicateFn,
    Space,
    SuccessFn,
    describe,
    flat,
    holding,
)
from .png import frame_of
from .protocol import PROTOCOL, ProtocolError, read_message, write_message

EnvFactory = Callable[[], Any]


def _gym_factory(env_id: str, render: bool, kwargs: Mapping[str, Any]) -> EnvFactory:
    def make() -> Any:
        import gymnasium as gym

        return gym.make(env_id, render_mode="rgb_array" if render else None, **kwargs)

    return make


class Connection:
    """One dualrep connection on one env: answers its requests in order."""

    def __init__(self, server: "EnvServer", env: Any, rfile: Any, wfile: Any) -> None:
        self.server = server
        self.env = env
        self.rfile = rfile
        self.wfile = wfile
        self.obs_space, self.act_space, self.declared = server.describe(env)
        self.in_episode = False

    def serve(self) -> None:
        while True:
            try:
                request = read_message(self.rfile)
            except ProtocolError as e:
                self._send({"type": "error", "message": f"malformed request: {e}"})
                return
            if request is None:
                return
            kind = request["type"]
            try:
                if kind == "hello":
                    self._hello(request)
                elif kind == "reset":
                    self._reset(request)
                elif kind == "step":
                    self._step(request)
                elif kind == "close":
                    self._send({"type": "close"})
                    return
                else:
                    self._send({"type": "error", "message": f"unknown request type {kind!r}"})
            except (BrokenPipeError, ConnectionResetError):
                return
            except Exception as e:  # the env's own failure: tell dualrep why, then go on
                self.server.log(f"{kind} failed: {traceback.format_exc(limit=3)}")
                self._send({"type": "error", "message": f"{kind} failed: {type(e).__name__}: {e}"})

    def _send(self, message: Dict[str, Any], attachment: Optional[bytes] = None) -> None:
        write_message(self.wfile, message, attachment)

    def _hello(self, request: Mapping[str, Any]) -> None:
        if request.get("protocol") != PROTOCOL:
            self._send({"type": "error", "message": f"this env speaks protocol {PROTOCOL}, not {request.get('protocol')}"})
            return
        d = self.declared
        env = {
            "id": d.id,
            "observation_space": self.obs_space.message(),
            "action_space": self.act_space.message(),
            "control_hz": d.control_hz,
            "max_episode_steps": d.max_episode_steps,
            "predicates": [{"name": n, "label": l} for n, l in d.predicates],
            "features": d.features,
            "render": d.render,
            "deterministic": d.deterministic,
        }
        self._send({"type": "hello", "protocol": PROTOCOL, "env": env})

    def _frame(self, render: bool) -> Tuple[Optional[Dict[str, Any]], Optional[bytes]]:
        if not render:
            return None, None
        if not self.declared.render:
            raise RuntimeError("a frame was asked for, but this env cannot render")
        fmt, data, width, height = frame_of(self.env.render())
        return {"format": fmt, "width": width, "height": height, "bytes": len(data)}, data

    def _reset(self, request: Mapping[str, Any]) -> None:
        seed = request.get("seed")
        result = self.env.reset(seed=int(seed) if seed is not None else None)
        obs, info = result if isinstance(result, tuple) and len(result) == 2 else (result, {})
        self.in_episode = True
        reply: Dict[str, Any] = {
            "type": "reset",
            "obs": flat(obs),
            "holding": holding(self.server.predicate_fn, self.declared, obs, None, info or {}),
        }
        header, data = self._frame(bool(request.get("render")))
        if header is not None:
            reply["frame"] = header
        self._send(reply, data)

    def _action(self, values: Any) -> Any:
        space = self.act_space
        if not isinstance(values, list) or len(values) != len(space.low):
            raise ValueError(f"expected an action of {len(space.low)} numbers, got {values!r}")
        try:
            import numpy as np
        except ImportError:  # pragma: no cover
            return values
        dtype = space.dtype if space.dtype is not None else np.float32
        return np.asarray(values, dtype=dtype).reshape(space.shape)

    def _step(self, request: Mapping[str, Any]) -> None:
        if not self.in_episode:
            raise RuntimeError("step before reset (or after the episode ended)")
        action = self._action(request.get("action"))
        obs, reward, terminated, truncated, info = self.env.step(action)
        info = info or {}
        terminated, truncated = bool(terminated), bool(truncated)
        reply: Dict[str, Any] = {
            "type": "step",
            "obs": flat(obs),
            "reward": float(reward),
            "terminated": terminated,
            "truncated": truncated,
            "holding": holding(self.server.predicate_fn, self.declared, obs, action, info),
        }
        if self.server.feature_fn is not None:
            reply["features"] = [float(v) for v in self.server.feature_fn(obs, action, info)]
        if terminated or truncated:
            self.in_episode = False
            success = self.server.success(obs, float(reward), terminated, truncated, info)
            if success is not None:
                reply["success"] = bool(success)
        header, data = self._frame(bool(request.get("render")))
        if header is not None:
            reply["frame"] = header
        self._send(reply, data)


class _Handler(socketserver.StreamRequestHandler):
    server: "_TcpServer"

    def setup(self) -> None:
        super().setup()
        self.connection.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)

    def handle(self) -> None:
        owner = self.server.owner
        with owner.turn():
            env = owner.env_for_connection()
            try:
                Connection(owner, env, self.rfile, self.wfile).serve()
            finally:
                owner.release(env)


class _TcpServer(socketserver.ThreadingTCPServer):
    daemon_threads = True
    allow_reuse_address = True
    owner: "EnvServer"


class EnvServer:
    """An env (or a factory of envs) behind a TCP port.

    ``env`` is a Gymnasium id (``"Pendulum-v1"``), a callable that returns a new env per
    connection, or one env object that every connection shares (a robot: one connection at a
    time). The functions declare and evaluate the scene graph's predicates, DRPL features and
    success; ``env_id``, ``control_hz``, ``max_episode_steps`` and ``deterministic`` override
    what the env says of itself.
    """

    def __init__(
        self,
        env: Union[str, EnvFactory, Any],
        *,
        predicates: Optional[PredicateFn] = None,
        features: Optional[FeatureFn] = None,
        success: Optional[SuccessFn] = None,
        host: str = "127.0.0.1",
        port: int = 0,
        env_id: Optional[str] = None,
        control_hz: Optional[float] = None,
        max_episode_steps: Optional[int] = None,
        deterministic: Optional[bool] = None,
        render: bool = True,
        gym_kwargs: Optional[Mapping[str, Any]] = None,
        quiet: bool = False,
    ) -> None:
        self.predicate_fn = predicates
        self.feature_fn = features
        self.success_fn = success
        self.overrides = dict(
            env_id=env_id,
            control_hz=control_hz,
            max_episode_steps=max_episode_steps,
            deterministic=deterministic,
        )
        self.quiet = quiet
        self._shared: Optional[Any] = None
        self._lock = threading.Lock()
        if isinstance(env, str):
            self._factory: Optional[EnvFactory] = _gym_factory(env, render, gym_kwargs or {})
            self.overrides["env_id"] = env_id or env
        elif isinstance(env, type) or (callable(env) and not hasattr(env, "step")):
            self._factory = env  # a class or a function: a new env per connection
        elif hasattr(env, "reset") and hasattr(env, "step"):
            self._factory = None
            self._shared = env
        else:
            raise TypeError("env must be a Gymnasium id, a factory, or an object with reset and step")
        # Read the description once now, so that a bad env fails here, not on a connection.
        probe = self._shared if self._shared is not None else self._factory()  # type: ignore[misc]
        self.id = self.describe(probe)[2].id
        if self._shared is None:
            self._spare: Optional[Any] = probe
        else:
            self._spare = None
        self._server = _TcpServer((host, port), _Handler)
        self._server.owner = self
        self._thread: Optional[threading.Thread] = None

    @property
    def address(self) -> Tuple[str, int]:
        host, port = self._server.server_address[:2]
        return str(host), int(port)

    @property
    def url(self) -> str:
        host, port = self.address
        return f"tcp://{host}:{port}"

    def describe(self, env: Any) -> Tuple[Space, Space, Declared]:
        return describe(
            env,
            predicate_fn=self.predicate_fn,
            feature_fn=self.feature_fn,
            **self.overrides,  # type: ignore[arg-type]
        )

    def success(self, obs: Any, reward: float, terminated: bool, truncated: bool, info: Mapping[str, Any]) -> Optional[bool]:
        if self.success_fn is not None:
            return bool(self.success_fn(obs, reward, terminated, truncated, info))
        if "is_success" in info:
            return bool(info["is_success"])
        return None

    def turn(self) -> Any:
        """A shared env serves one connection at a time; envs of their own need no turns."""
        if self._shared is not None:
            return self._lock
        return _NoLock()

    def env_for_connection(self) -> Any:
        if self._shared is not None:
            return self._shared
        with self._lock:
            spare, self._spare = self._spare, None
        return spare if spare is not None else self._factory()  # type: ignore[misc]

    def release(self, env: Any) -> None:
        if self._shared is None and hasattr(env, "close"):
            env.close()

    def log(self, text: str) -> None:
        if not self.quiet:
            print(f"dualrep.env: {text}", file=sys.stderr, flush=True)

    def serve_forever(self) -> None:
        """Serve on this thread until :meth:`shutdown`."""
        self._server.serve_forever(poll_interval=0.1)

    def start(self) -> "EnvServer":
        """Serve on a background thread (tests, notebooks)."""
        self._thread = threading.Thread(target=self.serve_forever, name="dualrep-env", daemon=True)
        self._thread.start()
        return self

    def shutdown(self) -> None:
        self._server.shutdown()
        self._server.server_close()
        if self._thread is not None:
            self._thread.join()

    def __enter__(self) -> "EnvServer":
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.shutdown()


class _NoLock:
    def __enter__(self) -> None:
        return None

    def __exit__(self, *exc: object) -> None:
        return None


def serve(env: Union[str, EnvFactory, Any], *, port: int = 0, host: str = "127.0.0.1", **options: Any) -> None:
    """Serve ``env`` until interrupted, printing the URL to give dualrep (``env: {"url": ...}``)."""
    server = EnvServer(env, host=host, port=port, **options)
    print(f"dualrep.env: serving {server.id} on {server.url}", flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        pass
    finally:
        server.shutdown()
