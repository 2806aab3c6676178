"""Training runs on disk: one folder layout, one curve statistic set, one CSV layout, one figure.

Whatever starts a run (``studio train``, ``studio reproduce``, a sweep, the page's run queue), it
goes through :class:`RunFolder`, so every run folder reads back with :meth:`RunFolder.load` and
the page lists, plots, watches and exports it.

A run folder ``<parent>/<id>/`` holds:

- ``config.json``: the :class:`RunRecord`, everything needed to repeat the run without the page or
  the demonstration files (format ``teach-studio-run``, version 1; see ``README.md``);
- ``status.json``: ``status`` (``queued``, ``running``, ``done``, ``stopped``, ``failed``),
  ``created``/``started``/``finished`` (ISO 8601 UTC), ``cpu_seconds``, ``error``, and ``pid``
  and ``host`` (:func:`this_host`), the process training it and where it runs;
- ``owner.lock``: held (``flock``) by the process that will train or is training the run, while
  it is ``queued`` or ``running`` (see ``_owner.py``). A ``queued`` or ``running`` run whose lock
  nobody holds is read as ``stopped``, by every process, without rewriting its status; a folder
  from before owners locked is judged by its pid and that process's start time instead;
- ``steps.csv``: real steps per episode, one row per experiment, ``-1`` where not done; rewritten
  atomically every :data:`CHECKPOINT_SECONDS` while training (less often only when one write
  takes over a tenth of that), so a killed process loses about that much of its curve;
- ``curves.csv``: the :func:`curve_statistics` of ``steps.csv`` in the layout
  :data:`CURVE_COLUMNS`, written when the run ends (or by :meth:`RunFolder.recover` after a
  crash);
- ``policy.policy.npz``: the best experiment's Q table (see ``_policy.py``), saved with every
  ``steps.csv`` checkpoint from the tables the kernels are filling (:attr:`LiveProgress.snapshot`)
  and again when the run ends, also when it was stopped (Stop, Ctrl-C). A process killed with
  ``kill -9`` leaves the policy of its last checkpoint.

No file of a run folder, nor the folder itself, is read through a symbolic link.

A folder is created atomically: it is built as a hidden temporary folder next to its final place
and renamed there, so a full disk leaves no half-made run behind (:class:`LearningError` says so).

Use::

    record = RunRecord.for_arm_grid(ArmGrid(), DynaQConfig(), 20, 100, seed=0, origin="cli")
    run = RunFolder.create(Path("runs"), record)   # runs/<time>-full-<hex>/
    result = run.train(workers=None)               # checkpoints, then policy + status
    again = RunFolder.load(run.path)
    curve_statistics(again.steps())                # the statistics the page and the CLI show
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import logging
import os
import secrets
import shutil
import socket
import sys
import threading
import time
import warnings
from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from studio import StudioError, read_bytes_bounded, read_json

from .._files import atomic_write_text, now_iso
from .._numbers import is_int
from ._arm import ArmGrid
from ._config import DEFAULT_SEED, MAX_STEPS_PER_EPISODE, DynaQConfig, check_budget
from ._errors import ConfigError, LearningError
from ._experiments import run_experiments
from ._learner import ExperimentResult, LiveProgress
from ._owner import OWNER_FILE, OwnerLock, owner_alive, process_started
from ._policy import save_policy
from ._reach import ArmReach
from ._tiles import TileCoding

log = logging.getLogger(__name__)

RUN_FORMAT = "teach-studio-run"
"""The ``format`` field of a run's ``config.json``."""
RUN_VERSION = 1
"""The version of the run folder layout this code writes and reads."""
CONFIG_FILE = "config.json"
STATUS_FILE = "status.json"
STEPS_FILE = "steps.csv"
CURVES_FILE = "curves.csv"
POLICY_FILE = "policy.policy.npz"
CHECKPOINT_SECONDS = 1.0
"""How often a training run's ``steps.csv`` is written to disk (at most this much is lost)."""
CHECKPOINT_COST_FACTOR = 10.0
"""A checkpoint waits at least this many times as long as the last one took to write, so a huge
run (20 x 50,000 episodes) spends under a tenth of a core on checkpoints."""
FIGURE_POINTS = 600
"""A curve figure draws at most about this many points per line (longer runs are averaged)."""
ORIGINS = ("cli", "page", "reproduce", "sweep")
"""What made a run: ``studio train``, the page's run queue, ``studio reproduce``, a sweep."""
STATUSES = ("queued", "running", "done", "stopped", "failed")
TASK_ARM_GRID = "arm-grid"
"""``task.kind`` of the paper's arm grid (``task`` also holds the :meth:`ArmGrid.to_dict` spec)."""
TASK_ARM_REACH = "arm-reach"
"""``task.kind`` of the continuous-joint task (``task`` also holds the :meth:`ArmReach.to_dict`
fields and ``tile_coding``, the :meth:`TileCoding.to_dict` settings); its demonstrations are
joint paths ``(N, joints)`` in radians."""
TASK_KINDS = (TASK_ARM_GRID, TASK_ARM_REACH)
MAX_STATUS_BYTES = 64 * 1024
"""Largest ``status.json`` read (the studio writes a few hundred bytes)."""
STEPS_HEADER_BYTES = 1024
"""Room for ``steps.csv``'s comment line when bounding its size."""

CURVE_COLUMNS = (
    "episode",
    "mean",
    "std",
    "median",
    "p10",
    "p90",
    "min",
    "max",
    "experiments",
)
"""The one ``curves.csv`` layout: per episode (1-based), statistics of the real steps over the
``experiments`` that finished it. ``studio reproduce`` puts a ``configuration`` column first."""
STATISTICS = CURVE_COLUMNS[1:-1]


# ----------------------------------------------------------------------------- statistics


