"""Laws about the kernel's random choices: tie-breaking, start states, and agreement in
distribution with an independent plain-Python Dyna-Q that draws from Python's own generator.

The bit-for-bit test in ``test_dynaq.py`` checks the kernel against a transcription that draws the
kernel's own random numbers the same way, so a bias in how the kernel turns random words into
choices would be copied there; these tests compare against choices made independently.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from studio.learning import ArmGrid, DynaQConfig, TabularMDP, run_experiments

REFERENCE = Path(__file__).resolve().parents[2] / "benchmarks" / "dynaq_reference.py"
MARGIN_SE = 4.0
"""Allowed difference of two means, in standard errors of the difference (fixed seeds: no flakes)."""


def _reference():
    spec = importlib.util.spec_from_file_location("dynaq_reference", REFERENCE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _many(mdp: TabularMDP, config: DynaQConfig, experiments: int, episodes: int, seed: int):
    """Final Q tables of ``experiments`` experiments, in runs of at most 1000."""
    runs = range(0, experiments, 1000)
    return np.concatenate(
        [
            run_experiments(mdp, config, min(1000, experiments - k), episodes, seed=seed + k).q
            for k in runs
        ]
    )


def _binomial_margin(n: int, p: float) -> float:
    return MARGIN_SE * np.sqrt(n * p * (1 - p))


def test_ties_are_broken_uniformly_at_random() -> None:
    # One state, five actions, each ending the episode with its own reward -(a + 1): after an
    # episode Q(0, a) = alpha * -(a + 1) names the action taken. Greedy (epsilon 0) from Q = 0 is a
    # five-way tie; in episode 2 the four untried actions (still 0) tie. Every ordered pair of
    # distinct actions must be equally likely, and no action may be taken twice.
    actions, experiments, alpha = 5, 4000, 0.5
    mdp = TabularMDP(
        np.ones((2, actions), np.int64),
        -np.arange(1.0, actions + 1)[None, :].repeat(2, axis=0),
        np.array([False, True]),
        np.array([0]),
    )
    config = DynaQConfig(epsilon=0.0, alpha=alpha)
    taken_first = np.argmax(_many(mdp, config, experiments, 1, seed=9)[:, 0] != 0, axis=1)
    both = _many(mdp, config, experiments, 2, seed=9)[:, 0] != 0
    assert np.all(both.sum(axis=1) == 2)  # two different actions
    taken_second = np.argmax(both & (np.arange(actions) != taken_first[:, None]), axis=1)
    counts = np.zeros((actions, actions), np.int64)
    np.add.at(counts, (taken_first, taken_second), 1)
    expected = experiments / (actions * (actions - 1))
    off_diagonal = counts[~np.eye(actions, dtype=bool)]
    assert np.all(np.diag(counts) == 0)
    margin = _binomial_margin(experiments, 1 / (actions * (actions - 1)))
    assert np.all(np.abs(off_diagonal - expected) < margin), counts


def test_episodes_start_uniformly_over_the_start_states() -> None:
    # States 0..5 each lead straight to the terminal state 6; only 1..5 are start states. After one
    # episode the single non-zero Q entry names the start.
    starts, experiments = np.arange(1, 6), 5000
    mdp = TabularMDP(np.full((7, 1), 6, np.int64), -np.ones((7, 1)), np.arange(7) == 6, starts)
    started = np.argmax(_many(mdp, DynaQConfig(), experiments, 1, seed=4)[:, :, 0] != 0, axis=1)
    counts = np.bincount(started, minlength=7)
    assert counts[0] == 0 and counts[6] == 0
    p = 1 / starts.size
    assert np.all(np.abs(counts[starts] - experiments * p) < _binomial_margin(experiments, p))


@pytest.mark.parametrize(("planning", "n"), [("zero", 0), ("full", 10), ("soft", 10)])
def test_kernel_learns_like_the_independent_plain_python_reference(planning: str, n: int) -> None:
    # Same task, same settings, different random number generators: the steps of each of the first
    # three episodes must have the same mean within MARGIN_SE standard errors. A bias in
    # tie-breaking, start states, exploration or planning draws shifts these means by far more.
    reference = _reference()
    mdp = ArmGrid(joints=2, bins=7).mdp()
    lists = (
        mdp.next_state.tolist(),
        mdp.reward.tolist(),
        mdp.terminal.tolist(),
        mdp.start_states.tolist(),
    )
    episodes = 3
    theirs = np.array(
        [
            reference.run_experiment(
                *lists, planning=planning, planning_steps=n, episodes=episodes, seed=e
            )[0]
            for e in range(600)
        ]
    )
    ours = run_experiments(
        mdp, DynaQConfig(planning=planning, planning_steps=n), 1000, episodes, seed=0
    ).steps
    se = np.hypot(
        theirs.std(axis=0, ddof=1) / np.sqrt(len(theirs)),
        ours.std(axis=0, ddof=1) / np.sqrt(len(ours)),
    )
    z = (ours.mean(axis=0) - theirs.mean(axis=0)) / se
    assert np.all(np.abs(z) < MARGIN_SE), (ours.mean(axis=0), theirs.mean(axis=0), z)
