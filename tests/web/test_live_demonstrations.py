"""Live capture and demonstration marking from the simulator, through the API."""

from __future__ import annotations

import numpy as np

from studio.capture import read_recording
from studio.learning import ArmGrid
from tests.web.conftest import wait_captured, wait_for


def test_record_and_mark_a_demonstration_live(open_client, tmp_path):
    client = open_client(source="simulator")
    assert wait_for(lambda: client.get("/api/source").json()["fit_residual_mm"] is not None)
    assert (
        client.post("/api/capture/start", json={"name": "live", "operator": "ada"}).status_code
        == 200
    )
    assert client.get("/api/source").json()["recording_active"] is True
    simulator = client.app.state.studio.pipeline.source
    # start from a known pose, so the segment never wanders to a joint limit
    assert client.post("/api/source/reach", json={"goal_deg": [40, 10, -40]}).status_code == 200
    assert wait_for(lambda: simulator._sim.motion.frames_to_goal() == 0, timeout=10)
    wait_captured(client, 0.2)  # a moment at the start pose
    r = client.post("/api/demonstrations/mark", json={"action": "start"})
    assert r.status_code == 200 and r.json()["marking"] is True and r.json()["t0"] > 0
    assert client.get("/api/demonstrations/mark").json()["marking"] is True
    r = client.post("/api/source/reach", json={"goal_deg": [0, 45, -90]})
    assert r.status_code == 200
    assert wait_for(lambda: simulator._sim.motion.frames_to_goal() == 0, timeout=10)
    wait_captured(client, 0.3)  # a moment at the goal
    r = client.post("/api/demonstrations/mark", json={"action": "stop", "name": "live-reach"})
    assert r.status_code == 200, r.text
    demo = r.json()["demonstration"]
    assert demo["name"] == "live-reach" and demo["recording"] == "live"
    assert demo["reaches_goal"] is True and demo["steps"] >= 1
    detail = client.get("/api/demonstrations/live-reach").json()
    grid = ArmGrid()
    assert detail["grid_path"][-1] == grid.goal_state

    made = client.post("/api/capture/stop").json()
    assert made["name"] == "live" and made["operator"] == "ada" and made["source"] == "simulator"
    rec = read_recording(tmp_path / "recordings" / "live.tape.csv")
    assert not rec.recovered and len(rec) == made["frames"]
    assert np.all(np.diff(rec.frame) == 1)  # every raw frame, none skipped
    # a run can replay it
    run = client.post(
        "/api/runs",
        json={
            "planning": "zero",
            "experiments": 1,
            "episodes": 2,
            "demonstrations": ["live-reach"],
        },
    )
    assert run.status_code == 201, run.text


def test_a_segment_that_misses_the_goal_is_refused_with_its_reason(open_client):
    client = open_client(source="simulator")
    client.post("/api/capture/start", json={"name": "wander"})
    assert wait_for(lambda: client.get("/api/capture").json()["seconds"] > 1.0)
    client.post("/api/capture/stop")
    r = client.post("/api/demonstrations", json={"recording": "wander", "t0": 0.0, "t1": 0.9})
    assert r.status_code == 422
    assert r.json()["reason"] in ("never_reaches_goal", "leaves_joint_range", "bad_fit")
    r = client.post("/api/demonstrations", json={"recording": "wander", "t0": 0.0, "t1": 0.001})
    assert r.status_code == 422 and r.json()["reason"] == "too_short"
    r = client.post(
        "/api/demonstrations",
        json={"recording": "wander", "t0": 0.0, "t1": 0.9, "goal_from_end": True, "name": "to-end"},
    )
    if r.status_code == 201:  # unless the motion left the joint range
        assert r.json()["reaches_goal"] is False
        listed = [d["name"] for d in client.get("/api/demonstrations").json()]
        assert "to-end" in listed


def test_the_shipped_samples_are_listed_and_train(open_client, tmp_path):
    import shutil

    from studio.samples import SAMPLES_DIR

    samples = sorted(SAMPLES_DIR.glob("sample-*"))
    assert samples, "the package ships sample recordings"
    (tmp_path / "recordings").mkdir()
    for path in samples:
        shutil.copy(path, tmp_path / "recordings" / path.name)
    client = open_client()
    recordings = client.get("/api/recordings").json()
    assert recordings and all(r["sample"] and r["error"] is None for r in recordings)
    demos = client.get("/api/demonstrations").json()
    assert demos and all(d["reaches_goal"] for d in demos)
    names = [d["name"] for d in demos]
    run = client.post(
        "/api/runs",
        json={
            "planning": "zero",
            "experiments": 2,
            "episodes": len(names) + 2,
            "demonstrations": names,
        },
    )
    assert run.status_code == 201, run.text
    assert client.app.state.studio.runs.wait_idle(60)
    done = client.get(f"/api/runs/{run.json()['id']}").json()
    assert done["status"] == "done"


def test_the_simulator_reaches_a_goal_of_the_robot_chosen(open_client):
    """With the Panda chosen, "reach" takes the Panda's goal (joints 1-3, the others at its
    default): the simulated operator moves until the Panda, retargeted from the fitted arm, holds
    its tool where the goal puts it, and the scene's goal is the Panda's."""
    from studio.kinematics import load_robot
    from studio.learning import default_goal_deg, goal_pose

    client = open_client(source="simulator")
    assert wait_for(lambda: client.get("/api/source").json()["fit_residual_mm"] is not None)
    assert client.put("/api/robot", json={"name": "panda"}).status_code == 200
    goal_deg = list(default_goal_deg("panda"))
    goal_deg[0] += 20.0  # off the default, so a Puma560 reading of it would land elsewhere
    r = client.post("/api/source/reach", json={"goal_deg": goal_deg})
    assert r.status_code == 200, r.text
    simulator = client.app.state.studio.pipeline.source
    assert wait_for(lambda: simulator._sim.motion.frames_to_goal() == 0, timeout=20)
    panda = load_robot("panda", geometry=False)
    wanted = panda.forward(goal_pose(goal_deg, "panda"))[:3, 3]

    def tool_error() -> float:
        q = np.asarray(client.app.state.studio.pipeline.q_robot())
        return float(np.linalg.norm(panda.forward(q)[:3, 3] - wanted))

    # the simulator's tremor and the tape's noise stay: within 2 cm of the goal's tool
    assert wait_for(lambda: tool_error() < 0.02, timeout=20), tool_error()
    # no goal given: the Panda's default goal (not the Puma560's angles read as the Panda's)
    assert client.post("/api/source/reach", json={}).status_code == 200
    wanted = panda.forward(goal_pose(default_goal_deg("panda"), "panda"))[:3, 3]
    assert wait_for(lambda: simulator._sim.motion.frames_to_goal() == 0, timeout=20)
    assert wait_for(lambda: tool_error() < 0.02, timeout=20), tool_error()


def test_a_goal_beyond_the_chosen_robots_limits_is_refused_naming_it(open_client):
    client = open_client(source="simulator")
    assert client.put("/api/robot", json={"name": "panda"}).status_code == 200
    r = client.post("/api/source/reach", json={"goal_deg": [0.0, 120.0, 0.0]})  # joint 2: ±101°
    assert r.status_code == 422
    assert "joint 2" in r.text
