"""A sweep's summary: each trial's metrics, ``sweep.csv`` and the figure ``sweep.png``/``.svg``.

The metrics (:data:`METRICS`) come from each trial's run folder (:func:`trial_metrics`), so the
summary of a running sweep is the same computation as the one written when it ends. The figure
plots the metric against the first swept setting, mean and standard error over seeds, one line
per combination of the other swept settings.
"""

from __future__ import annotations

import contextlib
import csv
import io
import math
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TypeAlias, cast

import numpy as np

from ..._numbers import is_number
from .._errors import LearningError
from .._registry import learner
from ..paper._reproduce import _standard_error, episodes_to_converge
from ..runs._curves import curve_statistics
from ..runs._folder import RunFolder
from ..runs._record import RunRecord
from ._folder import (
    FIGURE_STEM,
    SUMMARY_FILE,
    sweep_folder,
    trial_records,
    trial_run_path,
)
from ._spec import METRICS, SweepError, SweepSpec, Trial, show_setting

FINAL_FRACTION = 0.1
"""``final_steps`` averages this fraction of the last episodes (at least one)."""
FIGURE_FORMATS = ("png", "svg")
"""The summary figure is written in these formats."""

Metrics: TypeAlias = dict[str, float]
"""A trial's :data:`METRICS` by name, with ``episodes_done`` and (once any episode is done)
``converged`` (NaN: not measured)."""
Cell: TypeAlias = str | int | float | bool | None
"""One value of ``sweep.csv`` (None: empty)."""
SummaryRow: TypeAlias = dict[str, Cell]
"""One row of ``sweep.csv``: ``trial``, ``seed``, the swept settings, ``status``, the metrics,
``converged``, ``episodes_done``, ``cpu_seconds``, ``wall_seconds``, ``attempts``, ``node``,
``run``."""
Series: TypeAlias = tuple[str, list[Cell], np.ndarray, np.ndarray]
"""One line of the figure: label, x values, mean over seeds, standard error over seeds."""


def trial_metrics(
    steps: np.ndarray,
    record: RunRecord,
    convergence_factor: float,
    level_steps: float | None = None,
) -> Metrics:
    """Every metric of :data:`METRICS` from a run's steps, over the episodes all experiments
    finished (a stopped or early-stopped run counts what it did). ``episodes_to_converge``'s level
    is ``level_steps`` when given, else ``convergence_factor`` x the grid's mean shortest path
    (NaN for the continuous task without ``level_steps``)."""
    steps = np.asarray(steps)
    done = int((steps >= 0).all(axis=0).cumprod().sum())
    start = min(len(record.demonstrations), done)
    out: Metrics = {"episodes_done": done}
    if done == 0:
        return {**out, **{name: math.nan for name in METRICS}}
    mean = np.asarray(curve_statistics(steps[:, :done])["mean"], dtype=np.float64)
    if level_steps is not None:
        level = level_steps
    else:
        shortest = learner(record.kind).mean_shortest_steps(record.task)
        level = math.nan if shortest is None else convergence_factor * shortest
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


def sweep_rows(data_dir: Path, spec: SweepSpec) -> list[SummaryRow]:
    """``sweep.csv``'s rows: per trial its settings, status, metrics, CPU and wall time."""
    records = trial_records(sweep_folder(data_dir, spec.name))
    return [_row(data_dir, spec, trial, records.get(trial.key, {})) for trial in spec.trials()]


def _row(data_dir: Path, spec: SweepSpec, trial: Trial, record: Mapping[str, object]) -> SummaryRow:
    """One trial's row; ``record`` is its end record (:class:`TrialEnd`), empty before it ends."""
    row: SummaryRow = {"trial": trial.key, "seed": trial.seed}
    row.update({name: show_setting(value) for name, value in trial.settings.items()})
    metrics: Metrics = {"episodes_done": 0, **{name: math.nan for name in METRICS}}
    run_path = trial_run_path(data_dir, spec.name, trial.key)
    cpu, status = math.nan, "not run"
    with contextlib.suppress(LearningError):
        run = RunFolder.load(run_path)
        metrics = trial_metrics(run.steps(), run.record, spec.convergence_factor, spec.level_steps)
        cpu, status = run.cpu_seconds, run.status
    ended = record.get("status")
    if ended == "failed" or (ended == "early-stopped" and status != "done"):
        status = ended  # a trial stopped so late that it had finished counts as done
    row["status"] = status
    row.update({name: metrics[name] for name in METRICS})
    row["converged"] = metrics.get("converged", "")
    row["episodes_done"] = metrics["episodes_done"]
    row["cpu_seconds"] = cpu
    row["wall_seconds"] = cast(Cell, record.get("wall_seconds", math.nan))
    row["attempts"] = cast(Cell, record.get("attempts", ""))
    row["node"] = cast(Cell, record.get("node", ""))
    row["run"] = run_path.name if run_path.is_dir() else ""
    return row


def sweep_csv(rows: Sequence[Mapping[str, Cell]]) -> str:
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


def metric_by_setting(rows: Sequence[Mapping[str, Cell]], spec: SweepSpec) -> list[Series]:
    """The metric against the first swept setting, one series per combination of the others:
    ``(label, x values, mean over seeds, standard error over seeds)``."""
    x_name, others = spec.swept[0], spec.swept[1:]
    series: dict[str, dict[Cell, list[float]]] = {}
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


def check_figure_format(fmt: object) -> None:
    """Refuse a figure format other than :data:`FIGURE_FORMATS`."""
    if fmt not in FIGURE_FORMATS:
        raise LearningError(f"The figure format {fmt!r} is not supported; use png or svg.")


def sweep_figure(rows: Sequence[Mapping[str, Cell]], spec: SweepSpec, fmt: str = "png") -> bytes:
    """The metric against the first swept setting (mean and standard error over seeds), one line
    per combination of the other swept settings, as PNG or SVG bytes."""
    return sweep_figures(rows, spec, (fmt,))[fmt]


def sweep_figures(
    rows: Sequence[Mapping[str, Cell]], spec: SweepSpec, formats: Sequence[str] = FIGURE_FORMATS
) -> dict[str, bytes]:
    """:func:`sweep_figure` in several formats, drawn once: ``{format: bytes}``."""
    from matplotlib.figure import Figure

    for fmt in formats:
        check_figure_format(fmt)
    fig = Figure(figsize=(7, 4), dpi=120, layout="constrained")
    ax = fig.add_subplot()
    x_name = spec.swept[0]
    series = metric_by_setting(rows, spec)
    values = spec.space[x_name]
    numeric = all(is_number(v) for v in (values if isinstance(values, list) else [0]))
    categories: list[Cell] = []
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


def write_summary(data_dir: Path, spec: SweepSpec) -> list[SummaryRow]:
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
