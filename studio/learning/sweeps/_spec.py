"""The sweep spec: a TOML file read, checked and expanded into trials.

A sweep asks how learning depends on its settings (planning, alpha, bins, demonstrations, ...)
over several seeds. :func:`load_sweep_spec` reads a spec (the format is documented in
``docs/sweeps.md``), :func:`parse_sweep_spec` checks one given as a mapping (a parsed TOML file,
or ``sweep.json``'s ``spec``), and :meth:`SweepSpec.trials` expands it into its trials.

Every setting is checked by the code that owns it (:class:`DynaQConfig`, :class:`ArmGrid`,
:class:`ArmReach`, :class:`RunRecord`) through :func:`resolve_trial`, the one place a trial's
settings become a run record: for the fixed values, for every listed or endpoint value of the
space, for every trial's combination, and when the trial runs.
"""

from __future__ import annotations

import itertools
import json
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import NotRequired, TypeAlias, TypedDict, cast

import numpy as np

from studio import StudioError, read_toml

from ..._numbers import is_int, is_number
from .._config import TASK_KINDS, DynaQConfig
from .._errors import ConfigError, LearningError
from .._registry import learner
from ..paper._reproduce import CONVERGENCE_FACTOR
from ..runs._record import RunRecord
from ..runs._request import RunRequest, resolve_run, task_settings
from ..tasks._robot import PUMA560

SWEEP_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")
"""A sweep id: a folder name, unique per data folder."""

TASKS = TASK_KINDS
"""Tasks a sweep can train (the run record's ``task.kind``): the paper's grid (tabular) and the
continuous joints (tile-coded linear Dyna-Q)."""
CONFIG_FIELDS = tuple(f.name for f in fields(DynaQConfig))
"""Learning settings: every :class:`DynaQConfig` field."""
RUN_SETTINGS = ("demonstrations",)
"""Run settings of the grid: ``demonstrations`` is the number of generated demonstrations replayed
first (the same generator and seed as ``studio train --generated-demos N``)."""
TASK_SETTINGS = {
    kind: learner(kind).sweep_keys + (RUN_SETTINGS if learner(kind).grid_states else ())
    for kind in TASKS
}
"""The settings a sweep of each task may set: its learner's task settings (the arm grid's joints,
bins, low_deg, high_deg, goal, robot; the continuous task's joints, step_deg, goal, tolerances,
shaping, actions, robot and tile coding), and the grid's generated demonstrations."""
SEARCH_KINDS = ("grid", "random")
DISTRIBUTIONS = ("uniform", "loguniform", "randint")
"""Random-search distributions: ``{uniform = [lo, hi]}``, ``{loguniform = [lo, hi]}``,
``{randint = [lo, hi]}`` (both ends included); a plain list is a uniform choice."""

METRICS = {
    "episodes_to_converge": "first episode (1-based, after the demonstrations) whose 5-episode "
    "moving mean of steps is at most convergence_factor x the grid's mean shortest path; "
    "episodes + 1 when it never gets there",
    "first_episode_steps": "mean steps of the first episode the agent chooses its own actions in",
    "final_steps": "mean steps over the last tenth of the episodes",
    "mean_steps": "mean steps over all episodes (the area under the curve, per episode)",
}
"""What a sweep can measure per trial; all are minimised."""
DEFAULT_METRIC = "episodes_to_converge"

MAX_TRIALS = 100_000
"""Upper bound on the trials of one sweep."""
DEFAULT_CPUS_PER_TRIAL = 1
"""Cores a trial reserves (its experiments run on that many threads)."""
MAX_CPUS_PER_TRIAL = 256
"""Upper bound on ``cpus_per_trial`` (a trial's experiments run on that many threads)."""
DEFAULT_REDUCTION_FACTOR = 3
"""ASHA keeps the best 1/reduction_factor of the trials at each rung."""
TOP_LEVEL = (
    "name",
    "task",
    "seeds",
    "experiments",
    "episodes",
    "cpus_per_trial",
    "fixed",
    "space",
    "search",
    "metric",
    "scheduler",
)
"""The settings a spec may give at its top level."""

