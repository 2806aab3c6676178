"""Laws of the 7-DOF human arm: frame, lengths, joint senses, mirroring, bad input."""

from __future__ import annotations

import importlib.metadata
import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from studio.kinematics import HumanArm, KinematicsError, _robot_specs
from studio.kinematics.human import _human
from studio.kinematics.human._human import ArmPose, mirror_human_q

RIGHT = HumanArm("right")
LEFT = HumanArm("left")
S = np.diag([1.0, -1.0, 1.0])  # sagittal reflection of the arm base frame
S_URDF = np.diag([1.0, 1.0, -1.0])  # the URDF's local frames keep their axes on both sides


def q_in_limits():
    return st.tuples(
        *[st.floats(lo, hi) for lo, hi in zip(RIGHT.lower, RIGHT.upper, strict=True)]
    ).map(np.array)


def test_model_is_the_seven_joint_arm_with_limits():
    assert RIGHT.nq == 7 and RIGHT.model.nq == 7
    assert RIGHT.joint_names == (
        "right_shoulder_Z",
        "right_shoulder_X",
        "right_shoulder_Y",
        "right_elbow_Z",
        "right_elbow_Y",
        "right_wrist_Z",
        "right_wrist_X",
    )
    assert LEFT.joint_names[0] == "left_shoulder_Z"
    assert np.all(RIGHT.lower < RIGHT.upper)
    assert np.all(RIGHT.lower <= RIGHT.neutral) and np.all(RIGHT.neutral <= RIGHT.upper)
    assert RIGHT.lower[3] == 0.0  # the elbow does not hyperextend


def test_neutral_arm_hangs_down_from_the_shoulder_in_a_z_up_frame():
    pose = RIGHT.forward(RIGHT.neutral)
    assert isinstance(pose, ArmPose)
    np.testing.assert_allclose(pose.shoulder[:3, 3], 0.0, atol=1e-12)
    np.testing.assert_allclose(pose.elbow[:3, 3], [0, 0, -RIGHT.upper_arm_length], atol=1e-12)
    reach = RIGHT.upper_arm_length + RIGHT.forearm_length
    np.testing.assert_allclose(pose.wrist[:3, 3], [0, 0, -reach], atol=1e-12)
    np.testing.assert_allclose(pose.hand[:3, 3], [0, 0, -reach - RIGHT.hand_length], atol=1e-12)
    assert (RIGHT.upper_arm_length, RIGHT.forearm_length) == pytest.approx((0.276, 0.287))


def test_joint_senses_flexion_forward_abduction_outward():
    q = np.zeros(7)
    q[0] = math.pi / 2  # shoulder flexion: arm forward (+x)
    np.testing.assert_allclose(
        RIGHT.forward(q).elbow[:3, 3], [RIGHT.upper_arm_length, 0, 0], atol=1e-12
    )
    q = np.zeros(7)
    q[1] = math.pi / 2  # abduction: right arm to the right (-y), left arm to the left
    np.testing.assert_allclose(
        RIGHT.forward(q).elbow[:3, 3], [0, -RIGHT.upper_arm_length, 0], atol=1e-12
    )
    np.testing.assert_allclose(
        LEFT.forward(q).elbow[:3, 3], [0, LEFT.upper_arm_length, 0], atol=1e-12
    )
    q = np.zeros(7)
    q[3] = math.pi / 2  # elbow flexion with the arm hanging: forearm forward
    wrist = RIGHT.forward(q).wrist[:3, 3]
    np.testing.assert_allclose(
        wrist, [RIGHT.forearm_length, 0, -RIGHT.upper_arm_length], atol=1e-12
    )


@settings(max_examples=40, deadline=None)
@given(q=q_in_limits())
def test_left_arm_is_the_right_arm_mirrored_through_the_sagittal_plane(q):
    right = RIGHT.forward(q)
    left = LEFT.forward(mirror_human_q(q))
    for name in ("shoulder", "elbow", "wrist", "hand"):
        r, l_ = getattr(right, name), getattr(left, name)
        np.testing.assert_allclose(l_[:3, 3], S @ r[:3, 3], atol=1e-12)
        np.testing.assert_allclose(l_[:3, :3], S @ r[:3, :3] @ S_URDF, atol=1e-12)


FULL = pin.buildModelFromUrdf(str(_human.find_human_urdf()))
FULL_DATA = FULL.createData()


