"""A value common to every action, for the arm task that follows demonstrations.

On a task that follows demonstrated paths (``ArmReach(actions="follow")`` with paths, under any
Gymnasium wrappers: ``EnvTask.follows``) the learner writes

    Q(s, a) = C(s) + A_a(s),    C(s) = sum_f w[f, n_actions],    A_a(s) = sum_f w[f, a]

over the active features ``f`` of ``s``: one weight column shared by every action beside each
action's own, the dueling decomposition (Wang et al., ICML 2016) in linear form. Each update
moves ``Q(s, a)`` by the usual ``alpha x TD error``, a quarter of it through the action's own
column and three quarters through the common one (:data:`COMMON_SHARE`).

Why: the follow action moves every joint at once, so under a discounted return its shaping pays
sooner, and every action's value bootstraps on it. Far from the demonstrations the actions are
all worth about 230 (60-80 without demonstrations) and differ by the 10 points between a
single joint's step toward its goal angle (+4) and away (-6). With a column per action, each
action fits that large, non-additive level on its own (per-joint tiles, over the states where it
was taken), and their errors did not cancel: a single joint's estimate stood 10-16 above its own
one-step target, and the greedy policy stepped it to and fro. The common column fits the level
once, for every action, so its error cancels when actions are compared; each action's own
column only fits how it differs. Measured (package README; 20 pairs, no planning): with the
default shaping, demonstrations now change greedy success by +8.4, 0.0 and +0.4 points after
1,000, 2,000 and 4,000 episodes, where with a column per action they cost 5.9 after 4,000 (8
pairs); under the paper's reward the follow default reaches 0.972, 0.992 and 0.995 (0.920
after 4,000 before).

Learned weights leave the learner as the ordinary ``(size, n_actions)`` table
(:func:`without_common`, ``W[f, a] = w[f, a] + w[f, n_actions]``, the same Q), so policy files,
rollouts and the page read them unchanged.

Caching caveat: :mod:`._linear`'s kernels compile these helpers in; after editing this file touch
``_linear.py``.
"""

from __future__ import annotations

import numpy as np
from numba import njit

COMMON_SHARE = 0.25
"""The share of an update that goes to the action's own column (the rest to the common one).
Measured (20 pairs, 2,000 episodes, default shaping, with - without demonstrations): 0.75 -4.4
points, 0.5 -2.4, 0.25 0.0, 0.1 +1.2. 0.1 scores higher still (under the paper's reward 1.000
from 1,000 episodes on), but each action's own column then learns at a tenth of the rate, so
where a single joint beats the demonstrations the policy finds it that much later; 0.25 meets
every goal with margin."""


@njit(nogil=True, cache=True, inline="always")
def add_common(w, feats, out):
    """Add the common value to every action's ``out[a]`` (nothing when ``w`` has no common
    column, ``out.shape[0]`` columns)."""
    n_actions = out.shape[0]
    if w.shape[1] > n_actions:
        common = 0.0
        for i in range(feats.shape[0]):
            common += w[feats[i], n_actions]
        for a in range(n_actions):
            out[a] += common


@njit(nogil=True, cache=True, inline="always")
def update_common(w, feats, n_actions, change):
    """Move the common column by its share of ``change`` (the update of the action's value);
    returns what the action's own column moves by (all of ``change`` without a common column)."""
    if w.shape[1] == n_actions:
        return change
    change *= COMMON_SHARE
    for i in range(feats.shape[0]):
        w[feats[i], n_actions] += change * (1.0 / COMMON_SHARE - 1.0)
    return change


@njit(nogil=True, cache=True, inline="always")
def q_values(w, feats, out):
    """``out[a] = Q(s, a)``: the active features' weights summed in feature order."""
    n_actions = out.shape[0]
    for a in range(n_actions):
        out[a] = 0.0
    for i in range(feats.shape[0]):
        f = feats[i]
        for a in range(n_actions):
            out[a] += w[f, a]
    add_common(w, feats, out)


def without_common(weights: np.ndarray) -> np.ndarray:
    """The ordinary ``(..., size, n_actions)`` table of weights with a common last column."""
    return weights[..., :-1] + weights[..., -1:]
