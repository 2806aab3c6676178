"""Retargeting laws: the joint map and its inverse, mirroring, clamping, cartesian IK, bad input."""

from __future__ import annotations

import math
import sys
import threading

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from studio.kinematics import (
    HumanArm,
    KinematicsError,
    Puma560,
    RetargetConfig,
    Retargeter,
    load_robot,
    retarget_path,
)
from studio.kinematics._retarget import DROPPED_HUMAN_JOINT, JOINT_MAP
from studio.kinematics.human._filter import turn_backs

RIGHT = HumanArm("right")
LEFT = HumanArm("left")
ROBOT = Puma560()
TABLE_D1 = 0.67183  # the Puma's pedestal: its shoulder height (DESIGN.md's DH table)
#: The Puma joints whose sign flips with mirroring, as the module docstring's table documents
#: them (J1 swings the arm sideways, J4 rolls the forearm, J6 is the wrist's sideways joint):
#: written out here, not read from JOINT_MAP, so a changed flag in the code fails the tests.
LATERAL = [0, 3, 5]
#: (human joint, sign, offset) per Puma joint, for the right arm unmirrored, as documented.
DOCUMENTED_MAP = [
    (1, -1.0, 0.0),
    (0, 1.0, -math.pi / 2),
    (3, 1.0, -math.pi / 2),
    (4, 1.0, 0.0),
    (5, 1.0, 0.0),
    (6, 1.0, 0.0),
]


def human_q():
    return st.tuples(
        *[st.floats(lo, hi) for lo, hi in zip(RIGHT.lower, RIGHT.upper, strict=True)]
    ).map(np.array)


def robot_q():
    return st.tuples(
        *[st.floats(lo, hi) for lo, hi in zip(ROBOT.lower, ROBOT.upper, strict=True)]
    ).map(np.array)


@settings(max_examples=40, deadline=None)
@given(q_human=human_q())
def test_joint_mode_is_the_documented_table(q_human):
    plain = Retargeter(mirror=False, robot=ROBOT, arm=RIGHT).robot_from_human(q_human)
    expected = [offset + sign * q_human[i] for i, sign, offset in DOCUMENTED_MAP]
    np.testing.assert_allclose(plain, np.clip(expected, ROBOT.lower, ROBOT.upper), atol=1e-15)
    assert [i for i, *_ in DOCUMENTED_MAP] == [i for i, *_ in JOINT_MAP]


def test_neutral_arm_hangs_the_robot_arm_down():
    q_robot = Retargeter(robot=ROBOT).robot_from_human(RIGHT.neutral)
    np.testing.assert_allclose(q_robot, [0, -math.pi / 2, -math.pi / 2, 0, 0, 0])


@settings(max_examples=60, deadline=None)
@given(q_robot=robot_q(), mirror=st.booleans(), side=st.sampled_from(["right", "left"]))
def test_joint_mode_human_from_robot_is_the_exact_inverse(q_robot, mirror, side):
    arm = RIGHT if side == "right" else LEFT
    retargeter = Retargeter(mirror=mirror, robot=ROBOT, arm=arm)
    q_human = retargeter.human_from_robot(q_robot)
    assert q_human[DROPPED_HUMAN_JOINT] == 0.0
    clipped = np.any(q_human <= arm.lower) or np.any(q_human >= arm.upper)
    if not clipped:
        np.testing.assert_allclose(retargeter.robot_from_human(q_human), q_robot, atol=1e-12)


@settings(max_examples=60, deadline=None)
@given(q_human=human_q(), mirror=st.booleans())
def test_joint_mode_robot_from_human_round_trips_where_not_clamped(q_human, mirror):
    retargeter = Retargeter(mirror=mirror, robot=ROBOT, arm=RIGHT)
    q_robot = retargeter.robot_from_human(q_human)
    assert np.all(q_robot >= ROBOT.lower) and np.all(q_robot <= ROBOT.upper)
    if np.all(q_robot > ROBOT.lower) and np.all(q_robot < ROBOT.upper):
        expected = q_human.copy()
        expected[DROPPED_HUMAN_JOINT] = 0.0
        np.testing.assert_allclose(retargeter.human_from_robot(q_robot), expected, atol=1e-12)


