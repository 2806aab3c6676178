"""A run's record: what it trains and how, as typed settings, and its ``config.json`` layout.

:class:`RunRecord` carries the task (:class:`ArmGrid`, or :class:`ArmReach` with its
:class:`TileCoding`) and the :class:`DynaQConfig` themselves; they become JSON only at the file's
edge (:meth:`RunRecord.to_dict`, :meth:`RunRecord.from_dict`). Every layout a studio has written
reads back, the page's and ``studio train``'s from before version 1 included.

``config.json`` holds ``format`` (``teach-studio-run``), ``version`` (1), ``task``
(:func:`task_spec`), ``config`` (the :class:`DynaQConfig` fields), ``experiments``, ``episodes``,
``seed``, ``demonstrations``, ``name``, ``origin``, ``group``, ``created``, for the page's
runs ``request``, the form as the user filled it in (:meth:`RunRecord.form`), and for runs of
recorded demonstrations ``demonstration_motions``, their times and joints
(:meth:`DemonstrationMotion.to_dict`; absent in folders written before it, which then have no
likeness card).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import TypedDict, cast

import numpy as np

from ..._files import now_iso
from ..._numbers import is_int, is_number
from .._config import (
    DEFAULT_SEED,
    TASK_ARM_GRID,
    TASK_KINDS,
    DynaQConfig,
    check_budget,
)
from .._errors import ConfigError, LearningError
from .._interface import Learner
from .._registry import OWN_LEARNER, learner, learner_for_task, run_learner
from .._tiles import TileCoding
from ..tasks._arm import ArmGrid
from ..tasks._demo_motion import DemonstrationMotion
from ..tasks._reach import ArmReach

RUN_FORMAT = "teach-studio-run"
"""The ``format`` field of a run's ``config.json``."""
RUN_VERSION = 1
"""The version of the run folder layout this code writes and reads."""
ORIGINS = ("cli", "page", "reproduce", "sweep")
"""What made a run: ``studio train``, the page's run queue, ``studio reproduce``, a sweep."""
CONFIG_FORM_FIELDS = ("planning", "planning_steps", "epsilon", "alpha", "gamma")
"""The :class:`DynaQConfig` fields a person sets for a run (the page's form, ``studio train``)."""

Demonstrations = list[list[int]] | list[list[list[float]]]
"""A record's demonstrations: grid state paths (the arm grid) or joint paths in radians
``(N, joints)`` (the continuous task)."""


def task_spec(task: ArmGrid | ArmReach, coding: TileCoding | None = None) -> dict[str, object]:
    """A task as run records and policy listings write it: its kind and its settings.

    ``{"kind": "arm-grid", **grid.to_dict()}``, or ``{"kind": "arm-reach", **task.to_dict(),
    "tile_coding": coding.to_dict()}`` for the continuous task.
    """
    return learner_for_task(task).task_spec(task, coding)


