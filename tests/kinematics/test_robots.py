"""Today's arms: every offered robot loads with its joints and limits, reaches by IK, and finds
its own self-collisions; ``studio robots`` lists them."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from studio.kinematics import TABLE, KinematicsError, load_robot, robot_names
from studio.kinematics._robots import robot_spec

OFFERED = ("puma560", "panda", "ur3", "ur5", "ur10", "so100", "so101", "xarm7", "z1", "kinova")


def test_the_puma_comes_first_and_every_arm_the_issue_names_is_offered():
    assert robot_names()[0] == "puma560"
    assert set(OFFERED) <= set(robot_names())


def test_an_unknown_robot_is_refused_with_the_names_that_exist():
    with pytest.raises(KinematicsError, match=r"Unknown robot 'pr2'; use one of puma560, panda"):
        robot_spec("pr2")


@pytest.mark.parametrize("name", OFFERED)
def test_each_robot_has_finite_limits_inside_which_its_home_lies(name):
    arm = load_robot(name, geometry=False)
    assert arm.nq == len(arm.joint_names) >= 5
    assert np.all(np.isfinite(arm.lower)) and np.all(np.isfinite(arm.upper))
    assert np.all(arm.lower < arm.upper)
    assert np.all((arm.home >= arm.lower) & (arm.home <= arm.upper))
    assert np.all(arm.velocity > 0) and np.all(arm.acceleration > 0)
    assert arm.reach > 0.2


def test_continuous_joints_get_one_angle_each_with_a_full_turn_either_way():
    arm = load_robot("kinova", geometry=False)
    assert arm.nq == arm.model.nv == 6
    assert arm.hard_upper[0] == pytest.approx(2 * math.pi, abs=1e-5)


def test_locked_grippers_are_not_arm_joints():
    assert "panda_finger_joint1" not in load_robot("panda", geometry=False).joint_names
    assert load_robot("so100", geometry=False).nq == 5


@pytest.mark.parametrize("name", OFFERED)
def test_ik_reaches_poses_the_arm_can_reach_within_1cm_and_5deg(name):
    arm = load_robot(name, geometry=False)
    rng = np.random.default_rng(7)
    reached = 0
    for _ in range(40):
        q_true = rng.uniform(arm.lower, arm.upper)
        target = arm.forward(q_true)
        start = np.clip(q_true + rng.normal(0.0, 0.15, arm.nq), arm.lower, arm.upper)
        result = arm.inverse(target, start)
        assert np.all((result.q >= arm.lower) & (result.q <= arm.upper))
        got = arm.forward(result.q)
        ok = np.linalg.norm(got[:3, 3] - target[:3, 3]) < 0.01
        if arm.spec.orientation:
            cos = (np.trace(got[:3, :3].T @ target[:3, :3]) - 1) / 2
            ok = ok and math.degrees(math.acos(np.clip(cos, -1, 1))) < 5
        reached += ok
    assert reached >= 38


def test_the_null_space_moves_a_redundant_arms_elbow_without_moving_its_tool():
    arm = load_robot("panda", geometry=False)
    target = arm.forward(arm.home)
    elbow_home = arm.elbow(arm.home.copy())
    wanted = elbow_home + np.array([0.0, 0.15, 0.0])
    result = arm.inverse(target, arm.home, elbow=wanted, iterations=200)
    assert result.success
    assert np.linalg.norm(arm.elbow(result.q) - wanted) < np.linalg.norm(elbow_home - wanted) - 0.03


@pytest.mark.parametrize("name", ["panda", "ur5", "so100", "z1"])
def test_home_is_free_and_a_folded_pose_is_found_in_collision_naming_the_links(name):
    arm = load_robot(name)
    assert arm.checks_collisions
    assert arm.self_collisions(arm.home) == []
    rng = np.random.default_rng(3)
    for _ in range(400):
        q = rng.uniform(arm.lower, arm.upper)
        found = arm.self_collisions(q)
        if found:
            break
    else:
        pytest.fail(f"no self-collision found for {name} in 400 random poses")
    worst = found[0]
    assert worst.distance < 0 and worst.link_a != worst.link_b
    link_names = {arm.model.frames[i].name for i in range(len(arm.model.frames))}
    assert {worst.link_a, worst.link_b} <= link_names


def test_studio_robots_lists_every_robot_with_joints_and_limits(capsys):
    from studio.cli import main

    assert main(["robots", "--json"]) == 0
    robots = json.loads(capsys.readouterr().out)
    assert [r["name"] for r in robots][0] == "puma560"
    panda = next(r for r in robots if r["name"] == "panda")
    assert [j["name"] for j in panda["joints"]][:2] == ["panda_joint1", "panda_joint2"]
    assert panda["joints"][3]["upper_deg"] == pytest.approx(-4.0, abs=0.1)
    assert main(["robots"]) == 0
    text = capsys.readouterr().out
    assert "puma560: Puma560" in text and "(default)" in text and "shoulder_pan_joint" in text


# --------------------------------------------------------------------------- retargeting


@pytest.fixture(scope="module")
def motion():
    from studio.kinematics import HumanArm, arm_motion

    arm = HumanArm()
    return arm_motion(np.arange(0.0, 8.0, 1 / 110), arm)


@pytest.mark.parametrize("name", [n for n in OFFERED if n != "puma560"])
def test_a_robot_follows_the_operator_within_limits_without_flips_or_self_collision(name, motion):
    from studio.kinematics import Retargeter

    arm = load_robot(name)
    retargeter = Retargeter(robot=arm)
    assert retargeter.mode == "cartesian"
    q = np.array([retargeter.robot_from_human(q_human) for q_human in motion])
    assert np.all((q >= arm.lower - 1e-12) & (q <= arm.upper + 1e-12))
    jumps = np.degrees(np.abs(np.diff(q, axis=0))).max()
    assert jumps <= 5.0
    assert all(arm.self_collisions(pose) == [] for pose in q[::7])
    # the hand's scaled path does leave the robot's base: the tool follows it much of the time
    tool = np.array([arm.forward(pose)[:3, 3] for pose in q[::11]])
    target = np.array([retargeter.hand_target(q_human)[:3, 3] for q_human in motion[::11]])
    assert np.mean(np.linalg.norm(tool - target, axis=1) < 0.01) > 0.05


@pytest.mark.parametrize("name", ["panda", "ur5", "xarm7", "kinova"])
def test_on_a_reachable_smooth_path_the_tool_stays_within_1cm_and_5deg(name):
    arm = load_robot(name, geometry=False)
    t = np.linspace(0.0, 4.0, 440)[:, None]
    centre = np.clip(arm.home, arm.lower + 0.4, arm.upper - 0.4)
    path = centre + 0.35 * np.sin(2 * np.pi * t / np.linspace(2.0, 4.0, arm.nq))
    q = path[0]
    within = 0
    for q_true in path:
        target = arm.forward(q_true)
        q = arm.inverse(target, q, iterations=20).q
        got = arm.forward(q)
        cos = (np.trace(got[:3, :3].T @ target[:3, :3]) - 1) / 2
        rot = math.degrees(math.acos(np.clip(cos, -1, 1)))
        within += np.linalg.norm(got[:3, 3] - target[:3, 3]) < 0.01 and rot < 5
    assert within / len(path) >= 0.98


def test_joint_mode_is_refused_for_a_robot_whose_joints_are_not_the_human_arms():
    from studio.kinematics import Retargeter

    with pytest.raises(KinematicsError, match="cartesian"):
        Retargeter(mode="joint", robot=load_robot("ur5", geometry=False))


def test_a_lowered_hand_is_kept_above_the_table_smoothly():
    from studio.kinematics import HumanArm, Retargeter

    retargeter = Retargeter(robot=load_robot("ur5", geometry=False))
    hanging = np.zeros(7)  # the arm hangs: the scaled hand would be under the robot's base
    z = retargeter.hand_target(hanging)[2, 3]
    assert z >= retargeter.config.floor_height
    raised = np.clip(
        np.array([1.5, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]), HumanArm().lower, HumanArm().upper
    )
    high = retargeter.hand_target(raised)[2, 3]
    assert high > 0.3 and high > z + 0.2


def test_a_pose_near_contact_reads_the_same_every_time_it_is_checked():
    arm = load_robot("kinova")
    rng = np.random.default_rng(11)
    poses = [rng.uniform(arm.hard_lower, arm.hard_upper) for _ in range(60)]
    first = [
        [(c.link_a, c.link_b, round(c.distance, 6)) for c in arm.self_collisions(q)] for q in poses
    ]
    for _ in range(2):
        again = [
            [(c.link_a, c.link_b, round(c.distance, 6)) for c in arm.self_collisions(q)]
            for q in poses
        ]
        assert again == first
    assert any(first)  # some of these poses do collide: the check is not vacuous


def test_the_links_a_joint_can_drive_into_the_table_are_found_and_the_base_is_not():
    panda = load_robot("panda")
    assert panda.table_contacts(panda.home, 0.005) == []  # standing up, well clear
    # the shoulder folded forward and down: the hand and the wrist go below the base's plane
    q = np.array(panda.home, dtype=float)
    q[1], q[3] = 1.7, -1.0
    under = panda.table_contacts(q)
    links = {c.link_a for c in under}
    assert {"panda_hand", "panda_link7"} <= links
    assert "panda_link0" not in links and "panda_link1" not in links  # they stand on it
    assert all(c.link_b == TABLE and c.distance < 0 for c in under)
    assert [c.distance for c in under] == sorted(c.distance for c in under)
    # the margin widens what counts; contacts() holds them with the self-collisions
    assert len(panda.table_contacts(q, 0.3)) >= len(under)
    assert set(panda.contacts(q)) == set(panda.self_collisions(q)) | set(under)
    assert load_robot("puma560").table_contacts(np.zeros(6)) == []  # upright, clear of the floor
