"""Potential-based shaping from demonstrations: how joint-path demonstrations speed up the arm task.

A demonstration replayed once teaches little to a linear learner whose features tile each joint
alone: a demonstrated "joint j up" raises that action's weights in every joint's tiles, also far
from the demonstration (the package README measures it). So besides being replayed, the
demonstrations define a shaping potential over joint space (Brys et al., IJCAI 2015, shaping from
demonstrations; Ng, Harada & Russell 1999 for why a potential leaves the optimal policies alone):

    phi(s) = -weight x min_i (kappa x |s - p_i|_1 / step + togo_i)

over the states ``p_i`` the demonstrations' walks visit (one joint step at a time), ``togo_i`` being
the demonstrated steps left from ``p_i`` to the goal. It is computed in joint space, not through
the tiles, so it says the same thing wherever the tiles generalise. Every transition's reward
gains ``phi(s') - phi(s)``, in the replayed demonstrations, the agent's own episodes and the model
the planners replay alike.

Why ``phi(s') - phi(s)`` and not Ng's ``gamma phi(s') - phi(s)``: the same form as the task's own
shaping (:data:`studio.learning.DEFAULT_SHAPING`, which says why). With ``gamma = 0.95`` and a potential of
hundreds of steps, Ng's form pays ``(1 - gamma) x weight x distance`` (+75 a step six joints
away) for every step taken far from the goal: measured, every own episode then ran to the cap,
with the default shaping too. Ours charges that amount instead, which only pulls toward the
demonstrated goal; with gamma = 1 the two forms agree and the optimal policies are unchanged.

With ``kappa = 1`` the minimum is reached at a demonstration's last state (the triangle
inequality), so ``phi`` is the joint distance to the nearest demonstrated final pose: the task's
own shaping (:data:`studio.learning.DEFAULT_SHAPING`) with the goal's joint angles read from the
demonstrations instead of given. ``kappa > 1`` makes a valley along the demonstrated paths.
With ``kappa = 1`` only the demonstrations' last states are kept (the potential is the same,
each step costs a few more additions instead of ``M``). What each gave is measured by
``benchmarks/bench_demos.py`` (package README).

Only joint-path demonstrations of the arm task shape; an environment without a compiled twin, or
action-sequence demonstrations, get the empty potential (no points), which changes nothing.
"""

from __future__ import annotations

from collections import namedtuple
from collections.abc import Sequence

import numpy as np
from numba import njit

from .._config import DEMO_SHAPING as DEMO_SHAPING
from ._reach import ArmReach, reach_step

DEMO_KAPPA = 1.0
"""Cost of a step away from the demonstrated states against one along them (see the module)."""
MAX_POINTS_PER_DEMO = 64
"""Demonstrated states kept per demonstration (evenly along its walk, the last always kept)."""

DemoPotential = namedtuple("DemoPotential", "points togo inv_step weight kappa")
"""The potential as arrays a numba kernel accepts: ``points (M, D)`` demonstrated states,
``togo (M,)`` demonstrated steps left from each, ``1 / step``, the weight and kappa.
``M = 0`` is no shaping."""


def no_potential(dims: int) -> DemoPotential:
    """The empty potential: no shaping at all (runs without joint-path demonstrations)."""
    return DemoPotential(np.zeros((0, dims)), np.zeros(0), 1.0, 0.0, DEMO_KAPPA)


def demo_potential(
    reach: ArmReach | None,
    starts: Sequence[np.ndarray | None],
    actions: Sequence[np.ndarray],
    dims: int,
    weight: float = DEMO_SHAPING,
    kappa: float = DEMO_KAPPA,
) -> DemoPotential:
    """The potential of the demonstrations' walks (each a start and its one-joint actions).

    Its weight is the task's :attr:`ArmReach.demo_potential` when set (0: no potential), else
    what the task's own shaping leaves of ``weight`` (``weight - reach.shaping``, at least 0):
    the two potentials are alike, and stacked (10 in all under the default shaping) they
    lowered greedy success (measured, package README).
    """
    if reach is not None and reach.demo_potential is not None:
        weight = reach.demo_potential
    elif reach is not None:
        weight = max(weight - reach.shaping, 0.0)
    if reach is None or not actions or any(s is None for s in starts) or weight == 0.0:
        return no_potential(dims)
    points, togo = [], []
    for start, acts in zip(starts, actions, strict=True):
        states = np.empty((len(acts) + 1, dims))
        state = np.array(start, dtype=np.float64)
        states[0] = state
        for k, a in enumerate(acts):
            reach_step(reach.params, state, int(a))
            states[k + 1] = state
        if (
            kappa == 1.0
        ):  # the minimum is at the last state: keep it alone (same potential, cheaper)
            keep = np.array([len(acts)], np.int64)
        else:
            count = min(MAX_POINTS_PER_DEMO, len(acts) + 1)
            keep = np.unique(np.linspace(0, len(acts), count)).astype(np.int64)
        points.append(states[keep])
        togo.append((len(acts) - keep).astype(np.float64))
    return DemoPotential(
        np.ascontiguousarray(np.concatenate(points)),
        np.concatenate(togo),
        1.0 / reach.step,
        float(weight),
        float(kappa),
    )


@njit(nogil=True, cache=True, inline="always")
def nearest(pot, obs):
    """``(i, min_i (kappa |obs - p_i|_1 / step + togo_i))``: the demonstrated state that sets
    ``phi(obs)`` (the first on ties) and its cost (needs at least one point)."""
    best = np.inf
    at = 0
    for i in range(pot.points.shape[0]):
        d = 0.0
        for j in range(pot.points.shape[1]):  # the joints (a followed task observes more)
            d += abs(obs[j] - pot.points[i, j])
        v = pot.kappa * d * pot.inv_step + pot.togo[i]
        if v < best:
            best = v
            at = i
    return at, best


@njit(nogil=True, cache=True, inline="always")
def potential(pot, obs):
    """``phi(obs)`` (0 for the empty potential)."""
    if pot.points.shape[0] == 0:
        return 0.0
    return -pot.weight * nearest(pot, obs)[1]


@njit(nogil=True, cache=True, inline="always")
def shaped(pot, reward, phi, obs_next):
    """``(reward + phi(s') - phi(s), phi(s'))`` given ``phi = phi(s)``; the reward untouched
    for the empty potential."""
    if pot.points.shape[0] == 0:
        return reward, 0.0
    phi_next = potential(pot, obs_next)
    return reward + (phi_next - phi), phi_next