@settings(max_examples=40, deadline=None)
@given(q_human=human_q())
def test_mirroring_flips_exactly_the_lateral_joints(q_human):
    mirrored = Retargeter(mirror=True, robot=ROBOT, arm=RIGHT).robot_from_human(q_human)
    plain = Retargeter(mirror=False, robot=ROBOT, arm=RIGHT).robot_from_human(q_human)
    lateral = np.zeros(6, dtype=bool)
    lateral[LATERAL] = True
    np.testing.assert_array_equal(mirrored[~lateral], plain[~lateral])
    # Puma limits are symmetric, so the flip survives clamping.
    np.testing.assert_allclose(mirrored[lateral], -plain[lateral])
    # A left arm is already a mirror image: mirroring it equals not mirroring the right arm.
    left = Retargeter(mirror=True, robot=ROBOT, arm=LEFT).robot_from_human(q_human)
    np.testing.assert_array_equal(left, plain)


def test_mirrored_abduction_moves_the_robot_to_the_operators_side():
    # Facing the robot, the operator swings the right arm out to their right (-y in their
    # frame). Mirrored, the robot's tool goes to its left (+y), the same side seen by the
    # operator; unmirrored it copies the motion in its own frame (-y).
    forward = np.zeros(7)
    forward[0] = math.pi / 2
    out = forward.copy()
    out[1] = 0.5
    assert RIGHT.forward(out).wrist[1, 3] < RIGHT.forward(forward).wrist[1, 3]
    for mirror, sign in ((True, 1.0), (False, -1.0)):
        retargeter = Retargeter(mirror=mirror, robot=ROBOT, arm=RIGHT)
        dy = (
            ROBOT.forward(retargeter.robot_from_human(out))[1, 3]
            - ROBOT.forward(retargeter.robot_from_human(forward))[1, 3]
        )
        assert math.copysign(1.0, dy) == sign and abs(dy) > 0.1


def test_joint_mode_clamps_at_the_puma_limits():
    q = np.zeros(7)
    q[0] = -math.pi  # shoulder extended far back: J2 would be -270 deg
    q_robot = Retargeter(robot=ROBOT).robot_from_human(q)
    assert q_robot[1] == ROBOT.lower[1]


def test_cartesian_mode_reaches_the_mirrored_scaled_hand_pose():
    rng = np.random.default_rng(5)
    retargeter = Retargeter(mode="cartesian", robot=ROBOT, arm=RIGHT)
    plain = Retargeter(mode="cartesian", mirror=False, robot=ROBOT, arm=RIGHT)
    start = np.array([0.8, 0.3, 0.2, 1.0, 0.3, 0.2, 0.1])
    reached = 0
    for q in start + 0.3 * rng.uniform(-1, 1, (30, 7)):
        q = np.clip(q, RIGHT.lower, RIGHT.upper)
        target = retargeter.hand_target(q)
        other = plain.hand_target(q)
        np.testing.assert_allclose(target[:3, 3] * [1, -1, 1], other[:3, 3], atol=1e-12)
        np.testing.assert_allclose(np.linalg.det(target[:3, :3]), 1.0)
        q_robot = retargeter.robot_from_human(q)
        assert np.all(q_robot >= ROBOT.lower) and np.all(q_robot <= ROBOT.upper)
        if np.linalg.norm(ROBOT.forward(q_robot)[:3, 3] - target[:3, 3]) < 1e-4:
            reached += 1
    assert reached >= 25  # positions reached (the full orientation when the Puma's wrist can)
    # An unreachable hand pose is reported, and the answer stays within the limits.
    far = Retargeter(mode="cartesian", robot=ROBOT, arm=RIGHT)
    far.config = RetargetConfig(reach_fraction=3.0)
    q_robot = far.robot_from_human(np.zeros(7))
    assert far.last_ik is not None and not far.last_ik.success
    assert np.all(q_robot >= ROBOT.lower) and np.all(q_robot <= ROBOT.upper)


@settings(max_examples=40, deadline=None)
@given(q_human=human_q())
def test_mirroring_a_mirror_image_gives_back_the_unmirrored_hand_target(q_human):
    # The left arm at q is the right arm at q reflected; reflecting it again (mirror=True) must
    # give exactly the right arm's unmirrored target: the cartesian mirror applied twice is the
    # identity, on positions and on the tool's orientation.
    for mirrored, plain in ((LEFT, RIGHT), (RIGHT, LEFT)):
        twice = Retargeter("cartesian", mirror=True, robot=ROBOT, arm=mirrored)
        once = Retargeter("cartesian", mirror=False, robot=ROBOT, arm=plain)
        np.testing.assert_allclose(
            twice.hand_target(q_human), once.hand_target(q_human), atol=1e-12
        )


