"""Training settings for Dyna-Q, and the limits a run must respect.

:class:`DynaQConfig` holds the paper's parameters as named defaults (alpha = 0.1, gamma = 0.95,
100 planning steps; Section III of the paper). Every field is validated on construction and each bad
field yields one sentence naming the field, the bad value and the allowed range, so the web page
can show the messages next to its form fields.

:func:`check_budget` refuses runs too big to finish on a workstation (for example a billion
episodes) before any work starts.

Also here, with their defaults, the other settings a person chooses for a run (the task's kind;
the continuous task's joints, step, actions and tilings) and a rollout's rate, pace and step cap: this
module imports neither numba nor the robot models, so ``studio train --help`` reads them at once.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields
from typing import Final

from .._numbers import is_int, is_number, is_numpy_scalar
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

TASK_ARM_GRID = "arm-grid"
"""``task.kind`` of the paper's arm grid (``task`` also holds the :meth:`ArmGrid.to_dict` spec)."""
TASK_ARM_REACH = "arm-reach"
"""``task.kind`` of the continuous-joint task (``task`` also holds the :meth:`ArmReach.to_dict`
fields and ``tile_coding``, the :meth:`TileCoding.to_dict` settings); its demonstrations are
joint paths ``(N, joints)`` in radians."""
TASK_KINDS = (TASK_ARM_GRID, TASK_ARM_REACH)
"""The kinds of task a run trains, each by its learner (:func:`studio.learning.learner`)."""
DEFAULT_JOINTS = 6
"""All six joints, so the tool's orientation is learned too."""
DEFAULT_STEP_DEG = 2.0
"""Joint increment per action, degrees (no coarser than 2 degrees)."""
DEFAULT_TILINGS = 8
"""Offset tilings of the arm's default features."""
ACTION_SETS = ("single", "pairs", "all", "follow", "all-follow")
"""What one action may move: one joint (2J actions), one joint or two together (2J**2), any
joints at once (3**J - 1), one joint or all of them along the demonstrated paths (2J + 1, see
:attr:`ArmReach.paths`), or any joints at once or all of them along the demonstrated paths
(3**J, :data:`FOLLOW_ACTION_SETS`); each of the first three begins with the one before it, in the
same order, ``"follow"`` with the singles and ``"all-follow"`` with ``"all"``."""
FOLLOW_ACTION_SETS = ("follow", "all-follow")
"""The action sets that end with the action following the demonstrated paths (when there are
any; without demonstrations ``"follow"`` is ``"single"`` and ``"all-follow"`` is ``"all"``)."""
FACTORED_ACTION_SETS = ("pairs", "all", "all-follow")
"""Action sets of the arm task learned with the factored value (one joint per action keeps its
one column per action: there each action already owns one joint's move)."""
DEFAULT_ACTIONS = "follow"
"""One joint per action, and with demonstrations one more that follows them (without any, the
task is ``"single"``'s bit for bit). With 3 demonstrations at six joints (package README): under
the paper's reward its first 20 own episodes take 0.037 of the real steps without them (one
joint per action: 0.204), 16 points ahead after 1,000 episodes and 4 after 4,000 (0.995); under
the default shaping greedy success from random starts is higher or level (+8.4 points after
1,000 episodes, +0.4 after 4,000, no planning; the learner's common value, :mod:`.linear._common_value`);
a policy taught by one demonstration moves like it (DTW 0.028-0.047 rad a sample, one joint per
action 0.17-0.39).
``"pairs"``, learned with the factored action value (:mod:`.linear._factored`), reaches 95% greedy
success in fewer real steps without demonstrations (81 k against 321 k at six joints), but its
greedy success swings as training goes on: at six joints, 2 experiments, Puma560 93% / 78% /
99% / 92% after 500 / 1,000 / 2,000 / 4,000 episodes and UR5 70% / 81% / 63% / 42%, where one
joint per action ends at 100% on the Puma560, the Panda and the UR5. A default that gets worse
with more training is the wrong default."""