Setting: TypeAlias = "str | int | float | bool | list[Setting]"
"""One setting's value as TOML gives it (``planning = "full"``, ``goal = [2, 3]``)."""
Settings: TypeAlias = dict[str, Setting]
"""Settings by name: a spec's ``[fixed]``, or a trial's swept values."""
Distribution: TypeAlias = dict[str, list[float]]
"""A random-search distribution: ``{"uniform": [low, high]}`` (see :data:`DISTRIBUTIONS`)."""
Space: TypeAlias = dict[str, "list[Setting] | Distribution"]
"""A spec's ``[space]``: per swept setting, its values (a list) or a distribution."""


class SweepError(LearningError):
    """A bad sweep spec, an unreachable cluster, or a sweep that cannot continue."""


class SearchDict(TypedDict):
    """``[search]`` as stored in ``sweep.json``."""

    kind: str
    samples: int
    seed: int


class MetricDict(TypedDict):
    """``[metric]`` as stored in ``sweep.json``."""

    name: str
    convergence_factor: float
    level_steps: NotRequired[float]


class SchedulerDict(TypedDict):
    """``[scheduler]`` as stored in ``sweep.json``."""

    kind: str
    grace_episodes: int
    reduction_factor: int


class SpecDict(TypedDict):
    """A spec as JSON-ready values (:meth:`SweepSpec.to_dict`; ``sweep.json``'s ``spec``)."""

    name: str
    task: str
    seeds: list[int]
    experiments: int
    episodes: int
    cpus_per_trial: int
    fixed: Settings
    space: Space
    search: SearchDict
    metric: MetricDict
    scheduler: NotRequired[SchedulerDict]


# ----------------------------------------------------------------------------- the types


@dataclass(frozen=True)
class Trial:
    """One trial: its swept settings and seed.

    Attributes:
        key: ``t0000``, ``t0001``, ... in the order of :meth:`SweepSpec.trials`.
        settings: the swept settings' values of this trial.
        seed: the run's seed.
    """

    key: str
    settings: Settings
    seed: int

    def label(self) -> str:
        """``planning=full, demonstrations=20, seed 3``: the run's name in the page."""
        parts = [f"{name}={show_setting(value)}" for name, value in self.settings.items()]
        return ", ".join([*parts, f"seed {self.seed}"])


@dataclass(frozen=True)
class Scheduler:
    """ASHA early stopping: trials are compared at rungs of ``grace_episodes * rf**i`` episodes
    and only the best ``1 / reduction_factor`` go on."""

    grace_episodes: int
    reduction_factor: int = DEFAULT_REDUCTION_FACTOR

    def milestones(self, episodes: int) -> list[int]:
        """The rungs below ``episodes``, where a trial reports its metric so far."""
        out, k = [], self.grace_episodes
        while k < episodes:
            out.append(k)
            k *= self.reduction_factor
        return out


@dataclass(frozen=True)
class SweepSpec:
    """A checked sweep spec (see ``docs/sweeps.md``); build it with :func:`load_sweep_spec`.

    Attributes:
        name: the sweep id (folder name).
        task: one of :data:`TASKS`.
        fixed: settings every trial shares.
        space: swept settings: lists (grid or choice) or distributions (random search).
        search: ``"grid"`` (every combination) or ``"random"`` (``samples`` draws).
        samples: random search: how many settings are drawn (each runs every seed).
        search_seed: random search: the draws' seed.
        seeds: each combination of settings runs once per seed.
        experiments: experiments per run.
        episodes: episodes per experiment.
        metric: one of :data:`METRICS`.
        convergence_factor: ``episodes_to_converge``'s level, in mean shortest paths.
        level_steps: ``episodes_to_converge``'s level in steps, instead (needed by the
            continuous task, which has no shortest path to scale).
        scheduler: ASHA settings, or None to run every trial to the end.
        cpus_per_trial: cores a trial reserves.
    """

    name: str
    task: str
    fixed: Settings
    space: Space
    seeds: tuple[int, ...]
    experiments: int
    episodes: int
    search: str = "grid"
    samples: int = 1
    search_seed: int = 0
    metric: str = DEFAULT_METRIC
    convergence_factor: float = CONVERGENCE_FACTOR
    level_steps: float | None = None
    scheduler: Scheduler | None = None
    cpus_per_trial: int = DEFAULT_CPUS_PER_TRIAL

    @property
    def swept(self) -> tuple[str, ...]:
        """The swept settings' names, in the spec's order."""
        return tuple(self.space)

    def trials(self) -> list[Trial]:
        """Every trial: settings (grid: every combination; random: seeded draws) x seeds."""
        names = list(self.space)
        if self.search == "grid":
            lists = [cast("list[Setting]", self.space[n]) for n in names]
            combos = [dict(zip(names, values, strict=True)) for values in itertools.product(*lists)]
        else:
            rng = np.random.default_rng(self.search_seed)
            combos = [{n: _draw(self.space[n], rng) for n in names} for _ in range(self.samples)]
        trials = []
        for combo in combos:
            for seed in self.seeds:
                trials.append(Trial(f"t{len(trials):04d}", combo, int(seed)))
        return trials

    def to_dict(self) -> SpecDict:
        """The spec as JSON-ready values (stored in ``sweep.json``; the inverse of
        :func:`parse_sweep_spec`)."""
        metric: MetricDict = {"name": self.metric, "convergence_factor": self.convergence_factor}
        data: SpecDict = {
            "name": self.name,
            "task": self.task,
            "seeds": list(self.seeds),
            "experiments": self.experiments,
            "episodes": self.episodes,
            "cpus_per_trial": self.cpus_per_trial,
            "fixed": self.fixed,
            "space": self.space,
            "search": {"kind": self.search, "samples": self.samples, "seed": self.search_seed},
            "metric": metric,
        }
        if self.level_steps is not None:
            metric["level_steps"] = self.level_steps
        if self.scheduler is not None:
            data["scheduler"] = {
                "kind": "asha",
                "grace_episodes": self.scheduler.grace_episodes,
                "reduction_factor": self.scheduler.reduction_factor,
            }
        return data


