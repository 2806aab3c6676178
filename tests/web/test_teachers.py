"""The camera and hand-guide sources through the API: contract, bad input, floods, the guard, and
recordings that keep every frame."""

from __future__ import annotations

import json
import math
import time

import numpy as np
import pandas as pd
import pytest
from fastapi.testclient import TestClient

from studio.capture import read_any_recording

REACH = {"position": [0.35, 0.0, -0.3], "wxyz": None}
"""A hand pose in front of the shoulder, well within reach."""


def landmarks(seed: int = 0) -> dict:
    """A plausible frame: a person facing the camera, arms down, all in view."""
    rng = np.random.default_rng(seed)
    world = np.zeros((33, 4))
    world[:, 3] = 0.99
    image = np.zeros((33, 3))
    image[:, :2] = 0.5 + rng.normal(0, 0.01, (33, 2))
    image[:, 2] = 0.99
    for i, (x, y) in {
        11: (0.17, -0.45),
        12: (-0.17, -0.45),
        13: (0.2, -0.2),
        14: (-0.2, -0.2),
        15: (0.22, 0.05),
        16: (-0.22, 0.05),
        23: (0.1, 0.0),
        24: (-0.1, 0.0),
    }.items():
        world[i, :3] = (x, y, 0.0)
        image[i, :2] = (0.5 + x / 2, 0.5 + y / 2)
    return {
        "t": 0.0,
        "world": world.tolist(),
        "image": image.tolist(),
        "width": 640,
        "height": 480,
        "fps": 3.5,
        "model": "lite",
    }


def camera(client: TestClient, side: str = "right") -> None:
    r = client.put("/api/source", json={"kind": "camera", "side": side})
    assert r.status_code == 200, r.text
    assert r.json()["kind"] == "camera" and r.json()["side"] == side


def test_landmarks_need_the_camera_source(client: TestClient) -> None:
    r = client.post("/api/source/landmarks", json=landmarks())
    assert r.status_code == 409
    assert "camera" in r.json()["detail"]
    assert client.post("/api/source/hand", json=REACH).status_code == 409


def test_no_person_is_counted_and_said(client: TestClient) -> None:
    camera(client)
    frame = {**landmarks(), "world": None, "image": None}
    r = client.post("/api/source/landmarks", json=frame)
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["person_detected"] is False
    assert "No person in view" in body["warning"]
    source = client.get("/api/source").json()
    assert source["frames"] == 1 and source["person_detected"] is False
    assert source["camera_fps"] == 3.5 and source["model"] == "lite"
    # nothing was fitted: no residual to show (it read "0.0 mm", as if the fit were exact)
    assert source["fit_residual_mm"] is None


def test_bad_landmarks_get_one_sentence(client: TestClient) -> None:
    camera(client)
    good = landmarks()
    nan = json.loads(json.dumps(good))
    nan["world"][3][1] = math.nan
    short = {**good, "world": good["world"][:32]}
    narrow = {**good, "image": [row[:2] for row in good["image"]]}
    cases = {
        "NaN": json.dumps(nan),
        "33": json.dumps(short),
        "shape": json.dumps(narrow),
        "width": json.dumps({**good, "width": 0}),
    }
    for word, body in cases.items():
        r = client.post(
            "/api/source/landmarks", content=body, headers={"Content-Type": "application/json"}
        )
        assert r.status_code == 422, (word, r.text)
        detail = r.json()["detail"]
        assert detail.count(". ") == 0 and detail.endswith("."), detail
    assert client.get("/api/source").json()["frames"] == 0  # nothing bad was counted
    r = client.post(
        "/api/source/landmarks",
        content=b'{"t": 0, "pad": "' + b"x" * 70_000 + b'"}',
        headers={"Content-Type": "application/json"},
    )
    assert r.status_code == 413
    assert "one frame" in r.json()["detail"]


def test_writes_from_another_site_are_refused(client: TestClient) -> None:
    camera(client)
    r = client.post(
        "/api/source/landmarks", json=landmarks(), headers={"Origin": "https://evil.example"}
    )
    assert r.status_code == 403
    r = client.post("/api/source/hand", json=REACH, headers={"Origin": "https://evil.example"})
    assert r.status_code == 403
    assert client.get("/api/source").json()["frames"] == 0


def flood(client: TestClient) -> None:
    """Make the live fed source believe it took a full second's worth of updates just now."""
    source = client.app.state.studio.pipeline.source
    source._admitted.extend([time.monotonic()] * source._admitted.maxlen)


