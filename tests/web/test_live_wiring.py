"""The web layer's wiring: the scene is handed a named live pose and poses the operator once per
pose, outside its thread; every list's owner announces its own changes through one callback."""

from __future__ import annotations

import threading

import numpy as np
import pytest
import viser

from studio.capture import (
    CameraSource,
    HandSource,
    RecordingError,
    RecordingWriter,
    SimulatorSource,
    read_recording,
)
from studio.kinematics import HumanArm, HumanBody, TapeConfig, reconstruct, tape_from_arm
from studio.web._errors import ConflictError
from studio.web.live._pipeline import Pipeline
from studio.web.scene import _scene
from studio.web.scene._protocols import LivePose
from studio.web.scene._scene import SceneLayout, StudioScene
from studio.web.services._store import demonstration_store, recording_store
from tests.capture.conftest import synthetic_frames
from tests.conftest import free_port
from tests.web.conftest import wait_for


@pytest.fixture(scope="module")
def scene():
    server = viser.ViserServer(host="127.0.0.1", port=free_port(), verbose=False)
    sc = StudioScene(server, body=HumanBody("right"), layout=SceneLayout(rate_hz=100.0))
    yield sc
    sc.close()
    server.stop()


def test_the_operator_is_posed_once_per_pose_shown_and_never_for_one_skipped(scene, monkeypatch):
    """The tape on the sleeve is the kinematics package's (``pose_body``), computed by the scene
    thread for the poses it shows only: a 110 Hz source hands in more poses than the scene
    pushes (60 a second with a browser, ``unviewed_rate_hz`` without), and posing each of them
    took a sixth of an idle studio's CPU."""
    calls: list[str] = []
    real = _scene.pose_body

    def counted(*args, **kwargs):
        calls.append(threading.current_thread().name)
        return real(*args, **kwargs)

    monkeypatch.setattr(_scene, "pose_body", counted)
    config = TapeConfig()
    arm = HumanArm("right")
    start = scene.pushes
    for k in range(40):  # handed in back to back: most are overtaken before they are shown
        q = np.array([0.5, 0.4, 0.1, 0.8 + 0.01 * k, 0.0, 0.0, 0.0])
        tape = reconstruct(*tape_from_arm(arm, q, config), config).positions
        scene.show_live(LivePose(q_human=q, q_robot=np.full(6, 0.1 + 0.001 * k), tape=tape))
    assert wait_for(lambda: scene._tape.visible and np.allclose(scene.current_q_human(), q))
    assert wait_for(lambda: np.allclose(scene.current_q_robot(), 0.1 + 0.001 * k))
    pushed = scene.pushes - start
    assert 1 <= len(calls) <= pushed < 40, (len(calls), pushed)
    assert set(calls) == {"studio-scene"}


def test_the_tape_goes_from_the_scene_with_a_source_that_has_none(scene):
    """The green tape stayed drawn in camera and hand-guide modes: a source without a tape
    takes it away at once (the hand guide sends nothing until its handle is dragged), and a
    pose without a tape never brings it back; the next tape source draws it again."""
    q = np.array([0.5, 0.4, 0.1, 0.8, 0.0, 0.0, 0.0])
    config = TapeConfig()
    tape = reconstruct(*tape_from_arm(HumanArm("right"), q, config), config).positions
    pipeline = Pipeline(scene=scene)
    pipeline.set_source(SimulatorSource(), "simulator")
    try:
        scene.show_live(LivePose(q_human=q, q_robot=np.full(6, 0.1), tape=tape))
        assert wait_for(lambda: scene._tape.visible)
        for source, kind in ((HandSource("right"), "hand"), (CameraSource("right"), "camera")):
            pipeline.set_source(source, kind)
            assert wait_for(lambda: not scene._tape.visible), kind
            scene.show_live(LivePose(q_human=q * 0.5, q_robot=np.full(6, 0.2), tape=None))
            assert wait_for(lambda: np.allclose(scene.current_q_human(), q * 0.5))
            assert not scene._tape.visible, kind
            scene.set_side("right")  # a tape source again: its first tape is drawn
            scene.show_live(LivePose(q_human=q, q_robot=np.full(6, 0.1), tape=tape))
            assert wait_for(lambda: scene._tape.visible), kind
    finally:
        pipeline.clear_source()


def test_a_capture_announces_its_recording_when_it_starts_and_when_the_disk_stops_it(tmp_path):
    """A capture that ends by itself (a failed write) changes the recordings list too: the
    pipeline says so, as when the user stops it."""
    announced: list[str] = []
    pipeline = Pipeline(on_change=announced.append)
    frames = synthetic_frames(10)
    path = tmp_path / "cut.tape.csv"
    writer = RecordingWriter(path, regions=frames[0].bend.shape[0])
    pipeline.start_capture(writer, "cut", path)
    assert announced == ["recordings"]
    pipeline._record(frames[:5])
    writer.close()
    pipeline._record(frames[5:])  # the write fails: the capture ends with its reason
    assert not pipeline.capture_status()["active"]
    assert announced == ["recordings", "recordings"]


def test_the_stores_announce_each_change_themselves(tmp_path):
    folder = tmp_path / "recordings"
    folder.mkdir()
    announced: list[str] = []
    recordings = recording_store(folder, on_change=announced.append)
    copy = recordings.copy("sample-reach-1")
    assert announced == ["recordings"]
    assert read_recording(recordings.path(copy)).meta["name"] == copy  # the copy's own header
    renamed = recordings.update(copy, new_name="take", notes="second try")
    assert renamed == "take" and sorted(announced) == [
        "demonstrations",  # the rename updates the demonstrations cut from it
        "recordings",
        "recordings",
    ]
    demonstrations = demonstration_store(folder, on_change=announced.append)
    tmp = folder / ".demo.tmp"
    tmp.write_text("{}")
    demonstrations.claim(tmp, "mine")
    assert announced[-1] == "demonstrations"
    recordings.delete("take")
    assert announced[-1] == "recordings" and not recordings.exists("take")


class _Live:
    """What holds recordings in a studio: the one played and the one captured."""

    def __init__(self, recording=None, capture_name=None):
        self.recording = recording
        self.capture_name = capture_name


def test_the_recording_store_refuses_what_the_studio_holds(tmp_path):
    folder = tmp_path / "recordings"
    folder.mkdir()
    live = _Live()
    recordings = recording_store(folder, live)
    name = recordings.copy("sample-reach-1", "played")
    live.recording = name
    with pytest.raises(ConflictError, match="live source"):
        recordings.delete(name)
    with pytest.raises(ConflictError, match="live source"):
        recordings.update(name, new_name="other")
    assert recordings.update(name, notes="kept") == name  # notes change under the player
    live.recording, live.capture_name = None, name
    with pytest.raises(ConflictError, match="being captured"):
        recordings.update(name, notes="x")
    live.capture_name = None
    with RecordingWriter(folder / "held.tape.csv", 2):  # captured by another process's writer
        with pytest.raises(ConflictError, match="another studio"):
            recordings.update("held", new_name="moved")
        with pytest.raises(RecordingError, match="being recorded"):
            recordings.delete("held")
