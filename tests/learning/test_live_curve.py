"""LiveCurve: the curve of a filling steps array, recomputed only where episodes finished."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from studio.learning import LiveCurve, curve_statistics


def fill_in_turns(rng: np.random.Generator, experiments: int, episodes: int, turns: int):
    """A steps array filled as a run fills it: each experiment finishes its episodes in order,
    experiments at different paces; yields the array after each turn."""
    steps = np.full((experiments, episodes), -1, np.int64)
    done = np.zeros(experiments, np.int64)
    for _ in range(turns):
        for e in range(experiments):
            more = int(rng.integers(0, 4))
            upto = min(episodes, done[e] + more)
            steps[e, done[e] : upto] = rng.integers(1, 5000, upto - done[e])
            done[e] = upto
        yield steps


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    experiments=st.integers(1, 6),
    episodes=st.integers(1, 40),
)
def test_the_live_curve_is_always_the_curve_of_the_steps(seed, experiments, episodes):
    rng = np.random.default_rng(seed)
    live = LiveCurve(episodes)
    assert live.curve() == curve_statistics(np.full((experiments, episodes), -1))
    seen = live.version
    copy: dict[str, list] = {key: [] for key in curve_statistics(np.zeros((1, 1)))}
    copy["episodes"] = []
    for steps in fill_in_turns(rng, experiments, episodes, 12):
        live.update(steps)
        expected = curve_statistics(steps)
        assert live.curve() == expected
        assert live.episodes_done == int((steps >= 0).sum())
        assert live.curve(2, 5) == {k: v[2:5] for k, v in expected.items()}
        # a reader that applies the changed spans to its copy holds the same curve
        for start, stop in live.changed_since(seen):
            piece = live.curve(start, stop)
            for key in copy:
                while len(copy[key]) < start:
                    copy[key].append(len(copy[key]) + 1 if key == "episodes" else 0)
                copy[key][start:stop] = piece[key]
        seen = live.version
        last = len(expected["episodes"])
        assert {k: v[:last] for k, v in copy.items()} == expected


def test_far_apart_experiments_change_two_small_spans():
    episodes = 20_000
    steps = np.full((3, episodes), -1, np.int64)
    steps[0] = 10  # experiment 0 finished every episode
    steps[1, :15_000] = 12  # experiment 1 is three quarters through
    live = LiveCurve(episodes)
    live.update(steps)
    seen = live.version
    steps[1, 15_000:15_010] = 9  # a moment later: experiment 1 moved on, experiment 2 started
    steps[2, :7] = 30
    live.update(steps)
    assert live.changed_since(seen) == [(0, 7), (15_000, 15_010)]
    assert live.curve() == curve_statistics(steps)
