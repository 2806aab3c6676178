"""Pose-landmark and hand-pose observations: their recording formats, playback, ``studio info``,
demonstrations, bad files, and the fed sources that take them."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from studio.capture import (
    CameraSource,
    CaptureError,
    FloodError,
    HandPose,
    HandSource,
    LandmarkFrame,
    ObservationRecording,
    PlaybackSource,
    RecordingError,
    RecordingWriter,
    describe,
    read_any_recording,
    read_recording,
    summarize_any_recording,
)
from studio.capture._observation_recording import ObservationWriter, recording_kind
from studio.capture._observations import hand_pose, landmark_frame
from studio.kinematics import HumanArm
from studio.motion import extract_demonstration


def some_landmarks(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    world = rng.normal(0, 0.3, (33, 4))
    world[:, 3] = rng.random(33)
    image = rng.random((33, 3))
    return world, image


def pose_frames(n: int = 6) -> list[LandmarkFrame]:
    rng = np.random.default_rng(0)
    out = []
    for i in range(n):
        if i == 2:  # nobody in view
            out.append(landmark_frame(i / 30, i, None, None, 640, 480))
            continue
        world, image = some_landmarks(rng)
        frame = landmark_frame(i / 30 + 1e-3 * rng.random(), i, world, image, 640, 480)
        observable = np.array([1, 1, 0, 1, 0, 0, 0], dtype=bool)
        out.append(
            LandmarkFrame(frame.t, frame.frame, frame.world, frame.image, 640, 480, observable)
        )
    return out


def write(path: Path, kind: str, observations: list) -> Path:
    with ObservationWriter(path, kind, side="left", operator="ada", notes="n") as writer:
        writer.write_many(observations)
    return path


def test_pose_recording_round_trips_exactly_and_pandas_reads_it(tmp_path: Path) -> None:
    frames = pose_frames()
    path = write(tmp_path / "a.pose.csv", "pose", frames)
    recording = read_any_recording(path)
    assert isinstance(recording, ObservationRecording) and recording.kind.name == "pose"
    assert len(recording) == len(frames) and not recording.recovered and recording.side == "left"
    for want, got in zip(frames, recording.frames(), strict=True):
        assert got.t == want.t and got.frame == want.frame and got.person == want.person
        if want.person:
            assert np.array_equal(got.world, want.world) and np.array_equal(got.image, want.image)
            assert np.array_equal(got.observable, want.observable)
        else:
            assert got.world is None and not got.observable.any()
    table = pd.read_csv(path, comment="#")
    assert table["person"].tolist() == [1, 1, 0, 1, 1, 1]
    assert table.filter(regex="^world_").to_numpy().reshape(-1, 33, 4)[2].size == 132
    assert np.isnan(table.filter(regex="^world_").to_numpy()[2]).all()
    assert recording_kind(path) == "pose"


def test_hand_recording_round_trips_and_plays_back(tmp_path: Path) -> None:
    poses = [hand_pose(i / 60, i, [0.1 * i, 0.0, -0.5], [1, 0, 0, 0]) for i in range(5)]
    path = write(tmp_path / "g.hand.csv", "hand", poses)
    table = pd.read_csv(path, comment="#")
    assert list(table.columns) == ["t", "frame", "x", "y", "z", "qw", "qx", "qy", "qz"]
    source = PlaybackSource(path, speed=None, loop=True)
    assert source.observation_kind == "hand" and source.side == "left"
    got: list = []
    with source:
        while len(got) < 12:
            got.extend(source.read(timeout=1.0))
    assert all(isinstance(p, HandPose) for p in got)
    assert np.allclose(got[3].position, poses[3].position)
    times = np.array([p.t for p in got])
    assert (np.diff(times) > 0).all()  # a loop keeps time moving forward


def test_a_hand_recording_whose_time_goes_backwards_loads_with_the_tapes_warning(
    tmp_path: Path,
) -> None:
    times = [0.0, 0.1, 0.05, 0.2]
    poses = [hand_pose(t, i, [0.0, 0.0, -0.5], [1, 0, 0, 0]) for i, t in enumerate(times)]
    summary = summarize_any_recording(write(tmp_path / "b.hand.csv", "hand", poses))
    assert summary["frames"] == 4  # every frame kept
    assert len(summary["warnings"]) == 1
    assert "time goes backwards 1 time (first at frame 2" in summary["warnings"][0]


def test_a_killed_capture_keeps_its_flushed_frames(tmp_path: Path) -> None:
    path = tmp_path / "k.pose.csv"
    writer = ObservationWriter(path, "pose")
    writer.write_many(pose_frames(4))
    writer.flush()
    with open(path, "a") as f:  # the row the kill cut short
        f.write("0.5,9,1,640")
    recording = read_any_recording(path, strict=False)
    assert recording.recovered and len(recording) == 4
    assert "incomplete last row" in recording.problems[-1]
    writer.close()


def test_info_and_summary_say_the_kind(tmp_path: Path) -> None:
    path = write(tmp_path / "a.pose.csv", "pose", pose_frames())
    summary = summarize_any_recording(path)
    assert summary["kind"] == "pose" and summary["frames"] == 6 and summary["operator"] == "ada"
    assert "pose landmarks from a camera, no images" in describe(summary)


@pytest.mark.parametrize(
    ("edit", "words"),
    [
        (lambda lines: lines.__setitem__(3, lines[3].replace(",1,640,", ",1,nan,", 1)), "line 4"),
        (lambda lines: lines.__setitem__(4, lines[4] + ",7"), "columns"),
        (
            lambda lines: lines.__setitem__(0, lines[0].replace('"version": 1', '"version": 9')),
            "version",
        ),
        (lambda lines: lines.__setitem__(0, lines[0].replace('"left"', '"middle"')), "side"),
        (
            lambda lines: lines.__setitem__(4, lines[4].replace(",0,640,", ",1,640,", 1)),
            "landmarks",
        ),
        (lambda lines: lines.append(lines[3]), "after the '# end' line"),
    ],
)
def test_bad_pose_files_name_the_problem(tmp_path: Path, edit, words: str) -> None:
    path = write(tmp_path / "b.pose.csv", "pose", pose_frames())
    lines = path.read_text().splitlines()
    edit(lines)
    path.write_text("\n".join(lines) + "\n")
    with pytest.raises(RecordingError, match=words):
        read_any_recording(path)
    if "line 1" not in words and words not in ("version", "side"):
        lenient = read_any_recording(path, strict=False)
        assert len(lenient) >= 4 and lenient.problems


def test_the_tape_reader_refuses_a_pose_file_in_one_sentence(tmp_path: Path) -> None:
    path = write(tmp_path / "a.pose.csv", "pose", pose_frames())
    with pytest.raises(RecordingError, match="not a Teach Studio recording"):
        read_recording(path)
    with pytest.raises(RecordingError, match="records pose observations"):
        ObservationWriter(tmp_path / "c.pose.csv", "pose").write(
            hand_pose(0, 0, [0, 0, 0], [1, 0, 0, 0])
        )


def test_the_tape_writer_refuses_another_observation_in_one_sentence(tmp_path: Path) -> None:
    """It used to fail with an AttributeError (a hand pose has no bend) instead of a sentence."""
    with (
        RecordingWriter(tmp_path / "t.tape.csv", 16) as out,
        pytest.raises(RecordingError, match="records tape frames, not HandPose"),
    ):
        out.write(hand_pose(0, 0, [0, 0, 0], [1, 0, 0, 0]))


def test_camera_source_checks_counts_and_refuses_floods(monkeypatch: pytest.MonkeyPatch) -> None:
    source = CameraSource("right")
    with pytest.raises(CaptureError, match="stopped"):
        source.submit(0.0, None, None, 640, 480)
    source.start()
    world, image = some_landmarks(np.random.default_rng(1))
    bad = world.copy()
    bad[5, 1] = np.nan
    for args, words in [
        ((0.0, bad, image, 640, 480), "NaN"),
        ((0.0, world[:30], image, 640, 480), "shape"),
        ((0.0, None, image, 640, 480), "without world"),
        ((float("inf"), world, image, 640, 480), "finite"),
        ((0.0, world, image, 0, 480), "width"),
    ]:
        with pytest.raises(CaptureError, match=words):
            source.submit(*args)
    assert source.status().frames == 0
    clock = [100.0]
    monkeypatch.setattr("studio.capture._push_sources.time.monotonic", lambda: clock[0])
    for _ in range(120):
        source.submit(0.0, None, None, 640, 480)
    with pytest.raises(FloodError):
        source.submit(0.0, None, None, 640, 480)
    clock[0] += 1.01
    assert source.submit(0.0, world, image, 640, 480).person
    status = source.status()
    assert status.frames == 121 and status.dropped == 1


def test_hand_source_keeps_the_orientation_when_none_is_given() -> None:
    source = HandSource("right")
    source.start()
    first = source.submit([0.1, 0.0, -0.5])
    rest = HumanArm("right").forward(np.zeros(7)).hand
    assert np.allclose(first.wxyz[0] ** 2, ((np.trace(rest[:3, :3]) + 1) / 4), atol=1e-9)
    second = source.submit([0.2, 0.0, -0.5], [0, 0, 0, 1])
    third = source.submit([0.2, 0.0, -0.4])
    assert np.allclose(third.wxyz, second.wxyz) and third.frame == 2
    with pytest.raises(CaptureError, match="zero quaternion"):
        source.submit([0, 0, 0], [0, 0, 0, 0])


def hand_recording(path: Path) -> Path:
    """A hand guided from hanging to a reach forward and up (the arm's own forward kinematics)."""
    arm = HumanArm("right")
    poses = []
    for i, s in enumerate(np.linspace(0.0, 1.0, 40)):
        q = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0])
        q[1] = 1.2 * s  # the shoulder raises the arm forward
        q[3] = 0.8 * s  # the elbow bends
        hand = arm.forward(q).hand
        poses.append(HandPose(i / 20, i, hand[:3, 3].copy(), _wxyz(hand)))
    with ObservationWriter(path, "hand", side="right") as writer:
        writer.write_many(poses)
    return path


def _wxyz(pose: np.ndarray) -> np.ndarray:
    import viser.transforms as vtf

    return vtf.SO3.from_matrix(pose[:3, :3]).wxyz


def test_a_hand_recording_cuts_into_a_demonstration(tmp_path: Path) -> None:
    path = hand_recording(tmp_path / "reach.hand.csv")
    recording = read_any_recording(path)
    demo = extract_demonstration(recording, 0.0, recording.duration, goal_from_end=True)
    assert demo.q_robot.shape == (40, 6) and len(demo.grid_path) >= 2
    assert demo.default_path().name.startswith("reach.") and demo.recording == path
    saved = demo.save(tmp_path / "reach.demo.json")
    assert os.path.getsize(saved) > 0


def test_recording_a_pose_playback_gives_the_same_landmarks(tmp_path: Path) -> None:
    from studio.capture import capture

    frames = pose_frames()
    path = write(tmp_path / "a.pose.csv", "pose", frames)
    out = capture(PlaybackSource(path, speed=None), tmp_path / "again.pose.csv")
    again = read_any_recording(out)
    assert again.kind.name == "pose" and again.side == "left" and len(again) == len(frames)
    assert np.array_equal(again.data, read_any_recording(path).data, equal_nan=True)
