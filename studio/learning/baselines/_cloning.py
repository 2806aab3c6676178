"""Behaviour cloning: toward the demonstrated next state of the nearest demonstrated state.

The simplest learner from demonstrations a researcher puts beside Dyna-Q: supervised learning of
state -> action over the demonstrated samples, with no reward and no exploration. Here the
"network" is one nearest neighbour (Euclidean, in joint space) over the demonstrated samples
(:data:`CLONING_SPACING_STEPS` apart), and its label is the state the demonstration went to next
from that sample (its end, at a demonstration's end): the policy moves toward that state, every
joint at once, by at most one task step (max-norm), as the follow action moves.

Why the next state and not the demonstrated move. Copying the move (the difference between the
sample and the next) moves parallel to the demonstration, so off it the arm ends where the
demonstration's end is offset to, and stops there (the move at a demonstration's end is nil):
measured on ``benchmarks/bench_teacher.py``'s split, that reached the goal from 0% of its 200
held-out starts (the next state: 100%). Labelled by
the next state, an action off the demonstration also closes the gap to it (the labels the
corrective data of DART, Laskey et al. 2017, or DAgger, Ross et al. 2011, would add near it), so
a cloned policy rejoins the demonstration and walks it to its end. It still learns nothing from
reward: it is as fast as the demonstrations it copies, and goes where they went.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numba import njit

from .._errors import LearningError
from ..tasks._reach import ArmReach, reach_success
from ..tasks._reach_layout import _LOWER, _STEP, _UPPER

CLONING_SPACING_STEPS = 1.0
"""Demonstrated samples are kept this many task steps apart (max-norm over the joints), and the
last: the move from each kept sample to the next is at least a step."""


@dataclass(frozen=True, eq=False)
class Cloning:
    """What behaviour cloning learned: each kept demonstrated state and the move made from it.

    Attributes:
        states: demonstrated joint angles ``(M, joints)`` (rad).
        moves: the joint move made from each ``(M, joints)`` (rad; zero at a demonstration's end).
    """

    states: np.ndarray
    moves: np.ndarray


def fit_cloning(task: ArmReach, paths: Sequence[np.ndarray]) -> Cloning:
    """The (state, move) pairs of ``paths`` (joint paths ``(N, joints)`` or wider, rad) on
    ``task``: samples :data:`CLONING_SPACING_STEPS` steps apart, each with the move to the next.

    Raises:
        LearningError: no demonstration, or one of the wrong shape.
    """
    if len(paths) == 0:
        raise LearningError(
            "Behaviour cloning learns from demonstrations; give the run at least one."
        )
    states, moves = [], []
    for i, path in enumerate(paths):
        q = np.asarray(path, dtype=np.float64)
        if q.ndim != 2 or q.shape[1] < task.joints or not np.all(np.isfinite(q)):
            raise LearningError(
                f"Demonstration {i} has shape {q.shape}; give (N, {task.joints}) finite joint angles in radians."
            )
        q = np.clip(q[:, : task.joints], task.lower, task.upper)
        kept = [0]
        for k in range(1, len(q)):
            if np.abs(q[k] - q[kept[-1]]).max() >= CLONING_SPACING_STEPS * task.step:
                kept.append(k)
        if kept[-1] != len(q) - 1:
            kept.append(len(q) - 1)
        kept_q = q[kept]
        states.append(kept_q)
        moves.append(np.vstack([np.diff(kept_q, axis=0), np.zeros((1, task.joints))]))
    return Cloning(np.ascontiguousarray(np.vstack(states)), np.ascontiguousarray(np.vstack(moves)))


@njit(nogil=True, cache=True)
def clone_walk(params, states, moves, state, max_steps, path):
    """The cloned policy from ``state`` (in place): at each step toward the demonstrated next
    state of the nearest demonstrated state (``states + moves``), at most one step (max-norm); a
    joint whose move would leave its limits stays. Writes each visited state into ``path`` rows
    (the start first) and returns the steps taken, negative (``-steps - 1``) when it stops short
    of the goal: ``max_steps`` ran out, or the move is nil (at that next state, or every joint
    at a limit)."""
    joints = state.shape[0]
    step = params[_STEP]
    path[0] = state
    if reach_success(params, state):
        return 0
    for steps in range(max_steps):
        best, nearest = 0, np.inf
        for i in range(states.shape[0]):
            d = 0.0
            for j in range(joints):
                diff = states[i, j] - state[j]
                d += diff * diff
            if d < nearest:
                nearest, best = d, i
        gap = 0.0
        for j in range(joints):
            gap = max(gap, abs(states[best, j] + moves[best, j] - state[j]))
        moved = False
        if gap > 0.0:
            scale = min(1.0, step / gap)
            for j in range(joints):
                q = state[j] + scale * (states[best, j] + moves[best, j] - state[j])
                if params[_LOWER + j] <= q <= params[_UPPER + j] and q != state[j]:
                    state[j] = q
                    moved = True
        if steps + 1 < path.shape[0]:
            path[steps + 1] = state
        if not moved:
            return -steps - 1
        if reach_success(params, state):
            return steps + 1
    return -max_steps - 1


def cloning_rollout(
    task: ArmReach, cloning: Cloning, start: np.ndarray, max_steps: int
) -> tuple[np.ndarray, bool]:
    """The cloned policy's path on ``task`` from ``start``: ``(states (K + 1, joints), reached)``."""
    state = np.array(start, dtype=np.float64).reshape(-1)[: task.joints].copy()
    path = np.empty((max_steps + 1, task.joints))
    steps = clone_walk(task.params, cloning.states, cloning.moves, state, np.int64(max_steps), path)
    reached = steps >= 0
    taken = steps if reached else -steps - 1
    return path[: taken + 1].copy(), bool(reached)
