"""Answer a session's queries from Python over the trainer websocket (docs/protocol.md): a
scripted or noisy trainer, or another preference library, in place of a person.

>>> def judge(query):                        # evaluative: 1, 0 or -1; preference: "left", ...
...     return 1 if "upright" in query["holding"] else -1
>>> Trainer.for_session(client, launched).run(judge)      # doctest: +SKIP
"""

from __future__ import annotations

import json
import time
import urllib.parse
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Mapping, Optional, Set, Union

from websockets.sync.client import ClientConnection, connect

from .client import Client

Answer = Union[int, str, None]
#: ``query -> answer``: the query message as the server sent it (``kind``, ``holding``,
#: ``action``, ``clip``... or ``left``/``right``), the answer 1/0/-1 for evaluative queries and
#: ``"left"``/``"right"``/``"equal"``/``"skip"`` for preferences. ``None`` leaves the query
#: unanswered (it times out as "no feedback").
AnswerFn = Callable[[Mapping[str, Any]], Answer]


@dataclass
class Result:
    """What a :meth:`Trainer.run` saw."""

    status: str
    reason: Optional[str]
    answered: Dict[int, Any] = field(default_factory=dict)
    frames: int = 0
    errors: List[Dict[str, Any]] = field(default_factory=list)


class Trainer:
    """A websocket trainer of one session."""

    def __init__(self, url: str, open_timeout: float = 10.0) -> None:
        self.url = url
        # `connect(...)` is the connection itself up to websockets 17.0 and a context manager
        # that opens it from 17.1 on; entering it gives the connection in both.
        self.ws: ClientConnection = connect(url, open_timeout=open_timeout, max_size=64 << 20).__enter__()
        self.hello: Dict[str, Any] = self._receive(open_timeout) or {}

    @classmethod
    def for_session(cls, client: Client, launched: Mapping[str, Any]) -> "Trainer":
        """The trainer of a session ``client.launch`` returned (its ``trainer_url`` token)."""
        token = urllib.parse.parse_qs(urllib.parse.urlparse(launched["trainer_url"]).query)["token"][0]
        return cls(client.websocket_url(launched["id"], token))

    def _receive(self, timeout: Optional[float]) -> Optional[Dict[str, Any]]:
        try:
            text = self.ws.recv(timeout=timeout)
        except TimeoutError:
            return None
        message = json.loads(text)
        if not isinstance(message, dict):
            raise ValueError(f"the server sent {message!r:.200}, not a JSON object")
        return message

    def answer(self, query_id: int, value: Answer) -> None:
        self.ws.send(json.dumps({"type": "answer", "id": query_id, "value": value}))

    def undo(self, query_id: int) -> None:
        self.ws.send(json.dumps({"type": "undo", "id": query_id}))

    def run(self, answer: AnswerFn, timeout: float = 600.0) -> Result:
        """Answer every query with ``answer`` until the session ends (or ``timeout`` seconds
        pass with nothing from the server); what was acknowledged, and how it ended.

        An answer refused as ``rate_limited`` is sent again after the ``retry_after_ms`` the
        refusal names (the server kept nothing of it), unless the query closed meanwhile; such
        refusals are not counted in ``Result.errors``."""
        result = Result(status="running", reason=None)
        asked: Set[int] = set()
        # Answers given but not acknowledged yet, to send again when one is refused for rate.
        given: Dict[int, Answer] = {}
        # query id -> when (time.monotonic()) to send its answer again.
        retry_at: Dict[int, float] = {}
        last_heard = time.monotonic()
        while True:
            now = time.monotonic()
            for query_id in [q for q, at in retry_at.items() if at <= now]:
                del retry_at[query_id]
                if query_id in given:
                    self.answer(query_id, given[query_id])
            silent_for = now - last_heard
            wait = timeout - silent_for
            if retry_at:
                wait = min(wait, max(0.0, min(retry_at.values()) - now))
            message = self._receive(max(0.0, wait))
            if message is None:
                if time.monotonic() - last_heard >= timeout:
                    raise TimeoutError(f"nothing from the session for {timeout} s")
                continue  # a retry is due
            last_heard = time.monotonic()
            kind = message.get("type")
            if kind == "query":
                query_id = int(message["id"])
                if query_id in asked:
                    continue  # sent again to a joining client: answered already
                asked.add(query_id)
                value = answer(message)
                if value is not None:
                    given[query_id] = value
                    self.answer(query_id, value)
            elif kind == "undone":
                asked.discard(int(message["id"]))
            elif kind == "ack":
                query_id = int(message["id"])
                given.pop(query_id, None)
                result.answered[query_id] = message["value"]
            elif kind == "withdrawn":
                query_id = int(message["id"])
                given.pop(query_id, None)
                retry_at.pop(query_id, None)
            elif kind == "frame":
                result.frames += 1
            elif kind == "error" and message.get("code") == "rate_limited" and message.get("id") in given:
                retry_at[int(message["id"])] = time.monotonic() + float(message.get("retry_after_ms", 1000)) / 1000.0
            elif kind == "error":
                result.errors.append(message)
            elif kind == "ended":
                result.status = message.get("status", "ended")
                result.reason = message.get("reason")
                self.close()
                return result

    def close(self) -> None:
        self.ws.close()

    def __enter__(self) -> "Trainer":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def wait_for_status(client: Client, session_id: str, status: str, timeout: float = 60.0) -> Dict[str, Any]:
    """Poll ``client`` until the session has ``status`` (a helper for scripts and tests)."""
    deadline = time.monotonic() + timeout
    while True:
        view = client.session(session_id)
        if view["status"] == status:
            return view
        if time.monotonic() > deadline:
            raise TimeoutError(f"session {session_id} is {view['status']}, not {status}")
        time.sleep(0.1)
