"""The studio stays responsive: blocking file work stays off the event loop (a request made while
an upload is being parsed is answered before the parse ends, and listing recordings during a
capture never reads the growing file), and training runs below the studio's CPU priority."""

from __future__ import annotations

import threading
from collections.abc import Callable
from pathlib import Path

import pytest
from fastapi.testclient import TestClient

import studio.web.services._store as store_module
from tests.web.conftest import TINY_RUN, wait_for

SAMPLES = Path(__file__).resolve().parents[2] / "studio" / "samples"
HOLD_S = 20.0
"""How long the held parser waits before giving up (only reached if the loop were blocked)."""


@pytest.mark.parametrize("kind", ["recording", "policy"])
def test_a_request_is_answered_while_an_upload_is_parsed(
    open_client: Callable[..., TestClient], monkeypatch: pytest.MonkeyPatch, kind: str
) -> None:
    parsing, release, finished = threading.Event(), threading.Event(), threading.Event()
    reader = "summarize_any_recording" if kind == "recording" else "load_any_policy"
    real = getattr(store_module, reader)

    def held(path: Path):  # the parser of an upload, held until the test lets it go
        if path.name.startswith(".upload-"):
            parsing.set()
            release.wait(HOLD_S)
            finished.set()
        return real(path)

    monkeypatch.setattr(store_module, reader, held)
    client = open_client()
    if kind == "recording":
        sample = next(SAMPLES.glob("*.tape.csv"))
        url, filename = "/api/recordings", "mine.tape.csv"
    else:
        client.post("/api/runs", json={"planning": "zero", "experiments": 1, "episodes": 2})
        assert client.app.state.studio.runs.wait_idle(60)
        run = client.get("/api/runs").json()[0]["id"]
        sample = client.app.state.studio.runs.get(run).policy_path
        url, filename = "/api/policies", "mine.policy.npz"
    answers: list[int] = []
    upload = threading.Thread(
        target=lambda: answers.append(
            client.post(url, files={"file": (filename, sample.read_bytes())}).status_code
        )
    )
    upload.start()
    try:
        assert parsing.wait(HOLD_S), "the upload never reached its parser"
        assert client.get("/api/capture").status_code == 200
        assert client.get("/api/config").status_code == 200
        assert not finished.is_set(), "the other requests waited for the parse to end"
    finally:
        release.set()
        upload.join(HOLD_S)
    assert answers == [201]


def test_listing_during_a_capture_never_reads_the_live_file(
    open_client: Callable[..., TestClient], monkeypatch: pytest.MonkeyPatch
) -> None:
    read: list[str] = []
    real = store_module.summarize_any_recording

    def counted(path: Path):
        read.append(path.name)
        return real(path)

    monkeypatch.setattr(store_module, "summarize_any_recording", counted)
    client = open_client(source="simulator")
    assert client.post("/api/capture/start", json={"name": "live"}).status_code == 200
    assert wait_for(lambda: client.get("/api/capture").json()["frames"] > 200)
    for _ in range(3):
        listed = client.get("/api/recordings")
        assert listed.status_code == 200
        assert "live" not in [r["name"] for r in listed.json()]
    assert "live.tape.csv" not in read
    assert client.get("/api/capture").json()["active"]
    stopped = client.post("/api/capture/stop")
    assert stopped.status_code == 200 and stopped.json()["frames"] > 200
    assert "live" in [r["name"] for r in client.get("/api/recordings").json()]


def test_training_runs_below_the_studios_priority(
    client: TestClient, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The kernels' threads lower their own CPU priority (the studio's threads keep theirs), so
    a heavy run takes only the CPU the API, the pipeline and the scene leave."""
    import os

    import studio.learning.tabular._dynaq as dynaq
    from studio.learning import ArmGrid, DynaQConfig, run_experiments
    from studio.web.services._runs import TRAINING_NICENESS

    seen: list[int] = []
    real = dynaq._run_experiment

    def observed(*args):
        seen.append(os.getpriority(os.PRIO_PROCESS, threading.get_native_id()))
        return real(*args)

    monkeypatch.setattr(dynaq, "_run_experiment", observed)
    base = os.getpriority(os.PRIO_PROCESS, os.getpid())
    mine = os.getpriority(os.PRIO_PROCESS, threading.get_native_id())
    run = client.post("/api/runs", json=TINY_RUN).json()
    assert client.app.state.studio.runs.wait_idle(60)
    assert client.get(f"/api/runs/{run['id']}").json()["status"] == "done"
    assert seen and all(n == min(base + TRAINING_NICENESS, 19) for n in seen)
    assert os.getpriority(os.PRIO_PROCESS, threading.get_native_id()) == mine
    # a plain call (the CLI's) leaves the priority alone
    seen.clear()
    run_experiments(ArmGrid().mdp(), DynaQConfig(planning="zero"), 2, 2, seed=1, workers=2)
    assert seen == [base, base]
