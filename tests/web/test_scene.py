"""The studio scene, headless: real meshes on the right frames, framed; the pure pose law; live
updates never block; playback animates, holds and hands back to live; errors are logged."""

from __future__ import annotations

import logging
import threading
import time

import numpy as np
import pytest
import viser
from hypothesis import given, settings
from hypothesis import strategies as st

from studio.kinematics import (
    HumanArm,
    HumanBody,
    KinematicsError,
    MeshConfig,
    Puma560,
    TapeConfig,
    puma560_meshes,
    reconstruct,
    tape_from_arm,
)
from studio.kinematics._meshes import simplify
from studio.web.scene._robot_view import wxyz_of
from studio.web.scene._scene import (
    Mode,
    Playback,
    SceneLayout,
    StudioScene,
    camera_projection,
    pose_at,
)
from tests.conftest import free_port as _free_port
from tests.web.conftest import wait_for

PLACEMENT_TOLERANCE_M = 0.16
"""How far a Puma560 link mesh's bounding box may lie from its DH frame's origin. The largest
gap is the upper arm's: its casting sits beside the shoulder axis by the d3 = 0.150 m offset."""
SCENE_ASPECTS = (1.2, 1.6, 2.0, 2.4)
"""Width/height of the page's scene pane, from a narrow window to a wide one."""


def _wait_until(cond, timeout: float = 5.0) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if cond():
            return True
        time.sleep(0.01)
    return cond()


@pytest.fixture(scope="module")
def server():
    srv = viser.ViserServer(host="127.0.0.1", port=_free_port(), verbose=False)
    yield srv
    srv.stop()


@pytest.fixture(scope="module")
def body():
    return HumanBody("right")


@pytest.fixture
def scene(server, body):
    sc = StudioScene(server, body=body, layout=SceneLayout(rate_hz=100.0, playback_hold_s=1.0))
    yield sc
    sc.close()


def _rotation_of(wxyz: np.ndarray) -> np.ndarray:
    return viser.transforms.SO3(np.asarray(wxyz, dtype=float)).as_matrix()


# ---------------------------------------------------------------------- the pure pose law


def _playback(n: int, duration: float, started: float = 0.0) -> Playback:
    times = np.linspace(0.0, duration, n)
    q = np.zeros((n, 6))
    q[:, 0] = np.linspace(0.0, 1.0, n)
    return Playback(times, q, np.zeros((n, 3)), np.array([0, n - 1]), started)


@given(
    n=st.integers(2, 50),
    duration=st.floats(0.01, 20.0),
    at=st.floats(-1.0, 30.0),
    hold=st.floats(0.0, 5.0),
)
@settings(max_examples=200, deadline=None)
def test_pose_at_is_playback_then_hold_then_live(n, duration, at, hold):
    live = np.full(6, 0.7)
    pb = _playback(n, duration)
    pose = pose_at(pb.started + at, live, pb, hold)
    if at < duration:
        assert pose.mode is Mode.PLAYBACK
        assert 0.0 <= pose.q_robot[0] <= 1.0  # between the samples it interpolates
        assert pose.q_robot[0] == pytest.approx(min(max(at, 0.0), duration) / duration, abs=1e-9)
        assert 0 <= pose.trace_upto <= n - 2
    elif at < duration + hold:
        assert pose.mode is Mode.HOLD
        np.testing.assert_array_equal(pose.q_robot, pb.q[-1])
        assert pose.trace_upto == n - 1
    else:
        assert pose.mode is Mode.LIVE
        np.testing.assert_array_equal(pose.q_robot, live)
    assert pose_at(at, live, None, hold).mode is Mode.LIVE
    assert pose_at(at, None, None, hold).q_robot is None


# ---------------------------------------------------------------------- meshes and placement


def _box_gap(points: np.ndarray, origin: np.ndarray) -> float:
    lo, hi = points.min(axis=0), points.max(axis=0)
    return float(np.linalg.norm(np.maximum(0.0, np.maximum(lo - origin, origin - hi))))