def test_a_flood_is_refused_and_the_recording_keeps_every_frame(client: TestClient) -> None:
    camera(client)
    assert client.post("/api/capture/start", json={"name": "cam"}).status_code in (200, 201)
    no_one = {**landmarks(), "world": None, "image": None}
    for i in range(5):
        assert client.post("/api/source/landmarks", json={**no_one, "t": i / 30}).status_code == 200
    flood(client)
    r = client.post("/api/source/landmarks", json={**no_one, "t": 1.0})
    assert r.status_code == 429, r.text
    assert "in one second" in r.json()["detail"]
    bad = {**no_one, "t": 1.1, "width": -1}
    assert client.post("/api/source/landmarks", json=bad).status_code == 422
    assert client.get("/api/source").json()["dropped"] == 1  # the studio runs on
    assert client.post("/api/capture/stop").status_code == 200
    path = client.app.state.studio.recordings.path("cam")
    assert path.name == "cam.pose.csv"
    recording = read_any_recording(path)
    assert len(recording) == 5 and not recording.recovered
    assert pd.read_csv(path, comment="#")["person"].tolist() == [0] * 5
    listed = {r["name"]: r for r in client.get("/api/recordings").json()}
    assert listed["cam"]["frames"] == 5


class FakeClock:
    """The studio's monotonic clock for fed sources, moved by the test."""

    def __init__(self, monkeypatch: pytest.MonkeyPatch) -> None:
        self.now = 1000.0
        monkeypatch.setattr("studio.capture._push_sources.time.monotonic", lambda: self.now)


def test_a_page_reload_keeps_time_moving_forward(client: TestClient, monkeypatch) -> None:
    clock = FakeClock(monkeypatch)
    camera(client)
    no_one = {**landmarks(), "world": None, "image": None}
    assert client.post("/api/capture/start", json={"name": "reload"}).status_code in (200, 201)
    for t in (10.0, 10.1, 0.0, 0.1):  # the page reloaded between the second and third
        if t == 0.0:
            clock.now += 3.0  # a reload: the page and its pose model load again
        assert client.post("/api/source/landmarks", json={**no_one, "t": t}).status_code == 200
        clock.now += 0.1
    client.post("/api/capture/stop")
    t = read_any_recording(client.app.state.studio.recordings.path("reload")).t
    assert (np.diff(t) > 0).all()
    assert np.allclose(np.diff(t), [0.1, 3.1, 0.1])  # the gap as the studio's clock saw it


def test_a_second_page_sending_frames_is_refused_and_time_stays_true(
    client: TestClient, monkeypatch
) -> None:
    """Two tabs with the camera source, each with its own clock: 120 frames over 4.8 s were once
    recorded as 23,504 s (every step back taken as a reload). The second page is refused while
    the first sends; once the first is gone, the second takes over."""
    clock = FakeClock(monkeypatch)
    camera(client)
    no_one = {**landmarks(), "world": None, "image": None}
    assert client.post("/api/capture/start", json={"name": "two"}).status_code in (200, 201)
    refused = []
    for k in range(60):
        for page_clock in (8000.0, 3.0):  # pages opened about two hours apart
            r = client.post("/api/source/landmarks", json={**no_one, "t": page_clock + k / 25})
            if r.status_code != 200:
                refused.append(r)
        clock.now += 1 / 25
    assert len(refused) == 60 and {r.status_code for r in refused} == {409}
    assert refused[0].json()["detail"].startswith("Another page is sending pose frames")
    clock.now += 2.0  # the first page is closed; the second takes over
    for k in range(10):
        r = client.post("/api/source/landmarks", json={**no_one, "t": 5.0 + k / 25})
        assert r.status_code == 200, r.text
        clock.now += 1 / 25
    client.post("/api/capture/stop")
    t = read_any_recording(client.app.state.studio.recordings.path("two")).t
    assert len(t) == 70 and (np.diff(t) > 0).all()
    assert t[-1] - t[0] == pytest.approx(59 / 25 + 2.0 + 1 / 25 + 9 / 25, abs=1e-6)


def test_a_page_named_by_its_id_is_one_sender_however_slowly_its_frames_are_estimated(
    client: TestClient, monkeypatch
) -> None:
    """A page stamps each frame with the camera's capture time. On a busy machine one frame may
    take seconds to estimate and the next a tenth: by its times alone the page would seem to jump
    clocks and be refused as a second tab (a browser test's camera once lost frames so). Pages
    name themselves; a second tab is still refused, even one whose clock runs with the first's."""
    clock = FakeClock(monkeypatch)
    camera(client)
    no_one = {**landmarks(), "world": None, "image": None}
    assert client.post("/api/capture/start", json={"name": "slow"}).status_code in (200, 201)
    # captured every 1/25 s and sent 0.1 s later, but for the fourth, estimated in 2.5 s
    latency = [0.1, 0.1, 0.1, 2.5, 0.1, 0.1]
    start = clock.now
    for k, late in enumerate(latency):
        clock.now = start + k / 25 + late
        r = client.post(
            "/api/source/landmarks", json={**no_one, "t": 50.0 + k / 25, "sender": "a-1"}
        )
        assert r.status_code == 200, r.text
    # a second tab opened a moment after the first: its clock runs with the first's
    r = client.post("/api/source/landmarks", json={**no_one, "t": 50.0 + 6 / 25, "sender": "b-2"})
    assert r.status_code == 409 and r.json()["detail"].startswith("Another page is sending")
    client.post("/api/capture/stop")
    t = read_any_recording(client.app.state.studio.recordings.path("slow")).t
    assert len(t) == 6 and np.allclose(np.diff(t), 1 / 25)  # the camera's own pace


