"""From what a person asks for to a checked run record: the one resolver of a run request.

The page's run form, ``studio train``'s flags and a sweep trial's settings all describe a run in
the same terms: a task kind, Dyna-Q settings, the task's settings (the grid's bins or the
continuous task's joints, step, tilings and tiles), a goal, a budget, a seed and demonstrations.
Each fills in a :class:`RunRequest`; :func:`resolve_run` turns it into a :class:`RunRecord`,
with the learning package's defaults for whatever was left out, and reports every bad setting at
once in one :class:`ConfigError` whose ``by_field`` keys each sentence by the field the person
set (``planning``, ``bins``, ``goal_deg``, ``joints``, ``tiles``, ``demonstrations``, ...).

Use::

    record = resolve_run(RunRequest(config={"planning": "zero"}, goal_deg=(0, 45, -90)))
    record = resolve_run(RunRequest(task="arm-reach", reach={"joints": 4}, experiments=5))
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field, replace
from typing import cast

import numpy as np

from ..._numbers import is_int
from .._config import (
    DEFAULT_EPISODES,
    DEFAULT_EXPERIMENTS,
    DEFAULT_SEED,
    REACH_DEFAULTS,
    TASK_ARM_GRID,
    TASK_ARM_REACH,
    TASK_KINDS,
    DynaQConfig,
)
from .._errors import ConfigError, LearningError
from .._registry import OWN_LEARNER, learner, run_learner
from .._tiles import TileCoding
from ..linear._learner import CODING_SETTINGS
from ..paper._reproduce import generate_demonstrations
from ..tasks._arm import ArmGrid
from ..tasks._demo_motion import DemonstrationMotion, demonstration_grid_path
from ..tasks._goal import goal_pose, goal_problems, grid_for_goal
from ..tasks._obstacles import task_obstacles
from ..tasks._reach import ArmReach
from ..tasks._robot import PUMA560, check_robot, robot_title, task_arm
from ._record import (
    CONFIG_FORM_FIELDS,
    RunRecord,
    raise_problems,
    run_problems,
)

GENERATED_DEMO_STREAM = 1
"""Generated demonstrations draw from ``default_rng([seed, 1])`` (``studio train``, sweeps)."""


@dataclass(frozen=True)
class DemonstrationPath:
    """A recorded demonstration a run replays: its joint path and how a message names it.

    Attributes:
        label: how a message names it (``Demonstration 'reach-1'``, ``The demonstration
            recordings/reach-1.demo.json``).
        q_robot: the robot's joint path ``(N, nq)``, radians (a demonstration file stores the
            Puma560's; for another robot, its recording's segment retargeted:
            ``studio.motion.demonstration_motion``).
        name: the name the page lists it by (kept in the run record), or "".
        times: its sample times ``(N,)`` (s), when known: the run keeps its motion for the
            likeness card (``likeness.json``).
        robot: the robot whose joints ``q_robot`` holds.
    """

    label: str
    q_robot: np.ndarray
    name: str = ""
    times: np.ndarray | None = None
    robot: str = PUMA560


@dataclass(frozen=True, kw_only=True)
class RunRequest:
    """A run as a person asks for it; every setting left out takes the learning package's default.

    Attributes:
        task: ``"arm-grid"`` (the paper's grid, tabular) or ``"arm-reach"`` (continuous joints,
            tile coding).
        robot: the robot learnt on (a registry name, ``studio robots``; the Puma560 by default):
            the grid's first three joints or the continuous task's first ``joints``.
        config: :class:`DynaQConfig` fields set (the others take its defaults).
        grid: :class:`ArmGrid` fields set (``joints``, ``bins``, ``low_deg``, ``high_deg``,
            ``goal`` as bins), for the arm grid.
        reach: the continuous task's settings: :data:`REACH_DEFAULTS`' keys, any other
            :class:`ArmReach` field and ``size`` of the tile coding.
        goal_deg: the goal as joint 1-3 angles in degrees (instead of ``grid``'s ``goal`` bins;
            the continuous task's goal when it replays no demonstration).
        experiments: independent experiments averaged.
        episodes: episodes per experiment.
        seed: the run's seed.
        demonstrations: recorded demonstrations replayed first (their joint paths).
        grid_paths: arm grid state paths replayed first, given as such.
        generated: how many generated demonstrations the arm grid replays (after the others).
        name: a label for the run.
        origin: what makes the run (``"page"``, ``"cli"``, ``"sweep"``, ``"reproduce"``).
        group: runs made together share it.
        obstacles: boxes in the robot's base frame (:class:`studio.kinematics.Obstacle`, their
            dicts or six numbers each) that no move of the task may touch.
        problems: ``(field, sentence)`` the caller found already (a flag that does not apply),
            reported with the others.
        learner: the learner that trains it: "" or ``"dyna-q"`` for its task's own, or a
            baseline (``"teacher"``, ``"cloning"``; :func:`studio.learning.run_learner`).
    """

    task: str = TASK_ARM_GRID
    robot: str = PUMA560
    config: Mapping[str, object] = field(default_factory=dict)
    grid: Mapping[str, object] = field(default_factory=dict)
    reach: Mapping[str, object] = field(default_factory=dict)
    goal_deg: Sequence[float] | None = None
    experiments: object = DEFAULT_EXPERIMENTS
    episodes: object = DEFAULT_EPISODES
    seed: object = DEFAULT_SEED
    demonstrations: Sequence[DemonstrationPath] = ()
    grid_paths: Sequence[Sequence[int]] = ()
    generated: int = 0
    name: str = ""
    origin: str = "cli"
    group: str | None = None
    obstacles: Sequence[object] = ()
    problems: Sequence[tuple[str, str]] = ()
    learner: str = ""

    @classmethod
    def from_form(
        cls,
        form: Mapping[str, object],
        *,
        demonstrations: Sequence[DemonstrationPath] = (),
        origin: str = "page",
    ) -> RunRequest:
        """The request of a run form's values, in the layout of :meth:`RunRecord.form` (the
        page's ``RunCreate``): its ``task``, Dyna-Q settings, budget, seed, name, goal in degrees
        and the task's settings; the demonstrations named in it are given as their paths."""
        task = str(form.get("task") or TASK_ARM_GRID)
        given = {key: form[key] for key in ("experiments", "episodes", "seed") if key in form}
        goal = form.get("goal_deg")
        return cls(
            task=task,
            robot=str(form.get("robot") or PUMA560),
            config={k: form[k] for k in CONFIG_FORM_FIELDS if k in form},
            **task_settings(task, form, "form"),
            goal_deg=None if goal is None else cast(Sequence[float], goal),
            demonstrations=demonstrations,
            name=str(form.get("name") or ""),
            origin=origin,
            obstacles=cast(Sequence[object], form.get("obstacles") or ()),
            learner=str(form.get("learner") or ""),
            **given,  # type: ignore[arg-type]
        )