def curve_statistics(steps: np.ndarray, start: int = 0) -> dict[str, list]:
    """Learning-curve statistics of an ``(experiments, episodes)`` steps array, -1 for not done.

    Episodes run from index ``start`` up to the last one that any experiment finished. Each
    statistic is over the experiments that finished that episode (``count``): mean, population
    standard deviation, median, 10th and 90th percentiles, min and max. Experiments of a stopped
    run end at different episodes, so ``count`` falls towards the end: a plot shows it rather than
    pretend every point averages all experiments.

    Returns:
        ``{"episodes": [1-based], "mean", "std", "median", "p10", "p90", "min", "max", "count"}``,
        lists of equal length.
    """
    steps = np.asarray(steps)
    if steps.ndim != 2:
        raise LearningError(
            f"steps has shape {steps.shape}; give an (experiments, episodes) array."
        )
    count = (steps >= 0).sum(axis=0)
    nonzero = np.flatnonzero(count)
    last = int(nonzero[-1]) + 1 if nonzero.size else 0
    start = max(0, min(int(start), last))
    values = steps[:, start:last].astype(np.float64)
    values[values < 0] = np.nan
    out: dict[str, list] = {"episodes": list(range(start + 1, last + 1))}
    if values.shape[1] == 0:
        out.update({key: [] for key in STATISTICS})
        out["count"] = []
        return out
    with np.errstate(invalid="ignore", divide="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # an episode nobody finished: 0, count 0
        p10, median, p90 = _column_percentiles(values, count[start:last], (10, 50, 90))
        stats = {
            "mean": np.nanmean(values, axis=0),
            "std": np.nanstd(values, axis=0),
            "median": median,
            "p10": p10,
            "p90": p90,
            "min": np.nanmin(values, axis=0),
            "max": np.nanmax(values, axis=0),
        }
    for key in STATISTICS:
        out[key] = np.round(np.nan_to_num(stats[key]), 3).tolist()
    out["count"] = count[start:last].astype(np.int64).tolist()
    return out


def _column_percentiles(
    values: np.ndarray, count: np.ndarray, percents: Sequence[float]
) -> list[np.ndarray]:
    """Per-column percentiles of the non-NaN values (numpy's default "linear" method), with
    ``count`` >= 1 valid values per column: one sort instead of ``nanpercentile``'s per-column loop."""
    ordered = np.sort(values, axis=0)  # NaN sorts last
    columns = np.arange(values.shape[1])
    out = []
    for percent in percents:
        position = np.maximum(count - 1, 0) * (percent / 100.0)
        low = np.floor(position).astype(np.int64)
        high = np.minimum(low + 1, np.maximum(count - 1, 0))
        a, b = ordered[low, columns], ordered[high, columns]
        out.append(a + (b - a) * (position - low))
    return out


def downsample_curve(curve: dict[str, list], points: int = FIGURE_POINTS) -> dict[str, list]:
    """A curve averaged in equal buckets of episodes so that it has at most ``points`` points.

    Each bucket's episode is its mean episode, its mean/std/median/percentiles are the means of
    the bucket's values, ``min``/``max`` the bucket's extremes and ``count`` its smallest count (so
    a point never claims more experiments than all of its episodes had). A curve with at most
    ``points`` episodes is returned as is.
    """
    n = len(curve["episodes"])
    if n <= points:
        return curve
    size = -(-n // points)
    edges = np.arange(0, n, size)

    def reduce(key: str, fn: Callable[..., np.ndarray]) -> list:
        return fn(np.asarray(curve[key], dtype=np.float64), edges).tolist()

    def mean_of(a: np.ndarray, e: np.ndarray) -> np.ndarray:
        return np.add.reduceat(a, e) / np.diff(np.append(e, a.size))

    out = {"episodes": reduce("episodes", mean_of)}
    for key in ("mean", "std", "median", "p10", "p90"):
        out[key] = np.round(reduce(key, mean_of), 3).tolist()
    out["min"] = reduce("min", np.minimum.reduceat)
    out["max"] = reduce("max", np.maximum.reduceat)
    out["count"] = [int(c) for c in reduce("count", np.minimum.reduceat)]
    return out


def curves_csv(curve: dict[str, list], configuration: str | None = None) -> str:
    """A curve as CSV text in the one layout :data:`CURVE_COLUMNS`.

    Args:
        curve: from :func:`curve_statistics`.
        configuration: when given, a leading ``configuration`` column holding it on every row
            (``studio reproduce`` writes several runs into one file this way).
    """
    out = io.StringIO()
    write_curves_csv(out, [(configuration, curve)] if configuration else [(None, curve)])
    return out.getvalue()


def write_curves_csv(
    stream: io.TextIOBase | Any, curves: Sequence[tuple[str | None, dict[str, list]]]
) -> None:
    """Write curves to an open text stream: a header, then one row per episode per curve.

    A ``configuration`` column comes first when the curves are named (several runs in one file).
    """
    named = any(name is not None for name, _ in curves)
    writer = csv.writer(stream, lineterminator="\n")
    writer.writerow((["configuration"] if named else []) + list(CURVE_COLUMNS))
    for name, curve in curves:
        columns = [curve["episodes"], *(curve[k] for k in STATISTICS), curve["count"]]
        for row in zip(*columns, strict=True):
            values = [row[0], *(f"{v:.6g}" for v in row[1:-1]), row[-1]]
            writer.writerow(([name] if named else []) + values)


def curve_plot(
    curves: Sequence[tuple[str, dict[str, list]]],
    *,
    log_steps: bool = False,
    title: str = "",
    points: int = FIGURE_POINTS,
) -> Any:
    """Learning curves as a matplotlib ``Figure``: per run its mean line and a 10-90 % band.

    Long runs are averaged to about ``points`` points per line (:func:`downsample_curve`), so a
    25,000-episode run draws as a line, not a solid block. Where fewer experiments than the run's
    most finished an episode, the line turns dotted, so a band never silently stops averaging all
    of them. Drawn on matplotlib's object API (no global state, safe in threads).
    """
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 4), dpi=120, layout="constrained")
    ax = fig.add_subplot()
    drawn = False
    for label, full in curves:
        curve = downsample_curve(full, points)
        x = np.asarray(curve["episodes"], dtype=np.float64)
        if not x.size:
            continue
        drawn = True
        mean = np.asarray(curve["mean"])
        count = np.asarray(curve["count"])
        complete = count >= count.max()
        (line,) = ax.plot(x, np.where(complete, mean, np.nan), lw=1.6, label=label)
        if not complete.all():
            fewer = ~complete
            fewer[:-1] |= fewer[1:]  # start at the last complete point, so the two lines join
            ax.plot(
                x,
                np.where(fewer, mean, np.nan),
                lw=1.2,
                ls=":",
                color=line.get_color(),
                label=f"{label} (fewer experiments)",
            )
        ax.fill_between(x, curve["p10"], curve["p90"], alpha=0.2, color=line.get_color())
    if not drawn:
        ax.text(
            0.5, 0.5, "no finished episodes yet", ha="center", va="center", transform=ax.transAxes
        )
    else:
        ax.legend(loc="upper right", fontsize="small")
    if log_steps:
        ax.set_yscale("log")
    ax.set_xlabel("episode")
    ax.set_ylabel("steps to the goal (line: mean, band: 10-90 %)")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    return fig