@pytest.mark.parametrize("sender", ["", "a" * 65, "caf\u00e9", "a b"])
def test_a_malformed_sender_id_is_refused_in_one_sentence(client: TestClient, sender) -> None:
    camera(client)
    no_one = {**landmarks(), "world": None, "image": None}
    r = client.post("/api/source/landmarks", json={**no_one, "t": 1.0, "sender": sender})
    assert r.status_code == 422 and "sender" in r.text


def test_hand_guide_moves_the_arm_and_the_robot(client: TestClient) -> None:
    r = client.put("/api/source", json={"kind": "hand"})
    assert r.status_code == 200 and r.json()["kind"] == "hand"
    before = np.array(client.get("/api/source").json()["q_robot"])
    r = client.post("/api/source/hand", json=REACH)
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["reached"] is True and body["position_error_m"] < 0.01
    after = np.array(client.get("/api/source").json()["q_robot"])
    assert np.allclose(after, body["q_robot"])
    assert np.abs(after - before).max() > 0.1
    source = client.get("/api/source").json()
    assert source["frames"] == 1 and source["side"] == "right"
    for bad in (
        {"position": [0, math.nan, 0]},
        {"position": [0, 0]},
        {"position": [0, 0, 0], "wxyz": [0, 0, 0, 0]},
    ):
        r = client.post(
            "/api/source/hand",
            content=json.dumps(bad),
            headers={"Content-Type": "application/json"},
        )
        assert r.status_code == 422, (bad, r.text)
    flood(client)
    assert client.post("/api/source/hand", json=REACH).status_code == 429


def test_hand_guide_recording_cuts_into_a_demonstration(client: TestClient) -> None:
    client.put("/api/source", json={"kind": "hand"})
    client.put("/api/source/retarget", json={"mode": "joint", "mirror": True})
    assert client.post("/api/capture/start", json={"name": "guide"}).status_code in (200, 201)
    for k in range(30):
        s = k / 29
        target = {"position": [0.3 + 0.15 * s, 0.05 + 0.05 * s, -0.4 + 0.35 * s], "wxyz": None}
        assert client.post("/api/source/hand", json=target).status_code == 200
    client.post("/api/capture/stop")
    path = client.app.state.studio.recordings.path("guide")
    assert path.name == "guide.hand.csv"
    recording = read_any_recording(path)
    assert len(recording) == 30
    r = client.post(
        "/api/demonstrations",
        json={"recording": "guide", "t0": 0, "t1": recording.duration, "goal_from_end": True},
    )
    assert r.status_code == 201, r.text
    demo = client.get(f"/api/demonstrations/{r.json()['name']}").json()
    assert demo["steps"] >= 1


def test_a_pose_recording_plays_back_as_the_source(open_client, tmp_path) -> None:
    from studio.capture._observation_recording import ObservationWriter
    from studio.capture._observations import landmark_frame

    folder = tmp_path / "recordings"
    folder.mkdir(parents=True, exist_ok=True)
    with ObservationWriter(folder / "seen.pose.csv", "pose") as writer:
        writer.write_many([landmark_frame(i / 30, i, None, None, 640, 480) for i in range(30)])
    client = open_client(source=str(folder / "seen.pose.csv"))
    source = client.get("/api/source").json()
    assert source["kind"] == "recording" and source["recording"] == "seen"
    assert source["playback"]["duration"] > 0.9
    listed = {r["name"]: r for r in client.get("/api/recordings").json()}
    assert listed["seen"]["frames"] == 30 and listed["seen"]["error"] is None
    assert listed["seen"]["kind"] == "pose"
    r = client.get("/api/recordings/seen/file")
    assert r.status_code == 200 and "seen.pose.csv" in r.headers["content-disposition"]


def arm_motion(n: int = 30) -> list[dict]:
    """Landmark frames of a right arm raising forward and bending (the studio's own arm model)."""
    from studio.kinematics import HumanArm, landmarks_from_arm

    arm = HumanArm("right")
    out = []
    for i, s in enumerate(np.linspace(0.0, 1.0, n)):
        q = np.zeros(7)
        q[1], q[3] = 1.1 * s, 0.9 * s
        world, image = landmarks_from_arm(q, arm)
        out.append({**landmarks(), "t": i / 30, "world": world.tolist(), "image": image.tolist()})
    return out


