"""Two studios on one data folder: neither destroys what the other is making.

Studio A and studio B are two apps on the same folder, as two ``studio serve`` processes would
be. Locks are ``flock`` locks, which two open files of one process contend for exactly as two
processes do, so two apps in one test process see each other as two processes would.
"""

from __future__ import annotations

import numpy as np
import pytest

from studio.capture import RecordingError, RecordingWriter, TapeFrame
from studio.samples import SAMPLES_DIR
from studio.web.services._store import recording_store
from tests.web.conftest import TINY_RUN, wait_for, wait_run


def _names(client) -> dict[str, dict]:
    return {r["name"]: r for r in client.get("/api/recordings").json()}


def test_a_capture_in_progress_is_safe_from_a_second_studio(open_client, tmp_path):
    a, b = open_client(), open_client()
    sample = sorted(SAMPLES_DIR.glob("*.tape.csv"))[0].name.removesuffix(".tape.csv")
    a.put("/api/source", json={"kind": "recording", "recording": sample, "loop": True})
    assert a.post("/api/capture/start", json={"name": "take1"}).status_code == 200
    assert wait_for(lambda: a.get("/api/capture").json()["frames"] >= 20)

    listed = _names(b)["take1"]
    assert listed["capturing"] is True and listed["recovered"] is False
    for response in (
        b.delete("/api/recordings/take1"),
        b.patch("/api/recordings/take1", json={"notes": "mine now"}),
        b.patch("/api/recordings/take1", json={"name": "taken"}),
        b.post(f"/api/recordings/{sample}/copy", json={"name": "take1"}),
    ):
        assert response.status_code == 409, response.text
    assert "another studio" in b.delete("/api/recordings/take1").json()["detail"]
    upload = b.post(
        "/api/recordings",
        files={"file": ("take1.tape.csv", (SAMPLES_DIR / f"{sample}.tape.csv").read_bytes())},
    )
    assert upload.status_code == 201 and upload.json()["name"] == "take1-2"  # never over it

    stopped = a.post("/api/capture/stop")
    assert stopped.status_code == 200, stopped.text
    assert stopped.json()["frames"] >= 20 and stopped.json()["recovered"] is False
    listed = _names(b)["take1"]
    assert listed["capturing"] is False and listed["recovered"] is False
    assert listed["frames"] == stopped.json()["frames"]
    assert b.delete("/api/recordings/take1").status_code == 204  # now it is B's to delete


def test_a_file_being_captured_is_never_deleted_by_the_store(tmp_path):
    """The store's delete checks the capture's lock itself, not only the router's question."""

    folder = tmp_path / "recordings"
    store = recording_store(folder)
    with RecordingWriter(folder / "live.tape.csv", 2) as writer:
        writer.write(TapeFrame(0.0, 0, np.zeros(2), np.zeros(2), 0))
        with pytest.raises(RecordingError, match="being recorded"):
            store.delete("live")
        assert (folder / "live.tape.csv").exists()
    store.delete("live")
    assert not (folder / "live.tape.csv").exists()


LONG_RUN = {
    "planning": "full",
    "planning_steps": 2000,
    "experiments": 1,
    "episodes": 100_000,
    "seed": 1,
}
"""Long enough (about 18 s of training here) to be stopped mid-training: with 100 planning updates
the 100,000 episodes ended in about 2 s, and a loaded machine once took longer than that to reach
the test's stop (the run then read "done", not "stopped")."""


def test_a_second_studio_reads_the_first_ones_runs_and_never_rewrites_them(open_client, tmp_path):
    a, b = open_client(), open_client()
    long = a.post("/api/runs", json=LONG_RUN).json()["id"]
    queued = a.post("/api/runs", json=TINY_RUN).json()["id"]
    status_file = tmp_path / "runs" / queued / "status.json"
    before = status_file.read_bytes()

    listed = {r["id"]: r for r in b.get("/api/runs").json()}
    assert listed[queued]["status"] == "queued" and listed[queued]["elsewhere"] is True
    assert listed[long]["status"] in ("queued", "running") and listed[long]["elsewhere"]
    assert status_file.read_bytes() == before  # listing wrote nothing
    for response in (
        b.delete(f"/api/runs/{queued}"),
        b.post(f"/api/runs/{queued}/mark-stopped"),
        b.post(f"/api/runs/{queued}/stop"),
    ):
        assert response.status_code == 409, response.text
    assert (tmp_path / "runs" / queued / "config.json").exists()

    a.post(f"/api/runs/{long}/stop")
    assert wait_run(a, queued)["status"] == "done"  # A trained it: nothing went missing
    assert wait_for(lambda: b.get(f"/api/runs/{queued}").json()["status"] == "done")
    assert b.get(f"/api/runs/{long}").json()["status"] == "stopped"
    assert b.delete(f"/api/runs/{queued}").status_code == 204  # finished: anyone may delete it


def test_queued_runs_of_a_studio_that_closed_read_as_stopped(open_client, tmp_path):
    a = open_client()
    long = a.post("/api/runs", json=LONG_RUN).json()["id"]
    queued = a.post("/api/runs", json=TINY_RUN).json()["id"]
    a.__exit__(None, None, None)  # its queue lets its runs go
    b = open_client()
    listed = {r["id"]: r for r in b.get("/api/runs").json()}
    assert listed[queued]["status"] == "stopped" and not listed[queued]["elsewhere"]
    assert "before this run started" in listed[queued]["error"]
    assert listed[long]["status"] == "stopped"
    assert b.delete(f"/api/runs/{queued}").status_code == 204


def test_a_take_another_studio_records_is_refused(open_client, tmp_path):
    """Studio B could stop A's take, keep it and make demonstrations of the part recorded so
    far; A's own Stop then answered 409 "No take is being recorded"."""
    a, b = open_client(), open_client()
    sample = sorted(SAMPLES_DIR.glob("*.tape.csv"))[0].name.removesuffix(".tape.csv")
    a.put("/api/source", json={"kind": "recording", "recording": sample, "loop": True})
    take = a.post("/api/takes/start", json={}).json()["takes"][0]["recording"]
    assert wait_for(lambda: a.get("/api/capture").json()["frames"] >= 20)
    for path in ("/api/takes/stop", "/api/takes/redo"):
        refused = b.post(path)
        assert refused.status_code == 409, refused.text
        assert refused.json()["detail"].startswith(f"Take {take} is being recorded by another")
    assert b.post("/api/takes/keep").status_code == 409
    assert b.post("/api/takes/demonstrations", json={"goal_from_end": True}).status_code == 409
    stopped = a.post("/api/takes/stop")  # A's own Stop still ends A's take
    assert stopped.status_code == 200, stopped.text
    assert stopped.json()["takes"][0]["state"] == "review"
    assert _names(a)[take]["frames"] >= 20 and not _names(a)[take]["capturing"]
