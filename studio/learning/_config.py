"""Training settings for Dyna-Q, and the limits a run must respect.

:class:`DynaQConfig` holds the paper's parameters as named defaults (alpha = 0.1, gamma = 0.95,
100 planning steps; Section III of the paper). Every field is validated on construction and each bad
field yields one sentence naming the field, the bad value and the allowed range, so the web page
can show the messages next to its form fields.

:func:`check_budget` refuses runs too big to finish on a workstation (for example a billion
episodes) before any work starts.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import numpy as np

from .._numbers import is_int, is_number
from ._errors import ConfigError

PLANNERS = ("zero", "full", "soft", "prioritized")
"""Planning modes: none, n uniform updates per real step, n falling by one per episode, and
prioritized sweeping (Sutton & Barto, section 8.4) with a budget of n updates per real step."""

MAX_PLANNING_STEPS = 10_000
"""Upper bound on ``planning_steps``: beyond it a single real step costs milliseconds."""
MAX_STEPS_PER_EPISODE = 10_000_000
"""Upper bound on ``max_steps_per_episode``."""
MAX_EXPERIMENTS = 1_000
"""Upper bound on independent experiments in one run."""
MAX_EPISODES = 100_000
"""Upper bound on episodes per experiment."""
MAX_EPISODE_RUNS = 2_000_000
"""Upper bound on experiments x episodes: about an hour of learning on the arm grid."""
DEFAULT_EXPERIMENTS = 20
"""Independent experiments averaged per run (the paper averaged 20)."""
DEFAULT_EPISODES = 100
"""Episodes per experiment; the paper's figures span about this many."""
DEFAULT_SEED = 0
"""Seed of a run when none is given (every random draw derives from it)."""
MAX_Q_ENTRIES = 200_000_000
"""Upper bound on experiments x states x actions: the final Q tables (8 bytes each, 1.6 GB)."""


@dataclass(frozen=True)
class DynaQConfig:
    """Settings of one Dyna-Q training run (the paper's values are the defaults).

    Attributes:
        alpha: learning rate of the Q-learning update (paper: 0.1).
        gamma: discount factor (paper: 0.95).
        epsilon: probability of a uniformly random action; otherwise greedy, ties broken at random.
        planning: ``"zero"``, ``"full"``, ``"soft"`` or ``"prioritized"``. The default is
            ``"full"``: the paper's Dyna-Q agent makes 100 planning updates per real step (its
            FPL agents), which is also what ``planning_steps``' default of 100 means; ``"zero"``
            is plain Q-learning, the paper's baseline rather than its method.
        planning_steps: planning updates per real step (``"full"``, ``"prioritized"``) or in the
            first episode (``"soft"``, falling by one per episode to 0); ignored for ``"zero"``.
        max_steps_per_episode: an episode that has not reached a terminal state after this many
            real steps is cut off (the paper had no cap; this one is far above its 2500 steps).
            Replayed demonstrations always run to their end.
        priority_threshold: prioritized sweeping queues a (state, action) only when its update
            would change Q by more than this (Sutton & Barto's theta).
    """

    alpha: float = 0.1
    gamma: float = 0.95
    epsilon: float = 0.1
    planning: str = "full"
    planning_steps: int = 100
    max_steps_per_episode: int = 100_000
    priority_threshold: float = 1e-4

    def __post_init__(self) -> None:
        problems = _problems(self)
        if problems:
            raise ConfigError([text for _, text in problems], [name for name, _ in problems])
        for f in fields(self):  # plain Python numbers, so the settings serialise to JSON as is
            value = getattr(self, f.name)
            if isinstance(value, np.integer | np.floating):
                object.__setattr__(self, f.name, value.item())

    def to_dict(self) -> dict[str, object]:
        """The settings as a JSON-ready dict (the inverse of :meth:`from_dict`)."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: object) -> DynaQConfig:
        """Settings from a dict such as a JSON body or a policy header; unknown keys are refused."""
        if not isinstance(data, dict):
            raise ConfigError(
                [
                    f"The training config is a {type(data).__name__}; give a mapping of field names to values."
                ]
            )
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ConfigError(
                [
                    f"Unknown config field {name!r}; use one of {', '.join(sorted(known))}."
                    for name in unknown
                ]
            )
        return cls(**data)


def _problems(config: DynaQConfig) -> list[tuple[str, str]]:
    """``(field, sentence)`` per bad field of ``config``."""
    problems: list[tuple[str, str]] = []

    def number(name: str, low: float, high: float, low_open: bool = False) -> None:
        value = getattr(config, name)
        lo = "(" if low_open else "["
        if not is_number(value) or value < low or value > high or (low_open and value <= low):
            problems.append((name, f"{name} is {value!r}; give a number in {lo}{low}, {high}]."))

    def integer(name: str, low: int, high: int) -> None:
        value = getattr(config, name)
        if not is_int(value) or value < low or value > high:
            problems.append(
                (name, f"{name} is {value!r}; give a whole number from {low} to {high:,}.")
            )

    number("alpha", 0.0, 1.0, low_open=True)
    number("gamma", 0.0, 1.0)
    number("epsilon", 0.0, 1.0)
    if config.planning not in PLANNERS:
        problems.append(
            ("planning", f"planning is {config.planning!r}; give one of {', '.join(PLANNERS)}.")
        )
    integer("planning_steps", 0, MAX_PLANNING_STEPS)
    integer("max_steps_per_episode", 1, MAX_STEPS_PER_EPISODE)
    value = config.priority_threshold
    if not is_number(value) or value < 0:
        problems.append(
            ("priority_threshold", f"priority_threshold is {value!r}; give a finite number >= 0.")
        )
    return problems


def check_budget(
    experiments: object, episodes: object, n_states: int = 1, n_actions: int = 1
) -> None:
    """Refuse a run that is malformed or too big, before any work starts.

    Args:
        experiments: independent repetitions (1 to :data:`MAX_EXPERIMENTS`).
        episodes: episodes per experiment (1 to :data:`MAX_EPISODES`).
        n_states: states of the task, to bound the memory of the final Q tables.
        n_actions: actions of the task.

    Raises:
        ConfigError: one sentence per problem, naming the value and the allowed range.
    """
    problems: list[tuple[str, str]] = []
    for name, value, high in (
        ("experiments", experiments, MAX_EXPERIMENTS),
        ("episodes", episodes, MAX_EPISODES),
    ):
        if not is_int(value) or not 1 <= value <= high:
            problems.append((name, f"{name} is {value!r}; give a whole number from 1 to {high:,}."))
    if problems:
        raise ConfigError([text for _, text in problems], [name for name, _ in problems])
    experiments, episodes = int(experiments), int(episodes)  # type: ignore[call-overload]
    if experiments * episodes > MAX_EPISODE_RUNS:
        raise ConfigError(
            [
                f"experiments x episodes is {experiments * episodes:,}; keep it at most {MAX_EPISODE_RUNS:,} by running fewer experiments or episodes."
            ],
            ["episodes"],
        )
    if experiments * n_states * n_actions > MAX_Q_ENTRIES:
        raise ConfigError(
            [
                f"{experiments} experiments of a {n_states:,} x {n_actions} table need {experiments * n_states * n_actions * 8 / 1e9:.1f} GB of Q tables; run at most {max(1, MAX_Q_ENTRIES // (n_states * n_actions))} experiments or a smaller grid."
            ],
            ["experiments"],
        )
