"""The live pipeline end to end: simulator -> kinematics -> status; capture and live marking."""

from __future__ import annotations

import time


def wait_for(predicate, timeout: float = 20.0, step: float = 0.05) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(step)
    return False


def test_the_simulator_drives_the_robot(open_client):
    client = open_client(source="simulator")
    assert wait_for(lambda: client.get("/api/source").json()["fit_residual_mm"] is not None)
    first = client.get("/api/source").json()
    assert first["kind"] == "simulator" and first["running"] and first["error"] is None
    assert wait_for(lambda: client.get("/api/source").json()["q_robot"] != first["q_robot"])
    later = client.get("/api/source").json()
    assert later["frames"] > first["frames"] and later["rate_hz"] > 50
    assert later["fit_residual_mm"] < 30  # the simulated tape fits the arm model
    assert later["dropped"] == 0


def test_switching_sources_stops_the_old_one(open_client):
    client = open_client(source="simulator")
    assert wait_for(lambda: client.get("/api/source").json()["frames"] > 0)
    old = client.app.state.studio.pipeline.source
    r = client.put("/api/source", json={"kind": "simulator", "seed": 5})
    assert r.status_code == 200 and r.json()["kind"] == "simulator"
    assert not old.status().running
    assert wait_for(lambda: client.get("/api/source").json()["frames"] > 0)
