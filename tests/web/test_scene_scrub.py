"""Scrubbing a watched rollout, camera presets and posing the robot by hand: the pure laws
(:func:`rescheduled`, :func:`playback_time`, :func:`pose_at` paused and at speed, the presets'
geometry) and the ``/api/scene`` routes on a real headless scene."""

from __future__ import annotations

import numpy as np
import pytest
import viser
from fastapi.testclient import TestClient
from hypothesis import given, settings
from hypothesis import strategies as st

from studio.kinematics import load_robot
from studio.web import create_app
from studio.web.scene._model import Mode, playback_time, pose_at, rescheduled
from studio.web.scene._scene import SceneLayout, StudioScene
from studio.web.scene._views import VIEW_NAMES, camera_view, following
from tests.conftest import free_port
from tests.web.conftest import make_settings, wait_for
from tests.web.test_policies import policy_bytes, upload
from tests.web.test_scene import _playback

# ---------------------------------------------------------------------- the pure laws


@given(
    n=st.integers(2, 40),
    duration=st.floats(0.05, 20.0),
    t=st.floats(0.0, 1.0),
    speed=st.sampled_from([0.25, 0.5, 1.0, 2.0, 4.0]),
    later=st.floats(0.0, 3.0),
)
@settings(max_examples=200, deadline=None)
def test_a_scrubbed_playback_runs_from_the_scrub_point_at_its_speed(n, duration, t, speed, later):
    pb = rescheduled(_playback(n, duration), 10.0, t=t * duration, speed=speed)
    assert playback_time(pb, 10.0) == pytest.approx(t * duration)
    assert playback_time(pb, 10.0 + later) == pytest.approx(t * duration + later * speed)
    # paused, it stands still however long it waits, and is never handed back to live
    paused = rescheduled(pb, 10.0 + later, paused=True)
    at = min(t * duration + later * speed, duration)
    for wait in (0.0, 1.0, 1000.0):
        pose = pose_at(10.0 + later + wait, np.full(6, 9.0), paused, hold_s=1.0)
        assert pose.mode is Mode.PLAYBACK
        assert pose.q_robot[0] == pytest.approx(at / duration, abs=1e-9)


@given(n=st.integers(2, 30), start=st.floats(0.0, 1.0), step=st.integers(-40, 40).filter(bool))
@settings(max_examples=200, deadline=None)
def test_a_step_lands_on_a_neighbouring_sample_and_pauses(n, start, step):
    pb = _playback(n, 3.0)
    at = start * 3.0
    stepped = rescheduled(pb, 5.0, t=at, step=step)
    assert stepped.paused
    k = int(np.flatnonzero(pb.times == stepped.offset)[0])  # on a sample exactly
    at_or_before = int(np.searchsorted(pb.times, at, side="right")) - 1
    at_or_after = int(np.searchsorted(pb.times, at, side="left"))
    if step > 0:  # the step-th sample after the time reached
        assert k == min(at_or_before + step, n - 1)
        assert pb.times[k] > at or k == n - 1
    elif step < 0:  # the step-th sample before it
        assert k == max(at_or_after + step, 0)
        assert pb.times[k] < at or k == 0
    # one forward then one back returns to the same sample (inside the trajectory)
    inside = (n - 1) // 2
    there = rescheduled(pb, 5.0, t=float(pb.times[inside]), step=1)
    back = rescheduled(there, 6.0, step=-1)
    assert back.offset == pb.times[inside]


def test_resuming_at_the_end_starts_over_and_keeps_the_speed():
    pb = rescheduled(_playback(5, 2.0), 0.0, t=2.0, paused=True, speed=2.0)
    again = rescheduled(pb, 1.0, paused=False)
    assert again.offset == 0.0 and not again.paused and again.speed == 2.0
    assert playback_time(again, 1.5) == pytest.approx(1.0)
    ended = _playback(5, 2.0)  # played to its end, never paused
    assert rescheduled(ended, 9.0, paused=False).offset == 0.0
    assert rescheduled(ended, 9.0, speed=2.0).offset == 2.0  # a speed change alone keeps it


def test_a_fast_playback_holds_its_last_pose_for_the_hold_in_clock_seconds():
    pb = rescheduled(_playback(5, 2.0), 0.0, speed=4.0)  # ends at clock 0.5 s
    assert pose_at(0.5 + 0.9, None, pb, hold_s=1.0).mode is Mode.HOLD
    assert pose_at(0.5 + 1.1, None, pb, hold_s=1.0).mode is Mode.LIVE


def test_presets_frame_the_target_from_the_default_distance_and_differ():
    layout = SceneLayout()
    target = np.array(layout.camera_look_at)
    distance = np.linalg.norm(np.array(layout.camera_position) - target)
    views = {name: camera_view(name, layout) for name in VIEW_NAMES}
    for v in views.values():
        assert np.allclose(v.look_at, target)
        assert np.linalg.norm(np.array(v.position) - target) == pytest.approx(distance)
    assert views["top"].position[2] > target[2] + 0.99 * distance  # looking down
    assert views["front"].position[1] < target[1] - 0.99 * distance  # from -Y
    assert views["side"].position[0] < target[0] - 0.99 * distance  # from behind the robot
    moved = following((1.0, 2.0, 3.0), (0.0, 0.0, 1.0), np.array([0.5, 0.5, 0.5]))
    assert np.allclose(moved.look_at, (0.5, 0.5, 0.5))
    assert np.allclose(moved.position, (1.5, 2.5, 2.5))


