"""Which robot a task learns on: the one place the learning tasks meet the robot registry.

A task (:class:`ArmReach`, :class:`ArmGrid`) names its robot by the registry's name
(``studio.kinematics.robot_names``; the Puma560, the paper's, by default). From the name come the
arm's joints, limits and forward kinematics (:func:`task_arm`), its default goal
(:func:`default_goal`), and the check that a policy is played on its own robot
(:func:`check_policy_robot`). A file written before tasks named a robot is the Puma560's.
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

import numpy as np

from studio.kinematics import DEFAULT_ROBOT, KinematicsError, robot_spec

from .._errors import ConfigError, LearningError

if TYPE_CHECKING:
    from studio.kinematics import RobotArm

PUMA560 = DEFAULT_ROBOT
"""The paper's robot, and the robot of every task or file that names none."""
DEFAULT_GOAL_DEG: tuple[float, ...] = tuple(robot_spec(DEFAULT_ROBOT).ready)
"""The default robot's default goal, degrees: its registry's ``ready`` pose (the Puma560's is the
paper's goal: joints 1-3 at (0, 45, -90), an arm reaching forward and down, the wrist at 0)."""


def check_robot(name: object) -> str:
    """``name`` if the registry offers it, else a ConfigError (field ``robot``) listing them."""
    try:
        return robot_spec(name).name
    except KinematicsError as err:
        raise ConfigError([str(err)], ["robot"]) from None


@functools.cache
def task_arm(name: str) -> RobotArm:
    """The robot ``name``'s arm without meshes (limits, forward kinematics), loaded once.

    Raises:
        ConfigError: an unknown robot, or one whose model cannot be built (field ``robot``).
    """
    from studio.kinematics import load_robot  # Pinocchio: only once a task needs the arm

    check_robot(name)
    try:
        return load_robot(name, geometry=False)
    except KinematicsError as err:
        raise ConfigError([str(err)], ["robot"]) from None


def robot_title(name: str) -> str:
    """The name people read (``Franka Emika Panda``) for a registry name."""
    return robot_spec(name).title


def default_goal(name: str) -> np.ndarray:
    """The default goal of robot ``name``'s tasks, radians ``(nq,)``.

    Its registry's ``ready`` pose where it names one (the Puma560's is the paper's goal,
    :data:`DEFAULT_GOAL_DEG`; the UR arms': their ``home`` is the arm stretched out level, where a
    degree of the shoulder moves the tool furthest), else its ``home``: the maker's ready pose
    where the SRDF gives one (the Panda's), else zero where the limits allow.
    """
    arm = task_arm(name)
    if arm.spec.ready:
        return np.radians(np.asarray(arm.spec.ready, dtype=np.float64))
    return np.array(arm.home, dtype=np.float64)


def check_policy_robot(
    policy_robot: str, robot: str, what: str = "This policy", fix: str | None = None
) -> None:
    """Refuse to play a policy of ``policy_robot`` on ``robot``, in one sentence naming both.

    Args:
        policy_robot: the robot the policy was learnt on (its file names it).
        robot: the robot asked for.
        what: how the sentence names the policy.
        fix: what to do instead (default: choose the policy's robot, or train on this one).

    Raises:
        LearningError: the robots differ.
    """
    if policy_robot != robot:
        fix = fix or f"choose the {policy_robot} to play it, or train a policy on the {robot}"
        raise LearningError(
            f"{what} was learnt on the {robot_title(policy_robot)} and drives only that robot, "
            f"not the {robot_title(robot)}; {fix}."
        )
