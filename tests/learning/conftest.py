"""Small hand-checkable tasks shared by the learning tests."""

from __future__ import annotations

import numpy as np
import pytest

from studio.learning import TabularMDP

GOAL_REWARD = 10.0


def corridor(length: int = 4, actions: int = 1) -> TabularMDP:
    """States 0..length-1 in a row, the last terminal; action 0 steps right, action 1 (if any) left.

    Reward -1 per step, +10 for the step into the terminal state; episodes start at state 0.
    """
    right = np.minimum(np.arange(length) + 1, length - 1)
    left = np.maximum(np.arange(length) - 1, 0)
    next_state = np.stack([right, left][:actions], axis=1)
    reward = np.where(next_state == length - 1, GOAL_REWARD, -1.0)
    terminal = np.arange(length) == length - 1
    return TabularMDP(next_state, reward, terminal, np.array([0]))


@pytest.fixture
def one_way_corridor() -> TabularMDP:
    return corridor(4, actions=1)


@pytest.fixture
def two_way_corridor() -> TabularMDP:
    return corridor(6, actions=2)