def test_puma_link_meshes_lie_around_their_dh_frames():
    """Each link mesh's box, placed on our DH frame j, holds frame j's origin within tolerance
    at qz and qr; the same meshes put one frame off miss it. (The rotations are checked by the
    flange landing on the tool and by the handles' orientations, below.)"""
    robot = Puma560()
    parts = puma560_meshes()
    assert [p.frame for p in parts] == list(range(7))

    def worst(q: np.ndarray, frame_of) -> float:
        frames = robot.joint_frames(q)
        gaps = []
        for part in parts:
            pose = frames[frame_of(part.frame)]
            world = part.vertices @ pose[:3, :3].T + pose[:3, 3]
            gaps.append(_box_gap(world, frames[part.frame][:3, 3]))
        return max(gaps)

    for q in (robot.qz, robot.qr):
        assert worst(q, lambda j: j) <= PLACEMENT_TOLERANCE_M, q
        assert worst(q, lambda j: max(j - 1, 0)) > PLACEMENT_TOLERANCE_M
        assert worst(q, lambda j: min(j + 1, 6)) > PLACEMENT_TOLERANCE_M


def test_the_whole_robot_stands_on_the_floor_and_reaches_the_tool(scene):
    robot = Puma560()
    for q in (robot.qz, robot.qr):
        pts = np.concatenate(scene.robot_mesh_points(q))
        assert pts[:, 2].min() == pytest.approx(0.0, abs=0.01)  # the pedestal's foot
        tool = robot.forward(q)[:3, 3]
        assert np.min(np.linalg.norm(pts - tool, axis=1)) < 0.06  # the flange is at the tool


def test_simplify_keeps_the_shape_and_cuts_triangles():
    part = puma560_meshes(MeshConfig(cell_m=0.0))[3]
    cell = 0.01
    v, f = simplify(part.vertices, part.faces, cell)
    assert len(f) < len(part.faces) / 2
    assert f.max() < len(v)
    # every new vertex is the mean of the old ones in its cell: within one cell diagonal
    d = np.linalg.norm(v[:, None, :] - part.vertices[None, ::7, :], axis=2).min(axis=1)
    assert d.max() < cell * np.sqrt(3) + 0.02
    lo, hi = part.vertices.min(axis=0), part.vertices.max(axis=0)
    assert np.all(v.min(axis=0) >= lo - 1e-6) and np.all(v.max(axis=0) <= hi + 1e-6)


@given(st.lists(st.floats(-1.5, 1.5), min_size=7, max_size=7))
@settings(max_examples=25, deadline=None)
def test_the_body_arm_is_the_fitted_arm(body, q):
    """The drawn body's elbow and wrist are where HumanArm puts them (one model, one frame),
    on either taped arm."""
    q = np.asarray(q)
    for side in ("right", "left"):
        taped = body.with_side(side)
        pose = HumanArm(side).forward(q)
        np.testing.assert_allclose(
            taped.link_pose(f"{side}_lowerarm", q)[:3, 3], pose.elbow[:3, 3], atol=1e-9
        )
        np.testing.assert_allclose(
            taped.link_pose(f"{side}_hand", q)[:3, 3], pose.wrist[:3, 3], atol=1e-9
        )
    assert body.side == "right"  # with_side leaves the body as it was


# ---------------------------------------------------------------------- live drawing


def test_robot_meshes_follow_live_q(scene):
    robot = Puma560()
    q = np.array([0.4, -0.3, 0.5, 0.2, -0.4, 0.1])
    scene.update_live(np.zeros(7), q, None)
    assert _wait_until(lambda: np.allclose(scene.current_q_robot(), q))
    frames = robot.joint_frames(q)
    for j, handle in enumerate(scene._robot_handles):
        np.testing.assert_allclose(handle.position, frames[j][:3, 3], atol=1e-5)
        np.testing.assert_allclose(_rotation_of(handle.wxyz), frames[j][:3, :3], atol=1e-6)


