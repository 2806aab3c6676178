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
obstacles. The continuous task's moves are checked as they are taken, inside the compiled
kernel, which cannot call coal: against spheres that hold every link's collision geometry
(:func:`studio.kinematics.sphere_cover`), swept along the move (:func:`move_blocked`), a
superset of the robot, so what they let through is clear by coal too.
"""

from __future__ import annotations

import functools
import math
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from studio.kinematics import KinematicsError

from .._errors import ConfigError
from ._chain import chain_frames
from ._reach_layout import _BOX, _FRAMES_N, _N_BOXES, _N_SPHERES, _OBST, _SPHERE, _SWEEP

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


# ------------------------------------------------------------- the continuous task's compiled check


@functools.lru_cache(maxsize=8)
def _spheres(robot: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from studio.kinematics import load_robot, sphere_cover

    return sphere_cover(load_robot(robot))


def obstacle_values(robot: str, obstacles: tuple[Obstacle, ...], frames: int) -> np.ndarray:
    """The boxes, then the spheres holding ``robot``'s links (:func:`studio.kinematics.sphere_cover`),
    as the continuous task's parameter array keeps them (:data:`._reach_layout._BOX`,
    :data:`._reach_layout._SPHERE`); the spheres of joints beyond the first ``frames`` are left
    out (the compiled chain does not reach them)."""
    if not obstacles:
        return np.zeros(0)
    joint, centre, radius = _spheres(robot)
    kept = joint <= frames
    boxes = np.array([[*box.centre, *(0.5 * np.asarray(box.size))] for box in obstacles])
    spheres = np.column_stack([joint[kept], centre[kept], radius[kept]])
    return np.concatenate([boxes.reshape(-1), spheres.reshape(-1)])


def sphere_count(robot: str, frames: int) -> int:
    """How many spheres :func:`obstacle_values` keeps."""
    return int(np.count_nonzero(_spheres(robot)[0] <= frames))


def sweep_bound(robot: str, translations: np.ndarray) -> float:
    """A bound on any sphere point's distance from any joint axis (m): the chain's link lengths
    and the largest sphere's reach from its joint."""
    joint, centre, radius = _spheres(robot)
    reach = float(np.max(np.linalg.norm(centre, axis=1) + radius)) if len(radius) else 0.0
    return float(np.linalg.norm(translations, axis=1).sum()) + reach


@njit(nogil=True, cache=True)
def _box_distance(params, box, x, y, z):
    """Distance (m) from a point to box ``box`` (0 inside)."""
    base = int(params[_OBST]) + _BOX * box
    gx = max(abs(x - params[base]) - params[base + 3], 0.0)
    gy = max(abs(y - params[base + 1]) - params[base + 4], 0.0)
    gz = max(abs(z - params[base + 2]) - params[base + 5], 0.0)
    return math.sqrt(gx * gx + gy * gy + gz * gz)


@njit(nogil=True, cache=True)
def move_blocked(params, start, end):
    """Whether moving the learned joints from ``start`` to ``end`` (every joint at a constant
    rate) would bring a sphere holding a link into a box.

    Each sphere's centre moves from ``c0`` to ``c1``; its path stays within
    ``sweep * (sum |dq|)**2 / 8`` of that chord (the sagitta of the turns, with ``sweep`` a
    bound on its distance from every axis), so spheres along the chord no more than their radius
    apart, each grown to cover the gaps between them and by that sagitta, hold every place the
    sphere passes. A superset: a move this finds clear is clear.
    """
    boxes = int(params[_N_BOXES])
    if boxes == 0:
        return False
    n = int(params[_FRAMES_N])
    scratch = np.empty((4, 4))
    rotation = np.empty(12)
    before = np.empty((n, 4, 4))
    after = np.empty((n, 4, 4))
    chain_frames(params, start, scratch, rotation, before)
    chain_frames(params, end, scratch, rotation, after)
    turn = 0.0
    for j in range(start.shape[0]):
        turn += abs(end[j] - start[j])
    sagitta = params[_SWEEP] * turn * turn / 8.0
    first = int(params[_OBST]) + _BOX * boxes
    for k in range(int(params[_N_SPHERES])):
        base = first + _SPHERE * k
        joint = int(params[base]) - 1
        lx, ly, lz = params[base + 1], params[base + 2], params[base + 3]
        m0, m1 = before[joint], after[joint]
        x0 = m0[0, 0] * lx + m0[0, 1] * ly + m0[0, 2] * lz + m0[0, 3]
        y0 = m0[1, 0] * lx + m0[1, 1] * ly + m0[1, 2] * lz + m0[1, 3]
        z0 = m0[2, 0] * lx + m0[2, 1] * ly + m0[2, 2] * lz + m0[2, 3]
        dx = m1[0, 0] * lx + m1[0, 1] * ly + m1[0, 2] * lz + m1[0, 3] - x0
        dy = m1[1, 0] * lx + m1[1, 1] * ly + m1[1, 2] * lz + m1[1, 3] - y0
        dz = m1[2, 0] * lx + m1[2, 1] * ly + m1[2, 2] * lz + m1[2, 3] - z0
        radius = params[base + 4]
        chord = math.sqrt(dx * dx + dy * dy + dz * dz)
        pieces = max(1, math.ceil(chord / radius))
        grown = math.sqrt(radius * radius + (0.5 * chord / pieces) ** 2) + sagitta
        for i in range(pieces + 1):
            u = i / pieces
            for b in range(boxes):
                if _box_distance(params, b, x0 + u * dx, y0 + u * dy, z0 + u * dz) < grown:
                    return True
    return False
