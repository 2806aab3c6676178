"""The hand guide's IK: the hand lands on the handle wherever the arm can reach it."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from studio.kinematics import HumanArm, KinematicsError, fit_hand_pose
from studio.kinematics.human._hand_ik import HandFit

REACH_M = 0.01


@pytest.fixture(scope="module", params=["right", "left"])
def arm(request: pytest.FixtureRequest) -> HumanArm:
    return HumanArm(request.param)


def in_limits(arm: HumanArm, q: np.ndarray) -> bool:
    return bool(np.all(q >= arm.lower - 1e-12) and np.all(q <= arm.upper + 1e-12))


def test_reachable_random_targets_are_reached_within_a_centimetre(arm: HumanArm) -> None:
    rng = np.random.default_rng(4)
    for q in rng.uniform(arm.lower, arm.upper, size=(150, arm.nq)):
        oMhand = arm.forward(q).hand
        fit = fit_hand_pose(oMhand, arm.side)
        assert isinstance(fit, HandFit)
        assert fit.reached and fit.position_error_m <= REACH_M
        assert in_limits(arm, fit.q_human)
        hand = arm.forward(fit.q_human).hand
        assert np.linalg.norm(hand[:3, 3] - oMhand[:3, 3]) == pytest.approx(fit.position_error_m)


@settings(max_examples=40, deadline=None)
@given(
    side=st.sampled_from(["right", "left"]),
    fractions=st.lists(st.floats(0.0, 1.0), min_size=7, max_size=7),
    step=st.lists(st.floats(-0.05, 0.05), min_size=7, max_size=7),
)
def test_dragging_from_the_previous_solution_follows_the_hand(side, fractions, step) -> None:
    """IK(FK(q')) seeded at q reaches FK(q') for a small move q -> q' within the limits."""
    arm = _ARMS[side]
    q = arm.lower + np.asarray(fractions) * (arm.upper - arm.lower)
    moved = np.clip(q + np.asarray(step), arm.lower, arm.upper)
    fit = fit_hand_pose(arm.forward(moved).hand, side, q_seed=q)
    assert fit.reached and in_limits(arm, fit.q_human)
    # Mostly the seed's own neighbourhood: the arm does not jump to another branch.
    assert np.linalg.norm(fit.q_human - moved) < 1.0 or fit.rotation_error_rad < 1e-3


_ARMS = {side: HumanArm(side) for side in ("right", "left")}


def test_out_of_reach_targets_clamp_smoothly(arm: HumanArm) -> None:
    """A handle dragged away from the shoulder: the arm stretches toward it, not reached."""
    reach = arm.upper_arm_length + arm.forearm_length + arm.hand_length
    direction = np.array([0.6, -0.3 if arm.side == "right" else 0.3, -0.2])
    direction /= np.linalg.norm(direction)
    q = None
    previous = None
    for distance in np.linspace(1.05, 2.0, 20) * reach:
        oMhand = np.eye(4)
        oMhand[:3, 3] = distance * direction
        fit = fit_hand_pose(oMhand, arm.side, q_seed=q)
        assert not fit.reached and in_limits(arm, fit.q_human)
        hand = arm.forward(fit.q_human).hand[:3, 3]
        assert fit.position_error_m == pytest.approx(np.linalg.norm(hand - oMhand[:3, 3]))
        assert fit.position_error_m >= distance - reach - 1e-6
        # The hand reaches out toward the target: within a few degrees of its direction.
        assert hand @ direction > 0.95 * np.linalg.norm(hand)
        points = arm.points(fit.q_human)
        if previous is not None:  # no jumps as the handle moves away (the arm is stretched,
            # so joint angles may trade along the arm's axis; its points may not jump)
            moved = np.linalg.norm(points - previous, axis=1)
            assert moved[3] < 0.002 and np.max(moved) < 0.02  # the hand stays, the arm settles
        previous, q = points, fit.q_human


def test_targets_beyond_a_limit_stay_within_the_limits(arm: HumanArm) -> None:
    """A hand behind the back: the arm stops at its limits, closest to the handle."""
    oMhand = np.eye(4)
    oMhand[:3, 3] = (-0.4, 0.0, -0.1)
    fit = fit_hand_pose(oMhand, arm.side)
    assert in_limits(arm, fit.q_human)
    assert np.isfinite(fit.position_error_m)


@pytest.mark.parametrize(
    ("target", "words"),
    [
        (np.eye(3), "4x4"),
        (np.full((4, 4), np.nan), "NaN"),
        (np.diag([1.0, 1.0, -1.0, 1.0]), "not a rotation"),
        (2.0 * np.eye(4), "not a rotation"),
        ("hand", "text"),
    ],
)
def test_bad_targets_raise_one_sentence(target, words: str) -> None:
    with pytest.raises(KinematicsError, match=words) as info:
        fit_hand_pose(target)
    assert str(info.value).endswith(".")


def test_bad_side_and_seed_raise_one_sentence() -> None:
    with pytest.raises(KinematicsError, match='"right" or "left"'):
        fit_hand_pose(np.eye(4), "up")
    with pytest.raises(KinematicsError, match=r"shape"):
        fit_hand_pose(np.eye(4), "right", q_seed=np.zeros(6))
    with pytest.raises(KinematicsError, match="NaN"):
        fit_hand_pose(np.eye(4), "right", q_seed=np.full(7, np.nan))