def resolve_run(request: RunRequest) -> RunRecord:
    """The checked record of the run ``request`` asks for.

    Raises:
        ConfigError: every bad setting at once, each keyed by the field the person set.
    """
    problems = list(request.problems)
    if request.task not in TASK_KINDS:
        problems.append(("task", f"task is {request.task!r}; give one of {', '.join(TASK_KINDS)}."))
        raise_problems(problems)
    try:
        check_robot(request.robot)
    except ConfigError as err:
        raise_problems(problems + list(err.by_field.items()))
    for demo in request.demonstrations:
        if demo.robot != request.robot:  # its joints mean nothing on this robot: say only that
            raise_problems(
                problems
                + [
                    (
                        "demonstrations",
                        f"{demo.label} holds joints of the {robot_title(demo.robot)}, not of the {robot_title(request.robot)}; retarget it to the {request.robot} from its recording, or train on the {demo.robot}.",
                    )
                ]
            )
    config = _dynaq_config(request.config, problems)
    record = _TASK_RUNS[request.task].record(request, config, problems)
    return _with_learner(record, request.learner)


def _with_learner(record: RunRecord, kind: str) -> RunRecord:
    """``record`` trained by the learner ``kind`` asks for (its task's own by default).

    Raises:
        ConfigError: a learner that does not train the run's task, or a baseline (which learns
            from demonstrations) without any.
    """
    if kind in ("", OWN_LEARNER):
        return record
    try:
        chosen = run_learner(kind, record.task)
    except LearningError as err:
        raise ConfigError([str(err)], ["learner"]) from None
    if not record.demonstrations:
        raise ConfigError(
            [f"The {chosen.title} learns from demonstrations; give the run at least one."],
            ["learner"],
        )
    return replace(record, learner=chosen.kind)


BASELINE_SUFFIX = " · no demos"
"""Added to the name of a run's twin without demonstrations (:func:`without_demonstrations`)."""


def without_demonstrations(request: RunRequest, record: RunRecord) -> RunRequest:
    """The same run without its demonstrations, to compare with: the same settings, budget, seed
    and goal (a continuous run's goal is its first demonstration's final pose, kept as such).

    Args:
        request: the run as asked for, with demonstrations.
        record: ``resolve_run(request)``.

    Returns:
        The request of its twin, named ``<name> · no demos``; an unnamed run's twin is named
        after its settings, as runs without a name are listed (``full x20 · no demos``).
    """
    base = request.name or replace(record, demonstrations=[]).label()
    name = base[: 100 - len(BASELINE_SUFFIX)] + BASELINE_SUFFIX
    bare = replace(request, demonstrations=(), grid_paths=(), generated=0, name=name)
    return _TASK_RUNS[record.kind].twin(bare, record)