@settings(max_examples=40, deadline=None)
@given(q_human=human_q(), mirror=st.booleans(), fraction=st.floats(0.5, 1.0))
def test_cartesian_target_is_the_hand_mirrored_scaled_to_the_robots_reach(
    q_human, mirror, fraction
):
    # Position: the shoulder-to-hand vector, reflected y -> -y when mirroring, scaled so that
    # the stretched arm reaches reach_fraction of the Puma's reach, from the Puma's shoulder.
    # Orientation: the tool's approach axis (z) along the fingers (hand -y), tool x = hand x.
    retargeter = Retargeter(
        "cartesian", mirror=mirror, robot=ROBOT, arm=RIGHT, config=RetargetConfig(fraction)
    )
    hand = RIGHT.forward(q_human).hand
    reflect = np.diag([1.0, -1.0 if mirror else 1.0, 1.0])
    human_reach = RIGHT.upper_arm_length + RIGHT.forearm_length + RIGHT.hand_length
    scale = fraction * ROBOT.reach / human_reach
    target = retargeter.hand_target(q_human)
    shoulder = np.array([0.0, 0.0, TABLE_D1])
    np.testing.assert_allclose(target[:3, 3], shoulder + scale * reflect @ hand[:3, 3], atol=1e-12)
    np.testing.assert_allclose(target[:3, 2], -reflect @ hand[:3, 1], atol=1e-12)
    np.testing.assert_allclose(target[:3, 0], reflect @ hand[:3, 0], atol=1e-12)
    stretched = retargeter.hand_target(RIGHT.neutral)
    distance = np.linalg.norm(stretched[:3, 3] - shoulder)
    assert distance == pytest.approx(fraction * ROBOT.reach, rel=1e-12)


def test_bad_retarget_settings_are_one_clear_error():
    for bad in (dict(reach_fraction=-0.5), dict(reach_fraction=math.nan), dict(ik_iterations=0)):
        with pytest.raises(KinematicsError, match="RetargetConfig"):
            RetargetConfig(**bad)
    with pytest.raises(KinematicsError, match="Puma560"):
        Retargeter(robot=RIGHT)  # type: ignore[arg-type]
    with pytest.raises(KinematicsError, match="HumanArm"):
        Retargeter(arm="right")  # type: ignore[arg-type]


def test_mode_switches_at_run_time_and_is_validated():
    retargeter = Retargeter(robot=ROBOT)
    q = np.array([0.9, 0.2, 0.1, 1.0, 0.2, 0.1, 0.0])
    joint = retargeter.robot_from_human(q)
    retargeter.mode = "cartesian"
    cartesian = retargeter.robot_from_human(q)
    assert not np.allclose(joint, cartesian)
    with pytest.raises(KinematicsError, match="mode"):
        retargeter.mode = "telepathy"
    with pytest.raises(KinematicsError, match="mode"):
        Retargeter(mode="both")  # type: ignore[arg-type]


@pytest.mark.parametrize("bad", [np.zeros(6), np.full(7, np.nan), "q"])
def test_bad_human_angles_raise(bad):
    with pytest.raises(KinematicsError):
        Retargeter(robot=ROBOT).robot_from_human(bad)


@pytest.mark.parametrize("bad", [np.zeros(7), np.full(6, np.inf)])
def test_bad_robot_angles_raise(bad):
    with pytest.raises(KinematicsError):
        Retargeter(robot=ROBOT).human_from_robot(bad)


def test_a_path_retargets_onto_the_puma_by_the_joint_map_and_onto_an_arm_as_live_or_planned() -> (
    None
):
    t = np.linspace(0.0, 1.0, 60)[:, None]
    q_human = np.zeros((60, 7))
    q_human[:, 0] = 0.3 + 0.6 * t[:, 0]  # the arm lifts forward, the elbow bends
    q_human[:, 3] = 0.2 + 0.8 * t[:, 0]
    puma = retarget_path(load_robot("puma560"), q_human)
    joint = Retargeter()
    assert np.allclose(puma.q, [joint.robot_from_human(q) for q in q_human])
    assert not puma.out_of_reach.any() and np.all(puma.position_error == 0.0)

    panda = load_robot("panda")
    path = retarget_path(panda, q_human)
    assert path.q.shape == (60, 7)
    assert np.all(path.q >= panda.lower - 1e-9) and np.all(path.q <= panda.upper + 1e-9)
    step = RetargetConfig().max_joint_step
    assert np.abs(np.diff(path.q, axis=0)).max() <= step + 1e-9
    tolerance = RetargetConfig().reach_tolerance
    assert (path.out_of_reach <= (path.position_error > tolerance)).all()  # flagged: far off
    # as_live: as a live session shows it, the same frames through one Retargeter, after
    # settling (the planned path above may take other branches, tests/kinematics/test_retarget_plan.py)
    live = Retargeter(robot=panda)
    for _ in range(RetargetConfig().settle_tries):
        live.robot_from_human(q_human[0])
        if live.last_ik is not None and live.last_ik.success:
            break
    as_live = retarget_path(panda, q_human, as_live=True)
    assert np.allclose(as_live.q, [live.robot_from_human(q) for q in q_human])


