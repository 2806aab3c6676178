"""Parameter sweeps on Ray Tune: a TOML spec in, one ordinary run per trial out, a summary beside.

A sweep asks how learning depends on its settings (planning, alpha, bins, demonstrations, ...)
over several seeds. :func:`load_sweep_spec` reads and checks a spec (the format is documented in
``docs/sweeps.md``); :func:`run_sweep` runs its trials on Ray Tune, on a local Ray using the
machine's cores or on an existing cluster (``address``). Tune brings the scheduling, the retries
of a trial whose worker died, and the optional ASHA early stopping; this module brings:

- **Trials as ordinary runs.** Each trial trains through :class:`RunFolder` (the one writer of run
  folders) into ``<data>/runs/<sweep>/<sweep>-<trial>/``, with ``origin="sweep"`` and
  ``group=<sweep>``, so the page lists, plots, watches and exports it like any run.
- **The sweep folder** ``<data>/sweeps/<sweep>/``: ``sweep.json`` (the spec, its trials, status),
  ``trials/<trial>.json`` (written by the driver when a trial ends: where it ran, i.e. Ray node,
  hostname and worker pid, attempts, times),
  ``sweep.csv`` (one row per trial: settings, metrics, CPU and wall time), ``sweep.png``/``.svg``
  (the metric against the first swept setting, mean and standard error over seeds) and ``ray/``
  (Tune's own bookkeeping).
- **Resumption by our own check**: a trial is finished when its record says ``done`` or
  ``early-stopped`` and its run folder reads back. ``resume=True`` runs only the others, so a sweep
  survives Ctrl-C, a killed driver or a lost cluster alike (Tune's experiment state does not
  survive a killed driver reliably, our records do).

Ray is an optional dependency (``pip install -e '.[cluster]'``), imported only when a sweep runs.
On a multi-machine cluster the data folder must be on storage every node sees at the same path
(as Ray Tune itself requires of its ``storage_path``).
"""

from __future__ import annotations

import contextlib
import csv
import io
import itertools
import json
import logging
import math
import os
import re
import shutil
import socket
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np

from studio import (
    MAX_JSON_BYTES,
    StudioError,
    is_loopback,
    read_bytes_bounded,
    read_json,
    read_toml,
)

from .._files import atomic_write_text, now_iso
from .._numbers import is_int, is_number
from ._arm import ArmGrid
from ._config import DynaQConfig
from ._curves import curve_statistics
from ._dynaq import LiveProgress
from ._errors import ConfigError, LearningError
from ._owner import pid_alive, this_host
from ._reach import ArmReach
from ._reproduce import (
    CONVERGENCE_FACTOR,
    _standard_error,
    episodes_to_converge,
    generate_demonstrations,
)
from ._run_record import TASK_ARM_GRID, TASK_ARM_REACH, RunRecord
from ._runs import RunFolder

SWEEP_FORMAT = "teach-studio-sweep"
"""The ``format`` field of ``sweep.json``."""
SWEEP_VERSION = 1
SWEEPS_DIR = "sweeps"
"""Sweep folders live in ``<data>/sweeps/<id>/``."""
RUNS_DIR = "runs"
"""Trial runs live in ``<data>/runs/<id>/<id>-<trial>/``."""
SWEEP_FILE = "sweep.json"
TRIALS_DIR = "trials"
SUMMARY_FILE = "sweep.csv"
FIGURE_STEM = "sweep"
RAY_DIR = "ray"
SWEEP_ID = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")
"""A sweep id: a folder name, unique per data folder."""

TASKS = (TASK_ARM_GRID, TASK_ARM_REACH)
"""Tasks a sweep can train (the run record's ``task.kind``): the paper's grid (tabular) and the
continuous joints (tile-coded linear Dyna-Q)."""
GRID_FIELDS = tuple(f.name for f in fields(ArmGrid))
"""Task settings of the arm grid: joints, bins, low_deg, high_deg, goal."""
REACH_FIELDS = tuple(f.name for f in fields(ArmReach))
"""Task settings of the continuous joints: joints, step_deg, goal, tolerances, shaping."""
CODING_SETTINGS = ("tilings", "tiles", "size")
"""The continuous task's tile coding (:meth:`ArmReach.features`, as the page and CLI build it)."""
CONFIG_FIELDS = tuple(f.name for f in fields(DynaQConfig))
"""Learning settings: every :class:`DynaQConfig` field."""
RUN_SETTINGS = ("demonstrations",)
"""Run settings of the grid: ``demonstrations`` is the number of generated demonstrations replayed
first (the same generator and seed as ``studio train --generated-demos N``)."""
TASK_SETTINGS = {
    TASK_ARM_GRID: GRID_FIELDS + RUN_SETTINGS,
    TASK_ARM_REACH: REACH_FIELDS + CODING_SETTINGS,
}
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
FINAL_FRACTION = 0.1
"""``final_steps`` averages this fraction of the last episodes (at least one)."""
DEMO_SEED_STREAM = 1
"""Generated demonstrations draw from ``default_rng([seed, 1])``, as ``studio train`` does."""