def task_settings(
    kind: str, settings: Mapping[str, object], given_by: str
) -> dict[str, Mapping[str, object]]:
    """The :class:`RunRequest` field of task ``kind``'s settings among ``settings``: those the
    page's form sets (``given_by="form"``) or a sweep may set (``"sweep"``); none for a kind no
    run trains (:func:`resolve_run` refuses it)."""
    if kind not in TASK_KINDS:
        return {}
    task = learner(kind)
    keys = task.form_keys if given_by == "form" else task.sweep_keys
    return {task.settings_field: {k: settings[k] for k in keys if k in settings}}


def _dynaq_config(
    settings: Mapping[str, object], problems: list[tuple[str, str]]
) -> DynaQConfig | None:
    """The Dyna-Q settings, or None with their problems added to ``problems``."""
    try:
        return DynaQConfig.from_dict(dict(settings))
    except ConfigError as err:
        problems += list(err.by_field.items())
        return None


def _grid(request: RunRequest, problems: list[tuple[str, str]]) -> ArmGrid | None:
    """The arm grid the request sets (a goal in degrees put on its bins), or None with its
    problems added to ``problems``."""
    spec = {**request.grid, "robot": request.robot}
    if spec.get("goal") is not None:
        spec["goal"] = tuple(cast(Sequence[int], spec["goal"]))
    try:
        obstacles = task_obstacles(list(request.obstacles))
    except ConfigError as err:
        problems += list(err.by_field.items())
        return None
    grid = _bare_grid(request, spec, problems)
    if grid is None or not obstacles:
        return grid
    try:
        return replace(grid, obstacles=obstacles)
    except ConfigError as err:
        problems += list(err.by_field.items())
    return None


def _bare_grid(
    request: RunRequest, spec: dict[str, object], problems: list[tuple[str, str]]
) -> ArmGrid | None:
    """:func:`_grid` before its obstacles."""
    try:
        if request.goal_deg is None:
            return ArmGrid(**spec)  # type: ignore[arg-type]
        wrong = goal_problems(request.goal_deg, request.robot)
        if wrong:
            problems += [("goal_deg", text) for text in wrong]
            return None
        if set(spec) - {"bins", "joints", "robot"} or spec.get("joints", 3) != 3:
            problems.append(
                (
                    "goal_deg",
                    "A goal in degrees sets the goal on the paper's 3-joint grid; give goal bins for another grid.",
                )
            )
            return None
        return grid_for_goal(
            request.goal_deg, cast(int, spec.get("bins", ArmGrid.bins)), request.robot
        )
    except ConfigError as err:
        problems += list(err.by_field.items())
    except TypeError as err:
        problems.append(
            (
                "grid",
                f"The grid settings are wrong ({err}); use joints, bins, low_deg, high_deg and goal.",
            )
        )
    except LearningError as err:
        problems.append(("bins", str(err)))
    return None


def _grid_paths(
    request: RunRequest, grid: ArmGrid, problems: list[tuple[str, str]]
) -> list[list[int]]:
    """The grid state paths the run replays: the given ones, then the recorded demonstrations'
    (each must end in the goal bin), then the generated ones."""
    paths = []
    for i, path in enumerate(request.grid_paths):
        bad = next((s for s in path if not is_int(s)), None)
        if bad is not None:
            problems.append(
                (
                    "demonstrations",
                    f"Demonstration {i} holds {bad!r}, not a grid state; give whole state "
                    f"numbers from 0 to {grid.n_states - 1}.",
                )
            )
            continue
        paths.append([int(s) for s in path])
    for demo in request.demonstrations:
        try:
            paths.append(demonstration_grid_path(demo.label, demo.q_robot, grid))
        except LearningError as err:
            problems.append(("demonstrations", str(err)))
    count = request.generated
    if not is_int(count) or count < 0:
        problems.append(
            (
                "demonstrations",
                f"demonstrations is {count!r}; give how many generated demonstrations to replay (0 or more).",
            )
        )
    elif count and not problems:  # (a refused request: nothing to generate them for)
        rng = np.random.default_rng([cast(int, request.seed), GENERATED_DEMO_STREAM])
        paths += generate_demonstrations(grid, count, rng)
    return paths


def _motions(request: RunRequest, problems: list[tuple[str, str]]) -> list[DemonstrationMotion]:
    """The motions of the demonstrations whose times are known (for the likeness card)."""
    motions = []
    for demo in request.demonstrations:
        if demo.times is None:
            continue
        try:
            name = demo.name or demo.label
            motions.append(DemonstrationMotion.checked(name, demo.times, demo.q_robot, demo.label))
        except LearningError as err:
            problems.append(("demonstrations", str(err)))
    return motions


