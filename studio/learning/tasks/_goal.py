"""The arm task's goal given as robot joint angles: one check for the page, the CLI and the scene.

A person states a goal as angles of the robot's joints 1-3 in degrees (the arm grid numbers its
goal in bins). :func:`check_goal_deg` checks those angles against the robot's own joint limits
(the Puma560's by default), and :func:`grid_for_goal` puts them on an
:class:`~studio.learning.ArmGrid`, refusing a goal whose bin centre the robot cannot reach.
Every caller (the run form, ``studio train --goal-deg``, the simulator's "reach" button) goes
through here, so a goal accepted in one place is accepted everywhere.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache

import numpy as np

from .._errors import ConfigError, LearningError
from ._arm import ArmGrid
from ._robot import DEFAULT_GOAL_DEG, PUMA560, default_goal, robot_title, task_arm

GOAL_JOINTS = 3
"""A goal names joints 1-3 of the robot: the paper's task (the Puma560's joints 4-6 rest at 0,
another robot's other joints at its default goal's)."""
DEFAULT_GOAL_JOINTS_DEG: tuple[float, ...] = tuple(DEFAULT_GOAL_DEG[:GOAL_JOINTS])
"""The Puma560's default goal for joints 1-3, degrees (the one default: :data:`DEFAULT_GOAL_DEG`)."""


FORM_GOAL_DECIMALS = 2
"""A goal in degrees is shown to a hundredth of a degree, as a person would type it."""


def default_goal_deg(robot: str = PUMA560) -> tuple[float, ...]:
    """Robot ``robot``'s default goal for joints 1-3 in degrees, as the run form and
    ``--goal-deg`` take a goal: joints 1-3 of :func:`default_goal`, the goal ``studio train
    --robot NAME`` trains towards when given none (the same grid bins; the same reach goal to
    within :data:`FORM_GOAL_DECIMALS`), kept within the robot's limits."""
    lower, upper = robot_limits_deg(robot)
    goal = np.degrees(default_goal(robot)[:GOAL_JOINTS]).round(FORM_GOAL_DECIMALS)
    return tuple(float(v) for v in np.clip(goal, lower, upper))


def goal_pose(goal_deg: Sequence[float] | np.ndarray, robot: str = PUMA560) -> np.ndarray:
    """Robot ``robot``'s whole pose for a goal of its first joints (degrees), radians ``(nq,)``:
    those joints at ``goal_deg``, the others at :func:`default_goal` (the Puma560's wrist at zero).
    The pose a run, the simulator's reach and the scene's goal take for a goal of joints 1-3.

    Raises:
        ConfigError: not three finite angles within the robot's limits (field ``goal_deg``).
    """
    full = default_goal(robot).copy()
    full[:GOAL_JOINTS] = np.radians(check_goal_deg(goal_deg, robot))
    return full


@cache
def robot_limits_deg(robot: str = PUMA560) -> tuple[np.ndarray, np.ndarray]:
    """The robot's joint limits for joints 1-3, degrees ``(lower, upper)``."""
    arm = task_arm(robot)
    return (
        np.degrees(arm.lower[:GOAL_JOINTS]).copy(),
        np.degrees(arm.upper[:GOAL_JOINTS]).copy(),
    )


def goal_problems(goal_deg: object, robot: str = PUMA560) -> list[str]:
    """One sentence per problem with a goal given as joint 1-3 angles in degrees (empty if fine)."""
    try:
        goal = np.asarray(goal_deg, dtype=np.float64)
    except (TypeError, ValueError):
        goal = np.zeros(0)
    if goal.shape != (GOAL_JOINTS,) or not np.all(np.isfinite(goal)):
        return [
            f"goal_deg is {goal_deg!r}; give {GOAL_JOINTS} finite angles in degrees, one per joint 1-{GOAL_JOINTS}."
        ]
    lower, upper = robot_limits_deg(robot)
    title = robot_title(robot)
    return [
        f"goal_deg joint {j + 1} is {goal[j]:g} degrees, which the {title} cannot reach; give an angle from {lower[j]:g} to {upper[j]:g}."
        for j in range(GOAL_JOINTS)
        if not lower[j] <= goal[j] <= upper[j]
    ]


def check_goal_deg(goal_deg: Sequence[float] | np.ndarray, robot: str = PUMA560) -> np.ndarray:
    """A goal for joints 1-3 as a float array in degrees, checked against the robot's limits.

    Raises:
        ConfigError: not three finite angles, or an angle beyond the robot's limits (field
            ``goal_deg``).
    """
    problems = goal_problems(goal_deg, robot)
    if problems:
        raise ConfigError(problems, ["goal_deg"] * len(problems))
    return np.asarray(goal_deg, dtype=np.float64)


def grid_for_goal(
    goal_deg: Sequence[float] | np.ndarray, bins: int = ArmGrid.bins, robot: str = PUMA560
) -> ArmGrid:
    """The 3-joint grid with ``bins`` bins and its goal in the bins nearest ``goal_deg``.

    Args:
        goal_deg: joint 1-3 angles in degrees (checked by :func:`check_goal_deg`).
        bins: bins per joint.
        robot: the robot (the Puma560's grid is the paper's).

    Raises:
        ConfigError: a bad goal or bin count (fields ``goal_deg``, ``bins``), or a goal whose bin
            centre lies beyond the robot's limits (so a rollout could never show it).
    """
    goal = check_goal_deg(goal_deg, robot)
    try:
        grid0 = ArmGrid(joints=GOAL_JOINTS, bins=bins, robot=robot)
    except LearningError as err:
        raise ConfigError([str(err)], ["bins"]) from None
    grid = ArmGrid(
        joints=GOAL_JOINTS,
        bins=bins,
        goal=tuple(int(b) for b in grid0.bins_of_angles(np.radians(goal))),
        robot=robot,
    )
    centre = np.degrees(grid.angles_of(grid.goal_state))
    lower, upper = robot_limits_deg(robot)
    title = robot_title(robot)
    problems = [
        f"goal_deg joint {j + 1} falls in the bin centred at {centre[j]:.1f} degrees, beyond the {title}'s limit of {upper[j] if centre[j] > 0 else lower[j]:g}; choose a goal nearer the middle of the range or another number of bins."
        for j in range(GOAL_JOINTS)
        if not lower[j] <= centre[j] <= upper[j]
    ]
    if problems:
        raise ConfigError(problems, ["goal_deg"] * len(problems))
    return grid
