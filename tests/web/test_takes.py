"""Recording in takes through the API, and a recording's timeline and review."""

from __future__ import annotations

import json
import shutil
import time

import numpy as np
import pytest

from studio.capture import TAKES_FILE, read_takes, write_takes
from studio.samples import SAMPLES_DIR
from tests.web.conftest import wait_captured

AWAY_DEG = [-40.0, 20.0, -40.0]
"""Robot joints 1-3 (degrees) the simulated operator waits at before a take, far from the goal."""


def _away_from_the_goal(client) -> None:
    """Send the simulated operator to a pose far from the goal, and wait until it is there."""
    client.post("/api/source/reach", json={"action": "reach", "goal_deg": AWAY_DEG})
    deadline = time.monotonic() + 30
    while True:
        q = np.degrees(client.get("/api/source").json()["q_robot"][:3])
        if np.abs(q - AWAY_DEG).max() < 10:
            return
        assert time.monotonic() < deadline, f"the operator stayed at {q}"
        time.sleep(0.1)


def test_a_session_of_takes_becomes_demonstrations(open_client, tmp_path):
    client = open_client(source="simulator")
    takes_file = tmp_path / "recordings" / TAKES_FILE
    assert client.get("/api/takes").json() == {"started": None, "finished": None, "takes": []}

    first = client.post("/api/takes/start", json={}).json()["takes"][0]["recording"]
    assert client.post("/api/takes/start").status_code == 409  # one take at a time
    wait_captured(client, 0.8)
    review = client.post("/api/takes/stop").json()
    assert review["takes"][0]["state"] == "review"
    assert client.post("/api/takes/start").status_code == 409  # keep or redo it first
    assert client.post("/api/takes/redo").json()["takes"] == []
    assert client.get(f"/api/recordings/{first}").status_code == 404  # thrown away

    for _ in range(2):
        # each take starts away from where it ends, so its end (the goal) is another grid cell
        # whatever the simulated operator's wandering did before
        _away_from_the_goal(client)
        client.post("/api/takes/start")
        wait_captured(client, 0.3)
        client.post("/api/source/reach", json={"action": "reach"})
        wait_captured(client, 2.5)
        client.post("/api/takes/stop")
        assert client.post("/api/takes/review").status_code == 202
        client.post("/api/takes/keep")
    on_disk = read_takes(takes_file)[-1]
    assert [t.state for t in on_disk.takes] == ["kept", "kept"]

    done = client.post("/api/takes/demonstrations", json={"goal_from_end": True}).json()
    assert done["finished"]
    made = [t["demonstration"] for t in done["takes"]]
    assert all(made), [t["error"] for t in done["takes"]]
    for name in made:
        assert (tmp_path / "recordings" / f"{name}.demo.json").is_file()
    assert client.get("/api/takes").json()["takes"] == []  # the next take opens a new session
    assert read_takes(takes_file)[-1].takes[0].demonstration == made[0]


def test_a_damaged_takes_file_is_one_sentence(open_client, tmp_path):
    client = open_client()
    (tmp_path / "recordings" / TAKES_FILE).write_text('{"format": "something else"}')
    r = client.get("/api/takes")
    assert r.status_code >= 400
    assert "takes file" in r.json()["detail"]


def test_the_takes_file_round_trips(tmp_path):
    from studio.capture import Take, TakeSession

    path = tmp_path / TAKES_FILE
    sessions = [TakeSession("2026-01-01T00:00:00Z", [Take("a", "kept", "a.0.00-1.00")], None)]
    write_takes(path, sessions)
    assert read_takes(path) == sessions
    assert json.loads(path.read_text())["format"] == "teach-studio-takes"


@pytest.fixture
def recording(tmp_path):
    (tmp_path / "recordings").mkdir(exist_ok=True)
    shutil.copy(SAMPLES_DIR / "sample-reach-1.tape.csv", tmp_path / "recordings" / "reach.tape.csv")
    return "reach"


def test_the_timeline_serves_both_arms_joints_downsampled(open_client, recording):
    client = open_client()
    timeline = client.get(f"/api/recordings/{recording}/timeline?points=50").json()
    assert len(timeline["times"]) == len(timeline["human"]) == len(timeline["robot"]) <= 50
    assert len(timeline["human"][0]) == 7 and len(timeline["robot"][0]) == 6
    assert timeline["times"][-1] == pytest.approx(timeline["duration"], abs=0.05)
    # and the tape's own bend and twist, per region, at the same times
    bend, twist = timeline["signals"]
    assert (bend["name"], twist["name"], bend["unit"]) == ("tape bend", "tape twist", "deg")
    assert len(bend["values"]) == len(timeline["times"]) and len(bend["values"][0]) == 16
    assert bend["labels"][0] == "region 1"
    assert client.post(f"/api/recordings/{recording}/review", json={"t": 1.5}).status_code == 202
    assert (
        client.post(f"/api/recordings/{recording}/review", json={"t0": 1, "t1": 3}).status_code
        == 202
    )
    assert client.get("/api/recordings/none/timeline").status_code == 404
    assert client.get(f"/api/recordings/{recording}/timeline?points=1").status_code == 422
