"""Fixtures: a dualrep server to talk to (the Rust test suite starts one and passes it in
``DUALREP_TEST_URL`` and ``DUALREP_TEST_TOKEN``), and env servers on free ports."""

from __future__ import annotations

import os
from typing import Iterator

import pytest

from dualrep import Client
from dualrep.env import EnvServer
from dualrep.scenes import pendulum


@pytest.fixture
def client() -> Client:
    url = os.environ.get("DUALREP_TEST_URL")
    if not url:
        pytest.skip("needs a running dualrep server: DUALREP_TEST_URL and DUALREP_TEST_TOKEN (the Rust suite's python_client tests pass them)")
    return Client(url, os.environ.get("DUALREP_TEST_TOKEN"))


@pytest.fixture
def pendulum_env() -> Iterator[EnvServer]:
    with EnvServer("Pendulum-v1", predicates=pendulum, quiet=True) as server:
        yield server
