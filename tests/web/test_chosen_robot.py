"""The page's pieces follow the robot chosen under Source: the train form's default goal, the
timeline's robot joints, the jog sliders and "use this pose as the goal"."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from fastapi.testclient import TestClient

from studio.capture import recording_series
from studio.kinematics import load_robot, robot_names
from studio.learning import ArmGrid, RunRequest, check_goal_deg, default_goal, resolve_run
from studio.samples import SAMPLES_DIR
from studio.web.scene._model import Mode
from studio.web.scene._scene import StudioScene
from tests.web.conftest import wait_for, wait_run
from tests.web.test_robot_playback import kept_meshes, studio  # noqa: F401  (a studio with a scene)

LOAD_S = 120.0
"""Reading a robot's model and meshes takes seconds alone, far longer on a shared machine."""


@pytest.fixture
def recording(tmp_path: Path) -> str:
    (tmp_path / "recordings").mkdir(exist_ok=True)
    shutil.copy(SAMPLES_DIR / "sample-reach-1.tape.csv", tmp_path / "recordings" / "reach.tape.csv")
    return "reach"


# ---------------------------------------------------------------------- the form's default goal


def test_each_robot_is_listed_with_the_goal_the_cli_trains_it_towards(client: TestClient) -> None:
    robots = {r["name"]: r for r in client.get("/api/robots").json()["robots"]}
    assert robots["puma560"]["goal_deg"] == pytest.approx([0.0, 45.0, -90.0])
    assert robots["panda"]["goal_deg"] == pytest.approx([0.0, -45.0, 0.0])
    for name in robot_names():
        goal = robots[name]["goal_deg"]
        assert goal == pytest.approx(np.degrees(default_goal(name)[:3]), abs=0.005)
        check_goal_deg(goal, name)  # a goal the form can send for that robot
        # the page's form sends it; the CLI sends none: the same grid goal either way
        form = resolve_run(RunRequest(robot=name, goal_deg=goal)).arm_grid()
        assert form.goal == ArmGrid(robot=name).goal, name


# ---------------------------------------------------------------------- the timeline


def test_the_timeline_plots_the_chosen_robots_joints_by_their_own_names(
    client: TestClient, recording: str
) -> None:
    puma = client.get(f"/api/recordings/{recording}/timeline?points=60").json()
    assert puma["robot_name"] == "puma560" and len(puma["robot"][0]) == 6
    assert client.put("/api/robot", json={"name": "panda"}).status_code == 200
    timeline = client.get(f"/api/recordings/{recording}/timeline?points=60").json()
    panda = load_robot("panda")
    assert timeline["robot_name"] == "panda"
    assert timeline["robot_title"] == panda.spec.title
    assert timeline["robot_joints"] == list(panda.joint_names)
    q = np.radians(np.array(timeline["robot"]))
    assert q.shape == (len(timeline["times"]), 7)
    assert np.all(q >= panda.lower - 1e-3) and np.all(q <= panda.upper + 1e-3)
    assert timeline["human"] == puma["human"]  # the same arm, on another robot
    # retargeted as an export retargets a recording: the one path onto a robot
    from studio.export import series_motion

    path = client.app.state.studio.recordings.path(recording)
    expected = series_motion(recording_series(path, 60), "panda").q
    assert np.allclose(q, expected, atol=np.radians(0.01))


def test_the_timeline_cursor_holds_the_chosen_robot_where_its_timeline_says(
    client: TestClient, recording: str
) -> None:
    client.put("/api/robot", json={"name": "panda"})
    timeline = client.get(f"/api/recordings/{recording}/timeline?points=60").json()
    reviewer = client.app.state.studio.reviewer
    k = len(timeline["times"]) // 2
    held = reviewer.hold(recording, timeline["times"][k])
    # the plot's points are downsampled and served to 0.01 degree; the cursor interpolates the
    # same retargeted path
    assert np.allclose(np.degrees(held), timeline["robot"][k], atol=0.05)


# ---------------------------------------------------------------------- the jog sliders


def test_the_jog_sliders_are_the_chosen_robots_joints_within_its_limits(
    studio: tuple[TestClient, StudioScene],  # noqa: F811  (the fixture imported above)
) -> None:
    client, scene = studio
    puma = client.get("/api/scene/jog").json()
    assert puma["robot"] == "puma560" and len(puma["joints"]) == 6
    assert client.put("/api/robot", json={"name": "panda"}).status_code == 200
    jog = client.get("/api/scene/jog").json()
    panda = load_robot("panda")
    assert jog["robot"] == "panda" and jog["title"] == panda.spec.title
    assert [j["name"] for j in jog["joints"]] == [f"joint {i}" for i in range(1, 8)]
    assert [j["joint"] for j in jog["joints"]] == list(panda.joint_names)
    lower = np.array([j["lower_deg"] for j in jog["joints"]])
    upper = np.array([j["upper_deg"] for j in jog["joints"]])
    assert np.allclose(lower, np.degrees(panda.lower), atol=1e-5)
    assert np.allclose(upper, np.degrees(panda.upper), atol=1e-5)
    # the limits are poses the arm may take: rounded inwards, never out
    assert np.all(np.radians(lower) >= panda.lower) and np.all(np.radians(upper) <= panda.upper)
    q0 = np.array(jog["q_deg"])
    assert len(q0) == 7 and np.all(lower <= q0) and np.all(q0 <= upper)
    # posed at its limits, joints 1-3 are a goal the learning package takes for the Panda
    q = [*lower[:3], *q0[3:]]
    assert client.post("/api/scene/jog", json={"q_deg": q}).status_code == 200
    check_goal_deg(q[:3], "panda")
    assert wait_for(lambda: scene.robot_name == "panda", timeout=LOAD_S)
    assert wait_for(lambda: np.allclose(scene.current_q_robot(), np.radians(q), atol=1e-6), 10)
    assert scene.mode is Mode.PLAYBACK
    # six angles were the Puma560's: refused for the Panda in one sentence
    r = client.post("/api/scene/jog", json={"q_deg": [0.0] * 6})
    assert r.status_code == 422 and "Panda has 7 joints" in r.json()["detail"]
    r = client.post("/api/scene/jog", json={"q_deg": [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]})
    assert r.status_code == 422 and "joint 4 is 0°" in r.json()["detail"]  # -176 to -4