@settings(max_examples=40, deadline=None)
@given(q=q_in_limits(), side=st.sampled_from(["right", "left"]))
def test_reduced_arm_moves_like_the_arm_of_the_full_human_urdf(q, side):
    # The same seven angles set in the full 36-DOF human.urdf (everything else neutral) put the
    # elbow, wrist and hand where HumanArm does, seen from the shoulder and turned Z-up.
    arm = RIGHT if side == "right" else LEFT
    full_q = pin.neutral(FULL)
    for value, name in zip(q, arm.joint_names, strict=True):
        full_q[FULL.idx_qs[FULL.getJointId(name)]] = value
    pin.forwardKinematics(FULL, FULL_DATA, full_q)
    oMi = [FULL_DATA.oMi[FULL.getJointId(name)] for name in arm.joint_names]
    wrist = oMi[-1]
    # The hand centre lies along the hand's axis at the depth of its centre of mass.
    hand = np.array([0.0, FULL.inertias[FULL.getJointId(arm.joint_names[-1])].lever[1], 0.0])
    expected = np.stack(
        [oMi[2].translation, oMi[3].translation, oMi[5].translation, wrist.act(hand)]
    )
    expected = (expected - oMi[0].translation) @ _human.YUP_TO_ZUP.T
    np.testing.assert_allclose(arm.points(q), expected, atol=1e-12)
    pose = arm.forward(q)
    for got, joint in ((pose.shoulder, oMi[2]), (pose.elbow, oMi[4]), (pose.wrist, oMi[6])):
        np.testing.assert_allclose(got[:3, :3], _human.YUP_TO_ZUP @ joint.rotation, atol=1e-12)


@settings(max_examples=30, deadline=None)
@given(q=q_in_limits())
def test_mirroring_twice_is_the_identity(q):
    np.testing.assert_array_equal(mirror_human_q(mirror_human_q(q)), q)


@settings(max_examples=30, deadline=None)
@given(q=q_in_limits())
def test_limb_lengths_hold_in_every_pose_and_scale(q):
    arm = HumanArm(upper_arm=0.31, forearm=0.25, hand=0.09)
    p = arm.points(q)
    assert np.linalg.norm(p[1] - p[0]) == pytest.approx(0.31)
    assert np.linalg.norm(p[2] - p[1]) == pytest.approx(0.25)
    assert np.linalg.norm(p[3] - p[2]) == pytest.approx(0.09)
    np.testing.assert_allclose(arm.points(np.stack([q, q]))[1], p)
    pose = arm.forward(q)
    np.testing.assert_allclose(pose.wrist[:3, 3], p[2])
    for m in (pose.shoulder, pose.elbow, pose.wrist, pose.hand):
        np.testing.assert_allclose(m[:3, :3].T @ m[:3, :3], np.eye(3), atol=1e-12)


@pytest.mark.parametrize(
    "q", [np.zeros(6), np.zeros((7, 1)), np.array([0, 0, 0, np.nan, 0, 0, 0.0])]
)
def test_forward_rejects_bad_angles(q):
    with pytest.raises(KinematicsError):
        RIGHT.forward(q)


def test_bad_construction_is_one_clear_error():
    with pytest.raises(KinematicsError, match="side"):
        HumanArm("middle")  # type: ignore[arg-type]
    with pytest.raises(KinematicsError, match="upper_arm"):
        HumanArm(upper_arm=-0.2)
    with pytest.raises(KinematicsError, match="NaN|finite"):
        mirror_human_q([np.inf] * 7)
    for bad in ("long", math.nan, math.inf, 0.0, True):
        with pytest.raises(KinematicsError, match="forearm"):
            HumanArm(forearm=bad)  # type: ignore[arg-type]
    for q in ("abcdefg", np.zeros(7) + 1j, [0, 0, 0, None, 0, 0, 0]):
        with pytest.raises(KinematicsError) as err:
            RIGHT.forward(q)
        assert str(err.value).endswith(".") and "\n" not in str(err.value)


def test_missing_example_robot_data_names_the_package(monkeypatch, tmp_path):
    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)

    monkeypatch.setattr(_robot_specs.importlib.metadata, "distribution", missing)
    monkeypatch.setattr(
        _robot_specs.sysconfig,
        "get_paths",
        lambda: {"purelib": str(tmp_path), "platlib": str(tmp_path)},
    )
    with pytest.raises(KinematicsError, match="example-robot-data"):
        HumanArm()