def test_taped_arm_follows_the_fit_and_the_other_arm_rests(scene, body):
    arm = HumanArm("right")
    names = [p.name for p in body.parts]
    hand = scene._operator_handles[names.index("right_hand/hand_mesh")]
    other = scene._operator_handles[names.index("left_hand/hand_mesh")]
    other_before = np.array(other.position)
    q = np.array([0.9, 0.3, 0.2, 1.1, 0.0, 0.2, 0.0])
    scene.update_live(q, np.zeros(6), None)
    assert _wait_until(lambda: np.allclose(scene.current_q_human(), q))
    np.testing.assert_allclose(
        hand.position, scene.to_world(arm.forward(q).wrist[:3, 3]), atol=1e-5
    )
    np.testing.assert_allclose(other.position, other_before, atol=1e-9)


def test_the_operator_stands_on_the_floor_facing_the_robot(scene):
    pts = np.concatenate(scene.operator_mesh_points(None))
    assert pts[:, 2].min() == pytest.approx(0.0, abs=1e-6)
    assert 1.6 < pts[:, 2].max() < 2.0  # a person's height
    # face forward (+x of the arm base frame) points at the robot (-x in the world)
    forward = scene.to_world(np.array([1.0, 0.0, 0.0])) - scene.to_world(np.zeros(3))
    assert forward @ np.array([-1.0, 0.0, 0.0]) > 0.99
    assert pts[:, 0].min() > 0.6  # clear of the robot's base


def test_tape_is_drawn_along_the_taped_arm(scene):
    arm = HumanArm("right")
    config = TapeConfig()
    q = np.array([0.5, 0.4, 0.1, 0.8, 0.0, 0.0, 0.0])
    bend, twist = tape_from_arm(arm, q, config)
    tape = reconstruct(bend, twist, config).positions
    scene.update_live(q, np.zeros(6), tape)
    assert _wait_until(lambda: scene._tape.visible and np.allclose(scene.current_q_human(), q))
    drawn = scene.to_world(scene.tape_on_sleeve(tape, q))
    np.testing.assert_allclose(scene._tape.points, drawn, atol=1e-5)
    # drawn on the sleeve: each point moves at most the lift off the fit's tape
    lift = max(scene.layout.tape_lift_m)
    assert np.all(np.linalg.norm(drawn - scene.to_world(tape), axis=1) <= lift + 1e-9)
    # the regions strapped to the arm run along the drawn upper arm and forearm, on its surface
    strapped = drawn[config.shoulder_region + 1 : config.wrist_region + 1]
    joints = scene.to_world(arm.points(q)[:3])

    def distance_to_arm(p: np.ndarray) -> float:
        best = np.inf
        for a, b in zip(joints[:-1], joints[1:], strict=True):
            t = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
            best = min(best, float(np.linalg.norm(a + t * (b - a) - p)))
        return best

    distances = [distance_to_arm(p) for p in strapped]
    assert max(distances) < 0.08
    assert min(distances) >= min(scene.layout.tape_lift_m) - 1e-6  # not inside the arm


@pytest.mark.parametrize("side", ["right", "left"])
def test_default_camera_frames_both_bodies_at_every_reachable_pose(scene, side):
    scene.set_side(side)
    rng = np.random.default_rng(0)
    arm, robot = HumanArm(side), Puma560()
    pts = [
        np.concatenate(scene.robot_mesh_points(rng.uniform(robot.lower, robot.upper)))
        for _ in range(60)
    ]
    pts += [
        np.concatenate(scene.operator_mesh_points(rng.uniform(arm.lower, arm.upper)))
        for _ in range(60)
    ]
    pts = np.concatenate(pts)
    for aspect in SCENE_ASPECTS:
        ndc, depth = camera_projection(pts, scene.layout, aspect)
        assert np.all(depth > 0)
        assert np.all(np.abs(ndc) <= 1.0), aspect


# ---------------------------------------------------------------------- the taped arm

ARM_LINKS = ("upperarm", "lowerarm", "hand")
"""The links of an arm whose origins are its shoulder, elbow and wrist."""