def show_setting(value: object) -> str:
    """A setting's value as the page and ``sweep.csv`` show it (a list joined by ``-``)."""
    return "-".join(map(str, value)) if isinstance(value, list | tuple) else f"{value}"


def _draw(values: list[Setting] | Distribution, rng: np.random.Generator) -> Setting:
    if isinstance(values, list):
        return values[int(rng.integers(len(values)))]
    (kind, (low, high)), *_ = values.items()
    if kind == "uniform":
        return float(rng.uniform(low, high))
    if kind == "loguniform":
        return float(np.exp(rng.uniform(np.log(low), np.log(high))))
    return int(rng.integers(low, high + 1))


# ----------------------------------------------------------------------------- one trial


def resolve_trial(
    task: str,
    settings: Mapping[str, object],
    experiments: int,
    episodes: int,
    seed: int,
    *,
    name: str = "",
    group: str | None = None,
) -> RunRecord:
    """The run record of one trial: its task and learning ``settings`` (fixed and swept
    together), budget and seed, resolved by the code that owns each setting. This is the one
    place a sweep turns settings into a run.

    The grid's generated demonstrations (``settings["demonstrations"]``) are drawn from the
    trial's seed, as ``studio train --generated-demos N`` draws them.

    Raises:
        ConfigError, LearningError: a setting its owner refuses.
    """
    request = RunRequest(
        task=task,
        robot=str(settings.get("robot", PUMA560)),  # both tasks' field, fixed or swept
        config=_pick(settings, CONFIG_FIELDS),
        **task_settings(task, settings, "sweep"),
        experiments=experiments,
        episodes=episodes,
        seed=seed,
        generated=settings.get("demonstrations", 0),
        name=name,
        origin="sweep",
        group=group,
    )
    return resolve_run(request)


def _pick(settings: Mapping[str, object], names: tuple[str, ...]) -> dict[str, object]:
    """The settings among ``names`` (those one owner checks)."""
    return {k: v for k, v in settings.items() if k in names}


def trial_record(spec: SweepSpec, trial: Trial) -> RunRecord:
    """The run record of a trial: fixed and swept settings, its seed, generated demonstrations."""
    return resolve_trial(
        spec.task,
        {**spec.fixed, **trial.settings},
        spec.experiments,
        spec.episodes,
        trial.seed,
        name=f"{spec.name}: {trial.label()}",
        group=spec.name,
    )


def _check(
    task: str,
    settings: Mapping[str, object],
    where: str,
    experiments: object = 1,
    episodes: object = 1,
    seed: object = 0,
) -> None:
    """Resolve the run record a trial with these settings would build, turning a refusal into a
    SweepError naming ``where``."""
    try:
        resolve_trial(task, settings, experiments, episodes, seed)
    except ConfigError as err:
        raise SweepError(f"{where}: {err.problems[0]}") from None
    except LearningError as err:
        raise SweepError(f"{where}: {err}") from None


