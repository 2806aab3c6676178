"""One entry point above both learners: :func:`run_experiments` picks the tabular learner
(:mod:`._dynaq`) for a :class:`TabularMDP` and the linear one (:mod:`._linear`) for a Gymnasium
environment. What both share lives below them, in :mod:`._learner`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from ._config import DynaQConfig
from ._errors import LearningError
from ._learner import ExperimentResult, LiveProgress
from ._tiles import TileCoding
from .linear._linear import run_linear_experiments
from .tabular._dynaq import run_tabular_experiments
from .tasks._mdp import TabularMDP

if TYPE_CHECKING:
    import gymnasium


def run_experiments(
    env: TabularMDP | str | Callable[[], gymnasium.Env],
    config: DynaQConfig,
    experiments: int,
    episodes: int,
    seed: int,
    demonstrations: Sequence[Sequence[int] | np.ndarray] | None = None,
    features: TileCoding | None = None,
    *,
    workers: int | None = None,
    live: LiveProgress | None = None,
) -> ExperimentResult:
    """Run ``experiments`` independent Dyna-Q learners for ``episodes`` episodes each.

    Experiment ``e`` draws its random numbers from a generator seeded by ``(seed, e)``, so the
    result is identical bit for bit for a given seed whatever ``workers`` is. Experiments run on a
    pool of ``workers`` threads; the compiled kernels release the GIL.

    Args:
        env: the task: a :class:`TabularMDP` (tabular Dyna-Q), or a Gymnasium environment (a
            registered id or a zero-argument callable returning one, Box observations, Discrete
            actions) learnt by linear Dyna-Q over ``features``.
        config: learning settings.
        experiments: independent repetitions to average over (the paper used 20).
        episodes: episodes per experiment.
        seed: a non-negative integer.
        demonstrations: replayed as the first ``len(demonstrations)`` episodes (the agent takes
            the demonstrated actions, learning and planning as usual): state sequences for a
            :class:`TabularMDP`; for an environment, see :func:`._linear.run_linear_experiments`.
        features: for a Gymnasium environment: the tile coding of linear Dyna-Q, which then
            returns a :class:`LinearResult` with the learned weights.
        workers: threads to use (default: one per CPU core).
        live: progress arrays to fill while running, and the stop flag to obey.

    Returns:
        The step and update counts per episode, CPU seconds per experiment and the final Q tables.

    Raises:
        LearningError: for a bad argument, a bad demonstration or a run over the limits.
    """
    if isinstance(env, TabularMDP):
        return run_tabular_experiments(
            env, config, experiments, episodes, seed, demonstrations, workers=workers, live=live
        )
    if isinstance(env, str) or callable(env):
        return run_linear_experiments(
            env, config, experiments, episodes, seed, demonstrations, features,
            workers=workers, live=live,
        )  # fmt: skip
    raise LearningError(
        f"env is a {type(env).__name__}; give a TabularMDP (for example ArmGrid().mdp()), a Gymnasium environment id or a zero-argument callable returning an environment."
    )
