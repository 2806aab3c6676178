"""The studio scene, headless: handles follow q, live updates never block, playback animates."""

from __future__ import annotations

import socket
import threading
import time
from dataclasses import dataclass

import numpy as np
import pytest
import viser

from studio.kinematics import Puma560
from studio.web._scene import SceneLayout, StudioScene, _segment_pose, _wxyz


@dataclass(frozen=True)
class _Pose:
    shoulder: np.ndarray
    elbow: np.ndarray
    wrist: np.ndarray
    hand: np.ndarray


class _PlanarArm:
    """A stand-in arm with the HumanArm shape: 7 joints, only the first two move the links."""

    nq = 7
    neutral = np.zeros(7)

    def forward(self, q: np.ndarray) -> _Pose:
        def at(p: np.ndarray) -> np.ndarray:
            m = np.eye(4)
            m[:3, 3] = p
            return m

        a, b = float(q[0]), float(q[1])
        elbow = 0.3 * np.array([np.sin(a), 0.0, -np.cos(a)])
        wrist = elbow + 0.25 * np.array([np.sin(a + b), 0.0, -np.cos(a + b)])
        hand = wrist + 0.08 * np.array([np.sin(a + b), 0.0, -np.cos(a + b)])
        return _Pose(at(np.zeros(3)), at(elbow), at(wrist), at(hand))


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _wait_until(cond, timeout: float = 5.0) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.01)
    return cond()


def _arm() -> object:
    try:
        from studio.kinematics import HumanArm  # noqa: PLC0415

        return HumanArm(side="right")
    except ImportError:
        return _PlanarArm()


@pytest.fixture(scope="module")
def server():
    srv = viser.ViserServer(host="127.0.0.1", port=_free_port(), verbose=False)
    yield srv
    srv.stop()


@pytest.fixture
def scene(server):
    sc = StudioScene(server, arm=_arm(), layout=SceneLayout(rate_hz=100.0, playback_hold_s=1.0))
    yield sc
    sc.close()


def test_wxyz_matches_rotation():
    rng = np.random.default_rng(0)
    for _ in range(20):
        a, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        if np.linalg.det(a) < 0:
            a[:, 0] *= -1
        w, x, y, z = _wxyz(a)
        back = np.array(
            [
                [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
            ]
        )
        np.testing.assert_allclose(back, a, atol=1e-9)


def test_segment_pose_puts_cylinder_between_points():
    rng = np.random.default_rng(1)
    for _ in range(20):
        a, b = rng.normal(size=3), rng.normal(size=3)
        centre, wxyz, length = _segment_pose(a, b)
        w, x, y, z = wxyz
        axis = np.array([2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)])
        np.testing.assert_allclose(centre + axis * length / 2, b, atol=1e-9)
        np.testing.assert_allclose(centre - axis * length / 2, a, atol=1e-9)


def test_robot_handles_follow_live_q(scene):
    robot = Puma560()
    q = np.array([0.4, -0.3, 0.5, 0.2, -0.4, 0.1])
    scene.update_live(_arm().neutral, q, None)
    assert _wait_until(lambda: np.allclose(scene.current_q_robot(), q))
    expected = robot.visual_poses(q)
    for handle, pose in zip(scene._robot_handles, expected, strict=True):
        np.testing.assert_allclose(handle.position, pose[:3, 3], atol=1e-5)
        np.testing.assert_allclose(np.abs(np.dot(handle.wxyz, _wxyz(pose[:3, :3]))), 1.0, atol=1e-6)


def test_human_limbs_follow_live_q(scene):
    arm = _arm()
    q0 = np.asarray(arm.neutral, dtype=float)
    scene.update_live(q0, np.zeros(6), None)
    assert _wait_until(lambda: np.allclose(scene.current_q_human(), q0))
    before = np.array(scene._limbs[1].position)
    q1 = q0.copy()
    q1[:4] += 0.6
    scene.update_live(q1, np.zeros(6), None)
    assert _wait_until(lambda: np.allclose(scene.current_q_human(), q1))
    after = np.array(scene._limbs[1].position)
    assert np.linalg.norm(after - before) > 0.02
    pts = scene._arm_points(arm.forward(q1))
    np.testing.assert_allclose(scene._joints[1].position, pts[1], atol=1e-5)


def test_tape_drawn_from_positions(scene):
    tape = np.stack([np.linspace(0, 0.5, 17), np.zeros(17), np.zeros(17)], axis=1)
    scene.update_live(_arm().neutral, np.zeros(6), tape)
    assert _wait_until(lambda: scene._tape.visible)
    np.testing.assert_allclose(scene._tape.points, scene._to_world(tape), atol=1e-5)