# ----------------------------------------------------------------------------- reading a spec


def load_sweep_spec(path: Path | str, name: str | None = None) -> SweepSpec:
    """Read and check a TOML sweep spec.

    Args:
        path: the ``.toml`` file.
        name: the sweep id; default the spec's ``name``, else the file's stem.

    Raises:
        SweepError: one sentence naming the file, the field and the fix.
    """
    path = Path(path)
    if not path.exists():
        raise SweepError(f"The sweep spec {path} does not exist; check the path.")
    try:
        data = read_toml(path, f"The sweep spec {path}")
    except StudioError as err:  # too big, not a file, not UTF-8, not TOML, too deep
        raise SweepError(str(err)) from None
    data.setdefault("name", path.stem)
    if name is not None:
        data["name"] = name
    return parse_sweep_spec(data, path.name)


def parse_sweep_spec(data: Mapping[str, object], source: str = "the sweep spec") -> SweepSpec:
    """Check a spec given as a mapping (a parsed TOML file, or ``sweep.json``'s ``spec``).

    Every setting is checked by the code that owns it (:class:`DynaQConfig`, :class:`ArmGrid`,
    :class:`RunRecord`, so the budget and the seed too), for the fixed values, for every listed
    or endpoint value of the space, and for every trial's combination.

    Raises:
        SweepError: one sentence naming ``source``, the field and the fix.
    """
    name, task = _name_and_task(data, source)
    fixed, space = _fixed_and_space(data, task, source)
    kind, samples, search_seed = _search(_table(data, "search", source), source)
    seeds = _seeds(data.get("seeds", [0]), space, kind, samples, source)
    experiments, episodes, cpus = _budget(data, source)
    for seed in seeds:  # the run-level checks (budget, seed) of the fixed settings
        _check(task, fixed, f"{source} seeds", experiments, episodes, seed)
    _check_space(task, fixed, space, kind, (experiments, episodes, seeds[0]), source)
    metric, factor, level = _metric(_table(data, "metric", source), task, source)
    scheduler = _scheduler(data, episodes, source) if "scheduler" in data else None
    spec = SweepSpec(
        name=name,
        task=task,
        fixed=fixed,
        space=space,
        seeds=tuple(int(s) for s in seeds),
        experiments=int(experiments),
        episodes=int(episodes),
        search=kind,
        samples=int(samples),
        search_seed=int(search_seed),
        metric=metric,
        convergence_factor=float(factor),
        level_steps=None if level is None else float(level),
        scheduler=scheduler,
        cpus_per_trial=int(cpus),
    )
    for trial in spec.trials():  # combinations can fail where single values pass (table size)
        _check(
            task,
            {**fixed, **trial.settings},
            f"{source} trial {trial.key} ({trial.label()})",
            spec.experiments,
            spec.episodes,
            trial.seed,
        )
    return spec


def _table(data: Mapping[str, object], key: str, source: str) -> dict[str, object]:
    value = data.get(key, {})
    if not isinstance(value, dict):
        raise SweepError(f"{source}: {key} must be a table ([{key}]), not {value!r}.")
    return dict(value)


def _refuse_unknown(table: Mapping[str, object], known: tuple[str, ...], where: str) -> None:
    for key in table:
        if key not in known:
            raise SweepError(
                f"{where} has an unknown setting {key!r}; use {', '.join(known[:-1])} and {known[-1]}."
            )


def _name_and_task(data: Mapping[str, object], source: str) -> tuple[str, str]:
    unknown = sorted(set(data) - set(TOP_LEVEL))
    if unknown:
        raise SweepError(
            f"{source} has an unknown top-level setting {unknown[0]!r}; use {', '.join(TOP_LEVEL)} (swept settings go under [space], shared ones under [fixed])."
        )
    name = data.get("name")
    if not isinstance(name, str) or not SWEEP_ID.match(name):
        raise SweepError(
            f"{source}: name is {name!r}; give 1 to 64 letters, digits, '.', '_' or '-', starting with a letter or digit."
        )
    task = data.get("task")
    if task is None:
        raise SweepError(
            f"{source} names no task; add task = {TASKS[0]!r} (the paper's arm grid) at the top."
        )
    if task not in TASKS:
        raise SweepError(f"{source}: task is {task!r}; give one of {', '.join(TASKS)}.")
    return name, str(task)


