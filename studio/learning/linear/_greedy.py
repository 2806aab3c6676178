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

On a task with obstacles (:func:`steps_around`) the greedy policy **steps around refused
moves**: it takes its best-valued move that neither leaves the arm where it is (a move a box
refuses, or every moved joint at its limit) nor puts it back where it was the step before, found
by trying each move on the task's own deterministic model, best first. Learned values generalise
over many poses, so the best-valued move where a box stands in the way can be one the box
refuses, and a greedy policy that presses it again stays there until the episode's cap (the
teacher does: it follows a demonstration into the box). With ``"all-follow"`` the hand-over is
tried right after the best move, and a handed-over follow action that a box refuses hands the
motion back. Measured (package README, ``benchmarks/bench_obstacles.py --task arm-reach``): on
the six-joint task with a box where the demonstration passes, each joint tiled alone, 77.0% of
held-out starts reached the goal pressing refused moves, 86.5% stepping around them with the
same weights.

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
def _moved(task, params, state, action, last, has_last, trial):
    """Try ``action`` from ``state`` on ``trial`` (a copy): ``(moved, terminal)``, where
    ``moved`` is False when the arm stays where it is (a refused move, or every moved joint at
    its limit) or when ``has_last`` and it goes back to ``last``."""
    trial[:] = state
    _, terminal = task_step(task, params, trial, action)
    moved = not np.array_equal(trial, state) and not (has_last and np.array_equal(trial, last))
    return moved, terminal


@njit(nogil=True, cache=True)
def _greedy_episode(task, params, spec, w, state, max_steps, path, hand_over=-1, around=False):
    """Follow the greedy policy (ties: lowest action) from ``state`` (in place).

    Writes each visited state into ``path`` rows (the start first) and returns the number of
    steps taken, negative (``-steps - 1``) when ``max_steps`` ran out before the goal. With
    ``hand_over`` an action (not -1), a greedy move that leaves the arm where it is or takes it
    back to the state before is replaced by that action, taken from then on (see the module).
    With ``around`` (a task with obstacles, :func:`steps_around`), no move is taken that leaves
    the arm where it is or takes it back to the state before: the best-valued move that does
    neither is (see the module); a handed-over action that the boxes refuse hands back.
    """
    n_actions = w.shape[1]
    obs = np.empty(spec.low.shape[0])
    feats = np.empty(spec.bases.size, np.int64)
    q = np.empty(n_actions)
    last = state.copy()
    trial = state.copy()
    handed = np.bool_(False)  # not the constant: _around would compile again for a literal
    path[0] = state
    for steps in range(max_steps):
        if around:
            terminal, handed = _around(
                task, params, spec, w, state, last, steps > 0, hand_over, handed,
                obs, feats, q, trial,
            )  # fmt: skip
        else:
            best = hand_over
            if not handed:
                observe(task, params, state, obs)
                active_features(spec, obs, feats)
                _q_values(w, feats, q)
                best = 0
                for a in range(1, n_actions):
                    if q[a] > q[best]:
                        best = a
            moved, terminal = _moved(task, params, state, best, last, steps > 0, trial)
            if hand_over >= 0 and not handed and not moved:  # looped: hand over
                handed = True
                _, terminal = _moved(task, params, state, hand_over, last, steps > 0, trial)
        last[:] = state
        state[:] = trial
        if steps + 1 < path.shape[0]:
            path[steps + 1] = state
        if terminal:
            return steps + 1
    return -max_steps - 1