# ---------------------------------------------------------------------- movement primitives


def test_a_movement_primitive_is_fitted_watched_scored_and_exported_on_the_chosen_robot(
    client: TestClient,
) -> None:
    assert client.put("/api/robot", json={"name": "panda"}).status_code == 200
    r = client.post("/api/demonstrations/sample-reach-1/dmp")
    assert r.status_code == 201, r.text
    made = r.json()
    name = made["name"]
    assert name == "reach-1-dmp-panda"  # the user's own, not a sample
    assert made["task"]["kind"] == "dmp" and made["task"]["robot"] == "panda"
    assert made["joints"] == 7 and made["error"] is None
    assert name in [p["name"] for p in client.get("/api/policies").json()]
    # watched on the Panda: its seven joints, to its goal, with its likeness card
    w = client.post("/api/watch", json={"policy": name})
    assert w.status_code == 200, w.text
    watched = w.json()
    q = np.array(watched["q_robot"])
    panda = load_robot("panda", geometry=False)
    assert q.shape[1] == 7 and watched["reached_goal"]
    assert np.all(q >= panda.lower - 0.02) and np.all(q <= panda.upper + 0.02)
    assert watched["likeness"] is not None and watched["likeness"]["name"] == "its demonstration"
    # scored against another demonstration: retargeted onto the Panda as the policy's own was
    other = client.post("/api/watch", json={"policy": name, "demonstration": "sample-reach-3"})
    assert other.status_code == 200, other.text
    assert other.json()["likeness"]["name"] == "sample-reach-3", other.json()["likeness_note"]
    # its rollout exports for the Panda: checked against the Panda's limits (at the pace it was
    # watched, a human reach's, its wrist may accelerate faster than the Panda's allows: then
    # refused naming the Panda's joint, and written anyway on request with the findings in it)
    r = client.get(f"/api/robot/export/rollout.mcap?policy={name}")
    if r.status_code == 422:
        assert r.json()["reason"] == "safety" and "panda_joint" in r.json()["detail"]
        r = client.get(f"/api/robot/export/rollout.mcap?policy={name}&unchecked=true")
    assert r.status_code == 200 and r.content[:5] == b"\x89MCAP"
    # a second fit takes the next free name
    again = client.post("/api/demonstrations/sample-reach-1/dmp").json()
    assert again["name"] == "reach-1-dmp-panda-2"
    assert client.delete(f"/api/policies/{again['name']}").status_code == 204
    # back on the Puma560 the Panda's primitive is refused in one sentence naming both
    client.put("/api/robot", json={"name": "puma560"})
    refused = client.post("/api/watch", json={"policy": name})
    assert refused.status_code == 409
    assert "Franka Emika Panda" in refused.json()["detail"]
    puma = client.post("/api/demonstrations/sample-reach-1/dmp").json()
    assert puma["name"] == "reach-1-dmp-puma560" and puma["joints"] == 6
    assert client.post("/api/demonstrations/nothing/dmp").status_code == 404


def test_a_movement_primitive_plays_on_its_robot_beside_its_demonstration_and_goal(
    studio: tuple[TestClient, StudioScene],  # noqa: F811  (the fixture imported above)
) -> None:
    client, scene = studio
    client.put("/api/robot", json={"name": "panda"})
    assert wait_for(lambda: scene.robot_name == "panda", timeout=LOAD_S)
    name = client.post("/api/demonstrations/sample-reach-2/dmp").json()["name"]
    assert client.post("/api/watch", json={"policy": name}).status_code == 200
    assert wait_for(lambda: "demonstration" in scene.path_names(), timeout=10)
    assert wait_for(lambda: scene.goal_shown, timeout=10)
    playback = scene.scrub()
    assert playback is not None and playback[0].robot == "panda" and playback[0].q.shape[1] == 7


def test_a_continuous_run_on_the_panda_plays_beside_its_demonstration(
    studio: tuple[TestClient, StudioScene],  # noqa: F811  (the fixture imported above)
) -> None:
    client, scene = studio
    client.put("/api/robot", json={"name": "panda"})
    assert wait_for(lambda: scene.robot_name == "panda", timeout=LOAD_S)
    body = {
        "task": "arm-reach",
        "joints": 3,
        "planning": "zero",
        "episodes": 3,
        "experiments": 1,
        "demonstrations": ["sample-reach-1"],
    }
    run = client.post("/api/runs", json=body)
    assert run.status_code == 201, run.text
    assert wait_run(client, run.json()["id"])["status"] == "done"
    assert client.post("/api/watch", json={"run": run.json()["id"]}).status_code == 200
    # its demonstration's path, on the Panda (its joints were drawn only for the Puma560 before)
    assert wait_for(lambda: "demonstration" in scene.path_names(), timeout=10)
