"""Client and Trainer against a running dualrep server (passed in by the Rust suite), on a
Gymnasium env served from this process: a person's DREF and DRPL sessions answered by Python
functions, and the REST calls around them."""

from __future__ import annotations

import base64
from typing import Any, Mapping

import pytest

from dualrep import ApiError, Client, Trainer
from dualrep.env import EnvServer

FAST = {"hidden": [16, 16], "batch_size": 32, "pace_hz": 1000, "answer_timeout_s": 30}


def test_a_scripted_trainer_answers_a_dref_session_on_a_remote_env(client: Client, pendulum_env: EnvServer) -> None:
    launched = client.launch("dref", env_url=pendulum_env.url, trainer="human", steps=150, params=FAST)
    shown: list = []

    def judge(query: Mapping[str, Any]) -> int:
        shown.append(query)
        return 1 if "pendulum upright" in query["holding"] else -1

    with Trainer.for_session(client, launched) as trainer:
        assert trainer.hello["kind"] == "evaluative"
        result = trainer.run(judge, timeout=120)
    assert result.status == "finished", result
    assert result.frames == 150 and not result.errors
    # DREF asks at every step until more than k + 1 abstract states have had feedback.
    assert len(result.answered) >= 5 and len(result.answered) == len(shown)
    clip = shown[0]["clip"]
    assert clip["geometry"] == {"task": "remote", "env": "Pendulum-v1", "frame_size": [500, 500]}
    frame = clip["frames"][-1]["frame"]
    assert frame["media_type"] == "image/png"
    assert base64.b64decode(frame["data"]).startswith(b"\x89PNG")
    stored = {a["query_id"]: a["value"] for a in client.answers(launched["id"])}
    assert stored == {k: int(v) for k, v in result.answered.items()}
    view = client.session(launched["id"])
    assert (view["task"], view["env"], view["progress"]) == ("remote", {"url": pendulum_env.url}, 150)
    records = client.export_records(launched["id"])
    assert records[0]["record"] == "session"
    assert sum(r["record"] == "answer" for r in records) == len(stored)
    assert "query_id" in client.export(launched["id"], format="csv").splitlines()[0]


def test_a_preference_library_answers_drpl_pairs_of_replayed_clips(client: Client, pendulum_env: EnvServer) -> None:
    params = {"trajectories": 8, "pace_hz": 1000, "answer_timeout_s": 30}
    launched = client.launch("drpl", env_url=pendulum_env.url, trainer="human", queries=4, params=params)
    pairs: list = []

    def prefer(query: Mapping[str, Any]) -> str:
        pairs.append(query)
        # Prefer the clip whose pendulum ends more upright (the observation's cos theta).
        left = query["left"]["frames"][-1]["observation"][0]
        right = query["right"]["frames"][-1]["observation"][0]
        return "left" if left >= right else "right"

    with Trainer.for_session(client, launched) as trainer:
        assert trainer.hello["kind"] == "preference"
        result = trainer.run(prefer, timeout=120)
    assert result.status == "finished", result
    assert len(result.answered) == 4
    for q in pairs:
        assert q["predicate"]["name"] in {"upright", "right_side", "fast", "clockwise"}
        for side in ("left", "right"):
            assert q[side]["frames"] and all("frame" in f for f in q[side]["frames"])


def test_stop_resume_and_refusals_come_back_as_api_errors(client: Client, pendulum_env: EnvServer) -> None:
    launched = client.launch("sac", env_url=pendulum_env.url, steps=200_000, params={"hidden": [8, 8], "batch_size": 16})
    client.wait(launched["id"], until=("running",), timeout=60)
    stopped = client.stop(launched["id"])
    assert stopped["status"] in ("stopped", "running")
    assert client.wait(launched["id"], timeout=60)["status"] == "stopped"
    assert client.resume(launched["id"])["status"] in ("queued", "running")
    client.wait(launched["id"], until=("running",), timeout=60)
    client.stop(launched["id"])
    assert launched["id"] in {s["id"] for s in client.sessions()}
    with pytest.raises(ApiError) as e:
        client.launch("dref", env_url="http://not-tcp:1", trainer="synthetic")
    assert e.value.status == 422 and "tcp://" in e.value.message
    with pytest.raises(ApiError) as e:
        client.launch("dref", trainer="synthetic")
    assert e.value.status == 422 and "env" in e.value.message
    with pytest.raises(ApiError) as e:
        client.stop("nosuchsession")
    assert e.value.status == 404


def test_an_unreachable_env_fails_its_session_with_the_reason(client: Client) -> None:
    with EnvServer("Pendulum-v1", quiet=True) as gone:
        url = gone.url
    launched = client.launch("sac", env_url=url, steps=100)
    view = client.wait(launched["id"], timeout=60)
    assert view["status"] == "failed"
    assert "unreachable" in view["reason"] and url in view["reason"]
