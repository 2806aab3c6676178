"""A camera recording fitted with the future: the smoother, and what it gives a demonstration."""

from __future__ import annotations

import math

import numpy as np
import pytest

from studio.capture import fitter_for
from studio.capture._fitters import fit_frames
from studio.capture._observations import LandmarkFrame
from studio.kinematics import (
    HumanArm,
    KinematicsError,
    PoseStreamFitter,
    Retargeter,
    arm_motion,
    landmarks_from_arm,
    smooth_landmarks,
)
from studio.kinematics.human._filter import ConstantVelocityFilter, smooth_constant_velocity
from studio.learning import ArmGrid
from tests.kinematics.test_pose_landmarks import PERSON, errors, noisy

RATE_HZ = 30.0
SIZE = (640, 480)


def test_the_smoother_ends_where_the_filter_ends_and_passes_a_steady_motion() -> None:
    rng = np.random.default_rng(0)
    t = np.cumsum(rng.uniform(0.02, 0.05, 200))
    z = np.sin(t)[:, None] + rng.normal(0.0, 0.05, (200, 2))
    smoothed = smooth_constant_velocity(t, z, 0.05, 0.5)
    causal = ConstantVelocityFilter(0.05, 0.5)
    filtered = np.array([causal(a, b) for a, b in zip(t, z, strict=True)])
    np.testing.assert_allclose(smoothed[-1], filtered[-1])  # the last frame has no future
    truth = np.sin(t)[:, None]
    rms = [float(np.sqrt(np.mean((x - truth) ** 2))) for x in (smoothed, filtered, z)]
    assert rms[0] < 0.6 * rms[1] < 0.6 * rms[2], rms
    line = (2.0 * t + 1.0)[:, None]
    np.testing.assert_allclose(smooth_constant_velocity(t, line, 0.05, 0.5), line, atol=1e-6)
    with pytest.raises(KinematicsError, match="do not increase"):
        smooth_constant_velocity(t[::-1], z, 0.05, 0.5)
    with pytest.raises(KinematicsError, match="one time per sample"):
        smooth_constant_velocity(t[:-1], z, 0.05, 0.5)


def noisy_stream(person: HumanArm, seconds: float, seed: int):
    """Times, true arms and noisy world landmarks (sigma 3 cm x, y; 8 cm depth) at 30 Hz."""
    rng = np.random.default_rng(seed)
    times = np.arange(0.0, seconds, 1.0 / RATE_HZ)
    truth = [arm_motion(t, person) for t in times]
    world = np.array([noisy(landmarks_from_arm(q, person)[0], rng, 0.03, 0.08) for q in truth])
    return times, np.array(truth), world


def same_cell(person: HumanArm, truth: np.ndarray, fitted: np.ndarray) -> float:
    """Share of frames whose Puma560 joints 1-3 (joint mode) lie in the true arm's grid cell."""
    retarget, grid = Retargeter("joint", arm=HumanArm(person.side)), ArmGrid()
    cells = [
        [grid.bins_of_angles(retarget.robot_from_human(q)[:3]) for q in arms]
        for arms in (truth, fitted)
    ]
    return float(np.mean([np.array_equal(a, b) for a, b in zip(*cells, strict=True)]))


@pytest.mark.parametrize("side", ["right", "left"])
def test_a_recorded_stream_smoothed_with_the_future_lands_in_the_true_cell_more_often(side):
    person = HumanArm(side, **PERSON)
    times, truth, world = noisy_stream(person, 20.0, seed=3)
    live, recorded = PoseStreamFitter(side), PoseStreamFitter(side)
    smoothed, _ = smooth_landmarks(times, world)
    fits = {"live": [], "recorded": []}
    for t, raw, smooth in zip(times, world, smoothed, strict=True):
        fits["live"].append(live.update(float(t), raw).q_human)
        fits["recorded"].append(recorded.update(float(t), smooth, smoothed=True).q_human)
    start = int(2.0 * RATE_HZ)  # after the live filter's warm-up
    shares = {k: same_cell(person, truth[start:], np.array(v)[start:]) for k, v in fits.items()}
    assert shares["recorded"] >= shares["live"] + 0.08, shares
    elbow = {
        k: math.sqrt(np.mean([errors(person, a, b)[0] ** 2 for a, b in zip(truth, v, strict=True)]))
        for k, v in fits.items()
    }
    assert elbow["recorded"] < elbow["live"], elbow


def test_a_recording_is_smoothed_run_by_run_and_frames_without_the_arm_are_held():
    person = HumanArm("right", **PERSON)
    times, truth, world = noisy_stream(person, 6.0, seed=4)
    frames = []
    for i, (t, w) in enumerate(zip(times, world, strict=True)):
        seen = not 80 <= i < 90  # the person steps out for a third of a second
        landmarks = w if seen else None
        frames.append(LandmarkFrame(float(t), i, landmarks, None, *SIZE))
    fitter = fitter_for(frames[0], side="right")
    recorded = fit_frames(fitter, frames)
    live_fitter = fitter_for(frames[0], side="right")
    live = [live_fitter.fit(f) for f in frames]
    assert len(recorded) == len(frames)
    for i in range(80, 90):  # held, and said, as live
        assert recorded[i].warning == live[i].warning and recorded[i].warning is not None
        np.testing.assert_array_equal(recorded[i].q_human, recorded[79].q_human)
    fitted = {k: np.array([f.q_human for f in v]) for k, v in (("r", recorded), ("l", live))}
    keep = [i for i in range(len(frames)) if i >= 60 and not 80 <= i < 100]
    error = {
        k: np.mean([errors(person, truth[i], v[i])[0] ** 2 for i in keep])
        for k, v in fitted.items()
    }
    assert error["r"] < error["l"], error


def test_smoothing_refuses_what_does_not_fit() -> None:
    times = np.arange(5) / RATE_HZ
    world = np.zeros((5, 33, 4))
    with pytest.raises(KinematicsError, match=r"\(N, 33, 3\)"):
        smooth_landmarks(times, np.zeros((5, 32, 3)))
    with pytest.raises(KinematicsError, match="one time per frame"):
        smooth_landmarks(times[:4], world)
    with pytest.raises(KinematicsError, match="image landmarks"):
        smooth_landmarks(times, world, np.zeros((4, 33, 3)), SIZE)
    out, image = smooth_landmarks(times, world)
    assert out.shape == world.shape and image is None
