"""The studio drives the scene: watch plays rollouts, previews draw paths, in-use checks."""

from __future__ import annotations

import numpy as np
import pytest
from fastapi.testclient import TestClient

from studio.learning import ArmGrid
from studio.web import create_app
from tests.web.conftest import make_settings
from tests.web.test_demonstrations import save_demo
from tests.web.test_policies import policy_bytes, upload


class _FakeObstacles:
    """Records the boxes the studio asks the scene to draw (``StudioScene.obstacles``)."""

    def __init__(self, calls: list) -> None:
        self.calls = calls

    def show_watched(self, boxes, robot=None) -> None:
        self.calls.append(("show_watched", (tuple(boxes), robot)))


class FakeScene:
    """Records the calls the studio makes on ``StudioScene`` (same method names)."""

    def __init__(self) -> None:
        self.calls: list[tuple[str, tuple]] = []
        self.playing = False
        self.q_robot = np.zeros(6)
        self.obstacles = _FakeObstacles(self.calls)

    def update_live(self, q_human, q_robot, tape_positions=None) -> None:
        self.calls.append(("update_live", (q_human, q_robot)))

    def set_side(self, side, taped=True) -> None:
        self.calls.append(("set_side", (side, taped)))

    def show_hand_handle(self, side, on_move) -> None:
        self.calls.append(("show_hand_handle", (side, on_move)))

    def set_goal(self, q_robot_goal, robot=None) -> None:
        self.calls.append(("set_goal", (q_robot_goal,)))

    def show_path(self, name, q_robot_path, robot=None) -> None:
        self.calls.append(("show_path", (name, q_robot_path)))

    def clear_path(self, name=None) -> None:
        self.calls.append(("clear_path", (name,)))

    def play_trajectory(self, times, q_robot, states=None, robot="puma560") -> None:
        self.playing = True
        self.calls.append(("play_trajectory", (times, q_robot, states)))

    def stop_playback(self) -> None:
        self.playing = False
        self.calls.append(("stop_playback", ()))

    def current_q_robot(self):
        return self.q_robot.copy()

    def shown_robot(self):
        return self.q_robot.copy(), -1

    def named(self, name: str) -> list[tuple]:
        return [args for call, args in self.calls if call == name]


@pytest.fixture
def scene_client(tmp_path):
    scene = FakeScene()
    with TestClient(create_app(make_settings(tmp_path), scene)) as client:
        yield client, scene


def test_the_default_goal_is_shown_at_start(scene_client):
    _, scene = scene_client
    (goal,) = scene.named("set_goal")[0]
    grid = ArmGrid()
    assert np.allclose(goal[:3], grid.angles_of(grid.goal_state)) and np.allclose(goal[3:], 0)


def test_watch_plays_the_rollout_and_blocks_deleting_the_policy(scene_client, tmp_path):
    client, scene = scene_client
    upload(client, "reach.policy.npz", policy_bytes(tmp_path))
    w = client.post("/api/watch", json={"policy": "reach", "seed": 1}).json()
    times, q, states = scene.named("play_trajectory")[-1]
    assert np.allclose(times, w["times"]) and np.allclose(q, w["q_robot"], atol=1e-6)
    assert list(states) == w["states"]
    r = client.delete("/api/policies/reach")
    assert r.status_code == 409 and "stop watching" in r.json()["detail"]
    assert client.post("/api/watch/stop").status_code == 204
    assert scene.named("stop_playback")
    assert client.delete("/api/policies/reach").status_code == 204


def test_watch_from_the_current_pose_starts_in_its_bin(scene_client, tmp_path):
    client, scene = scene_client
    upload(client, "reach.policy.npz", policy_bytes(tmp_path))
    scene.q_robot = np.radians([100.0, -60.0, 20.0, 10.0, 20.0, 30.0])
    w = client.post("/api/watch", json={"policy": "reach", "start": "current"}).json()
    grid = ArmGrid(bins=5)
    assert w["states"][0] == grid.state_of_angles(scene.q_robot[:3])
    # the wrist holds where it was
    assert np.allclose(np.asarray(w["q_robot"])[:, 3:], scene.q_robot[3:], atol=1e-6)