MAX_TRIALS = 100_000
"""Upper bound on the trials of one sweep."""
DEFAULT_CPUS_PER_TRIAL = 1
"""Cores a trial reserves (its experiments run on that many threads)."""
MAX_CPUS_PER_TRIAL = 256
"""Upper bound on ``cpus_per_trial`` (a trial's experiments run on that many threads)."""
MAX_RETRIES = 3
"""A trial whose worker dies (a crash, a lost node, ``kill -9``) is run again up to this often."""
DEFAULT_REDUCTION_FACTOR = 3
"""ASHA keeps the best 1/reduction_factor of the trials at each rung."""
ADDRESS_TIMEOUT_SECONDS = 5.0
"""How long to try to reach a cluster's ``HOST:PORT`` before calling it unreachable."""
RAY_HINT = "install it with pip install -e '.[cluster]'"
STOP_WAIT_SECONDS = 300
"""How long a worker whose trial the scheduler stopped waits for the trial to save its run (the
learners end at their next episode boundary) before Tune gives up re-using the worker for the next
trial, which would then fail. Tune's own default, 2 s, is shorter than one episode of a big trial."""
TUNE_SNAPSHOT_SECONDS = 600
"""At most how often Tune snapshots its experiment state while a sweep runs (its default is every
10 s, longer for big sweeps). A sweep resumes from its own records (:func:`finished_trials`), not
from Tune's snapshot, so these writes only cost the driver time."""
RAY_ENVIRONMENT = {
    "RAY_USAGE_STATS_ENABLED": "0",  # never phone home
    "RAY_AIR_NEW_OUTPUT": "0",  # the classic reporter honours verbose=0: our bar is the output
    "TUNE_DISABLE_AUTO_CALLBACK_LOGGERS": "1",  # no CSV/JSON/TensorBoard copies of the metrics
    "TUNE_FUNCTION_THREAD_TIMEOUT_S": str(STOP_WAIT_SECONDS),  # read by each worker
    "TUNE_GLOBAL_CHECKPOINT_S": str(TUNE_SNAPSHOT_SECONDS),  # read by the driver
}
"""Set (unless already set) before Ray is imported, in the driver and in every worker (a cluster's
workers do not inherit the driver's environment)."""
LOCAL_RAY_ENVIRONMENT = {"RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0"}
"""Set (always) before Ray is imported when the sweep starts its own Ray. This is Ray's switch for
a single-machine Ray: the node's address is then loopback, so the GCS, the raylet, the workers and
the agents all listen on 127.0.0.1 only. Without it every one of them listens on all interfaces,
and anyone who reaches the machine could join the Ray and run code as the user. (Ray turns
``ray.init(_node_ip_address="127.0.0.1")`` back into the machine's network address, so that is no
way to do it.) Set while Ray is imported and while it starts its processes, which inherit it;
then put back, so that nothing else the process starts inherits it."""


class SweepError(LearningError):
    """A bad sweep spec, an unreachable cluster, or a sweep that cannot continue."""


# ----------------------------------------------------------------------------- the spec


@dataclass(frozen=True)
class Trial:
    """One trial: its swept settings and seed.

    Attributes:
        key: ``t0000``, ``t0001``, ... in the order of :meth:`SweepSpec.trials`.
        settings: the swept settings' values of this trial.
        seed: the run's seed.
    """

    key: str
    settings: dict[str, Any]
    seed: int

    def label(self) -> str:
        """``planning=full, demonstrations=20, seed 3``: the run's name in the page."""
        parts = [f"{name}={_show(value)}" for name, value in self.settings.items()]
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
    fixed: dict[str, Any]
    space: dict[str, Any]
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
            combos = [
                dict(zip(names, values, strict=True))
                for values in itertools.product(*(self.space[n] for n in names))
            ]
        else:
            rng = np.random.default_rng(self.search_seed)
            combos = [{n: _draw(self.space[n], rng) for n in names} for _ in range(self.samples)]
        trials = []
        for combo in combos:
            for seed in self.seeds:
                trials.append(Trial(f"t{len(trials):04d}", combo, int(seed)))
        return trials

    def to_dict(self) -> dict[str, Any]:
        """The spec as JSON-ready values (stored in ``sweep.json``; the inverse of
        :func:`parse_sweep_spec`)."""
        data: dict[str, Any] = {
            "name": self.name,
            "task": self.task,
            "seeds": list(self.seeds),
            "experiments": self.experiments,
            "episodes": self.episodes,
            "cpus_per_trial": self.cpus_per_trial,
            "fixed": self.fixed,
            "space": self.space,
            "search": {"kind": self.search, "samples": self.samples, "seed": self.search_seed},
            "metric": {"name": self.metric, "convergence_factor": self.convergence_factor},
        }
        if self.level_steps is not None:
            data["metric"]["level_steps"] = self.level_steps
        if self.scheduler is not None:
            data["scheduler"] = {
                "kind": "asha",
                "grace_episodes": self.scheduler.grace_episodes,
                "reduction_factor": self.scheduler.reduction_factor,
            }
        return data


def _show(value: Any) -> str:
    return "-".join(map(str, value)) if isinstance(value, list | tuple) else f"{value}"


def _draw(values: Any, rng: np.random.Generator) -> Any:
    if isinstance(values, list):
        return values[int(rng.integers(len(values)))]
    (kind, (low, high)), *_ = values.items()
    if kind == "uniform":
        return float(rng.uniform(low, high))
    if kind == "loguniform":
        return float(np.exp(rng.uniform(np.log(low), np.log(high))))
    return int(rng.integers(low, high + 1))


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


