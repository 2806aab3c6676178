"""Choosing the robot the operator teaches: the API, the live chain onto it, and what the page is
told when it cannot follow the hand."""

from __future__ import annotations

import io
import json
import zipfile

import numpy as np
import viser
from fastapi.testclient import TestClient

from studio.kinematics import RetargetConfig, Retargeter, load_robot, robot_names
from studio.kinematics._workspace import Workspace
from studio.web.live._pipeline import robot_note
from studio.web.scene._model import SceneLayout
from studio.web.scene._protocols import LivePose
from studio.web.scene._scene import StudioScene

from .conftest import wait_for

EVIL = "http://evil.example"


def test_the_offered_robots_are_listed_with_their_joints_puma560_taught_by_default(
    client: TestClient,
) -> None:
    body = client.get("/api/robots").json()
    assert [r["name"] for r in body["robots"]] == list(robot_names())
    panda = next(r for r in body["robots"] if r["name"] == "panda")
    assert panda["joints"] == list(load_robot("panda").joint_names)
    assert body["robot"] == "puma560"
    assert client.get("/api/source").json()["robot"] == "puma560"


def test_an_unknown_robot_is_refused_in_one_sentence_and_changes_nothing(
    client: TestClient,
) -> None:
    r = client.put("/api/robot", json={"name": "r2d2"})
    assert r.status_code == 422
    detail = r.json()["detail"]
    assert isinstance(detail, str) and "r2d2" in detail and "panda" in detail
    assert client.get("/api/robots").json()["robot"] == "puma560"


def test_another_site_cannot_switch_the_robot(client: TestClient) -> None:
    refused = client.put("/api/robot", json={"name": "panda"}, headers={"Origin": EVIL})
    assert refused.status_code == 403
    assert client.get("/api/robots").json()["robot"] == "puma560"


def test_the_simulator_drives_the_panda_within_its_limits_and_the_puma_again(
    client: TestClient,
) -> None:
    client.put("/api/source", json={"kind": "simulator", "seed": 3})
    r = client.put("/api/robot", json={"name": "panda"})
    assert r.status_code == 200 and r.json()["robot"] == "panda"
    panda = load_robot("panda")
    seen: list[np.ndarray] = []

    def moved() -> bool:
        s = client.get("/api/source").json()
        q = np.array(s["q_robot"])
        if s["robot"] == "panda" and q.shape == (7,):
            seen.append(q)
        return len(seen) >= 2 and not np.allclose(seen[0], seen[-1])

    assert wait_for(moved), (
        f"the Panda did not move with the simulated operator: {client.get('/api/source').json()}"
    )
    assert all(np.all(q >= panda.lower - 1e-9) and np.all(q <= panda.upper + 1e-9) for q in seen)
    assert client.get("/api/source").json()["retarget"]["mode"] == "cartesian"
    joint = client.put("/api/source/retarget", json={"mode": "joint"})
    assert joint.status_code == 409 and "cartesian" in joint.json()["detail"]

    client.put("/api/robot", json={"name": "puma560"})
    assert wait_for(lambda: len(client.get("/api/source").json()["q_robot"]) == 6)
    source = client.get("/api/source").json()
    assert source["robot"] == "puma560" and source["retarget"]["mode"] == "joint"


def test_the_page_is_told_when_the_hand_is_out_of_reach_or_the_pose_is_held() -> None:
    panda = load_robot("panda")
    far = Retargeter(robot=panda, config=RetargetConfig(reach_fraction=3.0))
    reaching = np.zeros(7)
    reaching[0] = np.pi / 2  # the arm straight out in front
    for _ in range(40):
        far.robot_from_human(reaching)
    note = robot_note(panda, far)
    assert note is not None and "out of the Franka Emika Panda's reach" in note and "cm" in note

    near = Retargeter(robot=panda)
    bent = np.zeros(7)
    bent[0], bent[3] = np.pi / 4, np.pi / 2  # a hand in front of the chest
    for _ in range(80):  # the robot gets there from its home, 4.5 degrees a frame at most
        near.robot_from_human(bent)
    assert robot_note(panda, near) is None
    near.held = True
    held = robot_note(panda, near)
    assert held is not None and held.startswith("The Franka Emika Panda holds its last pose")


def test_the_page_is_told_when_the_hand_is_drawn_back_into_reach(monkeypatch) -> None:
    # a human arm's targets lie within the workspace; mapped twice as far, they go beyond reach
    into = Workspace.into
    monkeypatch.setattr(Workspace, "into", lambda w, r: w.centre + 2.0 * (into(w, r) - w.centre))
    ur5 = load_robot("ur5", geometry=False)
    retargeter = Retargeter(robot=ur5)
    raised = np.array([1.2, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0])  # the arm raised forward, outstretched
    for _ in range(80):
        retargeter.robot_from_human(raised)
    note = robot_note(ur5, retargeter)
    assert retargeter.pulled_in > 0.01
    assert note is not None and "beyond the Universal Robots UR5's reach" in note and "cm" in note


