"""The live chain as one object: tracking a tape of a known arm gives that arm and its robot pose."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from studio.kinematics import (
    ArmFitter,
    ArmTracker,
    FitConfig,
    HumanArm,
    KinematicsError,
    Retargeter,
    TapeConfig,
    TrackerConfig,
    reconstruct,
    smooth_recorded_arm,
    tape_from_arm,
)
from studio.kinematics.human._filter import turn_backs, white_noise
from studio.kinematics.human._tracker import Tracked
from tests.kinematics.test_fit import observable_box, observable_q

TRACKERS = {side: ArmTracker(TapeConfig(side=side)) for side in ("right", "left")}
OBSERVABLE_LOW, OBSERVABLE_HIGH = observable_box()


STEP_RAD = 0.05
"""Largest joint change between two tracked frames: 5.5 rad/s at 110 Hz, a fast human reach."""


@settings(max_examples=30, deadline=None)
@given(
    start=observable_q(),
    steps=st.lists(
        st.lists(st.floats(-STEP_RAD, STEP_RAD), min_size=7, max_size=7), min_size=0, max_size=4
    ),
    side=st.sampled_from(["right", "left"]),
    mode=st.sampled_from(["joint", "cartesian"]),
)
def test_tracking_the_tape_of_an_arm_recovers_the_arm_and_retargets_it(start, steps, side, mode):
    """Frame after frame of a continuous motion (warm-started), the tracked arm is the arm."""
    tracker = TRACKERS[side]
    tracker.reset()
    tracker.mode = mode
    arm = tracker.arm
    retargeter = Retargeter(mode, mirror=True, arm=arm)  # the reference, fed the same arms
    motion = start + np.cumsum([np.zeros(7), *steps], axis=0)
    for q_true in np.clip(motion, OBSERVABLE_LOW, OBSERVABLE_HIGH):
        bend, twist = tape_from_arm(arm, q_true, tracker.tape)
        tracked = tracker.track(bend, twist)
        assert isinstance(tracked, Tracked)
        np.testing.assert_allclose(arm.points(tracked.q_human), arm.points(q_true), atol=1e-4)
        assert tracked.success and tracked.residual < 1e-4
        np.testing.assert_array_equal(tracked.q_robot, retargeter.robot_from_human(tracked.q_human))
        np.testing.assert_array_equal(
            tracked.tape_points, reconstruct(bend, twist, tracker.tape).positions
        )
        assert (tracked.ik is not None) == (mode == "cartesian")


def test_it_composes_the_fitter_and_the_retargeter_exactly():
    config = TrackerConfig(tape=TapeConfig(), mode="joint", fit=FitConfig(warm_iterations=3))
    tracker = ArmTracker(config)
    arm = HumanArm()
    fitter = ArmFitter(arm, config.tape, config.fit)
    retargeter = Retargeter("joint", mirror=True, arm=arm)
    rng = np.random.default_rng(0)
    base = np.array([0.4, 0.2, 0.3, 1.0, 0.1, 0.1, 0.0])
    for _ in range(5):
        q = base + rng.normal(0, 0.05, 7)
        bend, twist = tape_from_arm(arm, q, config.tape)
        tracked = tracker.track(bend, twist)
        fit = fitter.fit(reconstruct(bend, twist, config.tape))
        np.testing.assert_array_equal(tracked.q_human, fit.q_human)
        assert tracked.fit.iterations == fit.iterations and tracked.residual == fit.residual
        np.testing.assert_array_equal(tracked.q_robot, retargeter.robot_from_human(fit.q_human))


def test_reset_forgets_the_warm_start():
    tracker = ArmTracker(TrackerConfig(mode="cartesian"))
    arm = tracker.arm
    first = np.array([0.3, 0.2, 0.4, 1.2, 0.3, 0.2, 0.1])
    second = first + 0.05
    frames = [tape_from_arm(arm, q, tracker.tape) for q in (first, second)]
    fresh = ArmTracker(TrackerConfig(mode="cartesian")).track(*frames[1])
    tracker.track(*frames[0])
    warm = tracker.track(*frames[1])
    # warm-started from the first frame, the unseen wrist direction keeps that frame's forearm
    # rotation; a cold start takes the closed-form one
    assert not np.array_equal(warm.q_human, fresh.q_human)
    np.testing.assert_allclose(arm.points(warm.q_human), arm.points(fresh.q_human), atol=1e-6)
    tracker.track(*frames[0])
    tracker.reset()
    again = tracker.track(*frames[1])
    assert again.fit.iterations == fresh.fit.iterations
    np.testing.assert_array_equal(again.q_human, fresh.q_human)
    np.testing.assert_array_equal(again.q_robot, fresh.q_robot)


def test_the_retarget_mode_and_mirror_switch_at_run_time():
    tracker = ArmTracker(TapeConfig())
    q = np.array([0.5, 0.4, 0.2, 1.0, 0.0, 0.1, 0.0])
    bend, twist = tape_from_arm(tracker.arm, q, tracker.tape)
    joint = tracker.track(bend, twist).q_robot
    tracker.mode = "cartesian"
    assert tracker.mode == tracker.retargeter.mode == "cartesian"
    cartesian = tracker.track(bend, twist)
    assert cartesian.ik is not None and not np.allclose(cartesian.q_robot, joint)
    tracker.mode = "joint"
    tracker.mirror = False
    unmirrored = tracker.track(bend, twist).q_robot
    assert unmirrored[0] == pytest.approx(-joint[0])  # joint 1 is lateral: it flips
    np.testing.assert_allclose(unmirrored[1:3], joint[1:3])
    with pytest.raises(KinematicsError, match="joint"):
        tracker.mode = "sideways"


def test_a_left_tape_tracks_the_left_arm():
    tracker = ArmTracker(TapeConfig(side="left"))
    assert tracker.arm.side == "left" and tracker.retargeter.arm is tracker.arm


def test_bad_input_is_one_sentence():
    tracker = ArmTracker()
    with pytest.raises(KinematicsError, match="one frame"):
        tracker.track(np.zeros((2, 16)), np.zeros((2, 16)))
    with pytest.raises(KinematicsError):
        tracker.track(np.zeros(3), np.zeros(3))
    with pytest.raises(KinematicsError):
        tracker.track(np.full(16, np.nan), np.zeros(16))
    with pytest.raises(KinematicsError, match="TrackerConfig"):
        ArmTracker("tape")  # type: ignore[arg-type]
    with pytest.raises(KinematicsError, match="mode"):
        TrackerConfig(mode="sideways")  # type: ignore[arg-type]
    with pytest.raises(KinematicsError, match="tape"):
        TrackerConfig(tape=None)  # type: ignore[arg-type]


def test_frames_tracked_with_their_time_are_smoothed_and_the_robot_stops_shaking():
    """The tape's sensor noise reaches the joints a frame sees poorly (the turns about the
    forearm) as about a degree back and forth a frame, which the Puma560's wrist copied; timed
    frames pass a One Euro filter, and the shoulder and elbow stay on the true arm."""
    from studio.capture import simulate

    sim = simulate(4.0, seed=3)
    raw, timed = ArmTracker(sim.config), ArmTracker(sim.config)
    q_raw, q_timed, human = [], [], []
    for frame in sim.frames:
        q_raw.append(raw.track(frame.bend, frame.twist).q_robot)
        tracked = timed.track(frame.bend, frame.twist, frame.t)
        q_timed.append(tracked.q_robot)
        human.append(tracked.q_human)
    assert turn_backs(sim.q_human) == 0, "the true arm moves smoothly"
    assert turn_backs(np.array(q_raw)) > 100, "one frame at a time, the robot shakes"
    assert turn_backs(np.array(q_timed)) <= 5
    shoulder_elbow = np.degrees(np.abs(np.array(human) - sim.q_human)[:, :4])
    assert shoulder_elbow.mean() < 1.5, "smoothed, the seen joints stay on the arm"


def test_the_smoothing_starts_afresh_at_a_reset_a_repeated_time_or_an_untimed_frame():
    arm = HumanArm()
    a, b = np.zeros(7), np.array([0.3, 0.4, 0.0, 0.8, 0.0, 0.0, 0.0])
    tapes = [tape_from_arm(arm, q, TapeConfig()) for q in (a, b)]
    for restart in ("reset", "same time", "untimed"):
        tracker = ArmTracker()
        tracker.track(*tapes[0], 0.0)
        tracker.track(*tapes[0], 0.01)
        if restart == "reset":
            tracker.reset()
            t = 0.02
        elif restart == "same time":
            t = 0.01  # a source started again
        else:
            tracker.track(*tapes[0])
            t = 0.02
        tracked = tracker.track(*tapes[1], t)
        np.testing.assert_allclose(tracked.q_human, tracked.fit.q_human, err_msg=restart)
    other_branch = a + np.array([np.pi, 0, 0, 0, 0, 0, 0])  # the shoulder's other branch
    tracker = ArmTracker()
    tracker._smoothed(0.0, a)
    np.testing.assert_array_equal(tracker._smoothed(0.01, other_branch), other_branch)
    tracker.track(*tapes[0], 0.0)
    smoothed = tracker.track(*tapes[1], 0.01)  # a jump: the filter lags behind it
    assert np.abs(smoothed.q_human - smoothed.fit.q_human).max() > 0.01
    off = ArmTracker(TrackerConfig(smoothing_cutoff_hz=None))
    off.track(*tapes[0], 0.0)
    unsmoothed = off.track(*tapes[1], 0.01)
    np.testing.assert_array_equal(unsmoothed.q_human, unsmoothed.fit.q_human)


def test_bad_smoothing_settings_and_times_are_one_sentence():
    with pytest.raises(KinematicsError, match="smoothing_cutoff_hz"):
        TrackerConfig(smoothing_cutoff_hz=0.0)
    with pytest.raises(KinematicsError, match="smoothing_cutoff_hz"):
        TrackerConfig(smoothing_cutoff_hz=(1.0, 2.0))
    with pytest.raises(KinematicsError, match="beta"):
        TrackerConfig(smoothing_beta=-1.0)
    for t in (float("nan"), "1.0", True):
        with pytest.raises(KinematicsError, match="finite time"):
            ArmTracker().track(np.zeros(16), np.zeros(16), t)


def test_a_recordings_arm_smoothed_with_the_future_stays_closer_to_the_true_arm_than_live():
    """A recording has every frame at hand: its fitted arm, smoothed with the past and the
    future, neither shakes nor lags as the live filter does."""
    from studio.capture import simulate

    sim = simulate(6.0, seed=7)
    times = np.array([frame.t for frame in sim.frames])
    raw, live = ArmTracker(sim.config), ArmTracker(sim.config)
    q_raw = np.array([raw.track(f.bend, f.twist).q_human for f in sim.frames])
    q_live = np.array([live.track(f.bend, f.twist, f.t).q_human for f in sim.frames])
    q_recorded = smooth_recorded_arm(times, q_raw)
    assert turn_backs(q_recorded) == 0
    seen = [0, 1, 3]  # shoulder flexion and abduction, elbow: what the tape sees well

    def error(q):
        return np.degrees(np.abs(q - sim.q_human)[:, seen]).mean()

    assert error(q_recorded) < 0.5 * error(q_raw)  # noise gone
    assert error(q_recorded) < 0.3 * error(q_live)  # and no lag
    assert error(q_recorded) < 0.2


def test_white_noise_is_read_from_the_samples_and_a_smooth_motion_is_not_taken_for_it():
    rng = np.random.default_rng(0)
    t = np.arange(2000) / 110.0
    motion = np.column_stack([np.sin(2 * np.pi * 0.5 * t), 0.3 * t])
    noise = np.array([0.01, 0.002])
    estimated = white_noise(motion + rng.normal(0.0, noise, motion.shape))
    np.testing.assert_allclose(estimated, noise, rtol=0.1)
    # a swing of 1 rad at 0.5 Hz reads as 0.35 mrad: under a fifth of the smaller noise
    assert np.all(white_noise(motion) < 4e-4)
    assert white_noise(motion[:2]).shape == (2,) and not white_noise(motion[:2]).any()


def test_a_recordings_arm_is_smoothed_in_runs_cut_at_a_branch_jump_and_a_restarted_time():
    rng = np.random.default_rng(1)
    n = 60
    times = np.arange(n) / 110.0
    q = np.tile(np.array([0.3, 0.4, 0.0, 0.8, 0.0, 0.0, 0.0]), (n, 1))
    q += rng.normal(0.0, 0.01, q.shape)
    q[30:, 0] += np.pi  # the shoulder's other branch from frame 30
    smoothed = smooth_recorded_arm(times, q)
    assert np.abs(smoothed[:30, 0] - 0.3).max() < 0.02  # nothing drawn halfway to the branch
    assert np.abs(smoothed[30:, 0] - 0.3 - np.pi).max() < 0.02
    assert np.std(smoothed[:30, 3]) < 0.5 * np.std(q[:30, 3])
    restarted = times.copy()
    restarted[40:] -= restarted[40]  # a source started again at frame 40
    again = smooth_recorded_arm(restarted, q)
    for run in (slice(0, 30), slice(30, 40), slice(40, n)):  # each run smoothed on its own
        np.testing.assert_array_equal(again[run], smooth_recorded_arm(restarted[run], q[run]))
    short = smooth_recorded_arm(times[:2], q[:2])  # too few frames to smooth: as fitted
    np.testing.assert_array_equal(short, q[:2])


def test_bad_recorded_smoothing_input_is_one_sentence():
    with pytest.raises(KinematicsError, match="recorded_acceleration"):
        TrackerConfig(recorded_acceleration=0.0)
    with pytest.raises(KinematicsError, match="one time per frame"):
        smooth_recorded_arm(np.arange(3.0), np.zeros((4, 7)))
    with pytest.raises(KinematicsError, match="7 joints"):
        smooth_recorded_arm(np.arange(3.0), np.zeros((3, 6)))
