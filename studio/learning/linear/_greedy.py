"""The greedy policy of tile-coded weights on the arm task: rollouts and success from many starts.

With ``actions="all-follow"`` and demonstrations (:func:`hand_over_action`) the greedy policy
hands the motion over to the follow action when its learned values loop: a greedy move that
would leave the arm where it is (a joint at its limit) or put it back where it was the step
before is replaced by the follow action, which then moves the arm for the rest of the way (the
teacher from there on). On a deterministic task that
pays for every step no optimal policy returns to a state it left, and per-joint (factored)
values cannot always tell such a two-step loop from progress near the goal, where the joints'
best moves depend on one another (measured, package README: without the hand-over the greedy
policy reached the goal from 85-100% of held-out starts, depending on the budget).

Caching caveat: numba's disk cache of these kernels is keyed on this file alone, yet they compile
in the arm task's dynamics (``tasks/``), ``_env.py``, ``_tiles.py`` and ``_common_value.py``;
after editing one, touch this file.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .._tiles import TileCoder, active_features
from ..tasks._follow import check_observed
from ..tasks._reach import ArmReach
from ._common_value import q_values as _q_values
from ._env import TASK_REACH, observe, task_step


@njit(nogil=True, cache=True)
def _greedy_episode(task, params, spec, w, state, max_steps, path, hand_over=-1):
    """Follow the greedy policy (ties: lowest action) from ``state`` (in place).

    Writes each visited state into ``path`` rows (the start first) and returns the number of
    steps taken, negative (``-steps - 1``) when ``max_steps`` ran out before the goal. With
    ``hand_over`` an action (not -1), a greedy move that leaves the arm where it is or takes it
    back to the state before is replaced by that action, taken from then on (see the module).
    """
    n_actions = w.shape[1]
    obs = np.empty(spec.low.shape[0])
    feats = np.empty(spec.bases.size, np.int64)
    q = np.empty(n_actions)
    before = state.copy()
    last = state.copy()
    handed = False
    path[0] = state
    for steps in range(max_steps):
        best = hand_over
        if not handed:
            observe(task, params, state, obs)
            active_features(spec, obs, feats)
            _q_values(w, feats, q)
            best = 0
            for a in range(1, n_actions):
                if q[a] > q[best]:
                    best = a
        before[:] = state
        _, terminal = task_step(task, params, state, best)
        looped = np.array_equal(state, before) or (steps > 0 and np.array_equal(state, last))
        if hand_over >= 0 and not handed and looped:
            handed = True
            state[:] = before
            _, terminal = task_step(task, params, state, hand_over)
        last[:] = before
        if steps + 1 < path.shape[0]:
            path[steps + 1] = state
        if terminal:
            return steps + 1
    return -max_steps - 1


def greedy_rollout(
    task: ArmReach, coder: TileCoder, weights: np.ndarray, start: np.ndarray, max_steps: int
) -> tuple[np.ndarray, bool]:
    """The greedy policy's path on the arm task from ``start``: ``(states (K + 1, joints), reached)``.

    Ties go to the lowest action, so a rollout is deterministic; with ``actions="all-follow"``
    it hands over to the follow action where its moves loop (:func:`hand_over_action`).

    Raises:
        LearningError: features of another observation than ``task``'s.
    """
    check_observed(task, coder)
    state = np.array(start, dtype=np.float64)
    path = np.empty((max_steps + 1, task.joints))
    steps = _greedy_episode(
        np.int64(TASK_REACH), task.params, coder.spec,
        np.ascontiguousarray(weights, np.float64), state, np.int64(max_steps), path,
        np.int64(hand_over_action(task)),
    )  # fmt: skip
    reached = steps >= 0
    taken = steps if reached else -steps - 1
    return path[: taken + 1].copy(), reached


def greedy_success(
    task: ArmReach,
    coder: TileCoder,
    weights: np.ndarray,
    starts: np.ndarray,
    max_steps: int,
    hand_over: bool = True,
) -> np.ndarray:
    """Per start ``(N, joints)``: whether the greedy policy reaches the goal within ``max_steps``
    (handing over where its moves loop, :func:`hand_over_action`, unless ``hand_over`` is False).

    Raises:
        LearningError: features of another observation than ``task``'s.
    """
    check_observed(task, coder)
    out = np.zeros(starts.shape[0], np.bool_)
    _success_many(
        task.params, coder.spec, np.ascontiguousarray(weights, np.float64),
        np.ascontiguousarray(starts, np.float64), np.int64(max_steps), out,
        np.int64(hand_over_action(task) if hand_over else -1),
    )  # fmt: skip
    return out


def hand_over_action(task: ArmReach) -> int:
    """The action a greedy rollout on ``task`` hands over to where its moves loop: the follow
    action of ``actions="all-follow"`` with demonstrated paths; else -1 (never)."""
    return task.n_actions - 1 if task.actions == "all-follow" and task.paths else -1


@njit(nogil=True, cache=True)
def _success_many(params, spec, w, starts, max_steps, out, hand_over):
    path = np.empty((1, starts.shape[1]))
    for i in range(starts.shape[0]):
        state = starts[i].copy()
        steps = _greedy_episode(TASK_REACH, params, spec, w, state, max_steps, path, hand_over)
        out[i] = steps >= 0