@dataclass(frozen=True, kw_only=True)
class RunRecord:
    """A run's ``config.json``: what it trains and how, self-describing without the page.

    Build a checked one with :func:`studio.learning.resolve_run` (from what a person asked for),
    :meth:`for_arm_grid` or :meth:`for_arm_reach`; read one back with :meth:`from_dict`.

    Attributes:
        task: what is learnt: the paper's :class:`ArmGrid`, or the continuous :class:`ArmReach`.
        config: the Dyna-Q settings.
        experiments: independent experiments averaged.
        episodes: episodes per experiment.
        seed: the run's seed.
        demonstrations: grid state paths (arm grid) or joint paths in radians (continuous task)
            replayed as the first episodes (so a run repeats without the demonstration files).
        coding: the continuous task's tile coding (None for the arm grid).
        name: a free label ("" for none).
        origin: what made the run, one of :data:`ORIGINS`.
        group: runs made together (a reproduce or a sweep) share it; None otherwise.
        created: ISO 8601 UTC.
        goal_deg: the goal as the person typed it (joints 1-3, degrees), when they did; the task
            holds the goal it trains for (the arm grid's goal bin).
        demonstration_names: the names of the recorded demonstrations replayed, when the tool
            that made the run chose them by name (the page).
        demonstration_motions: the recorded demonstrations' own motions (times and joints),
            when known, so the run's likeness card is scored without the demonstration files.
        learner: the learner that trains it, by kind: "" for its task's own (Dyna-Q), else a
            baseline such as ``"teacher"`` or ``"cloning"`` (:func:`studio.learning.run_learner`).
    """

    task: ArmGrid | ArmReach
    config: DynaQConfig
    experiments: int
    episodes: int
    seed: int = DEFAULT_SEED
    demonstrations: Demonstrations = field(default_factory=list)
    coding: TileCoding | None = None
    name: str = ""
    origin: str = "cli"
    group: str | None = None
    created: str = ""
    goal_deg: tuple[float, ...] | None = None
    demonstration_names: tuple[str, ...] = ()
    demonstration_motions: tuple[DemonstrationMotion, ...] = ()
    learner: str = ""

    @classmethod
    def for_arm_grid(
        cls,
        grid: ArmGrid,
        config: DynaQConfig,
        experiments: int,
        episodes: int,
        seed: int = DEFAULT_SEED,
        demonstrations: Sequence[Sequence[int]] = (),
        *,
        name: str = "",
        origin: str = "cli",
        group: str | None = None,
        goal_deg: Sequence[float] | None = None,
        demonstration_names: Sequence[str] = (),
        demonstration_motions: Sequence[DemonstrationMotion] = (),
    ) -> RunRecord:
        """A checked record for the arm grid.

        Raises:
            ConfigError: one sentence per bad field (budget, seed, name, origin, demonstrations).
        """
        problems = run_problems(experiments, episodes, seed, name, grid)
        paths = [[int(s) for s in path] for path in demonstrations]
        raise_problems(_shared_problems(problems, origin, episodes, len(paths)))
        return cls(
            task=grid,
            config=config,
            demonstrations=paths,
            **_run_fields(experiments, episodes, seed, name, origin, group, goal_deg),
            demonstration_names=tuple(demonstration_names),
            demonstration_motions=tuple(demonstration_motions),
        )

    @classmethod
    def for_arm_reach(
        cls,
        task: ArmReach,
        coding: TileCoding,
        config: DynaQConfig,
        experiments: int,
        episodes: int,
        seed: int = DEFAULT_SEED,
        demonstrations: Sequence[np.ndarray] = (),
        *,
        name: str = "",
        origin: str = "cli",
        group: str | None = None,
        goal_deg: Sequence[float] | None = None,
        demonstration_names: Sequence[str] = (),
        demonstration_motions: Sequence[DemonstrationMotion] = (),
    ) -> RunRecord:
        """A checked record for the continuous-joint task learnt with tile coding.

        Raises:
            ConfigError: one sentence per bad field (budget, seed, name, origin, weight table,
                demonstrations, each naming the demonstration and the fix).
        """
        from ..linear._linear import weight_problem  # imports the kernels: import when needed

        problems = run_problems(experiments, episodes, seed, name)
        try:
            coder = coding.bind(task.lower, task.upper)
            problem = is_int(experiments) and weight_problem(
                cast(int, experiments), coder, task.n_actions
            )
            if problem:
                problems.append(("tiles", problem))
        except LearningError as err:
            problems.append(("tiles", str(err)))
        paths: list[list[list[float]]] = []
        for i, path in enumerate(demonstrations):
            try:
                task.demonstration_actions(path, i)
                paths.append(np.asarray(path, dtype=np.float64)[:, : task.joints].tolist())
            except LearningError as err:
                problems.append(("demonstrations", str(err)))
        raise_problems(_shared_problems(problems, origin, episodes, len(paths)))
        return cls(
            task=task,
            coding=coding,
            config=config,
            demonstrations=paths,
            **_run_fields(experiments, episodes, seed, name, origin, group, goal_deg),
            demonstration_names=tuple(demonstration_names),
            demonstration_motions=tuple(demonstration_motions),
        )

    @property
    def kind(self) -> str:
        """The task's kind: ``"arm-grid"`` (the paper's task) or ``"arm-reach"`` (continuous)."""
        return learner_for_task(self.task).kind

    def trained_by(self) -> Learner:
        """The learner that trains the run: its task's own, or the baseline it names."""
        return run_learner(self.learner, self.task)

    def arm_reach(self) -> ArmReach:
        """The task as an :class:`ArmReach` (for kind ``"arm-reach"``)."""
        if not isinstance(self.task, ArmReach):
            raise LearningError(
                f"This run's task is {self.kind!r}, not the continuous arm task; open it with the tool that made it."
            )
        return self.task

    def tile_coding(self) -> TileCoding:
        """The tile coding of an ``"arm-reach"`` run."""
        task = self.arm_reach()
        return self.coding if self.coding is not None else task.features()

    def arm_grid(self) -> ArmGrid:
        """The task as an :class:`ArmGrid` (for kind ``"arm-grid"``)."""
        if not isinstance(self.task, ArmGrid):
            raise LearningError(
                f"This run's task is {self.kind!r}, not the arm grid; open it with the tool that made it."
            )
        return self.task

    @property
    def robot(self) -> str:
        """The robot the run learns on (the Puma560 for a run written before runs named one)."""
        return self.task.robot

    def dynaq_config(self) -> DynaQConfig:
        """The Dyna-Q settings."""
        return self.config

    def label(self) -> str:
        """The run's name, else its planner, size and demonstrations."""
        if self.name:
            return self.name
        demos = len(self.demonstrations)
        extra = f", {demos} demos" if demos else ""
        if self.learner not in ("", OWN_LEARNER):
            return f"{self.learner} x{self.experiments}{extra}"
        return f"{self.config.planning} x{self.experiments}{extra}"

    def form(self) -> dict[str, object]:
        """The run in the terms a person sets it in (the page's run form, ``studio train``'s
        flags): the Dyna-Q settings, the budget, the task's settings, the goal in degrees (when
        the person gave one) and the demonstrations' names. The page shows it; ``config.json``
        keeps the page's as ``request``."""
        config = self.config.to_dict()
        form: dict[str, object] = {
            "name": self.name or None,
            **{key: config[key] for key in CONFIG_FORM_FIELDS},
            "episodes": self.episodes,
            "experiments": self.experiments,
            "task": self.kind,
            "robot": self.task.robot,
        }
        form.update(learner_for_task(self.task).task_form(self.task, self.coding))
        if self.goal_deg is not None:
            form["goal_deg"] = list(self.goal_deg)
        obstacles = getattr(self.task, "obstacles", ())
        if obstacles:
            form["obstacles"] = [box.to_dict() for box in obstacles]
        form["demonstrations"] = list(self.demonstration_names)
        form["seed"] = self.seed
        if self.learner:
            form["learner"] = self.learner
        return form

    def to_dict(self) -> dict[str, object]:
        """The JSON object stored as ``config.json``."""
        data: dict[str, object] = {
            "format": RUN_FORMAT,
            "version": RUN_VERSION,
            "task": task_spec(self.task, self.coding),
            "config": self.config.to_dict(),
            "experiments": self.experiments,
            "episodes": self.episodes,
            "seed": self.seed,
            "demonstrations": self.demonstrations,
            "name": self.name,
            "origin": self.origin,
            "group": self.group,
            "created": self.created,
        }
        if self.demonstration_motions:
            data["demonstration_motions"] = [m.to_dict() for m in self.demonstration_motions]
        if self.learner:
            data["learner"] = self.learner
        if self.origin == "page":
            data["request"] = self.form()
        return data

    @classmethod
    def from_dict(cls, data: object) -> RunRecord:
        """A record from ``config.json``'s object; also reads the layouts written before version 1
        (the page's ``{"request", "grid", ...}`` and ``studio train``'s ``{"grid", "config", ...}``).

        Raises:
            LearningError: not a run record, a newer version, missing fields, or settings this
                studio refuses (each naming ``config.json``).
        """
        if not isinstance(data, dict):
            raise LearningError("config.json holds no JSON object; it is not a run folder.")
        version = data.get("version", 0)
        if data.get("format", RUN_FORMAT) != RUN_FORMAT or not is_int(version):
            raise LearningError(
                f"config.json has format {data.get('format')!r}; it is not a {RUN_FORMAT} folder."
            )
        if version > RUN_VERSION:
            raise LearningError(
                f"This run folder has version {version}, newer than this studio's {RUN_VERSION}; update Teach Studio."
            )
        task = data.get("task")
        if task is None and isinstance(data.get("grid"), dict):  # before version 1
            task = {"kind": TASK_ARM_GRID, **data["grid"]}
        request = data.get("request")
        request = request if isinstance(request, dict) else {}
        given = {
            key: data.get(key, request.get(key)) for key in ("experiments", "episodes", "seed")
        }
        missing = [
            key
            for key, value in (
                ("task", task),
                ("config", data.get("config")),
                ("experiments", given["experiments"]),
                ("episodes", given["episodes"]),
            )
            if value is None
        ]
        if missing:
            raise LearningError(
                f"config.json lacks {', '.join(missing)}; it is not a complete run record."
            )
        grid_or_reach, coding = _task_of(task)
        try:
            config = DynaQConfig.from_dict(data["config"])
        except LearningError as err:
            raise LearningError(f"config.json's training settings are refused: {err}") from None
        group = data.get("group")
        if group is not None and not isinstance(group, str):
            raise LearningError(f"config.json's group is {group!r}; delete the run.")
        chosen = data.get("learner", "")
        try:
            run_learner(chosen if isinstance(chosen, str) else repr(chosen), grid_or_reach)
        except LearningError as err:
            raise LearningError(f"config.json's learner is refused: {err}") from None
        return cls(
            task=grid_or_reach,
            coding=coding,
            config=config,
            experiments=int(given["experiments"]),
            episodes=int(given["episodes"]),
            seed=int(given["seed"] or DEFAULT_SEED),
            demonstrations=_demonstrations_of(data.get("demonstrations"), grid_or_reach),
            name=str(data.get("name") or request.get("name") or ""),
            origin=str(data.get("origin") or ("page" if request else "cli")),
            group=group,
            created=str(data.get("created") or ""),
            goal_deg=_goal_of(request.get("goal_deg")),
            demonstration_names=tuple(
                str(n) for n in request.get("demonstrations") or () if isinstance(n, str)
            ),
            demonstration_motions=tuple(
                DemonstrationMotion.from_dict(m) for m in data.get("demonstration_motions") or ()
            ),
            learner=str(chosen),
        )


