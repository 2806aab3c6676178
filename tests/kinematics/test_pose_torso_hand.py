"""The live camera fit's torso and hand: the torso's shape filtered slowly, the hand's points
fitted as one rigid hand that pins the wrist."""

from __future__ import annotations

import numpy as np

from studio.kinematics import (
    BodyShape,
    HumanArm,
    PoseStreamFitter,
    Retargeter,
    StreamConfig,
    arm_motion,
    landmarks_from_arm,
)
from studio.learning import ArmGrid
from tests.kinematics.test_pose_landmarks import PERSON, errors

RATE_HZ = 30.0
SIZE = (640, 480)
BEFORE = StreamConfig(torso_acceleration=StreamConfig().acceleration, rigid_hand=False)
"""The live fit without either change: the torso as fast as the arm, no rigid hand."""
STILL_ARM = np.array([0.6, 0.35, 0.2, 1.1, 1.2, 0.1, 0.0])
RIGHT_SHOULDER = 12
PIXELS_PER_M = 554.0 / 2.5  # the synthetic camera's focal length (px) over its distance (m)


def test_exact_landmarks_give_the_exact_arm_with_the_rigid_hand() -> None:
    """The hand shape learned from exact frames is the hand's own, so the rigid hand changes
    nothing where the landmarks are right (filters passed by, as for a smoothed recording)."""
    arm = HumanArm("right", **PERSON)
    fitter = PoseStreamFitter("right")
    for k in range(40):
        q = arm_motion(k / RATE_HZ, arm)
        world, image = landmarks_from_arm(q, arm)
        fit = fitter.update(k / RATE_HZ, world, image, SIZE, smoothed=True)
        assert fit.hand_seen
        _, upper, fore = errors(arm, q, fit.q_human)
        assert upper < 1e-3 and fore < 1e-3


def _same_cell_shares(seed: int, seconds: float) -> list[float]:
    """The share of frames (after 2 s) in the true arm's Puma cell, before and now, both fed the
    same noisy frames (sigma 3 cm x, y, 8 cm depth, 3 px in the picture)."""
    arm = HumanArm("right", **PERSON)
    rng = np.random.default_rng(seed)
    fitters = [PoseStreamFitter("right", BEFORE), PoseStreamFitter("right")]
    retarget, grid = Retargeter("joint", arm=HumanArm("right")), ArmGrid()
    same: list[list[bool]] = [[], []]
    for k in range(int(seconds * RATE_HZ)):
        t = k / RATE_HZ
        q = arm_motion(t, arm)
        world, image = landmarks_from_arm(q, arm)
        world[:, :2] += rng.normal(0.0, 0.03, (33, 2))
        world[:, 2] += rng.normal(0.0, 0.08, 33)
        image[:, :2] += rng.normal(0.0, 3.0, (33, 2)) / SIZE
        true_cell = grid.bins_of_angles(retarget.robot_from_human(q)[:3])
        for fitter, shares in zip(fitters, same, strict=True):
            fit = fitter.update(t, world, image, SIZE)
            if t >= 2.0:
                cell = grid.bins_of_angles(retarget.robot_from_human(fit.q_human)[:3])
                shares.append(bool(np.array_equal(cell, true_cell)))
    return [float(np.mean(shares)) for shares in same]


def test_the_live_fit_puts_more_frames_in_the_true_cell_than_before() -> None:
    shares = np.array([_same_cell_shares(seed, 30.0) for seed in (0, 1)])
    before, now = shares.mean(axis=0)
    assert now >= before + 0.015, shares


def _still_stream(config: StreamConfig, frames: int) -> tuple[PoseStreamFitter, np.ndarray]:
    """A fitter that has seen ``frames`` frames of a still arm, and its elbow (from the shoulder)."""
    arm = HumanArm("right", **PERSON)
    world, image = landmarks_from_arm(STILL_ARM, arm)
    fitter = PoseStreamFitter("right", config)
    for k in range(frames):
        fit = fitter.update(k / RATE_HZ, world, image, SIZE)
    return fitter, fit.points[1]


def _shoulder_moved(up_m: float) -> tuple[np.ndarray, np.ndarray]:
    """The still arm's landmarks with the right shoulder landmark ``up_m`` higher."""
    world, image = landmarks_from_arm(STILL_ARM, HumanArm("right", **PERSON))
    world[RIGHT_SHOULDER, 1] -= up_m  # MediaPipe's y is down
    image[RIGHT_SHOULDER, 1] -= up_m * PIXELS_PER_M / SIZE[1]
    return world, image


def test_a_shoulder_jump_moves_the_fitted_shoulder_little_per_frame_yet_it_follows() -> None:
    """A one-frame glitch of the shoulder landmark moves the arm read from it far less than it
    did; a shoulder that truly moves (a shrug) is followed within a few seconds."""
    moves = []
    for config in (BEFORE, StreamConfig()):
        fitter, elbow = _still_stream(config, 60)
        glitch = fitter.update(2.0, *_shoulder_moved(0.10), SIZE)
        moves.append(float(np.linalg.norm(glitch.points[1] - elbow)))
    assert moves[1] < 0.6 * moves[0] and moves[1] < 0.025, moves
    ends = []
    for config in (BEFORE, StreamConfig()):
        fitter, elbow = _still_stream(config, 60)
        shrug = _shoulder_moved(0.04)
        first = fitter.update(2.0, *shrug, SIZE).points[1]
        for k in range(1, 120):
            fit = fitter.update(2.0 + k / RATE_HZ, *shrug, SIZE)
        ends.append(fit.points[1])
        if config == BEFORE:
            continue
        assert np.linalg.norm(first - elbow) < 0.4 * 0.04
    assert np.linalg.norm(ends[1] - ends[0]) < 0.01  # both end where the shoulder is now


def _body_move(config: StreamConfig, kind: str) -> np.ndarray:
    """Per frame, the largest error (deg) of the joints the Puma cell reads (shoulder flexion,
    abduction, elbow), while the body turns or steps aside between 2 and 2.5 s, the arm still."""
    arm = HumanArm("right", **PERSON)
    fitter = PoseStreamFitter("right", config)
    out = []
    for k in range(int(5.5 * RATE_HZ)):
        t = k / RATE_HZ
        share = min(max((t - 2.0) / 0.5, 0.0), 1.0)
        if kind == "turn":
            world, image = landmarks_from_arm(STILL_ARM, arm, BodyShape(yaw=0.5 * share))
        else:  # a step aside: every landmark moves in the picture, none in the hip-centred world
            world, image = landmarks_from_arm(STILL_ARM, arm)
            image[:, 0] += 0.15 * share
        fit = fitter.update(t, world, image, SIZE)
        out.append(np.degrees(np.abs(fit.q_human - STILL_ARM)[[0, 1, 3]]).max())
    return np.array(out)


def test_a_body_that_turns_or_steps_aside_is_followed_in_time() -> None:
    turn = _body_move(StreamConfig(), "turn")
    after = int(4.0 * RATE_HZ)  # 1.5 s after the turn ended
    assert turn[after:].max() < 2.0, turn[after:]
    step_now, step_before = (_body_move(config, "step") for config in (StreamConfig(), BEFORE))
    # The body's place in the picture keeps the arm's pace: a step costs no more than before.
    assert step_now[60:].max() <= step_before[60:].max() + 0.5
