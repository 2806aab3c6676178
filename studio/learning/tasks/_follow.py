"""The arm task's follow action: every joint at once, along the demonstrated paths to the goal.

``ArmReach(actions="follow")`` keeps its demonstrations as paths (:func:`checked_paths`), writes
their points into the parameter array (:func:`followed_points`, layout in :mod:`._reach_layout`),
and :func:`._reach.reach_step` moves by :func:`follow` when the follow action is taken.

The follow action's worth is a function of how far following has to go, not of each joint
alone, so a task that follows paths also observes that: its observation is the joints and then
the follow cost (:func:`follow_cost`, between 0 and :func:`cost_bound`), tiled on its own
(:func:`with_cost_group`). Per-joint tiles alone fit the follow action's value poorly under the
default shaping (a step there pays anything from -31 to +29): measured, 3 demonstrations then
lowered greedy success from random starts by 14.8 points after 1,000 episodes; with the cost
observed they do not lower it (package README).

Its compiled functions read the parameter array by the offsets of :mod:`._reach_layout`, which
numba bakes in: numba's disk cache is keyed on this file alone, so touch it when the layout moves.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING, Protocol

import numpy as np
from numba import njit

from .._config import FOLLOW_ACTION_SETS
from .._errors import ConfigError, LearningError
from .._tiles import TileCoding
from ._reach_layout import _COUNTS, _LOWER, _POINT, _STEP, _TABLE, _UPPER, MAX_JOINTS

if TYPE_CHECKING:
    from .._tiles import TileCoder


class ObservedTask(Protocol):
    """What :func:`check_observed` reads of a task (an :class:`._reach.ArmReach`, which imports
    this module: named by what it offers, so the two do not depend on each other)."""

    @property
    def joints(self) -> int: ...

    @property
    def observation_bounds(self) -> tuple[np.ndarray, np.ndarray]: ...


FOLLOW_KAPPA = 2.0
"""How much more a radian off the demonstrated paths costs the follow action than a radian along
them (:func:`follow`): joining a path is worth it where the path from there is shorter than
twice the way straight to its end. With 1 the cheapest point is always a path's end (no path is
shorter than the straight line), and the action would head straight for the goal's joints."""
FOLLOW_LENGTH_STEPS = 2.0
"""A followed path's length is measured along its samples this many steps apart
(:func:`_path_left`)."""
FOLLOW_SPACING_STEPS = 0.25
"""A followed path keeps a demonstration's samples this many steps apart (max-norm over the
joints), and always its last: closer samples add search work and no shape."""


def checked_paths(
    paths: Sequence[object] | None,
    actions: str,
    joints: int,
    lower: np.ndarray,
    upper: np.ndarray,
    step: float,
) -> tuple[tuple[tuple[float, ...], ...], ...]:
    """:attr:`._reach.ArmReach.paths` as the task keeps them: each ``(N, joints)`` path clipped
    to the limits, its samples :data:`FOLLOW_SPACING_STEPS` apart.

    Raises:
        ConfigError: paths with an action set that does not follow (:data:`FOLLOW_ACTION_SETS`), a path of the wrong shape,
            or one holding NaN.
    """
    if paths is None or len(paths) == 0:  # (an array of paths has no single truth value)
        return ()
    if actions not in FOLLOW_ACTION_SETS:
        raise ConfigError(
            [
                f'paths are given with actions={actions!r}; give actions="follow" or "all-follow" to follow them, or no paths.'
            ],
            ["paths"],
        )
    checked = []
    for i, path in enumerate(paths):
        try:
            q = np.asarray(path, dtype=np.float64)
        except (TypeError, ValueError):
            q = np.zeros((0, 0))
        if q.ndim != 2 or q.shape[0] < 1 or q.shape[1] < joints:
            raise ConfigError(
                [f"Path {i} has shape {q.shape}; give (N, {joints}) joint angles in radians."],
                ["paths"],
            )
        if not np.all(np.isfinite(q)):
            raise ConfigError(
                [f"Path {i} holds NaN or infinite angles; re-record that demonstration."],
                ["paths"],
            )
        q = np.clip(q[:, :joints], lower, upper)
        kept = q[_spaced(q, FOLLOW_SPACING_STEPS * step)]
        checked.append(tuple(tuple(float(x) for x in row) for row in kept))
    return tuple(checked)


def followed_points(
    paths: Sequence[Sequence[Sequence[float]]], joints: int, step: float
) -> np.ndarray:
    """Every followed point: ``(M, joints + 2)``, its joints, the index of its path's last
    point, and the length of the path from it to that end (rad, Euclidean; :func:`_path_left`)."""
    rows = []
    for path in paths:
        q = np.asarray(path, dtype=np.float64)
        end = len(rows) + len(q) - 1
        rows += [(*row, end, rest) for row, rest in zip(q, _path_left(q, step), strict=True)]
    return np.asarray(rows, dtype=np.float64).reshape(-1, joints + 2)