class _RunFields(TypedDict):
    experiments: int
    episodes: int
    seed: int
    name: str
    origin: str
    group: str | None
    created: str
    goal_deg: tuple[float, ...] | None


def _run_fields(
    experiments: int,
    episodes: int,
    seed: int,
    name: str,
    origin: str,
    group: str | None,
    goal_deg: Sequence[float] | None,
) -> _RunFields:
    """The fields every task's record sets alike, once checked (created now)."""
    return _RunFields(
        experiments=int(experiments),
        episodes=int(episodes),
        seed=int(seed),
        name=name,
        origin=origin,
        group=group,
        created=now_iso(),
        goal_deg=None if goal_deg is None else tuple(float(g) for g in goal_deg),
    )


def _task_of(task: object) -> tuple[ArmGrid | ArmReach, TileCoding | None]:
    """``config.json``'s ``task`` as typed settings (refusing a kind this studio does not know)."""
    if not isinstance(task, dict):
        raise LearningError(f"config.json's task is {task!r}; it is not a run record.")
    kind = task.get("kind", TASK_ARM_GRID)
    if kind not in TASK_KINDS:
        raise LearningError(
            f"config.json's task kind {kind!r} is none of {', '.join(TASK_KINDS)}; update Teach Studio or delete the run."
        )
    try:
        task, coding = learner(kind).task_from_spec({k: v for k, v in task.items() if k != "kind"})
    except LearningError as err:
        raise LearningError(f"config.json's task is refused: {err}") from None
    return task, coding  # type: ignore[return-value]


