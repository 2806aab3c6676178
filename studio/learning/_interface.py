"""The learner interface: what every learner offers, whatever it learns and however.

A learner trains on a run, saves and loads its policy files, rolls a policy out from a start,
evaluates it from given starts, and scores its likeness to a demonstration. Tabular Dyna-Q on
the arm grid (:mod:`.tabular`), linear Dyna-Q over tile coding on the continuous arm task
(:mod:`.linear`) and the movement primitive (:mod:`.primitives`) each implement
:class:`Learner`, and :mod:`._registry` registers them by their kind. Everything above them (run
folders, likeness cards, ``studio export``, the page) calls a learner through the registry and
never asks which class a policy is: a new learner (a baseline) is one more registration.

Use::

    from studio.learning import Start, learner_of, load_any_policy

    policy = load_any_policy("runs/abc/policy.policy.npz")
    learner = learner_of(policy)
    rollout = learner.roll_out(policy, Start(seed=0), rate_hz=50.0)
    rollout.times, rollout.q, rollout.reached
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

if TYPE_CHECKING:
    from ._config import DynaQConfig
    from ._learner import LiveProgress
    from ._tiles import TileCoding
    from .likeness._likeness import LikenessCard
    from .tasks._demo_motion import DemonstrationMotion


GOAL_DECIMALS = 6
"""Goal angles are listed to a micro-degree: exact enough to compare, short enough to read."""


def listed_degrees(q_rad: np.ndarray) -> list[float]:
    """Joint angles (rad) as a listing gives them: degrees to :data:`GOAL_DECIMALS` places."""
    return [round(float(x), GOAL_DECIMALS) for x in np.degrees(np.asarray(q_rad))]


@dataclass(frozen=True, eq=False)
class Start:
    """Where a rollout starts: at most one of ``q``, ``state`` and ``seed``.

    Attributes:
        q: joint angles (rad): the policy's learned joints, or a whole pose of its robot (the
            joints it does not learn then hold where they are).
        state: a grid state number (grid policies only).
        seed: a random start, drawn as the task draws its episodes' starts from
            ``np.random.default_rng(seed)`` (a movement primitive starts where its
            demonstration did).

    With none of them, the learner's own: the learned joints at 0, or a movement primitive's
    demonstration's start.
    """

    q: np.ndarray | None = None
    state: int | None = None
    seed: int | None = None


@dataclass(frozen=True, eq=False)
class Rollout:
    """A policy rolled out to a joint trajectory of its robot.

    Attributes:
        times: sample times ``(N,)`` (s), from 0.
        q: the robot's joints ``(N, nq)`` (rad).
        reached: whether it reaches the goal.
        steps: the policy's steps (grid steps, joint steps, or the primitive's samples).
        states: the grid states visited (grid policies; empty otherwise).
        seed: the seed of a random start (None for any other start).
        goal: the goal as a whole pose of the robot ``(nq,)`` (rad).
        robot: the robot's registry name.
    """

    times: np.ndarray
    q: np.ndarray
    reached: bool
    steps: int
    states: tuple[int, ...]
    seed: int | None
    goal: np.ndarray
    robot: str


@dataclass(frozen=True)
class Evaluation:
    """A policy (or a controller: the teacher) rolled out from given starts
    (:meth:`Learner.evaluate`, ``studio evaluate``, ``benchmarks/bench_teacher.py``).

    Attributes:
        starts: how many starts.
        success: the share of starts from which it reaches the goal.
        mean_steps: its mean steps to the goal over the starts that reach it (NaN if none).
        mean_seconds: the same in seconds of motion at the policy's pace (NaN if none).
        collisions: the share of starts whose rollout would collide (self or table; 0 where
            nobody checked).
    """

    starts: int
    success: float
    mean_steps: float
    mean_seconds: float
    collisions: float = 0.0

    @classmethod
    def of(
        cls,
        reached: Sequence[bool],
        steps: Sequence[int],
        seconds_per_step: float | None = None,
        *,
        seconds: Sequence[float] | None = None,
        collided: Sequence[bool] = (),
    ) -> Evaluation:
        """The evaluation of per-start outcomes: each start's reached flag and steps, and its
        seconds of motion (``seconds``) or one pace for every step (``seconds_per_step``), and
        whether its rollout collided."""
        hit = np.asarray(reached, dtype=bool)
        taken = np.asarray(steps, dtype=np.float64)[hit]
        mean = float(taken.mean()) if taken.size else float("nan")
        if seconds is not None:
            took = np.asarray(seconds, dtype=np.float64)[hit]
            mean_seconds = float(took.mean()) if took.size else float("nan")
        else:
            mean_seconds = mean * (seconds_per_step or 0.0)
        return cls(
            starts=int(hit.size),
            success=float(hit.mean()) if hit.size else 0.0,
            mean_steps=mean,
            mean_seconds=mean_seconds,
            collisions=float(np.mean(collided)) if len(collided) else 0.0,
        )

    def as_json(self) -> dict[str, float | None]:
        """``success``, ``collisions``, ``mean_steps`` and ``mean_seconds`` for JSON (NaN as
        null), as ``studio evaluate --json`` prints them."""
        figures = {
            "success": self.success,
            "collisions": self.collisions,
            "mean_steps": self.mean_steps,
            "mean_seconds": self.mean_seconds,
        }
        return {k: (None if v != v else v) for k, v in figures.items()}


class TrainingRun(Protocol):
    """What a learner reads of a run it trains (a :class:`studio.learning.RunRecord`)."""

    @property
    def task(self) -> object: ...
    @property
    def config(self) -> DynaQConfig: ...
    @property
    def experiments(self) -> int: ...
    @property
    def episodes(self) -> int: ...
    @property
    def seed(self) -> int: ...
    @property
    def demonstrations(self) -> Sequence[Sequence[object]]: ...
    @property
    def demonstration_motions(self) -> tuple[DemonstrationMotion, ...]: ...
    def tile_coding(self) -> TileCoding: ...


@runtime_checkable
class Learner(Protocol):
    """What every learner offers (see the module's docstring).

    Attributes:
        kind: its registry key, as policy listings name what a policy acts on: ``"arm-grid"``,
            ``"arm-reach"`` or ``"dmp"``.
        title: how a sentence names its policies ("grid policy", "tile-coded policy",
            "movement primitive").
        format: the ``format`` field of its policy files' header.
        policy_type: the class of its loaded policies.
        watch_max_steps: the cap on a watched rollout's steps (None: the policy's own end).
        grid_states: whether a rollout may start from a grid state (:attr:`Start.state`).
        settings_field: the :class:`studio.learning.RunRequest` field that holds its task's
            settings (``"grid"``, ``"reach"``; ``""`` for a learner no run trains).
        form_keys: its task's settings the page's run form sets.
        sweep_keys: its task's settings a sweep may set.
        shortest_paths: whether its task knows its mean shortest path (the level a sweep's
            ``episodes_to_converge`` reaches by default).
        prepare_seconds: about how long its compiled kernels take to compile (0: none).
        trains: the task class whose runs it trains (None: no run trains it, a movement
            primitive); a run picks a learner other than its task's own by kind
            (:func:`studio.learning.run_learner`).
    """

    kind: str
    title: str
    format: str
    policy_type: type
    watch_max_steps: int | None
    grid_states: bool
    settings_field: str
    form_keys: tuple[str, ...]
    sweep_keys: tuple[str, ...]
    shortest_paths: bool
    prepare_seconds: float
    trains: type | None

    def train(self, run: TrainingRun, live: LiveProgress, workers: int | None = None) -> object:
        """Learn what ``run`` asks for; the result :meth:`save` writes."""
        ...

    def kernels(self) -> list[object]:
        """Its compiled entry points (numba dispatchers; their callees compile into them)."""
        ...

    def warm(self) -> None:
        """Compile (or load from the disk cache) every kernel it runs, with a tiny run."""
        ...

    def save(
        self,
        path: str | Path,
        run: TrainingRun,
        result: object,
        *,
        notes: str = "",
        compress: bool = True,
    ) -> None:
        """Write the best of ``result`` (what :meth:`train` returned) as a policy file."""
        ...

    def load(self, path: str | Path) -> object:
        """Read one of its policy files (a :class:`PolicyFileError` if it is not one)."""
        ...

    def learned_joints(self, policy: object) -> int:
        """How many joints, from joint 1, the policy learns (0 off the arm)."""
        ...

    def pose_start(self, policy: object, q: np.ndarray) -> Start:
        """The start of a rollout from the robot's pose ``q`` (the scene's current pose)."""
        ...

    def roll_out(
        self,
        policy: object,
        start: Start,
        rate_hz: float,
        *,
        max_steps: int | None = None,
        seconds_per_step: float | None = None,
    ) -> Rollout:
        """The policy from ``start`` as a joint trajectory sampled at ``rate_hz``; ``max_steps``
        and ``seconds_per_step`` default to the policy's own."""
        ...

    def summary(self, rollout: Rollout) -> str:
        """One phrase saying what ``rollout`` did ("the greedy policy reaches the goal")."""
        ...

    def evaluate(
        self, policy: object, starts: np.ndarray, *, max_steps: int | None = None
    ) -> Evaluation:
        """The policy rolled out from each of ``starts`` ``(N, learned joints)`` (rad)."""
        ...

    def likeness(
        self, policy: object, demo_times: np.ndarray, demo_q: np.ndarray, rate_hz: float
    ) -> LikenessCard:
        """Its likeness card to a demonstration ``(N, nq)``, rolled out from the demonstration's
        first sample (:func:`studio.learning.policy_likeness_card` checks the demonstration)."""
        ...

    def own_demonstration(self, policy: object) -> DemonstrationMotion | None:
        """The demonstration the policy file itself holds (a movement primitive's), if any."""
        ...

    def beside(
        self, policy: object, demonstrations: Sequence[Sequence[Sequence[float]]]
    ) -> np.ndarray | None:
        """The joint path ``(N, nq)`` to show beside its rollout: its demonstration, or the
        first of the run's ``demonstrations`` (joint paths) when it learns joint paths."""
        ...

    def not_an_arm(self, policy: object, what: str) -> str | None:
        """The sentence refusing a policy of another environment than the arm (``what`` it
        then cannot do: "can be watched"), or None for an arm's policy."""
        ...

    def describe(self, policy: object) -> dict[str, object]:
        """The listing facts only its kind knows: ``task``, ``grid``, ``joints``, ``goal_deg``
        and ``planning`` (:func:`studio.learning.policy_summary` adds the rest)."""
        ...

    # ---------------------------------------------------------------- its task, in a run record

    def task_spec(self, task: object, coding: TileCoding | None = None) -> dict[str, object]:
        """The task as run records and policy listings write it: ``{"kind": ..., **settings}``."""
        ...

    def task_from_spec(self, spec: dict[str, object]) -> tuple[object, TileCoding | None]:
        """The task (and tile coding) of a record's ``task`` object, without its ``kind``."""
        ...

    def task_form(self, task: object, coding: TileCoding | None) -> dict[str, object]:
        """The task's settings as the page's run form holds them (:meth:`RunRecord.form`)."""
        ...

    def demonstrations_of(self, paths: list[object]) -> list[object]:
        """A record's stored demonstrations as the task replays them."""
        ...

    def mean_shortest_steps(self, task: object) -> float | None:
        """The task's mean shortest path in steps, if it knows it (:attr:`shortest_paths`)."""
        ...
