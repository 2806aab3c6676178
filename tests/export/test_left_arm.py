"""A recording of the left arm is retargeted as the left arm: its export, its playback on a robot
and its timeline move the robot as the page did live, not as the mirror image of that."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from studio.capture import read_any_recording, recording_series
from studio.export import Motion, recording_motion, series_motion
from studio.kinematics import RobotArm, load_robot

from .conftest import write_arm_recording


def sideways_reach(frames: int = 120) -> np.ndarray:
    """The arm lifting forwards and out to the side, turning and bending: every lateral joint
    moves, so a left arm read as a right one would go the other way."""
    s = np.linspace(0.0, 1.0, frames)
    blend = 10 * s**3 - 15 * s**4 + 6 * s**5
    q = np.zeros((frames, 7))
    q[:, 0] = 0.5 * blend  # shoulder flexion
    q[:, 1] = 0.4 * blend  # abduction
    q[:, 2] = 0.3 * blend  # humeral rotation
    q[:, 3] = 0.4 + 0.5 * blend  # elbow flexion
    q[:, 4] = 0.3 * blend  # forearm rotation
    return q


@pytest.fixture(scope="module")
def recordings(tmp_path_factory) -> dict[str, Path]:
    folder = tmp_path_factory.mktemp("sides")
    return {
        side: write_arm_recording(folder / f"{side}.tape.csv", sideways_reach(), side)
        for side in ("right", "left")
    }


def tool_paths(robot: RobotArm, paths: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """The robot's tool positions from its shoulder along each side's joint path."""
    return {
        side: np.array([robot.forward(row)[:3, 3] for row in q]) - robot.shoulder
        for side, q in paths.items()
    }


def assert_mirrored(robot: RobotArm, motions: dict[str, Motion]) -> None:
    """The left arm's tool path is the right arm's mirrored across the robot's sagittal plane
    (the same angles on the left arm are the right arm's motion mirrored across the body),
    wherever both tools reach the hand's target: where neither pose reaches, each is the
    nearest its own IK search found, and the searches' fixed restarts are not mirrored."""
    tools = tool_paths(robot, {side: motion.q for side, motion in motions.items()})
    both = np.ones(len(tools["left"]), dtype=bool)
    for motion in motions.values():
        assert motion.path is not None
        both &= motion.path.reached
    assert both.mean() >= 0.5, f"only {both.sum()} of {len(both)} frames reached on both sides"
    facing = robot.base_rotation
    flip = facing.T @ np.diag([1.0, -1.0, 1.0]) @ facing
    np.testing.assert_allclose(tools["left"][both], tools["right"][both] @ flip.T, atol=0.02)
    assert np.abs(tools["left"] - tools["right"]).max() > 0.1  # the motion is not symmetric


@pytest.mark.parametrize("side", ["right", "left"])
def test_a_recordings_puma560_export_is_the_path_its_live_fit_showed(recordings, side):
    recording = read_any_recording(recordings[side])
    assert recording.side == side
    # every frame, each fitted by the recording's own fitter as the live page fits it
    live = recording_series(recording, points=len(recording))
    assert len(live.q_robot) == len(recording)
    np.testing.assert_allclose(
        recording_motion(recordings[side], "puma560").q, live.q_robot, atol=1e-9
    )


def test_a_left_arm_recording_moves_another_robot_as_the_mirror_image_of_a_right_arms(
    recordings,
):
    ur5 = load_robot("ur5")
    motions = {side: recording_motion(path, "ur5") for side, path in recordings.items()}
    assert_mirrored(ur5, motions)


def test_a_left_arm_recordings_timeline_on_a_robot_is_the_mirror_image_of_a_right_arms(
    recordings,
):
    panda = load_robot("panda")
    series = {side: recording_series(path, points=40) for side, path in recordings.items()}
    assert series["left"].side == "left" and series["right"].side == "right"
    assert_mirrored(panda, {side: series_motion(s, "panda") for side, s in series.items()})