def _arm_handles(scene, side: str) -> dict[str, object]:
    """The operator's mesh handles of one arm (shoulder to hand), by part name."""
    names = [p.name for p in scene.body.parts]
    return {
        name: scene._operator_handles[i]
        for i, name in enumerate(names)
        if name.split("/")[0] in {f"{side}_{link}" for link in ARM_LINKS}
    }


def _expected_positions(scene, q_human) -> dict[str, np.ndarray]:
    """World position of every operator mesh with the taped arm at ``q_human``."""
    poses = scene._operator.worldMbase @ scene.body.poses(q_human)
    return {p.name: poses[i, :3, 3] for i, p in enumerate(scene.body.parts)}


def _assert_drawn(scene, q_human) -> None:
    """Every operator handle is where the current taped arm at ``q_human`` puts it."""
    expected = _expected_positions(scene, q_human)
    for part, handle in zip(scene.body.parts, scene._operator_handles, strict=True):
        np.testing.assert_allclose(handle.position, expected[part.name], atol=1e-5)


def _switch(scene, side: str) -> None:
    scene.set_side(side)
    assert scene.side == side
    assert wait_for(lambda: scene.shown_side == side)


def _distance_to_polyline(p: np.ndarray, joints: np.ndarray) -> float:
    best = np.inf
    for a, b in zip(joints[:-1], joints[1:], strict=True):
        t = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
        best = min(best, float(np.linalg.norm(a + t * (b - a) - p)))
    return best


def _world_arm(scene, side: str, q_human) -> np.ndarray:
    """World shoulder, elbow and wrist of ``side``'s arm (the taped arm at ``q_human``)."""
    body = scene.body
    return scene.to_world(
        np.stack([body.link_pose(f"{side}_{link}", q_human)[:3, 3] for link in ARM_LINKS])
    )


def test_a_left_tape_moves_the_left_arm_and_rests_the_right(scene):
    """After set_side("left") the left arm's meshes follow q_human (where HumanArm("left") puts
    them) and the right arm keeps its rest pose; back on the right, the left arm rests again."""
    rest = _expected_positions(scene, None)
    rest_rotation = {
        p.name: m[:3, :3]
        for p, m in zip(
            scene.body.parts, scene._operator.worldMbase @ scene.body.poses(None), strict=True
        )
    }
    q = np.array([0.9, 0.3, 0.2, 1.1, 0.0, 0.2, 0.0])
    _switch(scene, "left")
    scene.update_live(q, np.zeros(6), None)
    assert wait_for(lambda: np.allclose(scene.current_q_human(), q))
    _assert_drawn(scene, q)
    left, right = _arm_handles(scene, "left"), _arm_handles(scene, "right")
    assert len(left) == len(right) == len(scene.body.moving) >= 3
    np.testing.assert_allclose(
        left["left_hand/hand_mesh"].position,
        scene.to_world(HumanArm("left").forward(q).wrist[:3, 3]),
        atol=1e-5,
    )
    for name, handle in left.items():  # moved off the rest pose (the shoulder only turns)
        turned = not np.allclose(_rotation_of(handle.wxyz), rest_rotation[name], atol=0.1)
        assert turned or np.linalg.norm(np.asarray(handle.position) - rest[name]) > 0.05, name
    for name, handle in right.items():  # resting
        np.testing.assert_allclose(handle.position, rest[name], atol=1e-5)

    _switch(scene, "right")
    assert np.allclose(scene.current_q_human(), 0.0)  # the new taped arm rests until a fit
    _assert_drawn(scene, None)  # the left arm went back to rest
    scene.update_live(q, np.zeros(6), None)
    assert wait_for(lambda: np.allclose(scene.current_q_human(), q))
    _assert_drawn(scene, q)
    for name, handle in _arm_handles(scene, "left").items():
        np.testing.assert_allclose(handle.position, rest[name], atol=1e-5)
    np.testing.assert_allclose(
        _arm_handles(scene, "right")["right_hand/hand_mesh"].position,
        scene.to_world(HumanArm("right").forward(q).wrist[:3, 3]),
        atol=1e-5,
    )