def test_update_live_never_blocks_while_viser_is_busy(scene):
    """A stalled push (slow client) must not hold up the 110 Hz caller."""
    release = threading.Event()
    held = threading.Event()

    def hog():
        with scene._viser_lock:
            held.set()
            release.wait(5.0)

    t = threading.Thread(target=hog)
    t.start()
    held.wait(1.0)
    calls = 0
    for i in range(2000):
        scene.update_live(np.zeros(7), np.full(6, i * 1e-4), None)
        calls += 1
    latest_q = np.full(6, 1999 * 1e-4)
    assert calls == 2000
    assert not np.allclose(scene.current_q_robot(), latest_q)  # nothing pushed while stalled
    release.set()
    t.join()
    # Latest wins: once unblocked, the scene shows the last value, not a backlog.
    assert _wait_until(lambda: np.allclose(scene.current_q_robot(), latest_q))


def test_push_rate_is_bounded(server):
    sc = StudioScene(server, arm=_arm(), layout=SceneLayout(rate_hz=20.0))
    try:
        start = sc.pushes
        end = time.monotonic() + 0.5
        i = 0
        while time.monotonic() < end:
            sc.update_live(np.zeros(7), np.full(6, 1e-3 * i), None)
            i += 1
            time.sleep(0.001)
        pushed = sc.pushes - start
        assert i > 3 * pushed  # many updates, few pushes
        assert pushed >= 1
    finally:
        sc.close()


def test_play_trajectory_moves_robot_and_traces(scene):
    times = np.linspace(0.0, 0.4, 41)
    q = np.zeros((41, 6))
    q[:, 0] = np.linspace(0.0, 1.0, 41)
    q[:, 1] = np.linspace(0.0, -0.5, 41)
    scene.play_trajectory(times, q, states=[5, 6, 7, 8])
    assert scene.playing
    seen = []
    assert _wait_until(lambda: seen.append(scene.current_q_robot()[0]) or not scene.playing, 3.0)
    assert len({round(s, 3) for s in seen}) >= 3  # it moved through intermediate poses
    np.testing.assert_allclose(scene.current_q_robot(), q[-1], atol=1e-9)
    assert scene._trace_line.visible
    assert len(scene._trace_marks.points) == 4
    np.testing.assert_allclose(
        scene._trace_marks.points[-1], scene.tool_positions(q[-1:])[0], atol=1e-4
    )


def test_live_resumes_after_playback_hold(scene):
    scene.play_trajectory(np.array([0.0, 0.05]), np.zeros((2, 6)))
    live_q = np.full(6, 0.2)
    scene.update_live(np.zeros(7), live_q, None)
    assert _wait_until(lambda: not scene.playing, 3.0)
    assert scene._trace_marks.visible  # the trace stays while the robot holds the last pose
    assert np.allclose(scene.current_q_robot(), 0.0)
    assert _wait_until(lambda: np.allclose(scene.current_q_robot(), live_q), 3.0)
    assert _wait_until(lambda: not scene._trace_marks.visible, 1.0)  # and goes with it


def test_stop_playback(scene):
    q = np.zeros((100, 6))
    q[:, 0] = np.linspace(0, 1, 100)
    scene.play_trajectory(np.linspace(0, 10, 100), q)
    scene.stop_playback()
    assert not scene.playing
    scene.update_live(np.zeros(7), np.full(6, -0.3), None)
    assert _wait_until(lambda: np.allclose(scene.current_q_robot(), -0.3))


def test_goal_and_paths(scene):
    robot = Puma560()
    goal = np.array([0.5, -0.6, 0.3, 0.0, 0.0, 0.0])
    scene.set_goal(goal)
    assert scene._goal_marker.visible
    np.testing.assert_allclose(scene._goal_marker.position, robot.forward(goal)[:3, 3], atol=1e-6)
    assert all(h.visible for h in scene._ghost_handles)
    scene.set_goal(None)
    assert not scene._goal_marker.visible

    path = np.linspace(np.zeros(6), goal, 30)
    scene.show_path("demo-1", path)
    scene.show_path("demo-2", path[:10])
    assert sorted(scene.path_names()) == ["demo-1", "demo-2"]
    line = scene._paths["demo-1"][-1]
    np.testing.assert_allclose(line.points[-1], robot.forward(goal)[:3, 3], atol=1e-5)
    scene.show_path("demo-1", path[:5])  # replacing keeps one entry
    assert sorted(scene.path_names()) == ["demo-1", "demo-2"]
    scene.clear_path("demo-1")
    scene.clear_path("unknown")
    assert scene.path_names() == ["demo-2"]
    scene.clear_path()
    assert scene.path_names() == []
