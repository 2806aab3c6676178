"""A factored action value for actions that move several joints at once.

With one weight column per action (``Q(s, a) = sum_f w[f, a]``), an action that moves several
joints learns only from its own visits: at six joints the 728 moves of ``actions="all"`` each get
1/60 of the data the 12 single-joint moves get, and measured, they learn far worse (package README).
The factored value shares them:

    Q(s, a) = sum_j Q_j(s, a_j),    Q_j(s, c) = sum_f w[f, 3 j + c + 1]

over the joints ``j``, ``a_j`` in {-1, 0, +1} being what action ``a`` does to joint ``j``; each
per-joint term has its own weights. A visit of "joints 1 and 2 up" teaches "joint 1 up", "joint
1 up and joint 3 down" and every other move that shares a component: the ``3 J`` columns replace
the ``n_actions`` (18 instead of 728 at six joints). It is a linear function of the features
``phi(s) x onehot(a_j)``, so the semi-gradient update is the ordinary one, the step divided among
the ``active x J`` weights it touches.

With ``actions="all-follow"`` and demonstrations the last action follows the demonstrated
paths: it moves no joint by a fixed step, so it has no per-joint terms but one column of its own,
``Q(s, follow) = sum_f w[f, 3 J]`` over every active feature (the follow cost's tiles included).
Its update is the ordinary one; a move whose next state's greedy action is the follow action
shares that value equally among its joints' targets. The follow cost's tiles also feed every
joint's term (``Q_j`` reads joint ``j``'s tiles and the cost's, so twice as many weights, and
the learner halves the step), so a joint's term can tell how far along the demonstrations the
arm is (package README: without them greedy success swung between 12% and 85% with the budget).

A factored table is expanded into the ordinary ``(size, n_actions)`` table (:func:`expand`),
``W[f, a] = sum_j w[f, comp[a, j]]``, which gives the same Q: policy files, rollouts and
greedy evaluations read that and need not know how it was learned.

Caching caveat: :mod:`._linear`'s kernels compile these helpers in; after editing this file touch
``_linear.py``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .._config import FACTORED_ACTION_SETS as FACTORED_ACTION_SETS
from .._tiles import TileCoder
from ..tasks._arm import GOAL_REWARD, STEP_REWARD
from ..tasks._demo_shaping import nearest


def action_components(directions: np.ndarray) -> np.ndarray:
    """Each action's weight column per joint: int64 ``(n_actions, J)``, ``3 j + d + 1`` for a
    move ``d`` in {-1, 0, +1} of joint ``j`` (:attr:`._reach.ArmReach.directions`)."""
    d = np.asarray(directions, dtype=np.int64)
    return np.ascontiguousarray(3 * np.arange(d.shape[1])[None, :] + d + 1)


def no_components(n_actions: int) -> np.ndarray:
    """The unfactored learner's components: none (``(n_actions, 0)``)."""
    return np.zeros((n_actions, 0), np.int64)


