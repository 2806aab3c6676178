"""The teacher: the demonstrations followed, with no learning.

A continuous arm task taught from demonstrations has one action that moves every joint along the
demonstrated paths to the goal (``actions="follow"``, :func:`studio.learning.tasks._follow.follow`).
Pressing it at every step is a controller that needs no learning at all: the baseline a policy
taught from those demonstrations must beat to claim it learned more than to press that button
(``studio evaluate`` puts the two side by side, on the same starts).
"""

from __future__ import annotations

import numpy as np

from .._config import FOLLOW_ACTION_SETS
from ..tasks._reach import ArmReach, reach_step, reach_success


def follows_demonstrations(task: ArmReach) -> bool:
    """Whether ``task`` has the action that follows demonstrated paths (so a teacher)."""
    return task.actions in FOLLOW_ACTION_SETS and bool(task.paths)


def teacher_walk(task: ArmReach, start: np.ndarray, max_steps: int) -> tuple[np.ndarray, bool]:
    """The learned joints' path ``(K + 1, joints)`` of always following the demonstrations from
    ``start``, and whether it reaches the goal within ``max_steps`` steps."""
    params = task.params
    state = np.array(start, dtype=np.float64).reshape(-1)
    follow = task.n_actions - 1  # the follow action is the last
    path = [state.copy()]
    done = bool(reach_success(params, state))
    while not done and len(path) <= max_steps:
        _, done = reach_step(params, state, follow)
        path.append(state.copy())
    return np.array(path), bool(done)