def _fixed_and_space(data: Mapping[str, object], task: str, source: str) -> tuple[Settings, Space]:
    settings = CONFIG_FIELDS + TASK_SETTINGS[task]
    fixed, space = _table(data, "fixed", source), _table(data, "space", source)
    for where, values in (("fixed", fixed), ("space", space)):
        for key in values:
            if key not in settings:
                raise SweepError(
                    f"{source} [{where}] has an unknown setting {key!r}; use one of {', '.join(settings)}."
                )
    both = sorted(set(fixed) & set(space))
    if both:
        raise SweepError(
            f"{source}: {both[0]} is both fixed and swept; keep it in [fixed] or in [space], not both."
        )
    if not space:
        raise SweepError(
            f'{source} has an empty [space]; sweep at least one setting, e.g. planning = ["zero", "full"].'
        )
    return cast(Settings, fixed), cast(Space, space)  # each value is checked by its owner


def _search(search: Mapping[str, object], source: str) -> tuple[str, int, int]:
    """``[search]``: its kind, samples and seed."""
    _refuse_unknown(search, ("kind", "samples", "seed"), f"{source} [search]")
    kind = search.get("kind", "grid")
    if kind not in SEARCH_KINDS:
        raise SweepError(f"{source} [search] kind is {kind!r}; give grid or random.")
    samples = search.get("samples", 1 if kind == "grid" else None)
    if kind == "random" and (not is_int(samples) or not 1 <= samples <= MAX_TRIALS):
        raise SweepError(
            f"{source} [search] samples is {samples!r}; random search needs a whole number of draws from 1 to {MAX_TRIALS:,}."
        )
    search_seed = search.get("seed", 0)
    if not is_int(search_seed) or search_seed < 0:
        raise SweepError(f"{source} [search] seed is {search_seed!r}; give a whole number >= 0.")
    return str(kind), cast(int, samples), search_seed


def _seeds(seeds: object, space: Space, kind: str, samples: int, source: str) -> list[int]:
    """The seeds (a list, or how many), once the trial count is known to be within bounds."""
    # Count the trials before anything is listed: seeds = 1000000000 must not build that list.
    seed_count = seeds if is_int(seeds) else len(seeds) if isinstance(seeds, list) else 0
    combos = math.prod(len(v) if isinstance(v, list) else 1 for v in space.values())
    count = (combos if kind == "grid" else samples) * seed_count
    if count > MAX_TRIALS:
        raise SweepError(
            f"{source} makes {count:,} trials, over the limit of {MAX_TRIALS:,}; sweep fewer values or seeds."
        )
    if is_int(seeds) and seeds >= 1:
        seeds = list(range(seeds))
    if not isinstance(seeds, list) or not seeds:
        raise SweepError(
            f"{source}: seeds is {seeds!r}; give a list of seeds such as [0, 1, 2], or how many (3)."
        )
    if len(set(map(str, seeds))) != len(seeds):
        raise SweepError(f"{source}: seeds lists a seed twice; give distinct seeds.")
    return seeds  # each seed is checked by the run record


def _budget(data: Mapping[str, object], source: str) -> tuple[int, int, int]:
    """Experiments and episodes per trial (checked by the run record), and cores per trial."""
    experiments = data.get("experiments")
    episodes = data.get("episodes")
    for key, value in (("experiments", experiments), ("episodes", episodes)):
        if value is None:
            raise SweepError(
                f"{source} gives no {key}; add {key} = N at the top (per trial's run)."
            )
    cpus = data.get("cpus_per_trial", DEFAULT_CPUS_PER_TRIAL)
    if not is_int(cpus) or not 1 <= cpus <= MAX_CPUS_PER_TRIAL:
        raise SweepError(
            f"{source}: cpus_per_trial is {cpus!r}; give a whole number of cores from 1 to {MAX_CPUS_PER_TRIAL}."
        )
    return cast(int, experiments), cast(int, episodes), cpus


