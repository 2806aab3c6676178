"""Fixtures of the API tests: a studio app on a temporary data directory, no live source."""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

from studio.web import Settings, create_app

TINY_RUN = {"planning": "zero", "experiments": 2, "episodes": 4, "seed": 1}
"""A run that trains in well under a second."""


def make_settings(data_dir: Path, **overrides: object) -> Settings:
    """Settings for tests: tmp data dir, the TestClient's host allowed, one training thread."""
    values: dict[str, object] = {
        "data_dir": data_dir,
        "source": None,
        "allowed_hosts": ("testserver",),
        "run_workers": 1,
        **overrides,
    }
    return Settings(**values)


@pytest.fixture
def open_client(tmp_path: Path) -> Iterator[Callable[..., TestClient]]:
    """Open studio clients on ``tmp_path`` (several in turn, to test restarts); all closed after."""
    opened: list[TestClient] = []

    def open_(**overrides: object) -> TestClient:
        client = TestClient(create_app(make_settings(tmp_path, **overrides)))
        client.__enter__()
        opened.append(client)
        return client

    yield open_
    for client in reversed(opened):
        client.__exit__(None, None, None)


@pytest.fixture
def client(open_client: Callable[..., TestClient]) -> TestClient:
    """A studio client on a fresh temporary data directory."""
    return open_client()


def wait_for(predicate: Callable[[], object], timeout: float = 20.0, step: float = 0.05) -> bool:
    """Poll ``predicate`` until it is true or ``timeout`` seconds pass; whether it became true."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(step)
    return False


def wait_captured(client: TestClient, seconds: float) -> None:
    """Wait until the capture under way has taken in ``seconds`` more of the source's time."""
    start = client.get("/api/capture").json()["seconds"]
    assert wait_for(lambda: client.get("/api/capture").json()["seconds"] >= start + seconds, 30), (
        "the capture took in no frames"
    )


def wait_run(client: TestClient, run_id: str, timeout: float = 60.0) -> dict:
    """Block until a run is no longer queued or running; returns its ``RunPublic``."""
    assert client.app.state.studio.runs.wait_idle(timeout), "the run did not finish in time"
    return client.get(f"/api/runs/{run_id}").json()