def test_paths_retargeted_in_threads_at_once_are_each_the_one_retargeted_alone() -> None:
    panda = load_robot("panda")
    rng = np.random.default_rng(3)
    paths = [np.cumsum(rng.normal(0.0, 0.01, (80, 7)), axis=0) + [0.5, 0, 0, 0.6, 0, 0, 0]]
    paths.append(paths[0][::-1].copy())
    alone = [retarget_path(panda, p).q for p in paths]
    together: list[np.ndarray | None] = [None, None]

    def run(i: int) -> None:
        together[i] = retarget_path(panda, paths[i]).q

    threads = [threading.Thread(target=run, args=(i,)) for i in range(2)]
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)  # the threads take turns between almost every two steps
    try:
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    finally:
        sys.setswitchinterval(interval)
    for a, b in zip(alone, together, strict=True):
        assert b is not None and np.array_equal(a, b)
    copy = panda.scratch_copy()
    assert copy.model is panda.model and copy.data is not panda.data
    assert np.allclose(copy.forward(panda.home), panda.forward(panda.home))


def test_near_a_singularity_a_ur_arm_does_not_flip_between_two_answers() -> None:
    """Sample 2 takes the UR5 near its shoulder and wrist singularities, where the exact IK
    answer swung between two poses about 12 degrees apart, frame after frame (about 530
    turn-backs); damped more there, the arm moves through smoothly and reaches as often."""
    from studio.capture import human_angles, read_any_recording
    from studio.kinematics._retarget_path import tool_reaches
    from studio.samples import SAMPLES_DIR

    ur5 = load_robot("ur5")
    q_human = human_angles(read_any_recording(SAMPLES_DIR / "sample-reach-2.tape.csv"), slice(None))
    path = retarget_path(ur5, q_human)
    assert turn_backs(path.q) <= 60
    targets = Retargeter(robot=ur5.scratch_copy())
    reached = [
        tool_reaches(ur5, q, targets.hand_target(h)) for q, h in zip(path.q, q_human, strict=True)
    ]
    assert np.mean(reached) >= 0.5  # (as before: the target is out of the UR5's reach early on)


def test_the_ik_is_damped_more_only_near_a_singularity_of_an_arm_without_joints_to_spare() -> None:
    from studio.kinematics._robots import IK_DAMPING

    ur5, panda = load_robot("ur5"), load_robot("panda")
    retargeter = Retargeter(robot=ur5.scratch_copy())
    regular = ur5.home + np.array([0.3, -0.5, 1.0, -0.5, 0.8, 0.2])
    wrist_singular = regular.copy()
    wrist_singular[4] = 0.0  # the UR wrist's first and last axes in line
    assert retargeter._damping(ur5, regular) == IK_DAMPING
    assert retargeter._damping(ur5, wrist_singular) > 5 * IK_DAMPING
    assert Retargeter(robot=panda.scratch_copy())._damping(panda, panda.home) == IK_DAMPING
    with pytest.raises(KinematicsError, match="singular_margin"):
        RetargetConfig(singular_margin=0.0)


def test_the_chains_jacobian_is_pinocchios() -> None:
    import pinocchio as pin

    for name in ("ur5", "panda"):
        arm = load_robot(name)
        q = np.random.default_rng(1).uniform(arm.lower, arm.upper)
        ours = arm.chain.jacobian(q)
        theirs = pin.computeFrameJacobian(
            arm.model, arm.model.createData(), q, arm.tool_frame, pin.LOCAL_WORLD_ALIGNED
        )
        np.testing.assert_allclose(ours, theirs, atol=1e-9, err_msg=name)