def _check_space(
    task: str, fixed: Settings, space: Space, kind: str, run: tuple[int, int, int], source: str
) -> None:
    """Every listed value, and both ends of every distribution, checked by its owner."""
    for key, values in space.items():
        where = f"{source} [space] {key}"
        if isinstance(values, list):
            if not values:
                raise SweepError(f"{where} is an empty list; give at least one value.")
            for value in values:
                _check(task, {**fixed, key: value}, f"{where} = {_toml(value)}", *run)
        elif isinstance(values, dict):
            if kind == "grid":
                raise SweepError(
                    f'{where} is a distribution; grid search needs a list of values, or set kind = "random" under [search].'
                )
            _check_distribution(task, fixed, key, values, where, run)
        else:
            raise SweepError(
                f"{where} is {values!r}; give a list of values (or a distribution such as {{uniform = [0.05, 0.5]}} with random search)."
            )


def _toml(value: object) -> str:
    return json.dumps(value) if isinstance(value, str | list) else f"{value}"


def _check_distribution(
    task: str,
    fixed: Settings,
    key: str,
    values: Mapping[str, object],
    where: str,
    run: tuple[int, int, int],
) -> None:
    if len(values) != 1 or next(iter(values)) not in DISTRIBUTIONS:
        raise SweepError(
            f"{where} is {values!r}; give one of {', '.join(f'{{{d} = [low, high]}}' for d in DISTRIBUTIONS)}, or a list of values."
        )
    (kind, bounds), *_ = values.items()
    numbers = is_int if kind == "randint" else is_number
    if (
        not isinstance(bounds, list)
        or len(bounds) != 2
        or not all(numbers(b) for b in bounds)
        or not bounds[0] < bounds[1]
    ):
        raise SweepError(
            f"{where} {kind} is {bounds!r}; give [low, high] with low below high{' (whole numbers)' if kind == 'randint' else ''}."
        )
    if kind == "loguniform" and bounds[0] <= 0:
        raise SweepError(f"{where} loguniform starts at {bounds[0]}; give a low end above 0.")
    for bound in bounds:  # the setting's owner checks both ends of the range
        value = float(bound) if kind != "randint" else int(bound)
        _check(task, {**fixed, key: value}, f"{where} {kind} end {bound}", *run)


def _metric(table: Mapping[str, object], task: str, source: str) -> tuple[str, float, float | None]:
    """``[metric]``: its name, convergence factor and level in steps (or None)."""
    _refuse_unknown(table, ("name", "convergence_factor", "level_steps"), f"{source} [metric]")
    metric = table.get("name", DEFAULT_METRIC)
    if metric not in METRICS:
        raise SweepError(f"{source} [metric] name is {metric!r}; give one of {', '.join(METRICS)}.")
    factor = table.get("convergence_factor", CONVERGENCE_FACTOR)
    if not is_number(factor) or factor <= 0:
        raise SweepError(
            f"{source} [metric] convergence_factor is {factor!r}; give a number above 0."
        )
    level = table.get("level_steps")
    if level is not None and (not is_number(level) or level <= 0):
        raise SweepError(f"{source} [metric] level_steps is {level!r}; give a number above 0.")
    if metric == "episodes_to_converge" and level is None and not learner(task).shortest_paths:
        raise SweepError(
            f"{source} [metric] episodes_to_converge on the {task} task needs level_steps (mean steps per episode that count as converged); add it, or choose another metric."
        )
    return str(metric), factor, level


def _scheduler(data: Mapping[str, object], episodes: int, source: str) -> Scheduler:
    """``[scheduler]``: ASHA's grace period and reduction factor."""
    sched = _table(data, "scheduler", source)
    keys = ("kind", "grace_episodes", "reduction_factor")
    _refuse_unknown(sched, keys, f"{source} [scheduler]")
    if sched.get("kind", "asha") != "asha":
        raise SweepError(
            f'{source} [scheduler] kind is {sched.get("kind")!r}; the one scheduler is "asha".'
        )
    grace = sched.get("grace_episodes", max(1, episodes // 10))
    if not is_int(grace) or not 1 <= grace <= episodes:
        raise SweepError(
            f"{source} [scheduler] grace_episodes is {grace!r}; give a whole number from 1 to the {episodes} episodes."
        )
    rf = sched.get("reduction_factor", DEFAULT_REDUCTION_FACTOR)
    if not is_int(rf) or rf < 2:
        raise SweepError(
            f"{source} [scheduler] reduction_factor is {rf!r}; give a whole number of at least 2."
        )
    return Scheduler(int(grace), int(rf))
