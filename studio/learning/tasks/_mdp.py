"""Finite deterministic MDPs as plain tables.

A :class:`TabularMDP` is the only thing the Dyna-Q kernels know about a task: where each action
leads, what it pays, which states end an episode and where episodes may start. The arm grid is one
such table (:mod:`._arm`); tests build tiny corridors by hand.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._errors import LearningError


@dataclass(frozen=True, eq=False)
class TabularMDP:
    """A finite deterministic MDP.

    Args:
        next_state: int array ``(S, A)``; ``next_state[s, a]`` is where action ``a`` leads from ``s``.
        reward: float array ``(S, A)``; the reward of taking ``a`` in ``s``.
        terminal: bool array ``(S,)``; an episode ends on entering a terminal state.
        start_states: int array of the states an episode may start from, drawn uniformly.
        intended: int array ``(S, A)`` or None: where each action would lead if nothing stood in
            its way (a grid's moves without its obstacles). A demonstration is a path of these
            moves: its replay tries each, and one that ``next_state`` refuses leaves the agent
            where it is. None: ``next_state``.

    The arrays are copied into C-contiguous ``int64`` / ``float64`` / ``bool`` arrays and made
    read-only, so one MDP can be shared by many threads.
    """

    next_state: np.ndarray
    reward: np.ndarray
    terminal: np.ndarray
    start_states: np.ndarray
    intended: np.ndarray | None = None

    def __post_init__(self) -> None:
        next_state = np.asarray(self.next_state)
        reward = np.asarray(self.reward)
        terminal = np.asarray(self.terminal)
        start_states = np.asarray(self.start_states).reshape(-1)
        if next_state.ndim != 2 or next_state.shape[0] < 1 or next_state.shape[1] < 1:
            raise LearningError(
                f"next_state has shape {next_state.shape}; give a non-empty (states, actions) integer array."
            )
        if not np.issubdtype(next_state.dtype, np.integer):
            raise LearningError(
                f"next_state has dtype {next_state.dtype}; give integer state indices."
            )
        n_states, _ = next_state.shape
        if next_state.min() < 0 or next_state.max() >= n_states:
            raise LearningError(
                f"next_state holds values outside [0, {n_states - 1}]; every entry must be a state index."
            )
        if reward.shape != next_state.shape:
            raise LearningError(
                f"reward has shape {reward.shape} but next_state has {next_state.shape}; give one reward per (state, action)."
            )
        if not np.issubdtype(reward.dtype, np.number) or not np.all(np.isfinite(reward)):
            raise LearningError(
                "reward holds non-numeric, NaN or infinite values; give finite numbers."
            )
        if terminal.shape != (n_states,) or terminal.dtype != np.bool_:
            raise LearningError(
                f"terminal has shape {terminal.shape} and dtype {terminal.dtype}; give a bool array of length {n_states}."
            )
        if start_states.size == 0:
            raise LearningError(
                "start_states is empty; give at least one state an episode may start from."
            )
        if not np.issubdtype(start_states.dtype, np.integer):
            raise LearningError(
                f"start_states has dtype {start_states.dtype}; give integer state indices."
            )
        if start_states.min() < 0 or start_states.max() >= n_states:
            raise LearningError(
                f"start_states holds values outside [0, {n_states - 1}]; every entry must be a state index."
            )
        intended = next_state if self.intended is None else np.asarray(self.intended)
        if intended.shape != next_state.shape or not np.issubdtype(intended.dtype, np.integer):
            raise LearningError(
                f"intended has shape {intended.shape}; give an integer array shaped as next_state."
            )
        for name, value, dtype in (
            ("intended", intended, np.int64),
            ("next_state", next_state, np.int64),
            ("reward", reward, np.float64),
            ("terminal", terminal, np.bool_),
            ("start_states", start_states, np.int64),
        ):
            array = np.ascontiguousarray(value, dtype=dtype).copy()
            array.flags.writeable = False
            object.__setattr__(self, name, array)

    @property
    def n_states(self) -> int:
        """Number of states ``S``."""
        return int(self.next_state.shape[0])

    @property
    def n_actions(self) -> int:
        """Number of actions ``A``."""
        return int(self.next_state.shape[1])

    def action_between(self, state: int, next_state: int) -> int:
        """The action that leads from ``state`` to ``next_state`` (:attr:`intended`: where
        nothing stands in its way), or -1 if none does.

        When several actions connect the two states, the lowest index wins, so a replayed
        demonstration is the same on every run.
        """
        hits = np.flatnonzero(self.intended[state] == next_state)
        return int(hits[0]) if hits.size else -1