def test_preview_and_delete_a_demonstration(scene_client, tmp_path):
    client, scene = scene_client
    demo = save_demo(tmp_path / "recordings", "reach-1")
    assert client.post("/api/demonstrations/reach-1/preview").status_code == 202
    name, path = scene.named("show_path")[-1]
    assert name == "demo-reach-1" and np.allclose(path, demo.q_robot)
    times, q, _ = scene.named("play_trajectory")[-1]
    assert np.allclose(times, demo.times)
    assert client.delete("/api/demonstrations/reach-1").status_code == 204
    assert scene.named("clear_path")[-1] == ("demo-reach-1",)


def test_ticking_loop_changes_the_playing_recording_in_place(tmp_path):
    """The page's "loop" box on a playing recording: same source, same position, new loop."""
    from tests.web.conftest import wait_for
    from tests.web.test_recordings import write_recording

    (tmp_path / "recordings").mkdir()
    write_recording(tmp_path / "recordings" / "take.tape.csv", frames=440)
    with TestClient(create_app(make_settings(tmp_path))) as client:
        body = {"kind": "recording", "recording": "take", "speed": 1.0, "loop": True}
        assert client.put("/api/source", json=body).status_code == 200
        studio = client.app.state.studio
        source = studio.pipeline.source
        assert wait_for(lambda: source.position > 0.5, timeout=10)
        before = source.position
        answer = client.put("/api/source", json={**body, "loop": False}).json()
        assert studio.pipeline.source is source  # not restarted
        assert answer["playback"]["loop"] is False and source.loop is False
        assert answer["playback"]["t"] >= before  # not back to 0
        answer = client.put("/api/source", json={**body, "loop": True, "speed": 2.0}).json()
        assert studio.pipeline.source is source and source.loop and source.speed == 2.0
        assert answer["playback"]["loop"] is True


def _write_taped_recording(path, side: str, frames: int = 330) -> None:
    """A recording of a tape on ``side``'s arm (its header says so), the arm raised forward."""
    from studio.capture import RecordingWriter, TapeFrame
    from studio.kinematics import HumanArm, TapeConfig, tape_from_arm

    config = TapeConfig(side=side)
    arm = HumanArm(side)
    with RecordingWriter(path, config=config) as writer:
        for k in range(frames):
            q = np.array([0.8 + 0.2 * np.sin(k / 30.0), 0.3, 0.1, 0.9, 0.0, 0.0, 0.0])
            bend, twist = tape_from_arm(arm, q, config)
            writer.write(TapeFrame(k / 110.0, k, bend, twist))


def test_a_recording_taped_on_the_left_arm_is_drawn_on_the_left_arm(tmp_path):
    """The pipeline puts the scene's tape on the recording's arm: left for a left-arm recording
    (the left arm follows the fit, the right rests), and back to the right for a right-arm one."""
    import viser

    from studio.web.scene._scene import SceneLayout, StudioScene
    from tests.conftest import free_port
    from tests.web.conftest import wait_for

    folder = tmp_path / "recordings"
    folder.mkdir()
    _write_taped_recording(folder / "lefty.tape.csv", "left")
    _write_taped_recording(folder / "righty.tape.csv", "right")
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    scene = StudioScene(server, layout=SceneLayout(rate_hz=100.0))
    parts = [p.name for p in scene.body.parts]
    rest = [np.array(h.position) for h in scene._operator_handles]

    def hand_moved(side: str) -> bool:
        i = parts.index(f"{side}_hand/hand_mesh")
        return np.linalg.norm(np.asarray(scene._operator_handles[i].position) - rest[i]) > 0.1

    def arm_rests(side: str) -> bool:
        return all(
            np.allclose(scene._operator_handles[i].position, rest[i], atol=1e-6)
            for i, name in enumerate(parts)
            if name.startswith((f"{side}_upperarm", f"{side}_lowerarm", f"{side}_hand"))
        )

    try:
        with TestClient(create_app(make_settings(tmp_path), scene)) as client:
            body = {"kind": "recording", "recording": "lefty", "loop": True}
            assert client.put("/api/source", json=body).status_code == 200
            assert wait_for(lambda: scene.shown_side == "left" and hand_moved("left"))
            assert client.get("/api/source").json()["error"] is None
            assert arm_rests("right")
            body = {**body, "recording": "righty"}
            assert client.put("/api/source", json=body).status_code == 200
            assert wait_for(lambda: scene.shown_side == "right" and hand_moved("right"))
            assert arm_rests("left")
    finally:
        scene.close()
        server.stop()