def _demonstrations_of(paths: object, task: ArmGrid | ArmReach) -> Demonstrations:
    """``config.json``'s demonstrations: grid state paths, or joint paths for the continuous task."""
    paths = paths or []
    if not isinstance(paths, list):
        raise LearningError(
            f"config.json's demonstrations are {type(paths).__name__}; delete the run."
        )
    return learner_for_task(task).demonstrations_of(paths)  # type: ignore[return-value]


def _goal_of(goal: object) -> tuple[float, ...] | None:
    """A stored form's goal in degrees, or None when it holds none (or a damaged one)."""
    if not isinstance(goal, list) or not all(is_number(g) for g in goal):
        return None
    return tuple(float(g) for g in goal)


def _shared_problems(
    problems: list[tuple[str, str]], origin: str, episodes: object, demonstrations: int
) -> list[tuple[str, str]]:
    """``problems`` and those of the checks every task shares: the origin, and at least as many
    episodes as demonstrations."""
    if origin not in ORIGINS:
        problems.append(("origin", f"origin is {origin!r}; give one of {', '.join(ORIGINS)}."))
    if is_int(episodes) and demonstrations > cast(int, episodes):
        problems.append(
            (
                "demonstrations",
                f"The run replays {demonstrations} demonstrations but has only {episodes} episodes; give at least as many episodes as demonstrations.",
            )
        )
    return problems


def run_problems(
    experiments: object,
    episodes: object,
    seed: object,
    name: object = "",
    grid: ArmGrid | None = None,
) -> list[tuple[str, str]]:
    """``(field, sentence)`` for each bad run-level setting: budget, seed and name."""
    problems: list[tuple[str, str]] = []
    try:
        if grid is None:
            check_budget(experiments, episodes)
        else:
            check_budget(experiments, episodes, grid.n_states, grid.n_actions)
    except ConfigError as err:
        problems += list(err.by_field.items())
    if not is_int(seed) or not 0 <= cast(int, seed) < 2**63:
        problems.append(("seed", f"seed is {seed!r}; give a whole number from 0 to 2**63 - 1."))
    if not isinstance(name, str) or (name and (not name.strip() or len(name) > 100)):
        problems.append(("name", "name must be 1 to 100 characters; give a shorter label or none."))
    return problems


def raise_problems(problems: Iterable[tuple[str, str]]) -> None:
    """Raise one :class:`ConfigError` carrying every ``(field, sentence)`` problem, if any."""
    problems = list(problems)
    if problems:
        raise ConfigError([text for _, text in problems], [name for name, _ in problems])