# ---------------------------------------------------------------------- the API, a real scene


@pytest.fixture
def scene_api(tmp_path):
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    scene = StudioScene(server, layout=SceneLayout(rate_hz=100.0))
    try:
        with TestClient(create_app(make_settings(tmp_path), scene)) as client:
            yield client, scene, tmp_path
    finally:
        scene.close()
        server.stop()


def test_scrub_a_watched_rollout_through_the_api(scene_api):
    client, scene, tmp_path = scene_api
    assert client.get("/api/scene/playback").json()["active"] is False
    r = client.post("/api/scene/playback", json={"t": 0.0})
    assert r.status_code == 409 and "watch a policy first" in r.json()["detail"]
    assert upload(client, "reach.policy.npz", policy_bytes(tmp_path)).status_code == 201
    w = client.post("/api/watch", json={"policy": "reach", "seed": 1}).json()
    times, q = np.array(w["times"]), np.array(w["q_robot"])
    assert len(times) > 4
    # scrub to the middle, paused: the scene shows that sample's joints and stays there
    mid = len(times) // 2
    p = client.post("/api/scene/playback", json={"t": times[mid], "paused": True}).json()
    assert p["paused"] and p["sample"] == mid and p["duration"] == pytest.approx(times[-1])
    assert wait_for(lambda: np.allclose(scene.current_q_robot(), q[mid], atol=1e-6), 5)
    # one sample forward and back
    p = client.post("/api/scene/playback", json={"step": 1}).json()
    assert p["sample"] == mid + 1
    assert wait_for(lambda: np.allclose(scene.current_q_robot(), q[mid + 1], atol=1e-6), 5)
    p = client.post("/api/scene/playback", json={"step": -1}).json()
    assert p["sample"] == mid
    assert wait_for(lambda: np.allclose(scene.current_q_robot(), q[mid], atol=1e-6), 5)
    now = client.get("/api/scene/playback").json()
    assert np.allclose(np.radians(now["q_robot_deg"]), q[mid], atol=1e-5)
    assert now["shown_sample"] == mid  # which sample the joints shown are
    # to the end: the joints read with shown_sample at the last sample are the last sample's
    client.post("/api/scene/playback", json={"t": times[-1], "paused": True})
    assert wait_for(
        lambda: client.get("/api/scene/playback").json()["shown_sample"] == len(times) - 1, 5
    )
    assert np.allclose(
        np.radians(client.get("/api/scene/playback").json()["q_robot_deg"]), q[-1], atol=1e-5
    )
    # speed and resume
    p = client.post("/api/scene/playback", json={"speed": 4, "paused": False}).json()
    assert p["speed"] == 4 and not p["paused"]
    # bad values: one sentence each
    for body, word in (
        ({"speed": 8}, "speed"),
        ({"t": times[-1] + 1}, "outside the rollout"),
        ({"t": -1}, "outside the rollout"),
        ({"warp": 1}, "warp"),
    ):
        r = client.post("/api/scene/playback", json=body)
        assert r.status_code == 422 and word in r.json()["detail"], (body, r.text)


def test_camera_presets_and_follow_through_the_api(scene_api):
    client, scene, _ = scene_api
    views = client.get("/api/scene/views").json()
    assert views["views"] == ["front", "top", "side"] and views["following"] is False
    assert client.post("/api/scene/view", json={"view": "top"}).status_code == 200
    r = client.post("/api/scene/view", json={"view": "back"})
    assert r.status_code == 422 and "view" in r.json()["detail"]
    assert client.post("/api/scene/follow", json={"on": True}).json()["following"] is True
    assert scene.camera.following
    assert client.post("/api/scene/follow", json={"on": False}).json()["following"] is False


def test_jog_the_robot_within_its_limits(scene_api):
    client, scene, _ = scene_api
    jog = client.get("/api/scene/jog").json()
    assert [j["name"] for j in jog["joints"]] == [f"joint {i}" for i in range(1, 7)]
    # The sliders span the usable limits: Corke's hard limits less the margin.
    puma = load_robot("puma560")
    assert jog["joints"][0]["lower_deg"] == pytest.approx(np.degrees(puma.lower[0]))
    assert jog["joints"][1]["upper_deg"] == pytest.approx(np.degrees(puma.upper[1]))
    assert -160 < jog["joints"][0]["lower_deg"] < -158 and 108 < jog["joints"][1]["upper_deg"] < 110
    q = [30.0, -20.0, 45.0, 0.0, 10.0, 0.0]
    assert client.post("/api/scene/jog", json={"q_deg": q}).status_code == 200
    assert wait_for(lambda: np.allclose(scene.current_q_robot(), np.radians(q), atol=1e-6), 5)
    assert scene.mode is Mode.PLAYBACK  # held, not handed back to the live pose
    r = client.post("/api/scene/jog", json={"q_deg": [170.0, 0, 0, 0, 0, 0]})
    assert r.status_code == 422 and "joint 1 is 170°" in r.json()["detail"]
    r = client.post("/api/scene/jog", json={"q_deg": [0.0, 0.0]})
    assert r.status_code == 422 and "one angle per joint" in r.json()["detail"]


def test_scene_changes_are_refused_from_another_site(scene_api):
    client, _, _ = scene_api
    r = client.post(
        "/api/scene/view", json={"view": "top"}, headers={"Origin": "http://evil.example"}
    )
    assert r.status_code == 403
