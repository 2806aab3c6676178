"""Obstacles in a learning task: boxes in the robot's base frame that no move may touch.

A task (:class:`ArmGrid`, :class:`ArmReach`) holds its boxes (``obstacles``, each a
:class:`studio.kinematics.Obstacle`). A move whose path would bring the robot's collision
geometry into a box does not happen: the arm stays where it is, the step costs the paper's -1
(the goal's +100 cannot be reached by a refused move), and the episode goes on. The check runs
along the whole move, not only at its end (:class:`studio.kinematics.ObstacleGuard`: coal's
distances and conservative advancement, so a move that passes through a box between two free
ends is refused too).

On the grid every move is known beforehand, so the refused ones are found once per grid and
written into its transition table (:func:`blocked_grid_moves`): learning runs as fast as without
obstacles.
"""

from __future__ import annotations

import functools
from typing import TYPE_CHECKING

import numpy as np

from studio.kinematics import KinematicsError

from .._errors import ConfigError

if TYPE_CHECKING:
    from studio.kinematics import Obstacle, ObstacleGuard

# The boxes' geometry (coal, Pinocchio) is imported where a task checks its boxes, not with this
# module: `studio train --help` never loads it.


def task_obstacles(value: object) -> tuple[Obstacle, ...]:
    """A task's boxes, checked, or a ConfigError (field ``obstacles``) naming the bad one."""
    from studio.kinematics import check_obstacles

    try:
        return check_obstacles(value)
    except KinematicsError as err:
        raise ConfigError([str(err)], ["obstacles"]) from None


TABLE_MARGIN_M = 0.01
"""How far (m) a grid keeps every link above the table its robot stands on: more than an
export's contact margin (5 mm), so a learned path passes the export's checks."""


@functools.lru_cache(maxsize=8)
def obstacle_guard(
    robot: str, obstacles: tuple[Obstacle, ...], table: bool = False
) -> ObstacleGuard:
    """The guard of ``robot``'s collision geometry against ``obstacles`` (and, with ``table``,
    the table it stands on, kept :data:`TABLE_MARGIN_M` away); made once per pair; not
    thread-safe: callers on other threads make their own."""
    from studio.kinematics import ObstacleGuard, load_robot

    return ObstacleGuard(load_robot(robot), obstacles, TABLE_MARGIN_M if table else None)


def check_goal_clear(
    robot: str, obstacles: tuple[Obstacle, ...], q_goal: np.ndarray, table: bool = False
) -> None:
    """Refuse a goal pose that touches a box (ConfigError, field ``obstacles``) or, with
    ``table``, comes within :data:`TABLE_MARGIN_M` of the table (field ``goal``)."""
    from studio.kinematics import OBSTACLE_TOUCH_M, TABLE

    touching = obstacle_guard(robot, obstacles, table).contacts(q_goal, OBSTACLE_TOUCH_M)
    if touching and touching[0].link_b == TABLE:
        raise ConfigError(
            [
                f"The goal brings the robot's {touching[0].link_a} within {TABLE_MARGIN_M * 100:.0f} cm of the table it stands on; choose a goal above the table."
            ],
            ["goal"],
        )
    if touching:
        box = int(touching[0].link_b.rpartition("_")[2])
        raise ConfigError(
            [
                f"Obstacle {box} ({obstacles[box - 1].text()}) touches the robot's {touching[0].link_a} at the goal; move or shrink the box, or choose another goal."
            ],
            ["obstacles"],
        )


def blocked_grid_moves(
    robot: str,
    obstacles: tuple[Obstacle, ...],
    poses: np.ndarray,
    next_state: np.ndarray,
    table: bool = False,
) -> tuple[np.ndarray, np.ndarray]:
    """Which of a grid's moves touch its obstacles (or the table), and which states do.

    Args:
        robot: the robot's registry name.
        obstacles: the boxes.
        table: keep every link :data:`TABLE_MARGIN_M` above the table the robot stands on too.
        poses: every state's whole pose ``(S, nq)`` (rad).
        next_state: the transition table without obstacles ``(S, A)``.

    Returns:
        ``(blocked (S, A) bool, colliding (S,) bool)``: a move blocked when its straight
        joint-space path from one bin centre to the next touches a box; a state colliding when
        its pose does (it is no start, and every move into it is blocked).
    """
    from studio.kinematics import OBSTACLE_TOUCH_M

    guard = obstacle_guard(robot, obstacles, table)
    gaps = np.array([guard.distances(q) for q in poses])  # (S, pairs)
    colliding = gaps.min(axis=1) < OBSTACLE_TOUCH_M
    blocked = np.zeros(next_state.shape, np.bool_)
    checked: dict[tuple[int, int], bool] = {}
    for s, a in zip(*np.nonzero(next_state != np.arange(len(poses))[:, None]), strict=True):
        t = int(next_state[s, a])
        key = (min(int(s), t), max(int(s), t))
        hit = checked.get(key)
        if hit is None:
            hit = guard.move_collides(poses[s], poses[t], gaps[s], gaps[t])
            checked[key] = hit
        blocked[s, a] = hit
    return blocked, colliding


def policy_obstacles(policy: object) -> tuple[Obstacle, ...]:
    """The boxes a policy's task holds (a grid policy's grid, a tile-coded policy's task; none
    for a policy whose task holds none)."""
    task = getattr(policy, "grid", None) or getattr(policy, "task", None)
    return tuple(getattr(task, "obstacles", ()))
