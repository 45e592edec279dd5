"""A client of dualrep's REST API (``GET /api/openapi.json`` describes it): launch, list,
inspect, stop and resume sessions, read their answers, episodes and exports. Standard library
only (``urllib``)."""

from __future__ import annotations

import json
import time
import urllib.error
import urllib.parse
import urllib.request
from typing import Any, Dict, Iterable, List, Mapping, Optional

#: Statuses after which a session does nothing more until resumed.
ENDED = ("finished", "failed", "stopped", "interrupted")


class ApiError(Exception):
    """The API refused: ``status`` is the HTTP status, ``code`` the stable error code."""

    def __init__(self, status: int, code: str, message: str) -> None:
        super().__init__(f"{status} {code}: {message}")
        self.status = status
        self.code = code
        self.message = message


def _object(value: Any) -> Dict[str, Any]:
    if not isinstance(value, dict):
        raise ApiError(200, "unexpected_reply", f"expected a JSON object, got {value!r:.200}")
    return value


def _objects(value: Any) -> List[Dict[str, Any]]:
    if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
        raise ApiError(200, "unexpected_reply", f"expected a list of JSON objects, got {value!r:.200}")
    return value


def _text(value: Any) -> str:
    if not isinstance(value, str):
        raise ApiError(200, "unexpected_reply", f"expected text, got {value!r:.200}")
    return value


class Client:
    """``Client("http://127.0.0.1:8080", token)``: the researcher's token (``data/token``)."""

    def __init__(self, url: str = "http://127.0.0.1:8080", token: Optional[str] = None, timeout: float = 30.0) -> None:
        self.url = url.rstrip("/")
        self.token = token
        self.timeout = timeout

    # ---- plumbing ----------------------------------------------------------------------

    def request(self, method: str, path: str, body: Optional[Mapping[str, Any]] = None) -> Any:
        """One API call; the decoded JSON reply (text for non-JSON replies)."""
        data = json.dumps(body).encode() if body is not None else None
        req = urllib.request.Request(self.url + path, data=data, method=method)
        if data is not None:
            req.add_header("Content-Type", "application/json")
        if self.token:
            req.add_header("Authorization", f"Bearer {self.token}")
        try:
            with urllib.request.urlopen(req, timeout=self.timeout) as reply:
                raw = reply.read()
                kind = reply.headers.get("Content-Type", "")
        except urllib.error.HTTPError as e:
            raw = e.read()
            try:
                error = json.loads(raw)["error"]
                raise ApiError(e.code, error.get("code", "error"), error.get("message", "")) from None
            except (ValueError, KeyError, TypeError):
                raise ApiError(e.code, "http_error", raw.decode(errors="replace")) from None
        if "json" in kind and "ndjson" not in kind:
            return json.loads(raw)
        return raw.decode()

    # ---- sessions ----------------------------------------------------------------------

    def launch(
        self,
        method: str,
        *,
        task: Optional[str] = None,
        env_url: Optional[str] = None,
        trainer: str = "synthetic",
        seed: int = 0,
        steps: Optional[int] = None,
        queries: Optional[int] = None,
        params: Optional[Mapping[str, Any]] = None,
    ) -> Dict[str, Any]:
        """Launch a session: a built-in ``task``, an env served at ``env_url`` (``tcp://...``,
        with ``task`` to reuse that task's scene graph, features and expert), or both. Returns
        ``{"id", "status", "trainer_url"}``."""
        body: Dict[str, Any] = {"method": method, "trainer": trainer, "seed": seed}
        if task is not None:
            body["task"] = task
        if env_url is not None:
            body["env"] = {"url": env_url}
        if steps is not None:
            body["steps"] = steps
        if queries is not None:
            body["queries"] = queries
        if params:
            body["params"] = dict(params)
        return _object(self.request("POST", "/api/sessions", body))

    def sessions(self) -> List[Dict[str, Any]]:
        return _objects(self.request("GET", "/api/sessions"))

    def session(self, session_id: str) -> Dict[str, Any]:
        return _object(self.request("GET", f"/api/sessions/{session_id}"))

    def stop(self, session_id: str) -> Dict[str, Any]:
        return _object(self.request("POST", f"/api/sessions/{session_id}/stop"))

    def resume(self, session_id: str) -> Dict[str, Any]:
        return _object(self.request("POST", f"/api/sessions/{session_id}/resume"))

    def answers(self, session_id: str) -> List[Dict[str, Any]]:
        return _objects(self.request("GET", f"/api/sessions/{session_id}/answers"))

    def episodes(self, session_id: str) -> List[Dict[str, Any]]:
        return _objects(self.request("GET", f"/api/sessions/{session_id}/episodes"))

    def alignment(self, session_id: str) -> List[Dict[str, Any]]:
        return _objects(self.request("GET", f"/api/sessions/{session_id}/alignment"))

    def export(self, session_id: str, format: str = "jsonl") -> str:
        """The session's export: JSONL (the session, every answer and episode) or CSV."""
        query = urllib.parse.urlencode({"format": format})
        return _text(self.request("GET", f"/api/sessions/{session_id}/export?{query}"))

    def export_records(self, session_id: str) -> List[Dict[str, Any]]:
        """The JSONL export, parsed: one dict per line, ``record`` naming its kind."""
        return [json.loads(line) for line in self.export(session_id).splitlines() if line]

    def tasks(self) -> Any:
        return self.request("GET", "/api/tasks")

    def wait(self, session_id: str, until: Iterable[str] = ENDED, timeout: float = 600.0, poll: float = 0.2) -> Dict[str, Any]:
        """Poll until the session's status is one of ``until``; its view then."""
        wanted = set(until)
        deadline = time.monotonic() + timeout
        while True:
            view = self.session(session_id)
            if view["status"] in wanted:
                return view
            if time.monotonic() > deadline:
                raise TimeoutError(f"session {session_id} is still {view['status']} after {timeout} s")
            time.sleep(poll)

    def websocket_url(self, session_id: str, token: str) -> str:
        """The trainer websocket of a session, for :class:`dualrep.Trainer`."""
        base = "ws" + self.url[len("http"):] if self.url.startswith("http") else self.url
        return f"{base}/ws/sessions/{session_id}?token={urllib.parse.quote(token)}"