def test_camera_frames_move_the_robot_and_cut_into_a_demonstration(client: TestClient) -> None:
    camera(client)
    client.put("/api/source/retarget", json={"mode": "joint", "mirror": True})
    assert client.post("/api/capture/start", json={"name": "cam-reach"}).status_code in (200, 201)
    answers = []
    for frame in arm_motion():
        r = client.post("/api/source/landmarks", json=frame)
        assert r.status_code == 200, r.text
        answers.append(r.json())
    assert all(a["person_detected"] for a in answers)
    assert answers[-1]["observable"][3]  # a bent elbow is seen
    first, last = np.array(answers[0]["q_robot"]), np.array(answers[-1]["q_robot"])
    assert np.abs(last - first).max() > 0.3
    source = client.get("/api/source").json()
    assert source["frames"] == 30 and source["observable"] == answers[-1]["observable"]
    assert np.allclose(source["q_robot"], answers[-1]["q_robot"])
    client.post("/api/capture/stop")
    recording = read_any_recording(client.app.state.studio.recordings.path("cam-reach"))
    kept = pd.read_csv(recording.path, comment="#").filter(regex="^observable_").to_numpy()
    assert kept[-1].astype(bool).tolist() == answers[-1]["observable"]
    r = client.post(
        "/api/demonstrations",
        json={"recording": "cam-reach", "t0": 0, "t1": recording.duration, "goal_from_end": True},
    )
    assert r.status_code == 201, r.text


def test_with_a_token_landmarks_and_hand_poses_need_it(open_client) -> None:
    client = open_client(token="t0k-en")
    auth = {"Authorization": "token t0k-en"}
    assert client.put("/api/source", json={"kind": "camera"}, headers=auth).status_code == 200
    no_one = {**landmarks(), "world": None, "image": None}
    assert client.post("/api/source/landmarks", json=no_one).status_code == 403
    assert client.post("/api/source/landmarks", json=no_one, headers=auth).status_code == 200
    assert client.put("/api/source", json={"kind": "hand"}, headers=auth).status_code == 200
    assert client.post("/api/source/hand", json=REACH).status_code == 403
    assert client.post("/api/source/hand", json=REACH, headers=auth).status_code == 200


def test_a_frame_posted_meanwhile_is_written_after_the_one_being_fitted(
    client: TestClient, monkeypatch
) -> None:
    """A frame was numbered and timed under one lock and written under another: with several
    senders, a later frame could be written first (time and counter going back in the file, the
    take impossible to cut). Here a second post arrives while the first is being fitted."""
    import threading

    camera(client)
    no_one = {**landmarks(), "world": None, "image": None}
    assert client.post("/api/capture/start", json={"name": "order"}).status_code in (200, 201)
    studio = client.app.state.studio
    pipeline, source = studio.pipeline, studio.pipeline.source
    second_arrived, entered = threading.Event(), []
    real_fit, real_submit = pipeline._fit, source.submit

    class Announcing:
        """The studio's lock, saying when the second post waits for it."""

        def __init__(self, lock) -> None:
            self.lock = lock

        def __enter__(self):
            entered.append(1)
            if len(entered) == 2:  # the second post
                second_arrived.set()
            return self.lock.__enter__()

        def __exit__(self, *exc):
            return self.lock.__exit__(*exc)

    def submit(t, *args, **kwargs):
        if t == 1.04:
            second_arrived.set()  # (were it not waiting, it would be numbered now)
        return real_submit(t, *args, **kwargs)

    def slow_fit(src, observations):
        if observations[0].frame == 0:
            assert second_arrived.wait(30)
        return real_fit(src, observations)

    sources = studio.sources  # the fed frames' lock is the sources service's
    monkeypatch.setattr(sources, "_fed_lock", Announcing(sources._fed_lock))
    monkeypatch.setattr(source, "submit", submit)
    monkeypatch.setattr(pipeline, "_fit", slow_fit)
    first = threading.Thread(
        target=client.post, args=("/api/source/landmarks",), kwargs={"json": {**no_one, "t": 1.0}}
    )
    first.start()
    assert wait_for_fit_of_frame_0(source)
    second = threading.Thread(
        target=client.post, args=("/api/source/landmarks",), kwargs={"json": {**no_one, "t": 1.04}}
    )
    second.start()
    first.join(30)
    second.join(30)
    client.post("/api/capture/stop")
    recording = read_any_recording(studio.recordings.path("order"))
    assert len(recording) == 2 and (np.diff(recording.t) > 0).all()


def wait_for_fit_of_frame_0(source) -> bool:
    """Whether the first frame was counted in (its fit then waits for the second post)."""
    from tests.web.conftest import wait_for

    return wait_for(lambda: source.status().frames >= 1)
