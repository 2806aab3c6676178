"""Learning curves: one statistic set, one CSV layout, one figure.

Every tool that shows a run's progress (the page, ``studio train``, ``studio reproduce``, a sweep)
takes its statistics from :func:`curve_statistics` of the run's ``(experiments, episodes)`` steps,
writes them in the one layout :data:`CURVE_COLUMNS` (:func:`curves_csv`) and draws them with
:func:`curve_plot`.
"""

from __future__ import annotations

import csv
import io
import warnings
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, TextIO

import numpy as np

from .._errors import LearningError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

FIGURE_POINTS = 600
"""A curve figure draws at most about this many points per line (longer runs are averaged)."""
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
TIME_COLUMNS = ("wall_seconds", "cpu_seconds")
"""Two more ``curves.csv`` columns, after :data:`CURVE_COLUMNS`, in a run trained since they were
added: per episode, the mean over the experiments that finished it of each experiment's own wall
and CPU seconds from its start to that episode's end (:func:`episode_seconds`). A file without
them (an older run) still reads: its curve has no times."""
MAX_CURVES_BYTES_PER_EPISODE = 256
"""Largest ``curves.csv`` row read back (the studio writes under 120 bytes)."""


# ----------------------------------------------------------------------------- statistics


def curve_statistics(
    steps: np.ndarray, start: int = 0, times: np.ndarray | None = None
) -> dict[str, list]:
    """Learning-curve statistics of an ``(experiments, episodes)`` steps array, -1 for not done.

    Episodes run from index ``start`` up to the last one that any experiment finished. Each
    statistic is over the experiments that finished that episode (``count``): mean, population
    standard deviation, median, 10th and 90th percentiles, min and max. Experiments of a stopped
    run end at different episodes, so ``count`` falls towards the end: a plot shows it rather than
    pretend every point averages all experiments.

    Args:
        steps: real steps per episode, ``(experiments, episodes)``, -1 where not done.
        start: the first episode (0-based) to return.
        times: float ``(2, episodes)``, the run's :func:`episode_seconds` (NaN where unknown);
            when given, the curve also has :data:`TIME_COLUMNS` (None where unknown).

    Returns:
        ``{"episodes": [1-based], "mean", "std", "median", "p10", "p90", "min", "max", "count"}``,
        lists of equal length (and :data:`TIME_COLUMNS` with ``times``).
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
    if times is not None:
        out.update(time_lists(times[:, start:last]))
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


def episode_seconds(steps: np.ndarray, seconds: np.ndarray) -> np.ndarray:
    """The :data:`TIME_COLUMNS` of a run, per episode: float ``(2, episodes)``, the mean over the
    experiments that finished each episode (and whose time was stamped) of
    ``seconds`` (``(2, experiments, episodes)``, :attr:`LiveProgress.episode_seconds`); NaN where
    no experiment has both."""
    seconds = np.asarray(seconds, dtype=np.float64)
    known = (np.asarray(steps) >= 0)[None] & np.isfinite(seconds)
    count = known.sum(axis=1)
    total = np.where(known, seconds, 0.0).sum(axis=1)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(count > 0, total / np.maximum(count, 1), np.nan)


def time_lists(times: np.ndarray) -> dict[str, list]:
    """:data:`TIME_COLUMNS` of a ``(2, n)`` array as lists, rounded to the millisecond, None for
    NaN (JSON has no NaN)."""
    return {
        key: [None if np.isnan(v) else v for v in np.round(row, 3).tolist()]
        for key, row in zip(TIME_COLUMNS, np.asarray(times, dtype=np.float64), strict=True)
    }


def read_curve_times(text: str, episodes: int) -> np.ndarray | None:
    """The :data:`TIME_COLUMNS` of a run's ``curves.csv`` text as float ``(2, episodes)`` (NaN
    where a row or a cell is missing), or None when the file has no such columns (an older run)
    or does not parse (the curve then shows without times)."""
    rows = csv.reader(io.StringIO(text))
    header = next(rows, [])
    if not all(key in header for key in TIME_COLUMNS) or "episode" not in header:
        return None
    at = [header.index(key) for key in ("episode", *TIME_COLUMNS)]
    out = np.full((2, episodes), np.nan)
    try:
        for row in rows:
            if len(row) <= max(at):
                continue
            episode = int(row[at[0]]) - 1
            if 0 <= episode < episodes:
                out[:, episode] = [float(row[i]) if row[i] else np.nan for i in at[1:]]
    except ValueError:
        return None
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
    if all(key in curve for key in TIME_COLUMNS):  # None (unknown) makes its bucket unknown
        times = [[np.nan if v is None else v for v in curve[key]] for key in TIME_COLUMNS]
        out.update(time_lists(np.stack([mean_of(np.asarray(t), edges) for t in times])))
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
    stream: io.TextIOBase | TextIO, curves: Sequence[tuple[str | None, dict[str, list]]]
) -> None:
    """Write curves to an open text stream: a header, then one row per episode per curve.

    A ``configuration`` column comes first when the curves are named (several runs in one file);
    :data:`TIME_COLUMNS` come last when any curve has them (empty where a curve has none).
    """
    named = any(name is not None for name, _ in curves)
    timed = any(all(key in curve for key in TIME_COLUMNS) for _, curve in curves)
    writer = csv.writer(stream, lineterminator="\n")
    header = list(CURVE_COLUMNS) + (list(TIME_COLUMNS) if timed else [])
    writer.writerow((["configuration"] if named else []) + header)
    for name, curve in curves:
        columns = [curve["episodes"], *(curve[k] for k in STATISTICS), curve["count"]]
        n = len(curve["episodes"])
        if timed:
            columns += [curve.get(key) or [None] * n for key in TIME_COLUMNS]
        k = len(STATISTICS) + 1  # the count's column
        for row in zip(*columns, strict=True):
            values = [row[0], *(f"{v:.6g}" for v in row[1:k]), row[k]]
            values += ["" if v is None else f"{v:.6g}" for v in row[k + 1 :]]
            writer.writerow(([name] if named else []) + values)


def curve_plot(
    curves: Sequence[tuple[str, dict[str, list]]],
    *,
    log_steps: bool = False,
    title: str = "",
    points: int = FIGURE_POINTS,
) -> Figure:
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