def expand(weights: np.ndarray, comp: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """The ordinary ``(..., size, n_actions)`` table of factored weights ``(..., size, 3 J)``:
    row ``f``, one of joint ``rows[f]``'s tiles, holds ``w[f, comp[a, rows[f]]]`` for action ``a``.
    Weights with a follow column (``3 J + 1`` columns) add the follow action last, from that
    column; the follow cost's rows (``rows[f] == J``) hold 0 for every other action."""
    joints = comp.shape[1]
    if weights.shape[-1] == 3 * joints:
        columns = comp[:, rows].T  # (size, n_actions): the column each row reads for each action
        shape = (*weights.shape[:-1], comp.shape[0])
        return np.take_along_axis(weights, np.broadcast_to(columns, shape), axis=-1)
    padded = np.concatenate([weights, np.zeros_like(weights[..., :1])], axis=-1)
    unread = np.full((comp.shape[0], 1), 3 * joints + 1)  # the zero column, for the cost's rows
    columns = np.hstack([comp, unread])[:, rows].T
    shape = (*weights.shape[:-1], comp.shape[0])
    moves = np.take_along_axis(padded, np.broadcast_to(columns, shape), axis=-1)
    cost = rows == joints
    moves[..., cost, :] = weights[..., cost, :][..., comp].sum(axis=-1)
    return np.concatenate([moves, weights[..., 3 * joints :]], axis=-1)


def slot_joints(coder: TileCoder, joints: int, follows: bool = False) -> np.ndarray | None:
    """Which joint's term each active feature slot feeds: int64 ``(tilings x groups,)``, or None
    when the features do not tile each of the ``joints`` joints alone in rows of their own (the
    default features of :meth:`._reach.ArmReach.features` do; hashed ones do not): then the
    value is not factored. A task that ``follows`` demonstrated paths also tiles its follow
    cost alone (:func:`..tasks._follow.with_cost_group`): its slots get ``joints``, no joint's."""
    own = [(j,) for j in range(joints)] + ([(joints,)] if follows else [])
    if coder.hashed or sorted(coder.groups) != own:
        return None
    return np.repeat(np.array([g[0] for g in coder.groups], np.int64), coder.coding.tilings)


def row_joints(coder: TileCoder) -> np.ndarray:
    """The joint each weight row belongs to, for features :func:`slot_joints` accepts."""
    per_group = coder.coding.tilings * (coder.coding.tiles + 1)
    return np.repeat(np.array([g[0] for g in coder.groups], np.int64), per_group)


GOAL_SHARE = 0.0
"""How much of the goal's reward (beyond a step's) the joints' terms share."""


def reward_split(reach, goal_share: float | None = None) -> np.ndarray:
    """What :func:`split_reward` reads of the arm task: ``[shaping, 1 / step, the goal's reward
    beyond a step's that no term gets, goal angles...]``."""
    share = GOAL_SHARE if goal_share is None else goal_share
    unshared = (1.0 - share) * (GOAL_REWARD - STEP_REWARD)
    return np.array(
        [reach.shaping, 1.0 / reach.step, unshared, *reach.goal[: reach.joints]], np.float64
    )


@njit(nogil=True, cache=True, inline="always")
def split_reward(split, pot, obs, obs_next, reward, terminal, out):
    """Each joint's share of ``reward`` into ``out``: the joint's own part of the task's shaping
    and of the demonstrations' potential, plus an equal share of the rest (the step cost, the
    goal's reward, the potential's steps-to-go). The shares sum to ``reward``."""
    joints = out.shape[0]
    shaping, inv_step = split[0], split[1]
    total = 0.0
    for j in range(joints):
        goal = split[3 + j]
        r = shaping * (abs(obs[j] - goal) - abs(obs_next[j] - goal)) * inv_step
        out[j] = r
        total += r
    if pot.points.shape[0] > 0:
        i0 = nearest(pot, obs)[0]
        i1 = nearest(pot, obs_next)[0]
        scale = pot.weight * pot.kappa * pot.inv_step
        for j in range(joints):
            r = scale * (abs(obs[j] - pot.points[i0, j]) - abs(obs_next[j] - pot.points[i1, j]))
            out[j] += r
            total += r
    if terminal:
        reward -= split[2]
    rest = (reward - total) / joints
    for j in range(joints):
        out[j] += rest


@njit(nogil=True, cache=True, inline="always")
def column_sums(w, slots, feats, sums):
    """``sums[3 j + c] = Q_j(s, c - 1)``: each joint's slots summed into its three columns; with
    a follow column (``sums`` of ``3 J + 1``), every slot summed into ``sums[3 J]``."""
    moves = sums.shape[0] - sums.shape[0] % 3  # 3 J
    for c in range(sums.shape[0]):
        sums[c] = 0.0
    for i in range(feats.shape[0]):
        f = feats[i]
        base = 3 * slots[i]
        if base < moves:
            for c in range(base, base + 3):
                sums[c] += w[f, c]
        else:  # the follow cost's tiles feed every joint's term
            for c in range(moves):
                sums[c] += w[f, c]
        if moves < sums.shape[0]:
            sums[moves] += w[f, moves]


@njit(nogil=True, cache=True, inline="always")
def factored_values(w, comp, slots, sums, feats, out):
    """``out[a] = Q(s, a)`` of factored weights (the follow action's, after the moves, from its
    own column); leaves the per-joint terms in ``sums``."""
    column_sums(w, slots, feats, sums)
    for a in range(comp.shape[0]):
        v = 0.0
        for j in range(comp.shape[1]):
            v += sums[comp[a, j]]
        out[a] = v
    if out.shape[0] > comp.shape[0]:
        out[comp.shape[0]] = sums[3 * comp.shape[1]]


@njit(nogil=True, cache=True, inline="always")
def factored_add(w, comp, slots, feats, action, changes):
    """Add ``changes[j]`` to each weight of joint ``j``'s term of ``Q(s, action)`` (a move)."""
    for i in range(feats.shape[0]):
        j = slots[i]
        if j < comp.shape[1]:
            w[feats[i], comp[action, j]] += changes[j]
        else:
            for k in range(comp.shape[1]):
                w[feats[i], comp[action, k]] += changes[k]


@njit(nogil=True, cache=True, inline="always")
def follow_add(w, feats, column, change):
    """Add ``change`` to each active weight of the follow action's own ``column``."""
    for i in range(feats.shape[0]):
        w[feats[i], column] += change