def cost_bound(lower: np.ndarray, upper: np.ndarray, points: np.ndarray) -> float:
    """An upper bound on :func:`follow_cost` within the joint limits ``lower``..``upper`` for
    the followed ``points`` (:func:`followed_points`): the observation space's."""
    longest = float(points[:, -1].max()) if len(points) else 0.0
    return FOLLOW_KAPPA * float(np.linalg.norm(np.asarray(upper) - np.asarray(lower))) + longest


def with_cost_group(coding: TileCoding, joints: int) -> TileCoding:
    """``coding`` for a task that follows paths: its observation's last dimension, the follow
    cost (index ``joints``), gets a group of its own where ``coding``'s groups leave it out (one
    group of every dimension, the default, already holds it)."""
    groups = coding.groups
    if groups is None or any(joints in group for group in groups):
        return coding
    return dataclasses.replace(coding, groups=(*groups, (joints,)))


def check_observed(task: ObservedTask, coder: TileCoder) -> None:
    """Refuse features bound to another observation than ``task``'s: its joints, and with
    followed paths the follow cost after them. A follow policy written before the cost was
    observed has joint features only: it rolls out as trained.

    Raises:
        LearningError: one sentence naming both counts and the fix.
    """
    features, observed = int(coder.spec.low.shape[0]), len(task.observation_bounds[0])
    if features not in (task.joints, observed):
        raise LearningError(
            f"The features observe {features} values but the task {observed}; roll the weights out on the task they were learned on (the run's result.task)."
        )


def _path_left(q: np.ndarray, step: float) -> np.ndarray:
    """Per sample of the path ``q``, the length of the path from it to its end (rad, Euclidean),
    measured along the samples :data:`FOLLOW_LENGTH_STEPS` steps apart: along every sample, a
    recorded wrist's jitter would count as path (sample 1: 2.1 rad against 1.15 measured so,
    and 0.93 straight)."""
    coarse = _spaced(q, FOLLOW_LENGTH_STEPS * step)
    lengths = np.linalg.norm(np.diff(q[coarse], axis=0), axis=1)
    coarse_left = np.append(np.cumsum(lengths[::-1])[::-1], 0.0)
    after = np.minimum(np.searchsorted(coarse, np.arange(len(q))), len(coarse) - 1)
    return np.linalg.norm(q[coarse[after]] - q, axis=1) + coarse_left[after]


def _spaced(q: np.ndarray, spacing: float) -> np.ndarray:
    """The indices of the rows of ``q`` at least ``spacing`` apart (max-norm) from the last
    kept, and the last's."""
    kept = [0]
    for i in range(1, len(q)):
        if np.abs(q[i] - q[kept[-1]]).max() >= spacing:
            kept.append(i)
    if kept[-1] != len(q) - 1:
        kept.append(len(q) - 1)
    return np.asarray(kept)


@njit(nogil=True, cache=True)
def max_gap(params, row, state):
    """The largest joint distance (rad) from ``state`` to the followed point at ``row``."""
    gap = 0.0
    for j in range(state.shape[0]):
        gap = max(gap, abs(params[row + j] - state[j]))
    return gap


@njit(nogil=True, cache=True)
def follow_cost(params, state):
    """``(i, cost)``: the followed point ``i`` with the least :data:`FOLLOW_KAPPA` x (Euclidean
    distance from ``state``) + (path from it to its end), and that cost (rad). The first point
    on ties; ``(0, inf)`` without points."""
    base = _TABLE + MAX_JOINTS * int(params[_COUNTS])
    best, cheapest = 0, np.inf
    for i in range(int(params[_COUNTS + 1])):
        row = base + _POINT * i
        d = 0.0
        for j in range(state.shape[0]):
            diff = params[row + j] - state[j]
            d += diff * diff
        cost = FOLLOW_KAPPA * math.sqrt(d) + params[row + MAX_JOINTS + 1]
        if cost < cheapest:
            cheapest, best = cost, i
    return best, cheapest


@njit(nogil=True, cache=True)
def follow(params, state):
    """The follow action: ``state`` (in place) moves every joint at once, by at most one step
    (max-norm), along the demonstrated paths to their end. It heads for the followed point with
    the least :data:`FOLLOW_KAPPA` x (Euclidean distance to it) + (path from it to its end): off
    the paths it cuts to the point where joining one costs least, and within a step of that
    point it moves on toward the first point a step ahead on its path (pure pursuit). That cost
    falls with every move, so no sequence of follow moves returns where it was; at a path's end
    it stays."""
    base = _TABLE + MAX_JOINTS * int(params[_COUNTS])
    joints = state.shape[0]
    best = follow_cost(params, state)[0]
    step = params[_STEP]
    end = int(params[base + _POINT * best + MAX_JOINTS])
    target = best
    while target < end and max_gap(params, base + _POINT * target, state) < step:
        target += 1
    row = base + _POINT * target
    gap = max_gap(params, row, state)
    scale = 1.0 if gap <= step else step / gap
    for j in range(joints):
        moved = state[j] + scale * (params[row + j] - state[j])
        if params[_LOWER + j] <= moved <= params[_UPPER + j]:
            state[j] = moved