def curve_figure(
    curves: Sequence[tuple[str, dict[str, list]]],
    fmt: str = "png",
    *,
    log_steps: bool = False,
    title: str = "",
    points: int = FIGURE_POINTS,
) -> bytes:
    """:func:`curve_plot` as PNG or SVG bytes (the page's "Plot PNG/SVG" downloads)."""
    if fmt not in ("png", "svg"):
        raise LearningError(f"The figure format {fmt!r} is not supported; use png or svg.")
    fig = curve_plot(curves, log_steps=log_steps, title=title, points=points)
    buffer = io.BytesIO()
    fig.savefig(buffer, format=fmt)
    return buffer.getvalue()


# ----------------------------------------------------------------------------- config.json


def task_spec(task: ArmGrid | ArmReach, coding: TileCoding | None = None) -> dict[str, Any]:
    """A task as run records and policy listings write it: its kind and its settings.

    ``{"kind": "arm-grid", **grid.to_dict()}``, or ``{"kind": "arm-reach", **task.to_dict(),
    "tile_coding": coding.to_dict()}`` for the continuous task.
    """
    if isinstance(task, ArmGrid):
        return {"kind": TASK_ARM_GRID, **task.to_dict()}
    spec: dict[str, Any] = {"kind": TASK_ARM_REACH, **task.to_dict()}
    if coding is not None:
        spec["tile_coding"] = coding.to_dict()
    return spec


