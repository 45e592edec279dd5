"""Trainer against a scripted websocket server (no dualrep server needed): an answer refused as
``rate_limited`` is sent again once the refusal's ``retry_after_ms`` has passed, not before."""

from __future__ import annotations

import json
import threading
import time
from typing import Any, Iterator, List, Tuple

import pytest
from websockets.sync.server import ServerConnection, serve

from dualrep import Trainer

RETRY_AFTER_MS = 300


@pytest.fixture
def rate_limiting_server() -> Iterator[Tuple[str, List[Tuple[float, Any]]]]:
    """A session that asks one query, refuses the first answer as rate limited, acknowledges
    the next, then ends. Yields its URL and the answers it received with their times."""
    received: List[Tuple[float, Any]] = []

    def session(ws: ServerConnection) -> None:
        ws.send(json.dumps({"type": "hello", "kind": "evaluative"}))
        ws.send(json.dumps({"type": "query", "id": 0, "kind": "evaluative", "holding": []}))
        first = json.loads(ws.recv(timeout=10))
        received.append((time.monotonic(), first))
        ws.send(json.dumps({
            "type": "error",
            "code": "rate_limited",
            "message": f"this one was not taken: send it again in {RETRY_AFTER_MS} ms",
            "id": 0,
            "retry_after_ms": RETRY_AFTER_MS,
        }))
        again = json.loads(ws.recv(timeout=10))
        received.append((time.monotonic(), again))
        ws.send(json.dumps({"type": "ack", "id": 0, "value": again["value"]}))
        ws.send(json.dumps({"type": "ended", "status": "finished", "reason": None}))
        try:
            ws.recv(timeout=5)  # until the trainer closes
        except Exception:
            pass

    with serve(session, "127.0.0.1", 0) as server:
        thread = threading.Thread(target=server.serve_forever, daemon=True)
        thread.start()
        host, port = server.socket.getsockname()[:2]
        yield f"ws://{host}:{port}/ws/sessions/s?token=t", received
        server.shutdown()


def test_a_rate_limited_answer_is_sent_again_after_retry_after_ms(rate_limiting_server: Tuple[str, List[Tuple[float, Any]]]) -> None:
    url, received = rate_limiting_server
    with Trainer(url) as trainer:
        result = trainer.run(lambda query: 1, timeout=10)
    assert result.status == "finished"
    assert result.answered == {0: 1}
    assert result.errors == [], "a refusal that was retried is not an error"
    (first_at, first), (again_at, again) = received
    assert first == again == {"type": "answer", "id": 0, "value": 1}
    assert again_at - first_at >= RETRY_AFTER_MS / 1000.0 * 0.95, "not before the wait it was told"
