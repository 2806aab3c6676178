"""Demonstrations, recordings and rollouts on the robot the operator teaches: played in the scene
retargeted onto it (its tool path drawn, its goal shown), exported from the page in each format,
and what cannot be shown said in one sentence."""

from __future__ import annotations

import hashlib
import shutil
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest
import viser
from fastapi.testclient import TestClient
from mcap_ros2.reader import read_ros2_messages

from studio.export import demonstration_motion
from studio.kinematics import MeshConfig, load_robot
from studio.learning import ROLLOUT_RATE_HZ
from studio.samples import SAMPLES_DIR
from studio.web import create_app
from studio.web.scene._mesh_cache import cached_parts, mesh_key
from studio.web.scene._model import Mode, SceneLayout
from studio.web.scene._scene import StudioScene
from tests.web.conftest import make_settings, wait_for
from tests.web.test_policies import policy_bytes, upload

EVIL = "http://evil.example"
DEMO = "sample-reach-1"
LOAD_S = 120.0
"""Reading a robot's model and meshes takes seconds alone, far longer on a shared machine."""


@pytest.fixture(scope="session")
def kept_meshes(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One mesh cache for the studios of the tests (their data folders are each their own): a
    robot's meshes are read and simplified once, as on a machine whose studio keeps them,
    not once a test."""
    return tmp_path_factory.mktemp("meshes")


@pytest.fixture
def studio(tmp_path: Path, kept_meshes: Path) -> Iterator[tuple[TestClient, StudioScene]]:
    """A studio with a scene (its robots' meshes kept in :func:`kept_meshes`)."""
    settings = make_settings(tmp_path)
    server = viser.ViserServer(host="127.0.0.1", port=0, verbose=False)
    scene = StudioScene(server, layout=SceneLayout(rate_hz=100.0), mesh_cache=kept_meshes)
    try:
        with TestClient(create_app(settings, scene)) as client:
            yield client, scene
    finally:
        scene.close()
        server.stop()


def _panda(client: TestClient, scene: StudioScene) -> None:
    assert client.put("/api/robot", json={"name": "panda"}).status_code == 200
    assert wait_for(lambda: scene.robot_name == "panda", timeout=LOAD_S)


def _notes(client: TestClient) -> list[str]:
    return client.get("/api/source").json()["robot_notes"]


def _files(folder: Path) -> dict[str, str]:
    """Every file under ``folder`` but the mesh cache, by its SHA-256."""
    return {
        str(p.relative_to(folder)): hashlib.sha256(p.read_bytes()).hexdigest()
        for p in sorted(folder.rglob("*"))
        if p.is_file() and "cache" not in p.parts
    }


def test_a_demonstration_plays_on_the_panda_retargeted_with_its_path_and_goal(
    studio: tuple[TestClient, StudioScene],
) -> None:
    client, scene = studio
    scene.set_goal(np.zeros(6))  # the Puma560's training goal
    _panda(client, scene)
    assert not scene.goal_shown  # a Puma560 goal is not the Panda's, and the page says why
    assert any("training goal is a Puma560 pose" in n for n in _notes(client))

    assert client.post(f"/api/demonstrations/{DEMO}/preview").status_code == 202
    expected = demonstration_motion(SAMPLES_DIR / f"{DEMO}.demo.json", "panda", ROLLOUT_RATE_HZ)
    assert wait_for(lambda: scene.playing, timeout=LOAD_S), _notes(client)
    seen = []

    def moving() -> bool:
        seen.append(scene.current_q_robot())
        return len(seen) > 2 and not np.allclose(seen[0], seen[-1])

    assert wait_for(moving)
    panda = load_robot("panda")
    for q in seen:  # the Panda's seven joints, on the retargeted path, within its limits
        assert q.shape == (7,)
        assert np.all(q >= panda.lower - 1e-9) and np.all(q <= panda.upper + 1e-9)
    # its tool path is the retargeted demonstration's, and its goal is where that path ends
    path = scene.path_points(f"demo-{DEMO}")
    assert np.allclose(path, scene.tool_positions(expected.q, "panda"), atol=1e-4)
    assert scene.goal_shown and np.allclose(
        scene._goal_marker.position, scene.tool_positions(expected.q[-1:], "panda")[0], atol=1e-4
    )
    # the sample's hand stays within the Panda's reach (its retargeted path passes the export's
    # reach check), and the Puma560 goal's sentence is gone with the Panda's own goal
    assert not any("out of the Franka Emika Panda's reach" in n for n in _notes(client))
    assert not any("training goal" in n for n in _notes(client))
    assert scene.errors == 0


def test_a_puma560_playback_leaves_the_panda_live_and_the_page_says_why(
    studio: tuple[TestClient, StudioScene],
) -> None:
    client, scene = studio
    _panda(client, scene)
    times = np.linspace(0.0, 5.0, 50)
    scene.play_trajectory(times, np.zeros((50, 6)))  # a policy's: the Puma560's joints
    assert wait_for(lambda: any("made for the Puma560" in n for n in _notes(client)))
    assert not scene.playing  # not shown, so nothing holds a policy "in use"
    assert scene.current_q_robot().shape == (7,)


def test_the_timeline_cursor_and_a_review_play_on_the_panda(
    studio: tuple[TestClient, StudioScene],
) -> None:
    client, scene = studio
    _panda(client, scene)
    held = client.post(f"/api/recordings/{DEMO}/review", json={"t": 1.0})
    assert held.status_code == 202
    assert wait_for(lambda: scene.current_q_robot().shape == (7,) and scene.mode is not Mode.LIVE)
    assert (
        client.post(f"/api/recordings/{DEMO}/review", json={"t0": 0.5, "t1": 1.5}).status_code
        == 202
    )
    assert wait_for(lambda: "review" in scene.path_names(), timeout=LOAD_S), _notes(client)
    assert wait_for(lambda: scene.playing)
    playback = scene.scrub()
    assert playback is not None and playback[0].robot == "panda"
    assert abs(playback[0].duration - 1.0) < 0.05  # the stretch asked for, at its own times


def test_a_demonstration_without_its_recording_says_why_it_cannot_play_or_export(
    studio: tuple[TestClient, StudioScene], tmp_path: Path
) -> None:
    client, scene = studio
    shutil.copy(SAMPLES_DIR / f"{DEMO}.demo.json", tmp_path / "recordings" / "orphan.demo.json")
    _panda(client, scene)
    assert client.post("/api/demonstrations/orphan/preview").status_code == 202
    assert wait_for(lambda: any("not next to it" in n for n in _notes(client)), timeout=LOAD_S)
    refused = client.get("/api/robot/export/demonstration/orphan", params={"format": "csv"})
    assert refused.status_code == 422 and "not next to it" in refused.json()["detail"]
    assert refused.json().get("reason") != "safety"  # not the checks: no "export anyway"


def test_a_recording_the_checks_refuse_on_the_panda_exports_only_when_asked(
    studio: tuple[TestClient, StudioScene], tmp_path: Path
) -> None:
    client, _ = studio
    before = _files(tmp_path)
    url = f"/api/robot/export/recording/{DEMO}"
    refused = client.get(url, params={"format": "mcap", "robot": "panda"})
    assert refused.status_code == 422
    body = refused.json()
    assert body["reason"] == "safety" and body["detail"].startswith("Refused")
    # the capture-rate fitting noise breaks the Panda's acceleration limits, named with a margin
    assert "acceleration" in body["detail"] and "rad/s^2" in body["detail"]
    written = client.get(url, params={"format": "csv", "robot": "panda", "unchecked": "true"})
    assert written.status_code == 200
    assert 'filename="sample-reach-1.panda.csv"' in written.headers["content-disposition"]
    assert "NOT checked" in written.text and "acceleration" in written.text
    header = next(line for line in written.text.splitlines() if not line.startswith("#"))
    assert header == "time," + ",".join(load_robot("panda").joint_names)
    assert _files(tmp_path) == before  # nothing on disk was touched


def test_a_demonstration_within_the_pandas_reach_exports_checked(
    studio: tuple[TestClient, StudioScene],
) -> None:
    client, _ = studio
    url = f"/api/robot/export/demonstration/{DEMO}"
    written = client.get(url, params={"format": "csv", "robot": "panda"})
    assert written.status_code == 200, written.text
    assert "NOT checked" not in written.text
    header = next(line for line in written.text.splitlines() if not line.startswith("#"))
    assert header == "time," + ",".join(load_robot("panda").joint_names)


@pytest.mark.parametrize("name", ["r2d2", "PANDA", "../panda", ""])
def test_a_bad_robot_name_is_one_sentence_and_changes_nothing(
    studio: tuple[TestClient, StudioScene], name: str
) -> None:
    client, scene = studio
    export = client.get(
        f"/api/robot/export/demonstration/{DEMO}", params={"format": "csv", "robot": name}
    )
    assert export.status_code == 422
    assert isinstance(export.json()["detail"], str) and "panda" in export.json()["detail"]
    put = client.put("/api/robot", json={"name": name})
    assert put.status_code == 422 and isinstance(put.json()["detail"], str)
    assert client.get("/api/robots").json()["robot"] == "puma560"
    assert scene.robot_name == "puma560"


def test_another_site_can_neither_switch_the_robot_nor_play_on_it(
    studio: tuple[TestClient, StudioScene],
) -> None:
    client, scene = studio
    evil = {"Origin": EVIL}
    assert client.put("/api/robot", json={"name": "panda"}, headers=evil).status_code == 403
    assert client.post(f"/api/demonstrations/{DEMO}/preview", headers=evil).status_code == 403
    review = client.post(f"/api/recordings/{DEMO}/review", json={"t": 1.0}, headers=evil)
    assert review.status_code == 403
    assert client.get("/api/robots").json()["robot"] == "puma560"
    assert scene.robot_loading is None and not scene.playing


def test_a_watched_rollout_exports_as_mcap_checked_or_refused_with_the_reason(
    studio: tuple[TestClient, StudioScene], tmp_path: Path
) -> None:
    client, _ = studio
    name = upload(client, "reach.policy.npz", policy_bytes(tmp_path)).json()["name"]
    url = "/api/robot/export/rollout.mcap"
    unwatched = client.get(url, params={"policy": name})
    assert unwatched.status_code == 409 and "watch it first" in unwatched.json()["detail"]
    assert client.post("/api/watch", json={"policy": name, "seed": 1}).status_code == 200
    answer = client.get(url, params={"policy": name})
    if answer.status_code == 422:  # a grid rollout may outrun the limits: refused, by name
        assert answer.json()["reason"] == "safety"
        answer = client.get(url, params={"policy": name, "unchecked": "true"})
    assert answer.status_code == 200 and answer.content.startswith(b"\x89MCAP")
    assert f'filename="{name}.rollout.mcap"' in answer.headers["content-disposition"]
    path = tmp_path / "rollout.mcap"
    path.write_bytes(answer.content)
    messages = list(read_ros2_messages(str(path), topics=["/joint_trajectory"]))
    assert messages and messages[0].schema.name == "trajectory_msgs/msg/JointTrajectory"
    csv = client.get("/api/watch/trajectory.csv", params={"policy": name})
    rows = [line for line in csv.text.splitlines()[1:] if line]
    assert len(messages[0].ros_msg.points) == len(rows)  # the same samples as the CSV


def test_the_mesh_cache_gives_the_same_parts_and_rebuilds_a_damaged_file(tmp_path: Path) -> None:
    built = []

    def build() -> list:
        from studio.kinematics import robot_meshes

        parts = robot_meshes(load_robot("so100").visual_model, MeshConfig())
        built.append(parts)
        return parts

    files = [str(g.meshPath) for g in load_robot("so100").visual_model.geometryObjects]
    key = mesh_key(files, 0.02, 1.0)
    first = cached_parts(tmp_path, "so100", key, build)
    again = cached_parts(tmp_path, "so100", key, build)
    assert len(built) == 1  # read from the cache the second time
    for a, b in zip(first, again, strict=True):
        assert (a.name, a.frame, a.rgb) == (b.name, b.frame, b.rgb)
        assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.faces, b.faces)
    cache = next(tmp_path.glob("so100-*.npz"))
    cache.write_bytes(b"not an archive")
    rebuilt = cached_parts(tmp_path, "so100", key, build)
    assert len(built) == 2 and len(rebuilt) == len(first)
    assert cached_parts(tmp_path, "so100", key, build) and len(built) == 2  # rewritten
    assert mesh_key(files, 0.01, 1.0) != key  # another simplification is read afresh


def test_the_simulated_motion_plays_on_the_robot_in_the_scene(
    studio: tuple[TestClient, StudioScene],
) -> None:
    """ "Play simulated": the scene's robot moves as MuJoCo moved it for what Export writes."""
    client, scene = studio
    url = f"/api/robot/simulate/demonstration/{DEMO}"
    report = client.get(url, params={"fit": "true"}).json()
    assert client.post(f"{url}/play").status_code == 202
    assert wait_for(lambda: scene.playing, timeout=LOAD_S), client.get("/api/source").json()
    playback = scene.scrub()
    assert playback is not None and playback[0].robot == "puma560"
    np.testing.assert_allclose(playback[0].times, report["times"], atol=1e-9)
    np.testing.assert_allclose(playback[0].q, report["q_simulated"], atol=1e-9)
    missing = client.post("/api/robot/simulate/recording/nope/play")
    assert missing.status_code == 404 and isinstance(missing.json()["detail"], str)