def test_the_resting_body_stands_on_the_same_spot_whichever_arm_is_taped(scene):
    rest_right = np.concatenate(scene.operator_mesh_points(None))
    scene.set_side("left")
    np.testing.assert_allclose(
        np.concatenate(scene.operator_mesh_points(None)), rest_right, atol=1e-9
    )


def test_a_left_tape_is_drawn_along_the_left_sleeve(scene):
    config = TapeConfig(side="left")
    q = np.array([0.5, 0.4, 0.1, 0.8, 0.0, 0.0, 0.0])
    bend, twist = tape_from_arm(HumanArm("left"), q, config)
    tape = reconstruct(bend, twist, config).positions
    scene.set_side("left")
    scene.update_live(q, np.zeros(6), tape)
    assert wait_for(lambda: scene._tape.visible and np.allclose(scene.current_q_human(), q))
    drawn = np.asarray(scene._tape.points, dtype=float)
    np.testing.assert_allclose(drawn, scene.to_world(scene.tape_on_sleeve(tape, q)), atol=1e-5)
    strapped = drawn[config.shoulder_region + 1 : config.wrist_region + 1]
    left, right = _world_arm(scene, "left", q), _world_arm(scene, "right", q)
    np.testing.assert_allclose(left, scene.to_world(HumanArm("left").points(q)[:3]), atol=1e-9)
    near = [_distance_to_polyline(p, left) for p in strapped]
    far = [_distance_to_polyline(p, right) for p in strapped]
    assert max(near) < 0.08  # on the left sleeve
    assert min(near) >= min(scene.layout.tape_lift_m) - 1e-6  # not inside the arm
    assert min(far) > 0.25  # nowhere near the resting right arm


def test_switching_the_arm_hides_the_old_arms_tape(scene):
    config = TapeConfig()
    q = np.array([0.5, 0.4, 0.1, 0.8, 0.0, 0.0, 0.0])
    bend, twist = tape_from_arm(HumanArm("right"), q, config)
    scene.update_live(q, np.zeros(6), reconstruct(bend, twist, config).positions)
    assert wait_for(lambda: scene._tape.visible and np.allclose(scene.current_q_human(), q))
    _switch(scene, "left")
    assert not scene._tape.visible  # it was strapped to the right arm, now resting


def test_set_side_is_a_no_op_on_the_taped_arm_and_refuses_a_bad_one(scene):
    operator = scene._operator
    scene.set_side("right")
    assert scene._operator is operator
    for bad in ("up", "RIGHT", None, ["left"]):
        with pytest.raises(KinematicsError, match="right.*left") as err:
            scene.set_side(bad)
        assert str(err.value).count(". ") == 0  # one sentence
    assert scene._operator is operator
    assert scene.side == "right"


def test_set_side_is_safe_against_the_scene_thread(scene):
    """Switching arms while live poses stream in: no failed push, and the scene settles on the
    last arm at the last pose, the other arm at rest."""
    rest = _expected_positions(scene, None)
    stop = threading.Event()
    rng = np.random.default_rng(3)
    poses = rng.uniform(-0.5, 0.5, (64, 7))

    def stream() -> None:
        k = 0
        while not stop.is_set():
            scene.update_live(poses[k % len(poses)], np.zeros(6), None)
            k += 1
            time.sleep(0.001)

    streamer = threading.Thread(target=stream)
    streamer.start()
    try:
        for k in range(20):
            scene.set_side("left" if k % 2 == 0 else "right")
            pushed = scene.pushes
            assert wait_for(lambda p=pushed: scene.pushes > p + 1)
    finally:
        stop.set()
        streamer.join()
    assert scene.errors == 0
    q = np.array([0.3, 0.2, 0.1, 0.6, 0.0, 0.0, 0.0])
    scene.update_live(q, np.zeros(6), None)
    assert wait_for(lambda: np.allclose(scene.current_q_human(), q))
    assert scene.shown_side == scene.side == "right"
    _assert_drawn(scene, q)
    for name, handle in _arm_handles(scene, "left").items():
        np.testing.assert_allclose(handle.position, rest[name], atol=1e-5)


