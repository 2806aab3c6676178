"""``Retargeter.human_reaching``: the operator's arm whose retargeting puts a robot at a pose, the
inverse the simulator uses to reach a goal of any robot."""

from __future__ import annotations

import numpy as np
import pytest

from studio.kinematics import Puma560, Retargeter, load_robot, robot_names

TABLE_ARMS = [n for n in robot_names() if n != "puma560"]


@pytest.mark.parametrize("name", TABLE_ARMS)
@pytest.mark.parametrize("mirror", [True, False])
def test_the_arm_found_puts_the_hands_target_on_the_robots_tool(name: str, mirror: bool) -> None:
    robot = load_robot(name, geometry=False)
    retargeter = Retargeter(robot=robot, mirror=mirror)
    rng = np.random.default_rng(7)
    # robot poses the operator can show: the retargeting of random arm poses
    errors = []
    for _ in range(40):
        if len(errors) == 5:
            break
        q_human = retargeter.arm.lower + rng.uniform(0.2, 0.8, 7) * (
            retargeter.arm.upper - retargeter.arm.lower
        )
        if retargeter._target(q_human)[1] > 0:  # drawn back into reach: not a pose to invert
            continue
        retargeter.reset()  # one pose, not the next frame of a motion (no step limit)
        q_robot = retargeter.robot_from_human(q_human)
        if not retargeter.last_ik.success:
            continue
        found = retargeter.human_reaching(q_robot)
        assert np.all(found >= retargeter.arm.lower) and np.all(found <= retargeter.arm.upper)
        errors.append(
            np.linalg.norm(retargeter.hand_target(found)[:3, 3] - robot.forward(q_robot)[:3, 3])
        )
    assert errors, "no pose to invert"
    assert max(errors) < 0.01, errors  # the hand's target within 1 cm of the tool


def test_joint_mode_is_its_exact_inverse() -> None:
    retargeter = Retargeter(robot=Puma560())
    q_robot = np.radians([20.0, 30.0, -60.0, 0.0, 10.0, 0.0])
    np.testing.assert_allclose(
        retargeter.human_reaching(q_robot), retargeter.human_from_robot(q_robot)
    )
