"""Laws of the Puma560 model: standard-DH forward kinematics, Jacobian, IK, visuals, bad input."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from studio import StudioError
from studio.kinematics import IKConfig, KinematicsError, Puma560
from studio.kinematics._puma import PUMA_QN, PUMA_QR, PUMA_QS, PUMA_QZ, IKResult, LinkVisual

ROBOT = Puma560()
FAST = settings(max_examples=50, deadline=None)

#: Corke's table, written out again here so the model is checked against an independent product.
TABLE = [  # d, a, alpha, limit (deg)
    (0.67183, 0.0, math.pi / 2, 160),
    (0.0, 0.4318, 0.0, 110),
    (0.15005, 0.0203, -math.pi / 2, 135),
    (0.4318, 0.0, math.pi / 2, 266),
    (0.0, 0.0, -math.pi / 2, 100),
    (0.0, 0.0, 0.0, 266),
]


def dh_frames(q: np.ndarray) -> list[np.ndarray]:
    """0T0 .. 0T6 as the plain product of Rz(q) Tz(d) Tx(a) Rx(alpha)."""
    frames = [np.eye(4)]
    for qi, (d, a, alpha, _) in zip(q, TABLE, strict=True):
        ct, st_, ca, sa = math.cos(qi), math.sin(qi), math.cos(alpha), math.sin(alpha)
        step = np.array(
            [
                [ct, -st_ * ca, st_ * sa, a * ct],
                [st_, ct * ca, -ct * sa, a * st_],
                [0.0, sa, ca, d],
                [0.0, 0.0, 0.0, 1.0],
            ]
        )
        frames.append(frames[-1] @ step)
    return frames


def within_limits(margin: float = 0.0) -> st.SearchStrategy[np.ndarray]:
    """Joint angles inside the limits (``margin`` rad away from them)."""
    return st.tuples(
        *(st.floats(-math.radians(lim) + margin, math.radians(lim) - margin) for *_, lim in TABLE)
    ).map(np.array)


# ------------------------------------------------------------------------- forward kinematics


@pytest.mark.parametrize(
    ("q", "position"),
    [
        (PUMA_QZ, (0.4521, -0.15005, 1.1036)),
        (PUMA_QN, (0.5963, -0.1501, 0.6575)),
        (PUMA_QR, (0.0203, -0.15005, 0.67183 + 0.4318 + 0.4318)),
        (PUMA_QS, (0.4318 + 0.4318, -0.15005, 0.67183 - 0.0203)),
    ],
)
def test_named_poses_put_the_tool_where_corke_does(q: np.ndarray, position: tuple) -> None:
    oMtool = ROBOT.forward(q)
    np.testing.assert_allclose(oMtool[:3, 3], position, atol=1e-4)


def test_named_poses_and_limits_are_corkes() -> None:
    assert ROBOT.nq == 6
    np.testing.assert_array_equal(ROBOT.qz, np.zeros(6))
    np.testing.assert_allclose(ROBOT.qr, [0, math.pi / 2, -math.pi / 2, 0, 0, 0])
    np.testing.assert_allclose(ROBOT.qn, [0, math.pi / 4, math.pi, 0, math.pi / 4, 0])
    np.testing.assert_allclose(ROBOT.qs, [0, 0, -math.pi / 2, 0, 0, 0])
    limits = np.radians([lim for *_, lim in TABLE])
    np.testing.assert_allclose(ROBOT.upper, limits)
    np.testing.assert_allclose(ROBOT.lower, -limits)
    with pytest.raises(ValueError):
        ROBOT.upper[0] = 0.0  # shared, so read-only


@FAST
@given(q=within_limits())
def test_forward_is_the_standard_dh_product(q: np.ndarray) -> None:
    np.testing.assert_allclose(ROBOT.forward(q), dh_frames(q)[-1], atol=1e-12)


@FAST
@given(q=within_limits())
def test_joint_frames_are_the_dh_frames(q: np.ndarray) -> None:
    frames = ROBOT.joint_frames(q)
    assert frames.shape == (7, 4, 4)
    np.testing.assert_allclose(frames, np.stack(dh_frames(q)), atol=1e-12)
    np.testing.assert_allclose(frames[0], np.eye(4))  # the base, on the floor under joint 1
    np.testing.assert_allclose(frames[-1], ROBOT.forward(q), atol=1e-12)


def test_forward_returns_a_fresh_array() -> None:
    first = ROBOT.forward(PUMA_QZ)
    first[:] = 0.0
    np.testing.assert_allclose(ROBOT.forward(PUMA_QZ)[:3, 3], (0.4521, -0.15005, 1.10363))


# -------------------------------------------------------------------------------- jacobian


@FAST
@given(q=within_limits())
def test_jacobian_matches_finite_differences(q: np.ndarray) -> None:
    h = 1e-6
    J = ROBOT.jacobian(q)
    assert J.shape == (6, 6)
    for j in range(6):
        dq = np.zeros(6)
        dq[j] = h
        plus, minus = ROBOT.forward(q + dq), ROBOT.forward(q - dq)
        linear = (plus[:3, 3] - minus[:3, 3]) / (2 * h)
        angular = pin.log3(plus[:3, :3] @ minus[:3, :3].T) / (2 * h)  # in the base frame
        np.testing.assert_allclose(J[:3, j], linear, atol=1e-7)
        np.testing.assert_allclose(J[3:, j], angular, atol=1e-7)


# -------------------------------------------------------------------------------------- IK


def assert_within_limits(q: np.ndarray) -> None:
    assert np.all(q >= ROBOT.lower) and np.all(q <= ROBOT.upper), q


@FAST
@given(q=within_limits())
# Joint 5 exactly at its limit: the closed form returns it a rounding error beyond.
@example(q=np.array([0.0, -1.25, 0.0, 3.0, np.deg2rad(100.0), 0.0]))
def test_full_pose_ik_round_trip(q: np.ndarray) -> None:
    oMdes = ROBOT.forward(q)
    result = ROBOT.inverse(oMdes)
    assert result.success, result.message
    assert result.error <= 1e-6
    assert_within_limits(result.q)
    np.testing.assert_allclose(ROBOT.forward(result.q), oMdes, atol=1e-5)


@FAST
@given(q=within_limits())
def test_position_only_ik_round_trip(q: np.ndarray) -> None:
    target = ROBOT.forward(q)[:3, 3]
    for goal in (target, ROBOT.forward(q)):  # a 3-vector or a pose whose rotation is ignored
        result = ROBOT.inverse(goal, position_only=True)
        assert result.success, result.message
        assert_within_limits(result.q)
        np.testing.assert_allclose(ROBOT.forward(result.q)[:3, 3], target, atol=1e-5)


@FAST
@given(q=within_limits(margin=0.05), nudge=st.tuples(*[st.floats(-0.02, 0.02)] * 6))
def test_warm_start_stays_on_the_nearby_solution(q: np.ndarray, nudge: tuple) -> None:
    # A Puma has up to eight solutions per pose: warm-started from a nearby q (the previous
    # frame), IK must return the nearby one, not jump to another branch. (At the wrist
    # singularity q5 = 0 only q4 + q6 matters, so the nearby solution is not unique there.)
    q[4] = math.copysign(max(abs(q[4]), 0.1), q[4])
    result = ROBOT.inverse(ROBOT.forward(q), q0=q + np.array(nudge), tolerance=1e-10)
    assert result.success, result.message
    np.testing.assert_allclose(result.q, q, atol=1e-4)  # other branches are radians away


@FAST
@given(
    q=within_limits(margin=0.2),
    nudge=st.tuples(*[st.floats(-0.1, 0.1)] * 6).map(np.array),
    position_only=st.booleans(),
)
def test_the_damped_least_squares_core_converges_from_a_nearby_start(
    q: np.ndarray, nudge: np.ndarray, position_only: bool
) -> None:
    # inverse() falls back on closed-form seeds, which would hide a broken DLS iteration from
    # the public results; so the DLS attempt itself (the warm-started live path) is checked
    # here: from a start near a solution, away from the wrist singularity, it meets a tight
    # tolerance within its iteration budget and stays within the limits.
    q[4] = math.copysign(max(abs(q[4]), 0.3), q[4])
    # Away from the elbow singularity too (forearm along the upper arm) and the shoulder one
    # (wrist centre near joint 1's axis, beyond the d3 offset), where damped steps converge
    # only linearly.
    elbow = q[2] + math.atan2(TABLE[3][0], TABLE[2][1])
    px, py, _ = ROBOT.forward(q)[:3, 3]
    assume(abs(math.sin(elbow)) > 0.3 and px * px + py * py - TABLE[2][0] ** 2 > 0.1**2)
    oMdes = ROBOT.forward(q)
    start = np.clip(q + nudge, ROBOT.lower, ROBOT.upper)
    q_found, error, iterations = ROBOT._solve(
        start, oMdes[:3, 3], oMdes[:3, :3], position_only, ROBOT.ik.max_iterations, 1e-10
    )
    assert error <= 1e-10 and iterations <= 20
    assert_within_limits(q_found)
    reached = ROBOT.forward(q_found)
    np.testing.assert_allclose(reached[:3, 3], oMdes[:3, 3], atol=1e-9)
    if not position_only:
        np.testing.assert_allclose(reached[:3, :3], oMdes[:3, :3], atol=1e-9)


@FAST
@given(
    target=st.tuples(*[st.floats(-1.2, 1.2)] * 2, st.floats(-0.3, 2.0)).map(np.array),
    position_only=st.booleans(),
    q0=st.tuples(*[st.floats(-5.0, 5.0)] * 6).map(np.array),
)
def test_ik_never_leaves_the_limits_and_never_lies(
    target: np.ndarray, position_only: bool, q0: np.ndarray
) -> None:
    # Random targets (many unreachable) and seeds far outside the limits.
    oMdes = np.eye(4)
    oMdes[:3, 3] = target
    result = ROBOT.inverse(oMdes, q0=q0, position_only=position_only)
    assert_within_limits(result.q)
    reached = ROBOT.forward(result.q)
    if position_only:
        error = float(np.linalg.norm(reached[:3, 3] - target))
    else:
        error = float(
            np.linalg.norm(
                np.concatenate(
                    (reached[:3, 3] - target, pin.log3(oMdes[:3, :3] @ reached[:3, :3].T))
                )
            )
        )
    if result.success:
        assert error <= 1e-6
    else:
        assert result.error > 1e-6
        assert result.message.endswith(".") and "\n" not in result.message


def test_target_beyond_reach_reports_failure() -> None:
    oMdes = np.eye(4)
    oMdes[:3, 3] = (2.0, 0.0, 0.7)
    for position_only in (False, True):
        result = ROBOT.inverse(oMdes, q0=PUMA_QZ, position_only=position_only)
        assert not result.success
        assert "reach" in result.message
        assert result.error > 1.0
        assert_within_limits(result.q)


def test_pose_that_needs_a_joint_beyond_its_limit_reports_failure() -> None:
    # Joint 5 at 170 deg (limit 100 deg): no other branch of the arm reaches this pose.
    beyond = np.array([0.0, 0.3, -0.5, 0.0, math.radians(170), 0.0])
    result = ROBOT.inverse(ROBOT.forward(beyond))
    assert not result.success
    assert "limits" in result.message
    assert_within_limits(result.q)
    # The position alone is reachable with the wrist folded within its limits.
    assert ROBOT.inverse(ROBOT.forward(beyond), position_only=True).success


def test_qn_pose_is_reached_on_a_branch_within_the_limits() -> None:
    # Corke's qn has q3 = pi, beyond joint 3's 135 deg limit; its pose is reachable elbow-up.
    assert PUMA_QN[2] > ROBOT.upper[2]
    oMdes = ROBOT.forward(PUMA_QN)
    for q0 in (None, PUMA_QN):
        result = ROBOT.inverse(oMdes, q0=q0)
        assert result.success, result.message
        assert_within_limits(result.q)
        np.testing.assert_allclose(ROBOT.forward(result.q), oMdes, atol=1e-5)


def test_ik_result_is_frozen() -> None:
    result = ROBOT.inverse(ROBOT.forward(PUMA_QR))
    assert isinstance(result, IKResult)
    with pytest.raises(dataclasses.FrozenInstanceError):
        result.success = False  # type: ignore[misc]


# ------------------------------------------------------------------------------- bad input


@pytest.mark.parametrize(
    "q",
    [
        np.zeros(5),
        np.zeros((6, 1)),
        [0, 0, 0, 0, 0, math.nan],
        [0, 0, math.inf, 0, 0, 0],
        "abc",
        None,
        np.zeros(6) + 0.1j,  # a cast would drop the imaginary part silently
        [[0, 0, 0], [0, 0]],
    ],
)
def test_bad_joint_angles_raise_one_clear_error(q: object) -> None:
    for method in (ROBOT.forward, ROBOT.jacobian, ROBOT.joint_frames, ROBOT.visual_poses):
        with pytest.raises(KinematicsError) as err:
            method(q)
        assert isinstance(err.value, StudioError)
        message = str(err.value)
        assert message.endswith(".") and "\n" not in message


def test_bad_ik_input_raises_one_clear_error() -> None:
    good = ROBOT.forward(PUMA_QR)
    nan_pose = good.copy()
    nan_pose[0, 3] = math.nan
    scaled = good.copy()
    scaled[:3, :3] *= 2.0
    mirrored = good.copy()
    mirrored[:3, 0] *= -1.0
    bad_row = good.copy()
    bad_row[3, 0] = 1.0
    cases = [
        dict(oMdes=np.eye(3)),
        dict(oMdes=nan_pose),
        dict(oMdes=scaled),
        dict(oMdes=mirrored),
        dict(oMdes=bad_row),
        dict(oMdes=np.zeros(3)),  # a position needs position_only=True
        dict(oMdes=[math.inf, 0, 0], position_only=True),
        dict(oMdes=good, q0=np.zeros(7)),
        dict(oMdes=good, q0=[math.nan] * 6),
        dict(oMdes=good, tolerance=-1.0),
        dict(oMdes=good, tolerance=math.nan),
        dict(oMdes=good, max_iterations=0),
        dict(oMdes=good, max_iterations=2.5),
        dict(oMdes=good, max_iterations="many"),
        dict(oMdes=good, max_iterations=math.inf),
        dict(oMdes=good, max_iterations=math.nan),
        dict(oMdes=good, tolerance="tight"),
        dict(oMdes="home"),
        dict(oMdes=[[1, 0], [0]], position_only=True),
        dict(oMdes=good + 0j),
    ]
    for kwargs in cases:
        with pytest.raises(KinematicsError) as err:
            ROBOT.inverse(**kwargs)
        message = str(err.value)
        assert message.endswith(".") and "\n" not in message, kwargs


def test_bad_ik_settings_are_one_clear_error() -> None:
    for bad in (
        dict(max_iterations=0),
        dict(max_iterations=1.5),
        dict(tolerance=0.0),
        dict(damping=math.nan),
        dict(max_step=-1.0),
        dict(stall_steps="ten"),
    ):
        with pytest.raises(KinematicsError, match="IKConfig") as err:
            IKConfig(**bad)
        assert str(err.value).endswith(".")
    assert Puma560(ik=IKConfig(max_iterations=20.0)).inverse(ROBOT.forward(PUMA_QR)).success


def test_an_improper_rotation_is_fine_when_only_the_position_matters() -> None:
    scaled = ROBOT.forward(PUMA_QR)
    scaled[:3, :3] *= 2.0
    assert ROBOT.inverse(scaled, position_only=True).success


def test_se3_targets_are_accepted() -> None:
    oMdes = pin.SE3(ROBOT.forward(PUMA_QR))
    assert ROBOT.inverse(oMdes, q0=PUMA_QR + 0.05).success


# --------------------------------------------------------------------------------- visuals


def test_visuals_are_well_formed() -> None:
    visuals = ROBOT.visuals()
    assert all(isinstance(v, LinkVisual) for v in visuals)
    assert len({v.name for v in visuals}) == len(visuals)
    assert {v.joint for v in visuals} >= {0, 1, 2, 3, 4, 6}
    for v in visuals:
        assert 0 <= v.joint <= 6
        assert len(v.dimensions) == {"cylinder": 2, "box": 3, "sphere": 1}[v.shape]
        assert all(size > 0 for size in v.dimensions)
        assert v.offset.shape == (4, 4)
        np.testing.assert_allclose(v.offset[:3, :3].T @ v.offset[:3, :3], np.eye(3), atol=1e-12)
        assert all(0.0 <= c <= 1.0 for c in v.rgb)


def assert_cylinder_spans(pose: np.ndarray, length: float, a: np.ndarray, b: np.ndarray) -> None:
    """The cylinder's two end centres are the points ``a`` and ``b`` (in either order)."""
    half = pose[:3, 2] * length / 2
    ends = [pose[:3, 3] - half, pose[:3, 3] + half]
    if np.linalg.norm(ends[0] - a) > np.linalg.norm(ends[1] - a):
        ends.reverse()
    np.testing.assert_allclose(ends, [a, b], atol=1e-12)


@FAST
@given(q=within_limits())
def test_visuals_follow_the_dh_geometry(q: np.ndarray) -> None:
    visuals = {v.name: v for v in ROBOT.visuals()}
    poses = dict(zip(visuals, ROBOT.visual_poses(q), strict=True))
    frames = ROBOT.joint_frames(q)
    origin = frames[:, :3, 3]
    for name, v in visuals.items():
        np.testing.assert_allclose(poses[name], frames[v.joint] @ v.offset, atol=1e-12)
    # The upper arm spans link 2 (DH frames 1 to 2), the forearm runs to the wrist centre.
    upper_arm, forearm = visuals["upper_arm"], visuals["forearm"]
    assert_cylinder_spans(poses["upper_arm"], upper_arm.dimensions[1], origin[1], origin[2])
    assert_cylinder_spans(poses["forearm"], forearm.dimensions[1], origin[3], origin[4])
    np.testing.assert_allclose(poses["wrist"][:3, 3], frames[4][:3, 3], atol=1e-12)
    # The pedestal stands on the floor, whatever the joints do.
    pedestal = poses["pedestal"]
    bottom = pedestal[2, 3] - visuals["pedestal"].dimensions[1] / 2
    assert abs(bottom) < 1e-12
