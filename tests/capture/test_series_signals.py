"""A timeline's own values of a recording: a tape's bend and twist per region, a camera's
visibility of the teaching arm's landmarks, a hand guide's hand position."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from studio.capture import read_any_recording, recording_series
from studio.capture._review import recording_signals
from studio.samples import SAMPLES_DIR
from tests.capture.test_observations import hand_recording, pose_frames, write


def test_a_tape_timeline_has_each_regions_bend_and_twist_at_its_times():
    path = SAMPLES_DIR / "sample-reach-1.tape.csv"
    rec = read_any_recording(path)
    series = recording_series(rec, points=40)
    bend, twist = series.signals
    assert (bend.name, twist.name, bend.unit) == ("tape bend", "tape twist", "deg")
    assert bend.labels == tuple(f"region {i + 1}" for i in range(rec.regions))
    rows = np.searchsorted(rec.t - rec.t[0], series.times - 1e-9)  # the frames plotted
    np.testing.assert_allclose(bend.values, np.degrees(rec.bend[rows]))
    np.testing.assert_allclose(twist.values, np.degrees(rec.twist[rows]))
    assert bend.values.shape == (len(series.times), rec.regions)


def test_a_camera_timeline_has_the_teaching_arms_landmark_visibility(tmp_path: Path):
    frames = pose_frames()
    rec = read_any_recording(write(tmp_path / "a.pose.csv", "pose", frames))  # the left arm
    (visibility,) = recording_signals(rec, np.arange(len(frames)))
    assert visibility.name == "landmark visibility" and visibility.labels == (
        "shoulder",
        "elbow",
        "wrist",
    )
    np.testing.assert_allclose(visibility.values[0], frames[0].world[[11, 13, 15], 3], atol=1e-4)
    assert np.isnan(visibility.values[2]).all()  # nobody in view: no value, not zero


def test_a_hand_timeline_has_the_hands_position_in_centimetres(tmp_path: Path):
    rec = read_any_recording(hand_recording(tmp_path / "reach.hand.csv"))
    (position,) = recording_signals(rec, np.array([0, 39]))
    assert (position.name, position.unit, position.labels) == (
        "hand position",
        "cm",
        ("x", "y", "z"),
    )
    np.testing.assert_allclose(position.values[1], rec.frame_at(39).position * 100, atol=1e-3)