@dataclass(frozen=True)
class RunRecord:
    """A run's ``config.json``: what it trains and how, self-describing without the page.

    Attributes:
        task: what is learnt: ``{"kind": "arm-grid", joints, bins, low_deg, high_deg, goal}``
            for the paper's grid (:meth:`ArmGrid.to_dict`); other kinds may add their own fields.
        config: the :class:`DynaQConfig` fields.
        experiments: independent experiments averaged.
        episodes: episodes per experiment.
        seed: the run's seed.
        demonstrations: grid state paths replayed as the first episodes (so a run repeats without
            the demonstration files).
        name: a free label ("" for none).
        origin: what made the run, one of :data:`ORIGINS`.
        group: runs made together (a reproduce or a sweep) share it; None otherwise.
        created: ISO 8601 UTC.
        request: what the user asked for in the terms of the tool that made the run (the page's
            form: ``goal_deg``, demonstration names); None when there is nothing beyond the above.
    """

    task: dict[str, Any]
    config: dict[str, Any]
    experiments: int
    episodes: int
    seed: int = DEFAULT_SEED
    demonstrations: list[list[int]] = field(default_factory=list)
    name: str = ""
    origin: str = "cli"
    group: str | None = None
    created: str = ""
    request: dict[str, Any] | None = None

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
        request: dict[str, Any] | None = None,
    ) -> RunRecord:
        """A checked record for the arm grid.

        Raises:
            ConfigError: one sentence per bad field (budget, seed, name, origin, demonstrations).
        """
        problems = run_problems(experiments, episodes, seed, name, grid)
        paths = [[int(s) for s in path] for path in demonstrations]
        return cls._checked(
            problems,
            task_spec(grid),
            config,
            experiments,
            episodes,
            seed,
            paths,
            name=name,
            origin=origin,
            group=group,
            request=request,
        )

    @classmethod
    def _checked(
        cls,
        problems: list[tuple[str, str]],
        task: dict[str, Any],
        config: DynaQConfig,
        experiments: int,
        episodes: int,
        seed: int,
        paths: list,
        *,
        name: str,
        origin: str,
        group: str | None,
        request: dict[str, Any] | None,
    ) -> RunRecord:
        """The record, once the checks every task shares (origin, demonstrations against
        episodes) join the task's own ``problems``; all of them raised at once."""
        if origin not in ORIGINS:
            problems.append(("origin", f"origin is {origin!r}; give one of {', '.join(ORIGINS)}."))
        if is_int(episodes) and len(paths) > episodes:
            problems.append(
                (
                    "demonstrations",
                    f"The run replays {len(paths)} demonstrations but has only {episodes} episodes; give at least as many episodes as demonstrations.",
                )
            )
        raise_problems(problems)
        return cls(
            task=task,
            config=config.to_dict(),
            experiments=int(experiments),
            episodes=int(episodes),
            seed=int(seed),
            demonstrations=paths,
            name=name,
            origin=origin,
            group=group,
            created=now_iso(),
            request=request,
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
        request: dict[str, Any] | None = None,
    ) -> RunRecord:
        """A checked record for the continuous-joint task learnt with tile coding.

        Raises:
            ConfigError: one sentence per bad field (budget, seed, name, origin, weight table,
                demonstrations, each naming the demonstration and the fix).
        """
        from ._linear import weight_problem  # imports the kernels: import when needed

        problems = run_problems(experiments, episodes, seed, name)
        try:
            coder = coding.bind(task.lower, task.upper)
            problem = is_int(experiments) and weight_problem(experiments, coder, task.n_actions)
            if problem:
                problems.append(("tiles", problem))
        except LearningError as err:
            problems.append(("tiles", str(err)))
        paths = []
        for i, path in enumerate(demonstrations):
            try:
                task.demonstration_actions(path, i)
                paths.append(np.asarray(path, dtype=np.float64)[:, : task.joints].tolist())
            except LearningError as err:
                problems.append(("demonstrations", str(err)))
        return cls._checked(
            problems,
            task_spec(task, coding),
            config,
            experiments,
            episodes,
            seed,
            paths,
            name=name,
            origin=origin,
            group=group,
            request=request,
        )

    @property
    def kind(self) -> str:
        """The task's kind: ``"arm-grid"`` (the paper's task) or ``"arm-reach"`` (continuous)."""
        return str(self.task.get("kind", TASK_ARM_GRID))

    def arm_reach(self) -> ArmReach:
        """The task as an :class:`ArmReach` (for kind ``"arm-reach"``)."""
        if self.kind != TASK_ARM_REACH:
            raise LearningError(
                f"This run's task is {self.kind!r}, not the continuous arm task; open it with the tool that made it."
            )
        spec = {k: v for k, v in self.task.items() if k not in ("kind", "tile_coding")}
        return ArmReach.from_dict(spec)

    def tile_coding(self) -> TileCoding:
        """The tile coding of an ``"arm-reach"`` run."""
        self.arm_reach()
        return TileCoding.from_dict(self.task["tile_coding"])

    def arm_grid(self) -> ArmGrid:
        """The task as an :class:`ArmGrid` (for kind ``"arm-grid"``)."""
        if self.kind != TASK_ARM_GRID:
            raise LearningError(
                f"This run's task is {self.kind!r}, not the arm grid; open it with the tool that made it."
            )
        spec = {k: v for k, v in self.task.items() if k != "kind"}
        if spec.get("goal") is not None:
            spec["goal"] = tuple(spec["goal"])
        return ArmGrid(**spec)

    def dynaq_config(self) -> DynaQConfig:
        """The Dyna-Q settings."""
        return DynaQConfig.from_dict(self.config)

    def label(self) -> str:
        """The run's name, else its planner, size and demonstrations."""
        if self.name:
            return self.name
        demos = len(self.demonstrations)
        extra = f", {demos} demos" if demos else ""
        return f"{self.config.get('planning', '?')} x{self.experiments}{extra}"

    def to_dict(self) -> dict[str, Any]:
        """The JSON object stored as ``config.json``."""
        data = {
            "format": RUN_FORMAT,
            "version": RUN_VERSION,
            "task": self.task,
            "config": self.config,
            "experiments": self.experiments,
            "episodes": self.episodes,
            "seed": self.seed,
            "demonstrations": self.demonstrations,
            "name": self.name,
            "origin": self.origin,
            "group": self.group,
            "created": self.created,
        }
        if self.request is not None:
            data["request"] = self.request
        return data

    @classmethod
    def from_dict(cls, data: Any) -> RunRecord:
        """A record from ``config.json``'s object; also reads the layouts written before version 1
        (the page's ``{"request", "grid", ...}`` and ``studio train``'s ``{"grid", "config", ...}``).

        Raises:
            LearningError: not a run record, a newer version, or missing fields.
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
        missing = [
            key
            for key, value in (
                ("task", task),
                ("config", data.get("config")),
                ("experiments", data.get("experiments", _from(request, "experiments"))),
                ("episodes", data.get("episodes", _from(request, "episodes"))),
            )
            if value is None
        ]
        if missing:
            raise LearningError(
                f"config.json lacks {', '.join(missing)}; it is not a complete run record."
            )
        return cls(
            task=dict(task),
            config=dict(data["config"]),
            experiments=int(data.get("experiments", _from(request, "experiments"))),
            episodes=int(data.get("episodes", _from(request, "episodes"))),
            seed=int(data.get("seed", _from(request, "seed") or DEFAULT_SEED)),
            demonstrations=[
                [[float(x) for x in row] for row in p]
                if task.get("kind") == TASK_ARM_REACH
                else list(map(int, p))
                for p in data.get("demonstrations") or []
            ],
            name=str(data.get("name") or _from(request, "name") or ""),
            origin=str(data.get("origin") or ("page" if request is not None else "cli")),
            group=data.get("group"),
            created=str(data.get("created") or ""),
            request=request if isinstance(request, dict) else None,
        )


def _from(request: Any, key: str) -> Any:
    return request.get(key) if isinstance(request, dict) else None


def _text(value: object) -> str | None:
    """A string field of ``status.json``, or None when missing or of another type (damaged)."""
    return value if isinstance(value, str) else None


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
    if not is_int(seed) or not 0 <= seed < 2**63:  # type: ignore[operator]
        problems.append(("seed", f"seed is {seed!r}; give a whole number from 0 to 2**63 - 1."))
    if not isinstance(name, str) or (name and (not name.strip() or len(name) > 100)):
        problems.append(("name", "name must be 1 to 100 characters; give a shorter label or none."))
    return problems


def raise_problems(problems: Iterable[tuple[str, str]]) -> None:
    """Raise one :class:`ConfigError` carrying every ``(field, sentence)`` problem, if any."""
    problems = list(problems)
    if problems:
        raise ConfigError([text for _, text in problems], [name for name, _ in problems])


# ----------------------------------------------------------------------------- the folder


def this_host() -> dict[str, str | None]:
    """Where this process runs, recorded beside every ``pid`` a run or a sweep writes (a pid names
    a process only on its own host): ``hostname``, and ``node``, the Ray node id when this process
    is part of a Ray cluster (a sweep's driver or worker), else None. Ray is never imported here."""
    ray = sys.modules.get("ray")
    node = None
    if ray is not None and ray.is_initialized():
        node = ray.get_runtime_context().get_node_id()
    return {"hostname": socket.gethostname(), "node": node}


def on_this_host(host: object) -> bool:
    """Whether a record's ``host`` (:func:`this_host`) is this machine; a record without one (older
    runs, written before hosts were recorded) counts as this machine's."""
    hostname = host.get("hostname") if isinstance(host, dict) else None
    return not isinstance(hostname, str) or hostname == socket.gethostname()


def pid_alive(pid: object, host: object = None, started: object = None) -> bool:
    """Whether ``pid`` is a live process other than this one: a run or sweep whose status says
    it is training but whose process is gone (a crash, ``kill -9``) reads as stopped.

    ``host`` is the record's :func:`this_host`. A pid recorded on another host (a sweep's trial
    on another node of a cluster, seen through shared storage) names no process here, so this
    host cannot judge it: it counts as alive (its driver records a trial whose worker died).
    ``started`` is when the record says its process started the work (ISO 8601): a live process
    with that pid that started later reused the pid after the recorded one ended.
    """
    if not is_int(pid) or pid <= 0:  # type: ignore[operator]
        return False
    if not on_this_host(host):
        return True
    if pid == os.getpid():  # this process's only trainer, the page's queue, never reloads its own
        return False
    try:
        os.kill(int(pid), 0)  # type: ignore[arg-type]
    except ProcessLookupError:
        return False
    except PermissionError:
        pass
    return not _started_after(int(pid), started)  # type: ignore[arg-type]


PID_CLOCK_SLACK_SECONDS = 2.0
"""How much later than a record's ``started`` (kept to the second) its process may seem to have
started before the pid counts as reused."""


def _started_after(pid: int, started: object) -> bool:
    """Whether process ``pid`` started after the ISO time ``started`` (unknown: False)."""
    if not isinstance(started, str):
        return False
    try:
        when = datetime.fromisoformat(started).timestamp()
    except ValueError:
        return False
    began = process_started(pid)
    return began is not None and began > when + PID_CLOCK_SLACK_SECONDS


def delete_run_folder(path: Path, owner: OwnerLock | None = None) -> None:
    """Delete a run folder, readable or damaged, or only the link when it is a symbolic link.

    Args:
        path: the run folder.
        owner: this process's lock on it, when it owns the run (let go once deleted).

    Raises:
        LearningError: a live process owns the run, or some files could not be deleted (the
            sentence counts them and names the first; what was deleted stays deleted).
    """
    path = Path(path)
    if path.is_symlink() or not path.is_dir():
        try:
            path.unlink(missing_ok=True)
        except OSError as err:
            raise _disk_error(err, "the run folder", path.parent) from None
        return
    owner = owner or OwnerLock(path)  # refuses a run another live process owns
    try:
        failed = _remove_tree(path)
    finally:
        owner.release()
    if failed:
        where, err = failed[0]
        raise LearningError(
            f"{len(failed)} file(s) of run {path.name} could not be deleted (first: {where}: {getattr(err, 'strerror', None) or err}); fix the folder's permissions and delete it again."
        )


def _remove_tree(path: Path) -> list[tuple[str, BaseException]]:
    """Delete a run folder (links inside are removed, never followed); every path that could
    not be deleted, with its error (none: all gone). ``config.json`` goes last, and only when
    everything else went, so a folder left half-deleted is still a run folder the page lists."""
    failed: list[tuple[str, BaseException]] = []

    def note(_f: object, where: str, err: object) -> None:
        failed.append((where, err[1] if isinstance(err, tuple) else err))  # type: ignore[arg-type]

    handler = {"onexc": note} if sys.version_info >= (3, 12) else {"onerror": note}
    for child in sorted(path.iterdir()):
        if child.name == CONFIG_FILE:
            continue
        try:
            if child.is_dir() and not child.is_symlink():
                shutil.rmtree(child, **handler)  # type: ignore[arg-type]
            else:
                os.unlink(child)
        except OSError as err:
            failed.append((str(child), err))
    if failed:
        return failed
    for last, remove in ((path / CONFIG_FILE, os.unlink), (path, os.rmdir)):
        try:
            remove(last)
        except FileNotFoundError:
            continue
        except OSError as err:
            return [(str(last), err)]
    return []


def _disk_error(err: OSError, what: str, where: Path) -> LearningError:
    if err.errno == 28:  # ENOSPC
        return LearningError(
            f"The disk holding {where} is full, so {what} could not be written; free some space and try again."
        )
    return LearningError(
        f"Cannot write {what} in {where} ({err.strerror or err}); check the folder's permissions or choose another."
    )


def steps_text(steps: np.ndarray) -> str:
    """``steps.csv``'s text: a comment line, then one comma-separated row per experiment."""
    lines = ["# steps per episode; one row per experiment; -1 = not done"]
    # row by row: a 100 x 20,000 checkpoint holds the GIL for one row at a time, not for all
    lines += [",".join(map(str, row.tolist())) for row in np.asarray(steps, dtype=np.int64)]
    return "\n".join(lines) + "\n"


class RunFolder:
    """One run on disk: its record, its status, its steps and its policy.

    Build one with :meth:`create` (a new run) or :meth:`load` (an existing folder). The status
    fields are plain attributes; :meth:`save_status` writes them.
    """

    def __init__(self, path: Path, record: RunRecord) -> None:
        self.path = Path(path)
        self.record = record
        self.status = "queued"
        self.created = record.created or now_iso()
        self.started: str | None = None
        self.finished: str | None = None
        self.cpu_seconds = 0.0
        self.error: str | None = None
        self.pid: int | None = None
        self.host: dict[str, str | None] | None = None  # this_host() of the process training it
        self.interrupted = False  # read as stopped because its training process is gone
        self._steps: np.ndarray | None = None
        self._owner: OwnerLock | None = None  # held while this process owns a live run

    @property
    def id(self) -> str:
        """The folder's name."""
        return self.path.name

    @property
    def policy_path(self) -> Path:
        """Where the run's policy is (or will be) saved."""
        return self.path / POLICY_FILE

    @property
    def has_policy(self) -> bool:
        """Whether the run has saved a policy (a link is never one)."""
        return self.policy_path.is_file() and not self.policy_path.is_symlink()

    def owner_alive(self) -> bool | None:
        """Whether a live process owns the run now (its ``owner.lock``); None for a folder from
        before owner locks."""
        return owner_alive(self.path)

    @property
    def owned_here(self) -> bool:
        """Whether this process owns the run (it will train it, or trains it now)."""
        return self._owner is not None and self._owner.held

    # ------------------------------------------------------------------ create and load

    @classmethod
    def create(
        cls, parent: Path, record: RunRecord, name: str | None = None, status: str = "queued"
    ) -> RunFolder:
        """Make a new run folder ``parent/name`` atomically (built hidden, then renamed).

        Args:
            parent: where runs live (``<data>/runs``); created if missing.
            record: the run's settings.
            name: the folder's name; default ``<UTC time>-<planning>-<4 hex digits>``.
            status: the status written (``queued`` for a queue, ``running`` for a command).

        Raises:
            LearningError: the folder exists and is not empty, or the disk refused (full, read
                only); nothing is left behind.
        """
        parent = Path(parent)
        try:
            parent.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise _disk_error(err, "the run folder", parent) from None
        stamp = datetime.now(UTC).strftime("%Y%m%d-%H%M%S")
        planning = record.config.get("planning", "run")
        while True:
            final = parent / (name or f"{stamp}-{planning}-{secrets.token_hex(2)}")
            if final.exists() and (not final.is_dir() or any(final.iterdir())):
                if name:
                    raise LearningError(
                        f"The run folder {final} already exists; choose another name or delete it."
                    )
                continue
            break
        tmp = parent / f".{final.name}.{secrets.token_hex(4)}.tmp"
        run = cls(tmp, record)
        run.status = status
        if status == "running":
            run.started = now_iso()
            run.pid, run.host = os.getpid(), this_host()
        try:
            tmp.mkdir()
            if status in ("queued", "running"):  # owned before anyone can see the folder
                run._owner = OwnerLock(tmp)
            (tmp / CONFIG_FILE).write_text(json.dumps(record.to_dict(), indent=1))
            run.save_status()
            if final.is_dir():  # an empty folder the user made for it
                final.rmdir()
            os.rename(tmp, final)
        except OSError as err:
            if run._owner is not None:
                run._owner.release()
            shutil.rmtree(tmp, ignore_errors=True)
            raise _disk_error(err, "the run folder", parent) from None
        run.path = final
        return run

    @classmethod
    def load(cls, path: Path) -> RunFolder:
        """Read a run folder back, whatever made it.

        A run whose status says ``queued`` or ``running`` but whose training process is gone (a
        crash, ``kill -9``, a studio restart) is read as ``stopped``, with its curve so far.

        Raises:
            LearningError: no readable ``config.json``.
        """
        path = Path(path)
        for link in (path, path / CONFIG_FILE):
            if link.is_symlink():
                raise LearningError(
                    f"{link} is a symbolic link, which the studio never follows in a data folder; delete the run (only the link goes)."
                )
        if not (path / CONFIG_FILE).exists():
            raise LearningError(f"{path} has no {CONFIG_FILE}; it is not a run folder.")
        try:
            data = read_json(path / CONFIG_FILE)  # bounded: size, nesting depth, regular file
        except StudioError as err:
            raise LearningError(f"{err} Delete the run {path.name} if it stays so.") from None
        try:
            record = RunRecord.from_dict(data)
        except LearningError:
            raise
        except (TypeError, ValueError, KeyError, AttributeError) as err:
            raise LearningError(
                f"{path / CONFIG_FILE} garbles a field ({type(err).__name__}: {err}); delete the run."
            ) from None
        try:  # the size of the steps array a listing allocates for it
            check_budget(record.experiments, record.episodes)
        except ConfigError as err:
            raise LearningError(f"{path / CONFIG_FILE}: {err} Delete the run.") from None
        run = cls(path, record)
        run.reload()
        return run

    def reload(self, owner: bool | None | str = "probe") -> None:
        """Read ``status.json`` and ``steps.csv`` again (another process may be training it).

        A ``queued`` or ``running`` run is read as ``stopped`` (``interrupted``) when its owner is
        gone; nothing is written.

        Args:
            owner: whether another live process owns the run, when the caller knows (it holds
                the lock itself: False); None to judge by the pid (a folder from before owner
                locks); by default, asked of the run's ``owner.lock``.
        """
        if owner == "probe":  # before the status: a lock let go means its final status is written
            owner = owner_alive(self.path)
        status: dict[str, Any] = {}
        if (self.path / STATUS_FILE).is_symlink():
            log.warning("run %s: %s is a link, ignored", self.id, STATUS_FILE)
        elif (self.path / STATUS_FILE).exists():
            try:
                read = read_json(self.path / STATUS_FILE, max_bytes=MAX_STATUS_BYTES)
                if not isinstance(read, dict):
                    raise LearningError(f"{self.path / STATUS_FILE} holds no JSON object.")
                status = read
            except (StudioError, OSError) as err:  # the status is derived from the steps then
                log.warning("run %s: status ignored: %s", self.id, err)
        steps = self._read_steps()
        if steps is not None:
            self._steps = steps
        default = "done" if steps is not None and bool(np.all(steps >= 0)) else "stopped"
        state = status.get("status", default)
        self.status = state if state in STATUSES else "stopped"
        self.created = _text(status.get("created")) or self.record.created or self.created
        self.started = _text(status.get("started"))
        self.finished = _text(status.get("finished"))
        cpu = status.get("cpu_seconds")
        self.cpu_seconds = float(cpu) if isinstance(cpu, int | float) and np.isfinite(cpu) else 0.0
        self.error = _text(status.get("error"))
        self.pid = status.get("pid")
        host = status.get("host")
        self.host = host if isinstance(host, dict) else None
        alive = owner if owner is not None else pid_alive(self.pid, self.host, self.started)
        self.interrupted = False
        if self.status in ("queued", "running") and not (self.owned_here or alive):
            self.interrupted = True
            self.error = (
                "The process training it stopped while this run was training; its curve so far is kept, start it again to finish."
                if self.status == "running"
                else "The studio stopped before this run started; start it again."
            )
            self.status = "stopped"
            self.finished = self.finished or now_iso()
            self.pid = self.host = None

    def _read_steps(self) -> np.ndarray | None:
        path = self.path / STEPS_FILE
        if not path.exists() or path.is_symlink():
            return None
        # at most one number of MAX_STEPS_PER_EPISODE's width (or -1) and a separator per episode
        cell = len(str(MAX_STEPS_PER_EPISODE)) + 1
        limit = STEPS_HEADER_BYTES + self.record.experiments * self.record.episodes * cell
        try:
            text = read_bytes_bounded(path, limit).decode("ascii")
            steps = np.loadtxt(
                io.StringIO(text), delimiter=",", dtype=np.int64, ndmin=2, comments="#"
            )
        except (StudioError, ValueError, OSError) as err:  # not a file, too large, not numbers
            log.warning("run %s: unreadable %s, curve dropped: %s", self.id, path, err)
            return None
        if steps.shape != (self.record.experiments, self.record.episodes):
            log.warning("run %s: %s has shape %s, curve dropped", self.id, path, steps.shape)
            return None
        return steps

    # ------------------------------------------------------------------ views

    def steps(self) -> np.ndarray:
        """Saved steps per episode ``(experiments, episodes)``, -1 where not done."""
        if self._steps is not None:
            return self._steps
        return np.full((self.record.experiments, self.record.episodes), -1, np.int64)

    def curve(self, start: int = 0) -> dict[str, list]:
        """The saved curve (:func:`curve_statistics`)."""
        return curve_statistics(self.steps(), start)

    # ------------------------------------------------------------------ writes

    def save_status(self) -> None:
        """Write ``status.json`` atomically."""
        status = {
            "status": self.status,
            "created": self.created,
            "started": self.started,
            "finished": self.finished,
            "cpu_seconds": self.cpu_seconds,
            "error": self.error,
            "pid": self.pid if self.status in ("queued", "running") else None,
            "host": self.host if self.status in ("queued", "running") else None,
        }
        try:
            atomic_write_text(self.path / STATUS_FILE, json.dumps(status, indent=1))
        except OSError as err:
            raise _disk_error(err, "the run's status", self.path) from None
        if self.status not in ("queued", "running") and self._owner is not None:
            self._owner.release()  # the final status is written: nobody owns a finished run
            self._owner = None

    def save_steps(self, steps: np.ndarray, curves: bool = True) -> None:
        """Write ``steps.csv`` and, unless ``curves`` is false (a checkpoint), ``curves.csv``,
        each atomically. ``steps.csv`` is the truth; ``curves.csv`` is derived from it."""
        steps = np.asarray(steps, dtype=np.int64).copy()
        try:
            atomic_write_text(self.path / STEPS_FILE, steps_text(steps))
            if curves:
                atomic_write_text(self.path / CURVES_FILE, curves_csv(curve_statistics(steps)))
        except OSError as err:
            raise _disk_error(err, "the run's curve", self.path) from None
        self._steps = steps

    def recover(self) -> None:
        """Write down what :meth:`load` found for a run whose process died: its ``stopped``
        status and a ``curves.csv`` of its last checkpoint (no-op for other runs, and for a run
        whose owner turns out to be alive). The run's lock is held while it is written."""
        if not self.interrupted:
            return
        locked = (self.path / OWNER_FILE).exists()  # else a folder from before owner locks
        try:
            owner = OwnerLock(self.path)
        except LearningError:  # its owner is alive after all
            self.reload()
            return
        try:
            self.reload(owner=False if locked else None)  # under the lock: the last status
            if self.interrupted:
                self.save_steps(self.steps())
                self.save_status()
                self.interrupted = False
        finally:
            owner.release()

    def mark_stopped(self) -> None:
        """Mark a ``queued`` or ``running`` run ``stopped`` by hand, when no live process owns
        it: a run written before owners locked whose pid now names another process, or whose
        host cannot be asked. Its curve so far is kept.

        Raises:
            LearningError: a live process owns it (stop it there), or the disk refused.
        """
        owner = OwnerLock(self.path)  # refuses a run whose owner is alive
        try:
            self.reload(owner=False)  # the user's word, for a folder from before owner locks too
            if self.interrupted or self.status in ("queued", "running"):
                self.status = "stopped"
                self.interrupted = False
                self.finished = self.finished or now_iso()
                self.error = "Marked stopped by hand: no live process was training it; its curve so far is kept."
                self.save_steps(self.steps())
                self.save_status()
        finally:
            owner.release()

    def delete(self) -> None:
        """Delete the run folder (see :func:`delete_run_folder`); this process's own lock on it,
        if any, is let go as it goes."""
        owner, self._owner = self._owner, None
        delete_run_folder(self.path, owner if owner is not None and owner.held else None)

    def disown(self) -> None:
        """Let the run go without training it (a queue shutting down): other processes then
        read it as stopped before it started."""
        if self._owner is not None:
            self._owner.release()
            self._owner = None

    def save_policy(self, result: ExperimentResult, compress: bool = True) -> None:
        """Write the best experiment's Q table (or tile-coded weights) as the run's policy
        (``compress`` false for a checkpoint: far quicker to write, read the same)."""
        best = result.best_experiment()
        tmp = self.path / f".{POLICY_FILE}.{secrets.token_hex(4)}.tmp.npz"
        notes = f"run {self.id}: experiment {best} of {self.record.experiments}, seed {self.record.seed}, {len(self.record.demonstrations)} demonstrations"
        if self.record.kind == TASK_ARM_REACH:
            from ._linear_policy import save_tile_policy

            try:
                save_tile_policy(tmp, result, best, notes=notes, compress=compress)  # type: ignore[arg-type]
                os.replace(tmp, self.policy_path)
            except OSError as err:
                with contextlib.suppress(OSError):
                    tmp.unlink()
                raise _disk_error(err, "the run's policy", self.path) from None
            return
        grid = self.record.arm_grid()
        try:
            save_policy(
                tmp,
                grid,
                result.q[best],
                result.config,
                result.mean_steps(),
                experiments=self.record.experiments,
                notes=notes,
                compress=compress,
            )
            os.replace(tmp, self.policy_path)
        except OSError as err:
            with contextlib.suppress(OSError):
                tmp.unlink()
            raise _disk_error(err, "the run's policy", self.path) from None

    # ------------------------------------------------------------------ training

    def train(
        self,
        live: LiveProgress | None = None,
        *,
        workers: int | None = None,
        on_checkpoint: Callable[[LiveProgress], None] | None = None,
        poll_seconds: float = 0.05,
    ) -> ExperimentResult | None:
        """Train the run: checkpoint its curve while it learns, then save steps, policy, status.

        The experiments run in a thread (the kernels release the GIL); this thread writes
        ``steps.csv`` at most every :data:`CHECKPOINT_SECONDS` when the curve moved, and calls
        ``on_checkpoint`` every ``poll_seconds`` (a progress bar). ``live.stop()`` (or Ctrl-C here)
        ends the run at the next episode boundary; a run stopped before it started trains nothing.

        Returns:
            The result, or None when the run failed (``status``/``error`` say why) or was stopped
            before any episode.

        Raises:
            KeyboardInterrupt: after saving what was learnt, when interrupted.
        """
        record = self.record
        live = live or LiveProgress(record.experiments, record.episodes)
        if not self.owned_here:  # a loaded folder trained here: own it first
            self._owner = OwnerLock(self.path)
        self.status, self.started, self.pid = "running", self.started or now_iso(), os.getpid()
        self.host = this_host()
        self.save_status()
        if live.stopped:  # stopped before training started: nothing to run
            return self._finish(live, None, None)
        box: dict[str, Any] = {}
        ended = threading.Event()  # not Thread.join: a Ctrl-C inside join can end it too early

        def target() -> None:
            try:
                from ._prepare import prepare_learner  # imports this module

                prepare_learner(record.kind, live)  # the first run here compiles the kernels
                if record.kind == TASK_ARM_REACH:
                    box["result"] = _train_arm_reach(record, workers, live)
                    return
                box["result"] = run_experiments(
                    record.arm_grid().mdp(),
                    record.dynaq_config(),
                    record.experiments,
                    record.episodes,
                    record.seed,
                    record.demonstrations,
                    workers=workers,
                    live=live,
                )
            except BaseException as err:  # handed to the caller's thread
                box["error"] = err
            finally:
                ended.set()

        thread = threading.Thread(target=target, name=f"studio-train-{self.id}", daemon=True)
        thread.start()
        interrupted = False
        saved, last, every = 0, time.monotonic(), CHECKPOINT_SECONDS
        while not ended.is_set():
            try:
                ended.wait(poll_seconds)
                if on_checkpoint is not None:
                    on_checkpoint(live)
                now = time.monotonic()
                done = live.completed
                if now - last >= every and done != saved and not ended.is_set():
                    self.save_steps(live.steps, curves=False)
                    self._checkpoint_policy(live)
                    saved, last = done, time.monotonic()
                    # a huge run's checkpoint costs: keep writing it under a tenth of the time
                    every = max(CHECKPOINT_SECONDS, CHECKPOINT_COST_FACTOR * (last - now))
            except KeyboardInterrupt:
                interrupted = True
                live.stop()
            except LearningError as err:  # a full disk mid-run: stop, keep what is on disk
                log.warning("run %s: %s", self.id, err)
                live.stop()
                box.setdefault("disk", err)
        result = box.get("result")
        self._finish(live, result, box.get("error") or box.get("disk"))
        if interrupted:
            raise KeyboardInterrupt
        return result

    def _checkpoint_policy(self, live: LiveProgress) -> None:
        """Save the policy learnt so far (the kernels' tables as they are now), so a process
        killed mid-run leaves one up to its last checkpoint; the run's end replaces it."""
        snapshot = live.snapshot
        if snapshot is None:  # the learner has not built its tables yet
            return
        result = snapshot()
        if not result.completed.any():
            return
        try:
            self.save_policy(result, compress=False)
        except (LearningError, ValueError) as err:  # diverged weights: keep the last good one
            log.warning("run %s: policy checkpoint skipped: %s", self.id, err)

    def _finish(
        self,
        live: LiveProgress,
        result: ExperimentResult | None,
        error: BaseException | None,
    ) -> ExperimentResult | None:
        self.finished = now_iso()
        self.pid = None
        try:
            self.save_steps(live.steps)
            if result is not None and result.completed.any() and error is None:
                self.save_policy(result)
        except LearningError as err:
            error = error or err
        if result is not None:
            self.cpu_seconds = float(result.cpu_seconds.sum())
        if error is not None:
            self.status = "failed"
            self.error = (
                str(error)
                if isinstance(error, LearningError)
                else f"The run failed unexpectedly ({type(error).__name__}: {error}); see the log."
            )
            if not isinstance(error, LearningError):
                log.error("run %s failed", self.id, exc_info=error)
        elif result is None:
            self.status = "stopped"
            self.error = self.error or "Stopped before it started."
        else:
            self.status = "stopped" if result.stopped else "done"
        with contextlib.suppress(LearningError):
            self.save_status()
        return result


def _train_arm_reach(
    record: RunRecord, workers: int | None, live: LiveProgress
) -> ExperimentResult:
    """Linear Dyna-Q on ``TeachStudio/ArmReach-v0`` as the record says."""
    import gymnasium

    from ._gym import ARM_REACH_ID

    task = record.arm_reach()
    spec = task.to_dict()
    return run_experiments(
        lambda: gymnasium.make(ARM_REACH_ID, **spec),
        record.dynaq_config(),
        record.experiments,
        record.episodes,
        record.seed,
        [np.asarray(p, dtype=np.float64) for p in record.demonstrations],
        record.tile_coding(),
        workers=workers,
        live=live,
    )


def find_runs(parent: Path) -> list[Path]:
    """Every run folder under ``parent``: its children with a ``config.json``, and their children
    when a child is a group (a ``studio reproduce`` output or a sweep), sorted by path."""
    parent = Path(parent)
    if not parent.is_dir():
        return []
    found: list[Path] = []
    for child in sorted(parent.iterdir()):
        if child.name.startswith("."):
            continue
        if child.is_symlink():  # never followed: listed, so that it shows as damaged
            found.append(child)
            continue
        if not child.is_dir():
            continue
        if (child / CONFIG_FILE).is_file():
            found.append(child)
            continue
        with contextlib.suppress(OSError):
            found += [
                sub
                for sub in sorted(child.iterdir())
                if not sub.name.startswith(".")
                and (sub.is_symlink() or (sub.is_dir() and (sub / CONFIG_FILE).is_file()))
            ]
    return found
