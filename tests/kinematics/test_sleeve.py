"""The tape laid on the operator's sleeve: one forward-kinematics pass per pose, the tape on the
arm's surface, never inside it, and points away from the arm left where they are."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from studio.kinematics import (
    SLEEVE_LIFT_M,
    HumanArm,
    HumanBody,
    TapeConfig,
    pose_body,
    reconstruct,
    tape_from_arm,
)
from studio.kinematics._meshes import tape_on_sleeve

AXIS = np.array([[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [0.55, 0.0, 0.0]])
"""A straight arm along +x: shoulder, elbow, wrist (m)."""


def _distance_to_segment(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    t = np.clip((p - a) @ (b - a) / ((b - a) @ (b - a)), 0.0, 1.0)
    return float(np.linalg.norm(a + t * (b - a) - p))


@pytest.fixture(scope="module")
def body() -> HumanBody:
    return HumanBody("right")


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.tuples(*(st.floats(-0.2, 0.7) for _ in range(3))),
        min_size=2,
        max_size=20,
    )
)
@example([(0.0, 0.0, 0.0), (0.3125, 0.0, 0.0)])  # on the axis just past the elbow
def test_no_point_stays_inside_the_sleeve_and_none_moves_beyond_it(points):
    tape = np.array(points)
    out = tape_on_sleeve(tape, AXIS)
    for p, q in zip(tape, out, strict=True):
        upper = _distance_to_segment(q, AXIS[0], AXIS[1])
        fore = _distance_to_segment(q, AXIS[1], AXIS[2])
        assert upper >= SLEEVE_LIFT_M[0] - 1e-6 or fore >= SLEEVE_LIFT_M[1] - 1e-6
        assert np.linalg.norm(q - p) <= max(SLEEVE_LIFT_M) + 1e-9


def test_points_away_from_the_arm_stay_and_points_on_its_axis_go_to_its_surface():
    tape = np.array([[0.1, 0.5, 0.0], [0.15, 0.0, 0.0], [0.4, 0.0, 0.0]])
    out = tape_on_sleeve(tape, AXIS)
    np.testing.assert_array_equal(out[0], tape[0])  # on the back, far from the arm
    assert _distance_to_segment(out[1], AXIS[0], AXIS[1]) == pytest.approx(SLEEVE_LIFT_M[0])
    assert _distance_to_segment(out[2], AXIS[1], AXIS[2]) == pytest.approx(SLEEVE_LIFT_M[1])
    assert out[1][0] == pytest.approx(0.15) and out[2][0] == pytest.approx(0.4)  # radially


def test_pose_body_poses_the_meshes_and_lays_the_tape_along_the_fitted_arm(body):
    q = np.array([0.5, 0.4, 0.1, 0.8, 0.0, 0.0, 0.0])
    config = TapeConfig()
    tape = reconstruct(*tape_from_arm(HumanArm("right"), q, config), config).positions
    posed = pose_body(body, q, tape)
    np.testing.assert_allclose(posed.parts, body.poses(q))
    links = [f"right_{link}" for link in ("upperarm", "lowerarm", "hand")]
    axis = body.link_poses(links, q)[:, :3, 3]  # the arm's own frames, by a second pass
    np.testing.assert_allclose(posed.tape, tape_on_sleeve(tape, axis))
    strapped = posed.tape[config.shoulder_region + 1 : config.wrist_region + 1]
    near = [
        min(_distance_to_segment(p, a, b) for a, b in zip(axis[:-1], axis[1:], strict=True))
        for p in strapped
    ]
    assert max(near) < 0.08 and min(near) >= min(SLEEVE_LIFT_M) - 1e-6


def test_pose_body_without_a_tape_poses_only_the_meshes(body):
    posed = pose_body(body, None)
    assert posed.tape is None
    np.testing.assert_allclose(posed.parts, body.poses(None))
    assert pose_body(body, None, np.zeros((1, 3))).tape is None  # one point is no line
