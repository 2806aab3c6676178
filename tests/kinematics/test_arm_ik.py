"""The live retargeting path: the compiled arm IK against Pinocchio, the self-collision guard
against the full check, the reach mapping, and the Puma560's continuity in cartesian mode."""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from studio.kinematics import HumanArm, Retargeter, arm_motion, load_robot, robot_names
from studio.kinematics._chain_ik import _heights, _log3, _solve
from studio.kinematics._clearance import ClearanceGuard
from studio.kinematics._puma import closed_form_solutions
from studio.kinematics._robot_load import prepare_arm_ik

RIGHT = HumanArm("right")
MAX_STEP_DEG = 5.0


def _human_q():
    return st.tuples(
        *[st.floats(lo, hi) for lo, hi in zip(RIGHT.lower, RIGHT.upper, strict=True)]
    ).map(np.array)


@pytest.mark.parametrize("name", robot_names())
def test_the_compiled_chain_puts_the_tool_where_pinocchio_does(name):
    arm = load_robot(name, geometry=False)
    rng = np.random.default_rng(7)
    for _ in range(40):
        q = rng.uniform(arm.lower, arm.upper)
        np.testing.assert_allclose(arm.chain.forward(q), arm.forward(q), atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(
    axis=st.tuples(*[st.floats(-1, 1)] * 3).filter(lambda v: np.linalg.norm(v) > 0.1),
    angle=st.one_of(st.floats(0.0, math.pi), st.floats(math.pi - 1e-3, math.pi)),
)
def test_the_compiled_rotation_error_is_pinocchios_log3_also_near_a_half_turn(axis, angle):
    w = angle * np.asarray(axis) / np.linalg.norm(axis)
    R = pin.exp3(w)
    got = np.zeros(3)
    _log3(np.ascontiguousarray(R), got)
    # near a half turn +w and -w are the same rotation: compare the rotations they give
    np.testing.assert_allclose(pin.exp3(got), R, atol=1e-7)
    assert np.linalg.norm(got) == pytest.approx(angle, abs=1e-6)


@pytest.mark.parametrize("name", ["panda", "ur5", "so101", "z1", "kinova"])
def test_the_guard_finds_exactly_the_pairs_the_full_check_finds(name):
    arm = load_robot(name)
    guard = ClearanceGuard(arm, 0.005)
    rng = np.random.default_rng(3)
    q = arm.home.copy()
    colliding = 0
    for i in range(300):
        jump = rng.uniform(arm.lower, arm.upper) - q if i % 10 == 0 else 0.0
        q = np.clip(q + rng.normal(0.0, 0.05, arm.nq) + jump, arm.lower, arm.upper)
        full = sorted((c.link_a, c.link_b) for c in arm.contacts(q, 0.005))  # links and table
        assert sorted((c.link_a, c.link_b) for c in guard.collisions(q)) == full
        colliding += bool(full)
    assert colliding > 0  # the walk does come close: the comparison is not vacuous
    assert guard.measured < 300 * len(arm.collision_model.collisionPairs)  # it skipped pairs


@pytest.mark.parametrize("name", ["kinova", "so101"])
def test_a_link_distance_reads_the_same_when_measured_again(name):
    # Collision shapes are true convex hulls: coal's GJK, warm-started from the last query,
    # gives the same distances (on meshes taken as their own hulls it drifted by centimetres).
    arm = load_robot(name)
    geom = arm.collision_model
    data = pin.GeometryData(geom)
    rng = np.random.default_rng(5)
    for _ in range(30):
        q = rng.uniform(arm.lower, arm.upper)
        pin.computeDistances(arm.model, arm.data, geom, data, q)
        first = np.array([r.min_distance for r in data.distanceResults])
        pin.computeDistances(arm.model, arm.data, geom, data, q)
        again = np.array([r.min_distance for r in data.distanceResults])
        np.testing.assert_allclose(again, first, atol=1e-5)


def test_the_shoulder_of_an_arm_with_a_shoulder_offset_lies_on_its_first_axis():
    ur5 = load_robot("ur5", geometry=False)
    assert ur5.shoulder[:2] == pytest.approx([0.0, 0.0], abs=1e-9)
    rng = np.random.default_rng(0)
    far = max(
        np.linalg.norm(ur5.forward(rng.uniform(ur5.lower, ur5.upper))[:3, 3] - ur5.shoulder)
        for _ in range(300)
    )
    assert far <= ur5.reach + 1e-9


@settings(max_examples=40, deadline=None)
@given(q_human=_human_q())
def test_a_table_arms_target_stays_within_its_reach_and_points_its_tool_along_the_fingers(
    q_human,
):
    z1 = Retargeter(robot=load_robot("z1", geometry=False))
    panda = Retargeter(robot=load_robot("panda", geometry=False))
    target = z1.hand_target(q_human)
    arm, config = z1.robot, z1.config
    assert np.linalg.norm(target[:3, 3] - arm.shoulder) < config.reach_fraction * arm.reach
    # the Z1's tool frame points along its x: x there is where the Panda's tool z points
    np.testing.assert_allclose(target[:3, 0], panda.hand_target(q_human)[:3, 2], atol=1e-12)
    np.testing.assert_allclose(np.linalg.det(target[:3, :3]), 1.0)


def test_a_hand_within_reach_is_not_moved_and_one_behind_the_arms_axis_is_moved_out_smoothly():
    retargeter = Retargeter(robot=load_robot("ur5", geometry=False))
    forward = np.array([1.2, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0])  # the arm raised forward: far
    folded = np.array([0.6, 0.3, 0.0, 1.8, 0.5, 0.0, 0.0])
    behind = np.array([-1.0, 0.0, 0.0, 0.2, 0.0, 0.0, 0.0])  # the arm stretched back
    retargeter.robot_from_human(folded)
    assert retargeter.pulled_in == 0.0
    retargeter.robot_from_human(forward)
    assert retargeter.pulled_in == 0.0, "an outstretched arm lands within the robot's reach"
    retargeter.robot_from_human(behind)
    assert retargeter.pulled_in > 0.0
    assert retargeter.pushed_out == pytest.approx(retargeter.pulled_in)  # all of it the hollow
    path = np.linspace(folded, behind, 200)
    targets = np.array([retargeter.hand_target(q)[:3, 3] for q in path])
    assert np.abs(np.diff(targets, axis=0)).max() < 0.02  # no jump where the moving-out starts


@pytest.fixture(scope="module")
def long_motion():
    # 15 s: past 13.2 s, where the mirrored hand passes near the Puma560's first axis
    return arm_motion(np.arange(0.0, 15.0, 1 / 110), RIGHT)


@pytest.mark.parametrize("mirror", [True, False])
def test_the_puma_in_cartesian_mode_never_steps_more_than_5_deg_a_frame(long_motion, mirror):
    retargeter = Retargeter(mode="cartesian", mirror=mirror)
    puma = retargeter.robot
    q = np.array([retargeter.robot_from_human(q_human) for q_human in long_motion])
    assert np.degrees(np.abs(np.diff(q, axis=0))).max() <= MAX_STEP_DEG
    assert np.all((q >= puma.lower) & (q <= puma.upper))
    within = reachable = 0
    for q_robot, q_human in zip(q, long_motion, strict=True):
        target = retargeter.hand_target(q_human)
        p, R = target[:3, 3], target[:3, :3]
        if not closed_form_solutions(puma.dh, p, R, q_robot, puma.lower, puma.upper):
            continue  # no pose of the arm within its limits reaches it
        reachable += 1
        got = puma.forward(q_robot)
        angle = math.degrees(math.acos(np.clip((np.trace(got[:3, :3].T @ R) - 1) / 2, -1, 1)))
        within += np.linalg.norm(got[:3, 3] - p) < 0.01 and angle < 5.0
    assert within / reachable >= 0.95


def test_an_arm_that_jumps_is_a_new_pose_the_puma_reaches_at_once():
    retargeter = Retargeter(mode="cartesian")
    first = np.array([0.8, 0.3, 0.2, 1.0, 0.3, 0.2, 0.1])
    retargeter.robot_from_human(first)
    jumped = first + np.array([0.4, -0.3, 0.3, -0.4, 0.3, 0.2, -0.2])
    q = retargeter.robot_from_human(jumped)
    assert retargeter.last_ik is not None and retargeter.last_ik.success
    target = retargeter.hand_target(jumped)
    assert np.linalg.norm(retargeter.robot.forward(q)[:3, 3] - target[:3, 3]) < 1e-4


def test_preparing_the_ik_leaves_the_kernels_compiled():
    assert prepare_arm_ik() >= 0.0
    assert _solve.signatures  # loaded or compiled: the first arm chosen will not compile it
    # nor the first pose checked against the table, whose geometry has these types
    (signature,) = _heights.signatures
    arm = load_robot("panda")
    assert arm.table_contacts(arm.home) == []
    assert _heights.signatures == [signature]