def test_the_scene_draws_the_chosen_robot_from_its_meshes_where_the_puma_stands() -> None:
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    scene = StudioScene(server, layout=SceneLayout(rate_hz=100.0))
    try:
        panda = load_robot("panda")
        scene.set_goal(np.zeros(6))  # the Puma560's training goal
        scene.set_robot(panda)
        assert wait_for(lambda: scene.robot_name == "panda", timeout=120.0)
        assert not scene._goal_marker.visible  # a Puma560 goal is not the Panda's
        assert scene.robot_mesh_count == len(panda.visual_model.geometryObjects)
        names = [h.name for h in scene._robot_handles]
        assert all(n.startswith("/robot/") and "panda_link" in n for n in names[:8])
        # framed where the Puma560 stands: on the floor at the origin, its shoulder at the
        # Puma560's height, far from the operator
        points = np.concatenate(scene.robot_mesh_points(panda.home))
        assert points[:, 2].min() > 0.0 and np.abs(points[:, :2]).max() < 1.0
        shoulder = scene.robot_mesh_points(panda.home)[2]  # link2 turns about the shoulder
        assert abs(np.median(shoulder[:, 2]) - load_robot("puma560").shoulder[2]) < 0.15
        # it follows a live pose of its seven joints
        q = np.array(panda.home) + 0.2
        scene.show_live(LivePose(np.zeros(7), q, None))
        assert wait_for(lambda: np.allclose(scene.current_q_robot(), q))
        scene.set_robot(None)
        assert wait_for(lambda: scene.robot_name == "puma560" and scene.robot_mesh_count == 7)
        assert scene._goal_marker.visible  # its goal is back with it
        assert scene.errors == 0
    finally:
        scene.close()
        server.stop()


def test_a_demonstration_downloads_for_the_robot_in_each_format(client: TestClient) -> None:
    url = "/api/robot/export/demonstration/sample-reach-1"
    csv = client.get(url, params={"format": "csv"})
    assert csv.status_code == 200
    assert 'filename="sample-reach-1.puma560.csv"' in csv.headers["content-disposition"]
    header = next(line for line in csv.text.splitlines() if not line.startswith("#"))
    assert header == "time," + ",".join(load_robot("puma560").joint_names)
    mcap = client.get(url, params={"format": "mcap"})
    assert mcap.status_code == 200 and mcap.content.startswith(b"\x89MCAP")
    lerobot = client.get(url, params={"format": "lerobot"})
    assert lerobot.status_code == 200
    names = zipfile.ZipFile(io.BytesIO(lerobot.content)).namelist()
    assert "meta/info.json" in names and "data/chunk-000/file-000.parquet" in names


def test_a_recording_too_fast_for_the_robot_exports_at_the_persons_pace_when_fitted(
    client: TestClient,
) -> None:
    """The page's export (``fit``): where the capture times break the robot's limits, the path
    goes out at the person's pace, slowed only where needed, and the answer says so in words;
    the file states the physics report, as ``studio export``'s does."""
    url = "/api/robot/export/recording/sample-reach-1"
    fitted = client.get(url, params={"format": "csv", "fit": "true"})
    assert fitted.status_code == 200, fitted.text
    assert "# safety checks: passed" in fitted.text
    assert "# note: at the source's pace" in fitted.text
    assert "# physics (MuJoCo, puma560" in fitted.text
    about = json.loads(fitted.headers["x-studio-export"])
    assert about["timed_by"] == "pace" and about["slowed_because"]
    assert about["slowed_because"][0]["what"] in ("velocity", "acceleration")
    assert "person's pace" in about["said"] and "--" not in about["said"]
    assert about["physics"] and about["physics"][0].startswith("physics (MuJoCo, puma560")
    assert about["findings"] == []
    # the physics check before it replays the very samples the export writes
    report = client.get("/api/robot/simulate/recording/sample-reach-1", params={"fit": "true"})
    assert report.status_code == 200 and report.json()["sentences"] == about["physics"]
    # a demonstration, already at the person's pace, is not slowed for its own times
    demo = client.get("/api/robot/export/demonstration/sample-reach-1", params={"fit": "true"})
    assert demo.status_code == 200
    assert json.loads(demo.headers["x-studio-export"])["slowed_because"] == []


def test_a_recording_failing_the_checks_is_refused_in_one_sentence_unless_unchecked(
    client: TestClient,
) -> None:
    url = "/api/robot/export/recording/sample-reach-1"
    refused = client.get(url, params={"format": "csv"})
    assert refused.status_code == 422
    body = refused.json()
    detail = body["detail"]
    assert isinstance(detail, str) and detail.startswith("Refused") and " joint joint" in detail
    # in plain words, with every finding as a structured list (the command line's flags are
    # the CLI's rendering of the same refusal)
    assert "--" not in detail and "person's pace" in detail
    assert body["reason"] == "safety" and body["findings"]
    assert {"sample", "time", "what", "where", "sentence"} <= set(body["findings"][0])
    assert body["findings"][0]["sentence"] in detail
    written = client.get(url, params={"format": "csv", "unchecked": "true"})
    assert written.status_code == 200 and "NOT checked" in written.text
    timed = client.get(url, params={"format": "csv", "retime": "true"})
    assert timed.status_code == 200 and "# safety checks: passed" in timed.text
    data = [line for line in timed.text.splitlines() if not line.startswith(("#", "time"))]
    rows = np.loadtxt(data, delimiter=",", ndmin=2)
    assert np.allclose(np.diff(rows[:, 0]), 1 / 50)  # at the rollout rate, as a demonstration
    missing = client.get("/api/robot/export/recording/nope", params={"format": "csv"})
    assert missing.status_code == 404 and isinstance(missing.json()["detail"], str)