GRID_DEFAULTS: Final = {"joints": 3, "bins": 11}
"""The paper's arm grid (:class:`ArmGrid`'s defaults): its first 3 joints, 11 bins each."""
REACH_DEFAULTS: Final = {
    "joints": DEFAULT_JOINTS,
    "step_deg": DEFAULT_STEP_DEG,
    "actions": DEFAULT_ACTIONS,
    "tilings": DEFAULT_TILINGS,
    "tiles": None,
}
"""The continuous task's settings a person sets, and their defaults (:class:`ArmReach` and its
default :meth:`ArmReach.features`; ``tiles`` None: the robot's :attr:`ArmReach.default_tiles`,
32 for the Puma560)."""
ROLLOUT_RATE_HZ = 50.0
"""Default control rate of a rollout trajectory (every policy kind's)."""
ROLLOUT_SECONDS_PER_STEP = 0.5
"""Default time the arm takes to move one grid step."""
ROLLOUT_MAX_STEPS = 1_000
"""Default cap on greedy steps in a rollout."""
TILE_ROLLOUT_SECONDS_PER_STEP = 0.04
"""Time the arm takes for one step of a tile-coded rollout (2 degrees in 0.04 s: 50 deg/s) when
the policy was not taught from timed demonstrations (:func:`studio.learning.demonstrated_pace`)."""
TILE_ROLLOUT_MAX_STEPS = 5_000
"""Default cap on greedy steps of a tile-coded rollout."""
DEFAULT_SHAPING = 5.0
"""Weight of the potential-based shaping reward (Ng, Harada & Russell 1999): ``shaping`` times the
change of :func:`.tasks._reach.reach_potential` (minus the joints' distance to the goal's angles, in steps). It
gives every step a direction toward the goal, without which a 6-joint random start almost never
finds the goal's few-degree region; 0 gives the paper's bare +100 / -1. With gamma = 1 the terms of
an episode telescope to a constant per start, so the optimal policies are unchanged; with the
paper's gamma = 0.95 the term also charges ``(1 - gamma) x shaping x distance``, which only pulls
harder toward the goal.

Why 5 and not 1. A joint step toward the goal pays ``shaping - 1``, one away ``-shaping - 1``.
With 1 the step cost cancels exactly: every move toward the goal pays 0, so which joint to move is
told apart only by the discounted +100, ``100 x 0.95 ** (sum of the joints' distances)``, a
*product* of per-joint factors that no sum of per-joint (or pair) tile weights represents; the
fitted error exceeds the true gaps and the greedy policy steps a near-goal joint back and forth
(measured at six joints: 16% greedy success after 4,000 episodes, 32% after 16,000). With 5, the
value is dominated by a sum over joints of per-joint terms (+4 per step toward the goal, -6 per
step away), which per-joint tilings represent exactly, and the +100 only settles the last steps:
100% after 4,000 episodes (package README). A cycle still costs (toward then away:
``4 - 0.95 x 6 < 0``), so no loop pays; that holds while ``shaping < (1 + gamma) / (1 - gamma)``
(39 at gamma = 0.95)."""
DEMO_SHAPING = 5.0
"""Weight of the demonstrations' potential, in reward per joint step: the task's own
:data:`DEFAULT_SHAPING`, for the same reason (with 1 a step toward the goal pays 0 and
the joints are told apart only by the discounted +100)."""
OWN_LEARNER = "dyna-q"
"""How a run names its task's own learner (tabular Dyna-Q on the grid, linear Dyna-Q with tile
coding on the continuous task), as ``studio train --learner`` takes it; the default."""
TEACHER_KIND = "teacher"
"""The teacher's kind (``studio train --learner teacher``)."""
CLONING_KIND = "cloning"
"""Behaviour cloning's kind (``studio train --learner cloning``)."""


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
            if is_numpy_scalar(value):
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