def _budget(request: RunRequest) -> tuple[int, int, int]:
    """The request's experiments, episodes and seed, once :func:`run_problems` found them whole
    numbers (the record checks them again)."""
    return cast(tuple[int, int, int], (request.experiments, request.episodes, request.seed))


def _grid_record(
    request: RunRequest, config: DynaQConfig | None, problems: list[tuple[str, str]]
) -> RunRecord:
    """:func:`resolve_run` for the arm grid."""
    grid = _grid(request, problems)
    problems += run_problems(
        request.experiments, request.episodes, request.seed, request.name, grid
    )
    paths = _grid_paths(request, grid, problems) if grid is not None else []
    motions = _motions(request, problems)
    raise_problems(problems)
    assert grid is not None and config is not None
    return RunRecord.for_arm_grid(
        grid,
        config,
        *_budget(request),
        paths,
        name=request.name,
        origin=request.origin,
        group=request.group,
        goal_deg=request.goal_deg,
        demonstration_names=[d.name for d in request.demonstrations if d.name],
        demonstration_motions=motions,
    )


def _reach_task(
    request: RunRequest, goal: tuple[float, ...] | None, problems: list[tuple[str, str]]
) -> tuple[ArmReach, TileCoding] | None:
    """The continuous task and its tile coding, or None with their problems added."""
    most = min(cast(int, REACH_DEFAULTS["joints"]), task_arm(request.robot).nq)
    settings = {**REACH_DEFAULTS, "joints": most, **request.reach, "robot": request.robot}
    coding_settings = {k: settings.pop(k) for k in CODING_SETTINGS if k in settings}
    if goal is not None:
        settings["goal"] = goal
    if request.obstacles:
        settings["obstacles"] = list(request.obstacles)
    try:
        task = ArmReach.from_dict(settings)
    except ConfigError as err:  # a bad goal is the goal the person typed
        problems += [(k if k != "goal" else "goal_deg", v) for k, v in err.by_field.items()]
        return None
    except TypeError as err:
        problems.append(("task", f"The continuous task's settings are wrong ({err})."))
        return None
    try:
        return task, task.features(**coding_settings)  # type: ignore[arg-type]
    except ConfigError as err:
        problems += list(err.by_field.items())
        return None


def _reach_record(
    request: RunRequest, config: DynaQConfig | None, problems: list[tuple[str, str]]
) -> RunRecord:
    """:func:`resolve_run` for the continuous task. Its goal is the first demonstration's final
    pose, else ``goal_deg`` for joints 1-3 (:func:`goal_pose`), else the task's default."""
    paths = [np.asarray(d.q_robot, dtype=np.float64) for d in request.demonstrations]
    goal: tuple[float, ...] | None = None
    robot = request.robot
    if paths:
        goal = tuple(paths[0][-1])
    elif request.goal_deg is not None:
        wrong = goal_problems(request.goal_deg, robot)
        problems += [("goal_deg", text) for text in wrong]
        if not wrong:
            goal = tuple(goal_pose(request.goal_deg, robot))
    built = _reach_task(request, goal, problems)
    if built is None or config is None:
        raise_problems(
            problems
            + run_problems(request.experiments, request.episodes, request.seed, request.name)
        )
    assert built is not None and config is not None
    task, coding = built  # "follow" without demonstrations is one joint per action
    try:
        record = RunRecord.for_arm_reach(
            task,
            coding,
            config,
            *_budget(request),
            [p[:, : task.joints] for p in paths],
            name=request.name,
            origin=request.origin,
            group=request.group,
            goal_deg=request.goal_deg,
            demonstration_names=[d.name for d in request.demonstrations if d.name],
            demonstration_motions=_motions(request, problems),
        )
    except ConfigError as err:
        raise_problems(problems + list(err.by_field.items()))
        raise
    raise_problems(problems)
    return record


def _reach_twin(bare: RunRequest, record: RunRecord) -> RunRequest:
    """A continuous run's twin keeps its goal: its first demonstration's final pose."""
    return replace(bare, goal_deg=None, reach={**bare.reach, "goal": record.arm_reach().goal})


@dataclass(frozen=True)
class _TaskRuns:
    """How a run of one task kind is resolved (:func:`resolve_run`), and its twin without
    demonstrations from the request stripped of them (:func:`without_demonstrations`)."""

    record: Callable[[RunRequest, DynaQConfig | None, list[tuple[str, str]]], RunRecord]
    twin: Callable[[RunRequest, RunRecord], RunRequest]


_TASK_RUNS = {
    TASK_ARM_GRID: _TaskRuns(_grid_record, lambda bare, record: bare),
    TASK_ARM_REACH: _TaskRuns(_reach_record, _reach_twin),
}
"""Each kind of :data:`TASK_KINDS`: what its runs need beyond what :func:`resolve_run` checks for
all (the task's own settings, its goal, its demonstrations)."""