def test_reset_view_puts_the_camera_back(server, scene):
    assert np.allclose(server.initial_camera.position, scene.layout.camera_position)
    scene.reset_view()  # no browser connected: nothing to move, and no error


def test_update_live_never_blocks_while_viser_is_busy(scene, monkeypatch):
    """A stalled push (slow client) must not hold up the 110 Hz caller."""
    release = threading.Event()
    held = threading.Event()
    push = scene._push_robot

    def stalled(handles, q):
        held.set()
        release.wait(5.0)
        push(handles, q)

    monkeypatch.setattr(scene, "_push_robot", stalled)
    scene.update_live(np.zeros(7), np.full(6, -1e-3), None)
    assert held.wait(2.0)
    for i in range(2000):
        scene.update_live(np.zeros(7), np.full(6, i * 1e-4), None)
    latest_q = np.full(6, 1999 * 1e-4)
    assert not np.allclose(scene.current_q_robot(), latest_q)  # nothing pushed while stalled
    release.set()
    # Latest wins: once unblocked, the scene shows the last value, not a backlog.
    assert _wait_until(lambda: np.allclose(scene.current_q_robot(), latest_q))


def test_push_rate_is_bounded(server, body):
    sc = StudioScene(server, body=body, layout=SceneLayout(rate_hz=20.0))
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


def test_an_error_in_the_loop_is_logged_and_the_scene_goes_on(scene, monkeypatch, caplog):
    push = scene._push_robot
    calls = {"n": 0}

    def flaky(handles, q):
        calls["n"] += 1
        if calls["n"] == 1:
            raise RuntimeError("client vanished mid-push")
        push(handles, q)

    monkeypatch.setattr(scene, "_push_robot", flaky)
    with caplog.at_level(logging.ERROR, logger="studio.web.scene._scene"):
        scene.update_live(np.zeros(7), np.full(6, 0.11), None)
        assert _wait_until(lambda: scene.errors >= 1)
        scene.update_live(np.zeros(7), np.full(6, 0.22), None)
        assert _wait_until(lambda: np.allclose(scene.current_q_robot(), 0.22))
    assert any("client vanished" in r.exc_text for r in caplog.records if r.exc_text)


# ---------------------------------------------------------------------- playback


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
    assert scene.mode is Mode.HOLD
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
    assert scene.mode is Mode.LIVE
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
    frames = robot.joint_frames(goal)
    for j, handle in enumerate(scene._ghost_handles):
        np.testing.assert_allclose(handle.position, frames[j][:3, 3], atol=1e-5)
    scene.set_goal(None)
    assert not scene._goal_marker.visible

    path = np.linspace(np.zeros(6), goal, 30)
    scene.show_path("demo-1", path)
    scene.show_path("demo-2", path[:10])
    assert sorted(scene.path_names()) == ["demo-1", "demo-2"]
    np.testing.assert_allclose(
        scene.path_points("demo-1")[-1], robot.forward(goal)[:3, 3], atol=1e-5
    )
    scene.show_path("demo-1", path[:5])  # replacing keeps one entry
    assert sorted(scene.path_names()) == ["demo-1", "demo-2"]
    scene.clear_path("demo-1")
    scene.clear_path("unknown")
    assert scene.path_names() == ["demo-2"]
    scene.clear_path()
    assert scene.path_names() == []


def test_wxyz_of_is_vectorised():
    rng = np.random.default_rng(0)
    rots = np.stack([np.linalg.qr(rng.normal(size=(3, 3)))[0] for _ in range(5)])
    rots[np.linalg.det(rots) < 0, :, 0] *= -1
    quats = wxyz_of(rots)
    assert quats.shape == (5, 4)
    for r, q in zip(rots, quats, strict=True):
        np.testing.assert_allclose(_rotation_of(q), r, atol=1e-9)