@njit(nogil=True, cache=True)
def _around(task, params, spec, w, state, last, has_last, hand_over, handed, obs, feats, q, trial):
    """The move of a greedy policy that steps around refused moves, from ``state``: whether it
    ends the episode and whether the motion is (still) handed over, its next state left in
    ``trial``.

    A handed-over action goes on while it moves. Else the actions are tried best-valued first
    (ties: lowest), and the first that moves the arm (:func:`_moved`) is taken; when the best
    does not, the hand-over action is tried right after it. When none moves, the best is taken.
    """
    if handed:
        moved, terminal = _moved(task, params, state, hand_over, last, has_last, trial)
        if moved:
            return terminal, True
    observe(task, params, state, obs)
    active_features(spec, obs, feats)
    _q_values(w, feats, q)
    n_actions = q.shape[0]
    tried = np.zeros(n_actions, np.bool_)
    # np.int64, not the constants: the kernels called with them would compile again for literals
    first = np.int64(-1)
    for rank in range(n_actions):
        best = np.int64(-1)
        for a in range(n_actions):
            if not tried[a] and (best < 0 or q[a] > q[best]):
                best = a
        tried[best] = True
        if first < 0:
            first = best
        moved, terminal = _moved(task, params, state, best, last, has_last, trial)
        if moved:
            return terminal, False
        if rank == 0 and hand_over >= 0 and not tried[hand_over]:
            tried[hand_over] = True
            moved, terminal = _moved(task, params, state, hand_over, last, has_last, trial)
            if moved:
                return terminal, True
    trial[:] = state
    _, terminal = task_step(task, params, trial, first)
    return terminal, False


def greedy_rollout(
    task: ArmReach,
    coder: TileCoder,
    weights: np.ndarray,
    start: np.ndarray,
    max_steps: int,
    step_around: bool = True,
) -> tuple[np.ndarray, bool]:
    """The greedy policy's path on the arm task from ``start``: ``(states (K + 1, joints), reached)``.

    Ties go to the lowest action, so a rollout is deterministic; with ``actions="all-follow"``
    it hands over to the follow action where its moves loop (:func:`hand_over_action`); on a
    task with obstacles it steps around refused moves (:func:`steps_around`) unless
    ``step_around`` is False.

    Raises:
        LearningError: features of another observation than ``task``'s.
    """
    check_observed(task, coder)
    state = np.array(start, dtype=np.float64)
    path = np.empty((max_steps + 1, task.joints))
    steps = _greedy_episode(
        np.int64(TASK_REACH), task.params, coder.spec,
        np.ascontiguousarray(weights, np.float64), state, np.int64(max_steps), path,
        np.int64(hand_over_action(task)), step_around and steps_around(task),
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
    step_around: bool = True,
) -> np.ndarray:
    """Per start ``(N, joints)``: whether the greedy policy reaches the goal within ``max_steps``
    (handing over where its moves loop, :func:`hand_over_action`, unless ``hand_over`` is False;
    stepping around refused moves on a task with obstacles, :func:`steps_around`, unless
    ``step_around`` is False).

    Raises:
        LearningError: features of another observation than ``task``'s.
    """
    check_observed(task, coder)
    out = np.zeros(starts.shape[0], np.bool_)
    _success_many(
        task.params, coder.spec, np.ascontiguousarray(weights, np.float64),
        np.ascontiguousarray(starts, np.float64), np.int64(max_steps), out,
        np.int64(hand_over_action(task) if hand_over else -1), step_around and steps_around(task),
    )  # fmt: skip
    return out


def hand_over_action(task: ArmReach) -> int:
    """The action a greedy rollout on ``task`` hands over to where its moves loop: the follow
    action of ``actions="all-follow"`` with demonstrated paths; else -1 (never)."""
    return task.n_actions - 1 if task.actions == "all-follow" and task.paths else -1


def steps_around(task: ArmReach) -> bool:
    """Whether a greedy rollout on ``task`` steps around refused moves: on a task with
    obstacles (see the module)."""
    return bool(task.obstacles)


@njit(nogil=True, cache=True)
def _success_many(params, spec, w, starts, max_steps, out, hand_over, around):
    path = np.empty((1, starts.shape[1]))
    for i in range(starts.shape[0]):
        state = starts[i].copy()
        # np.int64: the constant itself would compile a second, literal-typed episode kernel
        steps = _greedy_episode(
            np.int64(TASK_REACH), params, spec, w, state, max_steps, path, hand_over, around
        )
        out[i] = steps >= 0