def parse_sweep_spec(data: Mapping[str, Any], source: str = "the sweep spec") -> SweepSpec:
    """Check a spec given as a mapping (a parsed TOML file, or ``sweep.json``'s ``spec``).

    Every setting is checked by the code that owns it (:class:`DynaQConfig`, :class:`ArmGrid`,
    :class:`RunRecord`, so the budget and the seed too), for the fixed values, for every listed
    or endpoint value of the space, and for every trial's combination.

    Raises:
        SweepError: one sentence naming ``source``, the field and the fix.
    """
    top = (
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
    unknown = sorted(set(data) - set(top))
    if unknown:
        raise SweepError(
            f"{source} has an unknown top-level setting {unknown[0]!r}; use {', '.join(top)} (swept settings go under [space], shared ones under [fixed])."
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
    settings = _settings_of(task)

    def table(key: str) -> dict[str, Any]:
        value = data.get(key, {})
        if not isinstance(value, dict):
            raise SweepError(f"{source}: {key} must be a table ([{key}]), not {value!r}.")
        return dict(value)

    fixed, space = table("fixed"), table("space")
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

    search = table("search")
    for key in search:
        if key not in ("kind", "samples", "seed"):
            raise SweepError(
                f"{source} [search] has an unknown setting {key!r}; use kind, samples and seed."
            )
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

    seeds = data.get("seeds", [0])
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
    for seed in seeds:  # the run-level checks (budget, seed) of the fixed settings
        _check(task, fixed, f"{source} seeds", experiments, episodes, seed)

    run = (experiments, episodes, seeds[0])

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

    metric_table = table("metric")
    for key in metric_table:
        if key not in ("name", "convergence_factor", "level_steps"):
            raise SweepError(
                f"{source} [metric] has an unknown setting {key!r}; use name, convergence_factor and level_steps."
            )
    metric = metric_table.get("name", DEFAULT_METRIC)
    if metric not in METRICS:
        raise SweepError(f"{source} [metric] name is {metric!r}; give one of {', '.join(METRICS)}.")
    factor = metric_table.get("convergence_factor", CONVERGENCE_FACTOR)
    if not is_number(factor) or factor <= 0:
        raise SweepError(
            f"{source} [metric] convergence_factor is {factor!r}; give a number above 0."
        )
    level = metric_table.get("level_steps")
    if level is not None and (not is_number(level) or level <= 0):
        raise SweepError(f"{source} [metric] level_steps is {level!r}; give a number above 0.")
    if metric == "episodes_to_converge" and level is None and task != TASK_ARM_GRID:
        raise SweepError(
            f"{source} [metric] episodes_to_converge on the {task} task needs level_steps (mean steps per episode that count as converged); add it, or choose another metric."
        )

    scheduler = None
    if "scheduler" in data:
        sched = table("scheduler")
        for key in sched:
            if key not in ("kind", "grace_episodes", "reduction_factor"):
                raise SweepError(
                    f"{source} [scheduler] has an unknown setting {key!r}; use kind, grace_episodes and reduction_factor."
                )
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
        scheduler = Scheduler(int(grace), int(rf))

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


def _settings_of(task: str) -> tuple[str, ...]:
    return CONFIG_FIELDS + TASK_SETTINGS[task]


def _toml(value: Any) -> str:
    return json.dumps(value) if isinstance(value, str | list) else f"{value}"


def _check_distribution(
    task: str, fixed: dict[str, Any], key: str, values: dict[str, Any], where: str, run: tuple
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


def _check(
    task: str,
    settings: Mapping[str, Any],
    where: str,
    experiments: Any = 1,
    episodes: Any = 1,
    seed: Any = 0,
) -> None:
    """Build the run record a trial with these settings would build (its task, settings, budget,
    seed), turning a refusal into a SweepError naming ``where``."""
    try:
        _record(task, settings, experiments, episodes, seed, demonstrations=None)
    except ConfigError as err:
        raise SweepError(f"{where}: {err.problems[0]}") from None
    except LearningError as err:
        raise SweepError(f"{where}: {err}") from None


def _record(
    task: str,
    settings: Mapping[str, Any],
    experiments: Any,
    episodes: Any,
    seed: Any,
    demonstrations: np.random.Generator | None,
    **names: Any,
) -> RunRecord:
    """A trial's run record; ``demonstrations`` draws the generated demonstrations (None: check
    only, the goal state standing in for each path, since only their count is checked)."""
    config = DynaQConfig.from_dict({k: v for k, v in settings.items() if k in CONFIG_FIELDS})
    if task == TASK_ARM_REACH:
        reach = ArmReach.from_dict({k: v for k, v in settings.items() if k in REACH_FIELDS})
        coding = reach.features(**{k: v for k, v in settings.items() if k in CODING_SETTINGS})
        return RunRecord.for_arm_reach(
            reach, coding, config, experiments, episodes, seed, origin="sweep", **names
        )
    grid_spec = {k: v for k, v in settings.items() if k in GRID_FIELDS}
    if isinstance(grid_spec.get("goal"), list):
        grid_spec["goal"] = tuple(grid_spec["goal"])
    grid = ArmGrid(**grid_spec)
    count = settings.get("demonstrations", 0)
    if not is_int(count) or count < 0:
        raise LearningError(
            f"demonstrations is {count!r}; give how many generated demonstrations to replay (0 or more)."
        )
    if demonstrations is None:
        paths = [[grid.goal_state]] * count
    else:
        paths = generate_demonstrations(grid, count, demonstrations) if count else []
    return RunRecord.for_arm_grid(
        grid, config, experiments, episodes, seed, paths, origin="sweep", **names
    )


# ----------------------------------------------------------------------------- one trial


def trial_record(spec: SweepSpec, trial: Trial) -> RunRecord:
    """The run record of a trial: fixed and swept settings, its seed, generated demonstrations."""
    return _record(
        spec.task,
        {**spec.fixed, **trial.settings},
        spec.experiments,
        spec.episodes,
        trial.seed,
        np.random.default_rng([trial.seed, DEMO_SEED_STREAM]),
        name=f"{spec.name}: {trial.label()}",
        group=spec.name,
    )


def trial_metrics(
    steps: np.ndarray,
    record: RunRecord,
    convergence_factor: float,
    level_steps: float | None = None,
) -> dict:
    """Every metric of :data:`METRICS` from a run's steps, over the episodes all experiments
    finished (a stopped or early-stopped run counts what it did). ``episodes_to_converge``'s level
    is ``level_steps`` when given, else ``convergence_factor`` x the grid's mean shortest path
    (NaN for the continuous task without ``level_steps``)."""
    steps = np.asarray(steps)
    done = int((steps >= 0).all(axis=0).cumprod().sum())
    start = min(len(record.demonstrations), done)
    out: dict[str, Any] = {"episodes_done": done}
    if done == 0:
        return {**out, **{name: math.nan for name in METRICS}}
    mean = np.asarray(curve_statistics(steps[:, :done])["mean"], dtype=np.float64)
    if level_steps is not None:
        level = level_steps
    elif record.kind == TASK_ARM_GRID:
        level = convergence_factor * record.arm_grid().mean_shortest_steps()
    else:
        level = math.nan
    converged = episodes_to_converge(mean, level, start) if not math.isnan(level) else None
    tail = max(1, int(np.ceil(done * FINAL_FRACTION)))
    if math.isnan(level):
        out["episodes_to_converge"] = math.nan
    else:
        out["episodes_to_converge"] = float(converged if converged is not None else done + 1)
    out["converged"] = converged is not None
    out["first_episode_steps"] = float(mean[start]) if start < done else math.nan
    out["final_steps"] = float(mean[-tail:].mean())
    out["mean_steps"] = float(mean.mean())
    return out


def trial_run_path(data_dir: Path, sweep_id: str, key: str) -> Path:
    """Where a trial's run folder lives."""
    return Path(data_dir) / RUNS_DIR / sweep_id / f"{sweep_id}-{key}"


@dataclass(frozen=True)
class _Job:
    """What every trial of a sweep shares (sent once to the cluster). The spec goes as the checked
    :class:`SweepSpec`: checking it again costs every trial time that grows with the sweep's
    size (each trial's combination is checked: 0.15 s per trial for a 1,000-trial sweep)."""

    spec: SweepSpec
    trials: dict[str, Trial]
    data_dir: str
    milestones: tuple[int, ...]


def _trainable(config: dict[str, Any], job: _Job) -> None:
    """Tune's trial function: train one trial as an ordinary run and report its metrics.

    Every report says where the trial runs (Ray node, hostname, worker pid). When Tune stops the
    trial (ASHA, Ctrl-C), its ``tune.report`` raises ``SystemExit``: the run stops at the next
    episode boundary and saves what it learnt, then the ``SystemExit`` goes on up, which is how
    Tune knows the trial ended and can re-use this worker for the next trial.
    """
    from ray import tune

    _set_ray_environment()  # in this worker too: e.g. how long a re-used worker waits for a stop
    spec = job.spec
    trial = job.trials[config["key"]]
    record = trial_record(spec, trial)
    path = trial_run_path(Path(job.data_dir), spec.name, trial.key)
    if path.exists():  # an earlier attempt died (a killed worker, a lost node): start over
        shutil.rmtree(path)
    host = this_host()
    where = {"node": host["node"], "hostname": host["hostname"], "pid": os.getpid()}
    start = time.perf_counter()
    run = RunFolder.create(path.parent, record, name=path.name, status="running")
    live = LiveProgress(spec.experiments, spec.episodes)
    pending = list(job.milestones)
    stopped: list[SystemExit] = []

    def on_checkpoint(live: LiveProgress) -> None:
        if not pending or stopped:
            return
        done = int((live.steps >= 0).all(axis=0).cumprod().sum())
        while pending and done >= pending[0]:
            k = pending.pop(0)
            metrics = trial_metrics(
                live.steps[:, :k], record, spec.convergence_factor, spec.level_steps
            )
            try:
                tune.report({**metrics, "episodes": k, "final": False, **where})
            except SystemExit as stop:  # Tune stopped the trial (ASHA, or Ctrl-C)
                live.stop()
                stopped.append(stop)
                return

    run.train(live, workers=spec.cpus_per_trial, on_checkpoint=on_checkpoint)
    if stopped:
        # Saved. A normal return would report once more and wait forever for Tune's answer, so
        # the worker could not be re-used: the SystemExit tells Tune the trial ended.
        raise stopped[0]
    if run.status == "failed":
        raise SweepError(f"Trial {trial.key} failed: {run.error}")
    metrics = trial_metrics(run.steps(), record, spec.convergence_factor, spec.level_steps)
    tune.report(
        {
            **metrics,
            "episodes": spec.episodes,
            "final": True,
            **where,
            "cpu_seconds": run.cpu_seconds,
            "wall_seconds": time.perf_counter() - start,
        }
    )


# ----------------------------------------------------------------------------- the sweep folder


@dataclass
class SweepProgress:
    """What the terminal shows while a sweep runs.

    Attributes:
        total: trials of the sweep.
        done: trials finished (also those finished before a resume).
        running: trials running now.
        failed: trials that failed after their retries.
        best: the best metric value so far, and its trial's label.
    """

    total: int
    done: int = 0
    running: int = 0
    failed: int = 0
    best: tuple[float, str] | None = None


@dataclass
class SweepResult:
    """What :func:`run_sweep` returns.

    Attributes:
        folder: the sweep folder.
        spec: the spec.
        rows: ``sweep.csv``'s rows.
        ran: keys of the trials run in this call.
        interrupted: whether the sweep stopped before every trial finished.
        failed: keys of the trials that failed after their retries.
    """

    folder: Path
    spec: SweepSpec
    rows: list[dict[str, Any]]
    ran: list[str] = field(default_factory=list)
    interrupted: bool = False
    failed: list[str] = field(default_factory=list)


def sweep_folder(data_dir: Path, sweep_id: str) -> Path:
    """``<data>/sweeps/<id>``."""
    return Path(data_dir) / SWEEPS_DIR / sweep_id


def _read_json(path: Path) -> Any:
    """A sweep's JSON file (bounded in size and depth), or None when missing or unreadable."""
    try:
        return read_json(path)
    except StudioError:
        return None


def trial_records(folder: Path) -> dict[str, dict[str, Any]]:
    """The driver's record of every trial that ended, by key."""
    out = {}
    for path in sorted((folder / TRIALS_DIR).glob("t*.json")):
        data = _read_json(path)
        if isinstance(data, dict) and "key" in data:
            out[data["key"]] = data
    return out


def finished_trials(data_dir: Path, spec: SweepSpec) -> set[str]:
    """Keys of the trials that need not run again (a resumed sweep skips exactly these): those
    whose run folder says ``done`` (every episode of every experiment; it may have ended while
    the driver was going down, before the driver recorded it), and those the driver recorded as
    stopped early by the scheduler, with a run folder that reads back."""
    records = trial_records(sweep_folder(data_dir, spec.name))
    finished = set()
    for trial in spec.trials():
        try:
            run = RunFolder.load(trial_run_path(data_dir, spec.name, trial.key))
        except LearningError:
            continue
        early = records.get(trial.key, {}).get("status") == "early-stopped"
        if run.status == "done" or (early and run.steps().max() >= 0):
            finished.add(trial.key)
    return finished


def sweep_rows(data_dir: Path, spec: SweepSpec) -> list[dict[str, Any]]:
    """``sweep.csv``'s rows: per trial its settings, status, metrics, CPU and wall time."""
    folder = sweep_folder(data_dir, spec.name)
    records = trial_records(folder)
    rows = []
    for trial in spec.trials():
        record = records.get(trial.key, {})
        row: dict[str, Any] = {"trial": trial.key, "seed": trial.seed}
        row.update({name: _show(value) for name, value in trial.settings.items()})
        metrics: dict[str, Any] = {"episodes_done": 0, **{name: math.nan for name in METRICS}}
        run_path = trial_run_path(data_dir, spec.name, trial.key)
        cpu, status = math.nan, "not run"
        with contextlib.suppress(LearningError):
            run = RunFolder.load(run_path)
            metrics = trial_metrics(
                run.steps(), run.record, spec.convergence_factor, spec.level_steps
            )
            cpu, status = run.cpu_seconds, run.status
        if record.get("status") == "failed" or (
            record.get("status") == "early-stopped" and status != "done"
        ):  # a trial stopped so late that it had finished counts as done
            status = record["status"]
        row["status"] = status
        row.update({name: metrics[name] for name in METRICS})
        row["converged"] = metrics.get("converged", "")
        row["episodes_done"] = metrics["episodes_done"]
        row["cpu_seconds"] = cpu
        row["wall_seconds"] = record.get("wall_seconds", math.nan)
        row["attempts"] = record.get("attempts", "")
        row["node"] = record.get("node", "")
        row["run"] = run_path.name if run_path.is_dir() else ""
        rows.append(row)
    return rows


def sweep_csv(rows: Sequence[Mapping[str, Any]]) -> str:
    """The rows as CSV text (numbers to 6 significant digits, NaN as empty)."""
    out = io.StringIO()
    if not rows:
        return ""
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(list(rows[0]))
    for row in rows:
        writer.writerow(
            [
                ("" if math.isnan(v) else f"{v:.6g}") if isinstance(v, float) else v
                for v in row.values()
            ]
        )
    return out.getvalue()


def metric_by_setting(
    rows: Sequence[Mapping[str, Any]], spec: SweepSpec
) -> list[tuple[str, list[Any], np.ndarray, np.ndarray]]:
    """The metric against the first swept setting, one series per combination of the others:
    ``(label, x values, mean over seeds, standard error over seeds)``."""
    x_name, others = spec.swept[0], spec.swept[1:]
    series: dict[str, dict[Any, list[float]]] = {}
    for row in rows:
        value = row[spec.metric]
        if isinstance(value, float) and math.isnan(value):
            continue
        label = ", ".join(f"{n}={row[n]}" for n in others) or spec.metric
        series.setdefault(label, {}).setdefault(row[x_name], []).append(float(value))
    out = []
    for label, points in series.items():
        xs = list(points)
        means = np.array([np.mean(points[x]) for x in xs])
        errors = np.array([_standard_error(np.asarray(points[x]))[()] for x in xs])
        out.append((label, xs, means, errors))
    return out


FIGURE_FORMATS = ("png", "svg")
"""The summary figure is written in these formats."""


def _check_figure_format(fmt: object) -> None:
    if fmt not in FIGURE_FORMATS:
        raise LearningError(f"The figure format {fmt!r} is not supported; use png or svg.")


def sweep_figure(rows: Sequence[Mapping[str, Any]], spec: SweepSpec, fmt: str = "png") -> bytes:
    """The metric against the first swept setting (mean and standard error over seeds), one line
    per combination of the other swept settings, as PNG or SVG bytes."""
    return sweep_figures(rows, spec, (fmt,))[fmt]


def sweep_figures(
    rows: Sequence[Mapping[str, Any]], spec: SweepSpec, formats: Sequence[str] = FIGURE_FORMATS
) -> dict[str, bytes]:
    """:func:`sweep_figure` in several formats, drawn once: ``{format: bytes}``."""
    from matplotlib.figure import Figure

    for fmt in formats:
        _check_figure_format(fmt)
    fig = Figure(figsize=(7, 4), dpi=120, layout="constrained")
    ax = fig.add_subplot()
    x_name = spec.swept[0]
    series = metric_by_setting(rows, spec)
    categories: list[str] = []
    numeric = all(
        is_number(v) for v in (spec.space[x_name] if isinstance(spec.space[x_name], list) else [0])
    )
    for label, xs, means, errors in series:
        if numeric:
            x = np.asarray([float(v) for v in xs])
        else:
            for v in xs:
                if v not in categories:
                    categories.append(v)
            x = np.asarray([categories.index(v) for v in xs], dtype=np.float64)
        order = np.argsort(x)
        ax.errorbar(
            x[order],
            means[order],
            yerr=np.nan_to_num(errors[order]),
            marker="o",
            capsize=3,
            label=label,
        )
    if categories:
        ax.set_xticks(range(len(categories)), categories)
    if not series:
        ax.text(
            0.5, 0.5, "no finished trials yet", ha="center", va="center", transform=ax.transAxes
        )
    else:
        ax.legend(fontsize="small")
    ax.set_xlabel(x_name)
    ax.set_ylabel(f"{spec.metric} (mean ± s.e. over {len(spec.seeds)} seeds)")
    ax.set_title(f"sweep {spec.name}")
    ax.grid(alpha=0.3)
    out = {}
    for fmt in formats:
        buffer = io.BytesIO()
        fig.savefig(buffer, format=fmt)
        out[fmt] = buffer.getvalue()
    return out


def write_summary(data_dir: Path, spec: SweepSpec) -> list[dict[str, Any]]:
    """Write ``sweep.csv`` and ``sweep.png``/``.svg`` into the sweep folder; returns the rows."""
    folder = sweep_folder(data_dir, spec.name)
    rows = sweep_rows(data_dir, spec)
    try:
        (folder / SUMMARY_FILE).write_text(sweep_csv(rows))
        for fmt, image in sweep_figures(rows, spec).items():
            (folder / f"{FIGURE_STEM}.{fmt}").write_bytes(image)
    except OSError as err:
        raise SweepError(
            f"Cannot write the sweep summary in {folder} ({err.strerror or err}); check the disk."
        ) from None
    return rows


@dataclass(frozen=True)
class SweepInfo:
    """A sweep folder read back (what the page lists).

    Attributes:
        id: the sweep id (also the runs' ``group``).
        spec: the spec as stored.
        status: ``running``, ``done`` or ``interrupted``.
        created: ISO 8601 UTC.
        trials: how many trials the sweep has.
        finished: how many of them finished.
        runs: the trials' run folder names that exist.
        folder: the sweep folder.
    """

    id: str
    spec: dict[str, Any]
    status: str
    created: str
    trials: int
    finished: int
    runs: list[str]
    folder: Path

    @property
    def metric(self) -> str:
        """The metric the summary reports."""
        return str(self.spec.get("metric", {}).get("name", DEFAULT_METRIC))

    @property
    def swept(self) -> list[str]:
        """The swept settings, in the spec's order (the figure's x axis is the first)."""
        return list(self.spec.get("space", {}))

    def summary_csv(self) -> str:
        """``sweep.csv``'s text: as written when the sweep ended, or computed from the run folders
        while it runs (the file is written at its end)."""
        if self.status != "running":
            with contextlib.suppress(StudioError, OSError, UnicodeDecodeError):  # bounded read
                return read_bytes_bounded(self.folder / SUMMARY_FILE, MAX_JSON_BYTES).decode()
        return sweep_csv(sweep_rows(self.folder.parent.parent, self._spec()))

    def rows(self) -> list[dict[str, str]]:
        """``sweep.csv``'s rows (strings, as in the file)."""
        return list(csv.DictReader(io.StringIO(self.summary_csv())))

    def figure(self, fmt: str = "png") -> bytes:
        """The summary figure (:func:`sweep_figure`): as written, or drawn from the run folders."""
        _check_figure_format(fmt)
        if self.status != "running":
            with contextlib.suppress(OSError):
                return (self.folder / f"{FIGURE_STEM}.{fmt}").read_bytes()
        spec = self._spec()
        return sweep_figure(sweep_rows(self.folder.parent.parent, spec), spec, fmt)

    def _spec(self) -> SweepSpec:
        return parse_sweep_spec(self.spec, f"sweep {self.id}")


def load_sweep(data_dir: Path, sweep_id: str) -> SweepInfo:
    """Read a sweep folder.

    Raises:
        SweepError: no such sweep, or an unreadable ``sweep.json``.
    """
    if not isinstance(sweep_id, str) or not SWEEP_ID.match(sweep_id):
        raise SweepError(f"{sweep_id!r} is not a sweep id; give a sweep's folder name.")
    folder = sweep_folder(data_dir, sweep_id)
    data = _read_json(folder / SWEEP_FILE)
    if not isinstance(data, dict) or data.get("format") != SWEEP_FORMAT:
        raise SweepError(f"There is no sweep {sweep_id!r} in {folder.parent}; check its name.")
    try:
        spec = parse_sweep_spec(data.get("spec", {}), f"sweep {sweep_id}")
    except SweepError as err:
        raise SweepError(
            f"Sweep {sweep_id!r} has an unreadable sweep.json ({err}); delete it."
        ) from None
    runs_parent = Path(data_dir) / RUNS_DIR / sweep_id
    runs = (
        sorted(p.name for p in runs_parent.iterdir() if p.is_dir()) if runs_parent.is_dir() else []
    )
    status = str(data.get("status", "interrupted"))
    if status == "running" and not _driver_alive(data):  # its driver died
        status = "interrupted"
    return SweepInfo(
        id=sweep_id,
        spec=data.get("spec", {}),
        status=status,
        created=str(data.get("created", "")),
        trials=len(data.get("trials", [])),
        finished=len(finished_trials(data_dir, spec)),
        runs=[r for r in runs if not r.startswith(".")],
        folder=folder,
    )


def list_sweeps(data_dir: Path) -> list[SweepInfo]:
    """Every readable sweep in the data folder, newest first."""
    parent = Path(data_dir) / SWEEPS_DIR
    if not parent.is_dir():
        return []
    out = []
    for child in parent.iterdir():
        if child.is_dir() and SWEEP_ID.match(child.name):
            with contextlib.suppress(SweepError):
                out.append(load_sweep(data_dir, child.name))
    return sorted(out, key=lambda s: s.created, reverse=True)


def resume_target(data_dir: Path, what: str | None) -> SweepSpec:
    """The spec of the sweep to resume: by id, or the most recent unfinished one."""
    if what is None:
        unfinished = [s for s in list_sweeps(data_dir) if s.status not in ("done", "running")]
        if not unfinished:
            raise SweepError(
                f"There is no unfinished sweep in {Path(data_dir) / SWEEPS_DIR} that is not running; start one with studio sweep SPEC."
            )
        info = unfinished[0]
    else:
        info = load_sweep(data_dir, what)
    return parse_sweep_spec(info.spec, f"sweep {info.id}")


# ----------------------------------------------------------------------------- running it


def _set_ray_environment() -> None:
    """Set :data:`RAY_ENVIRONMENT` (each variable unless already set) in this process."""
    for key, value in RAY_ENVIRONMENT.items():
        os.environ.setdefault(key, value)


@contextlib.contextmanager
def _environment(values: Mapping[str, str]) -> Iterator[None]:
    """``values`` set in this process's environment for the block, then put back as they were
    (so that nothing else this process starts, e.g. a later ``ray start``, inherits them)."""
    before = {key: os.environ.get(key) for key in values}
    os.environ.update(values)
    try:
        yield
    finally:
        for key, value in before.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


def _import_ray(local: bool = False) -> Any:
    """Import Ray (with :data:`RAY_ENVIRONMENT` set); ``local``: the sweep starts its own Ray, on
    loopback only (:data:`LOCAL_RAY_ENVIRONMENT`, read by Ray when it is imported)."""
    _set_ray_environment()
    try:
        with _environment(LOCAL_RAY_ENVIRONMENT if local else {}):
            import ray
            from ray import tune  # noqa: F401
    except ImportError:
        raise SweepError(f"Sweeps run on Ray Tune, which is not installed; {RAY_HINT}.") from None
    return ray


def _check_address(address: str) -> None:
    if address == "auto":
        return
    host, sep, port = address.rpartition(":")
    if not sep or not host or not port.isdigit():
        raise SweepError(
            f"--address is {address!r}; give auto or HOST:PORT of a Ray cluster's head node."
        )
    try:
        with socket.create_connection((host, int(port)), timeout=ADDRESS_TIMEOUT_SECONDS):
            pass
    except OSError as err:
        raise SweepError(
            f"Cannot reach a Ray cluster at {address} ({err.strerror or err}); start one with ray start --head --port={port} or check --address."
        ) from None


def _connect(ray: Any, address: str | None, workers: int | None) -> bool:
    """Start or join Ray; returns whether this call started it (and must shut it down)."""
    if ray.is_initialized():
        return False
    quiet = {"log_to_driver": False, "configure_logging": True, "logging_level": "ERROR"}
    if address is None:
        cpus = workers or os.cpu_count() or 1
        with _environment(LOCAL_RAY_ENVIRONMENT):  # the processes it starts inherit it
            ray.init(address="local", num_cpus=cpus, include_dashboard=False, **quiet)
        node_ip = ray.util.get_node_ip_address()
        if not is_loopback(node_ip):  # Ray was imported before the switch was set
            ray.shutdown()
            raise SweepError(
                f"The local Ray would listen on {node_ip}, beyond this machine; run the sweep in a new process (studio sweep), or join a cluster you secured with --address."
            )
        return True
    try:
        ray.init(address=address, **quiet)
    except Exception as err:  # refused, no cluster at "auto", a token mismatch: one sentence
        raise SweepError(
            f"Cannot join the Ray cluster at {address} ({str(err).splitlines()[0]}); check that it runs (ray status) and --address."
        ) from None
    return True


def _prepare(data_dir: Path, spec: SweepSpec, resume: bool) -> Path:
    folder = sweep_folder(data_dir, spec.name)
    stored = _read_json(folder / SWEEP_FILE)
    if isinstance(stored, dict):
        if _driver_alive(stored):  # two drivers would train the same trials into the same folders
            raise SweepError(
                f"Sweep {spec.name!r} is still running (process {stored.get('pid')} on {_hostname(stored)}); wait for it to end, or stop it with Ctrl-C and then studio sweep --resume {spec.name}."
            )
        if not resume:
            state = "finished" if stored.get("status") == "done" else "unfinished"
            raise SweepError(
                f"Sweep {spec.name!r} already exists in {folder.parent} ({state}); continue it with studio sweep --resume {spec.name}, or give another --name."
            )
        if stored.get("spec") != json.loads(json.dumps(spec.to_dict())):
            raise SweepError(
                f"The spec differs from the one sweep {spec.name!r} started with; resume with studio sweep --resume {spec.name} alone, or give another --name."
            )
    elif resume:
        raise SweepError(
            f"There is no sweep {spec.name!r} in {folder.parent} to resume; start it without --resume."
        )
    try:
        (folder / TRIALS_DIR).mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise SweepError(
            f"Cannot create {folder} ({err.strerror or err}); check the disk."
        ) from None
    if not isinstance(stored, dict):
        stored = {
            "format": SWEEP_FORMAT,
            "version": SWEEP_VERSION,
            "spec": spec.to_dict(),
            "created": now_iso(),
            "trials": [
                {"key": t.key, "settings": t.settings, "seed": t.seed} for t in spec.trials()
            ],
        }
    stored["status"] = "running"
    stored["pid"], stored["host"] = os.getpid(), this_host()
    atomic_write_text(folder / SWEEP_FILE, json.dumps(stored, indent=1))
    return folder


def _driver_alive(stored: Mapping[str, Any]) -> bool:
    """Whether the driver that ``sweep.json`` names as running still runs."""
    return stored.get("status") == "running" and pid_alive(stored.get("pid"), stored.get("host"))


def _hostname(stored: Mapping[str, Any]) -> str:
    host = stored.get("host")
    name = host.get("hostname") if isinstance(host, dict) else None
    return name if isinstance(name, str) else "this machine"


def _set_status(folder: Path, status: str, **fields: Any) -> None:
    """Write the sweep's ``status`` (and other top-level ``fields``) into ``sweep.json``."""
    data = _read_json(folder / SWEEP_FILE)
    if isinstance(data, dict):
        data.update(status=status, **fields)
        atomic_write_text(folder / SWEEP_FILE, json.dumps(data, indent=1))


def run_sweep(
    spec: SweepSpec,
    data_dir: Path,
    *,
    address: str | None = None,
    workers: int | None = None,
    resume: bool = False,
    on_progress: Callable[[SweepProgress], None] | None = None,
) -> SweepResult:
    """Run a sweep's trials on Ray Tune, each as an ordinary run; write the summary.

    Args:
        spec: from :func:`load_sweep_spec`.
        data_dir: the data folder (runs go to ``runs/<id>/``, the summary to ``sweeps/<id>/``).
        address: None for a local Ray on this machine, ``"auto"`` or ``"HOST:PORT"`` for an
            existing cluster. A Ray already initialised in this process is used as it is.
        workers: local Ray only: cores to use (default: all).
        resume: continue the sweep of this id, running only the trials not finished.
        on_progress: called from this thread whenever a trial starts or ends.

    Returns:
        The summary rows, the trials run now, and whether the sweep was interrupted (Ctrl-C: Tune
        stops the running trials and this returns; resume later with ``resume=True``).

    Raises:
        SweepError: Ray missing, a cluster out of reach, the sweep exists (or not, to resume).
    """
    if workers is not None and (not is_int(workers) or workers < 1):
        raise SweepError(f"--workers is {workers!r}; give a whole number of cores, at least 1.")
    # before anything is written: a missing Ray or cluster leaves no trace
    ray = _import_ray(local=address is None)
    if address is not None and not ray.is_initialized():
        _check_address(address)
    data_dir = Path(data_dir).resolve()
    folder = _prepare(data_dir, spec, resume)
    trials = spec.trials()
    finished = finished_trials(data_dir, spec) if resume else set()
    todo = [t for t in trials if t.key not in finished]
    progress = SweepProgress(total=len(trials), done=len(finished))
    notify = on_progress or (lambda _p: None)
    rows = sweep_rows(data_dir, spec) if finished else []  # the best so far, on resume
    labels = {t.key: t.label() for t in trials}
    for row in rows:
        if row["trial"] in finished:
            _improve(progress, row[spec.metric], labels[row["trial"]])
    notify(progress)
    if not todo:
        rows = write_summary(data_dir, spec)
        _set_status(folder, "done")
        return SweepResult(folder, spec, rows)

    from ray import tune
    from ray.tune.schedulers import ASHAScheduler

    started = _connect(ray, address, workers)
    if started:  # the driver's host now has its Ray node id
        _set_status(folder, "running", host=this_host())
    ran: list[str] = []
    failed: list[str] = []
    try:
        job = _Job(
            spec=spec,
            trials={t.key: t for t in trials},
            data_dir=str(data_dir),
            milestones=tuple(spec.scheduler.milestones(spec.episodes) if spec.scheduler else ()),
        )
        callback = _progress_callback(tune, folder, spec, progress, notify, ran, failed)
        scheduler = None
        if spec.scheduler is not None:
            scheduler = ASHAScheduler(
                time_attr="episodes",
                max_t=spec.episodes,
                grace_period=spec.scheduler.grace_episodes,
                reduction_factor=spec.scheduler.reduction_factor,
            )
        session = (
            len(list((folder / RAY_DIR).glob("session-*"))) if (folder / RAY_DIR).is_dir() else 0
        )
        tuner = tune.Tuner(
            tune.with_resources(
                tune.with_parameters(_trainable, job=job), {"cpu": spec.cpus_per_trial}
            ),
            param_space={"key": tune.grid_search([t.key for t in todo])},
            tune_config=tune.TuneConfig(
                metric=spec.metric,
                mode="min",
                scheduler=scheduler,
                # A new worker process costs seconds (Python, Ray, Tune, this package, the
                # kernels): every trial runs in a worker an earlier trial of the sweep started,
                # also after the scheduler stopped that trial (_trainable re-raises the stop).
                reuse_actors=True,
            ),
            run_config=tune.RunConfig(
                name=f"session-{session}",
                storage_path=str(folder / RAY_DIR),
                verbose=0,
                callbacks=[callback],
                failure_config=tune.FailureConfig(max_failures=MAX_RETRIES),
            ),
        )
        tune_log = logging.getLogger("ray.tune")
        level = tune_log.level
        tune_log.setLevel(logging.ERROR)  # our progress is the output; errors still show
        try:
            tuner.fit()
        finally:
            tune_log.setLevel(level)
    finally:
        if started:
            ray.shutdown()
    done = finished_trials(data_dir, spec)
    interrupted = len(done) + len(failed) < len(trials)
    rows = write_summary(data_dir, spec)
    _set_status(folder, "done" if len(done) == len(trials) else "interrupted")
    return SweepResult(folder, spec, rows, ran=ran, interrupted=interrupted, failed=failed)


def _improve(progress: SweepProgress, value: Any, label: str) -> None:
    is_number = isinstance(value, int | float) and not isinstance(value, bool)
    if is_number and not math.isnan(value) and (progress.best is None or value < progress.best[0]):
        progress.best = (float(value), label)


def _progress_callback(
    tune: Any,
    folder: Path,
    spec: SweepSpec,
    progress: SweepProgress,
    notify: Callable[[SweepProgress], None],
    ran: list[str],
    failed: list[str],
) -> Any:
    """A Tune callback that records each ended trial and keeps the progress counts."""
    by_key = {t.key: t for t in spec.trials()}
    running: set[str] = set()

    def count() -> None:
        progress.running = len(running)
        notify(progress)

    class Progress(tune.Callback):  # type: ignore[misc, name-defined]
        def on_trial_start(self, iteration: int, trials: list, trial: Any, **info: Any) -> None:
            running.add(trial.config["key"])
            count()

        def on_trial_complete(self, iteration: int, trials: list, trial: Any, **info: Any) -> None:
            key = trial.config["key"]
            result = dict(trial.last_result or {})
            running.discard(key)
            # Without a scheduler nothing stops a trial early: a trial ending without its final
            # report was stopped (Ctrl-C) and must run again on resume.
            if result.get("final"):
                status = "done"
            elif spec.scheduler is not None:
                status = "early-stopped"
            else:
                status = "stopped"
            self._record(key, trial, result, status)
            if status != "stopped":
                progress.done += 1
                ran.append(key)
            _improve(progress, result.get(spec.metric), by_key[key].label())
            count()

        def on_trial_error(self, iteration: int, trials: list, trial: Any, **info: Any) -> None:
            key = trial.config["key"]
            running.discard(key)
            progress.failed += 1
            failed.append(key)
            error = getattr(trial, "error_file", None)
            self._record(key, trial, dict(trial.last_result or {}), "failed", error)
            count()

        def _record(
            self, key: str, trial: Any, result: dict, status: str, error: Any = None
        ) -> None:
            record = {
                "key": key,
                "status": status,
                "attempts": int(getattr(trial, "num_failures", 0)) + 1,
                "node": result.get("node"),
                "hostname": result.get("hostname"),
                "pid": result.get("pid"),
                "episodes": result.get("episodes"),
                "wall_seconds": result.get("wall_seconds"),
                "cpu_seconds": result.get("cpu_seconds"),
                "finished": now_iso(),
            }
            if error:
                record["error"] = str(error)
            atomic_write_text(folder / TRIALS_DIR / f"{key}.json", json.dumps(record, indent=1))

    return Progress()
