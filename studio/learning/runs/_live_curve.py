"""A run's learning curve while its steps fill: recomputed only where episodes finished.

:func:`curve_statistics` over a whole ``(experiments, episodes)`` array costs time in proportion to
its size: for the largest run the studio accepts (100 x 20,000) about a tenth of a second of
sorting and averaging, and as much again to turn the lists into JSON. A page that follows such a
run live asks for it several times a second, from several clients. Yet between two looks only the
episodes an experiment finished meanwhile changed (an episode's statistics change only when one
more experiment finishes it), a few hundred columns at most. :class:`LiveCurve` keeps the
statistics of every episode and recomputes just those, with the same :func:`curve_statistics`,
so the curve it gives is always equal to ``curve_statistics(steps)``.

Each episode also keeps the :attr:`LiveCurve.version` at which it last changed, so a reader who
saw version ``v`` asks :meth:`LiveCurve.changed_since` for the spans to send again.

Given the run's per-episode times too (:attr:`LiveProgress.episode_seconds`, stamped by the run's
watcher a poll after the steps), the curve carries :data:`TIME_COLUMNS`; an episode whose time
was not stamped yet is recomputed at the next update until it is.
"""

from __future__ import annotations

import threading

import numpy as np

from ._curves import STATISTICS, TIME_COLUMNS, curve_statistics, episode_seconds, time_lists

SPAN_GAP = 64
"""Changed episodes closer than this are sent as one span (fewer, slightly longer pieces)."""


class LiveCurve:
    """The :func:`curve_statistics` of a steps array that only fills (``-1`` becomes a count).

    Thread-safe: :meth:`update` may be called from several threads (request handlers, the event
    stream); each reads a consistent snapshot of the columns it recomputes.

    Args:
        episodes: the steps array's number of columns.
    """

    def __init__(self, episodes: int) -> None:
        self._count = np.zeros(episodes, np.int64)
        self._stats = np.zeros((len(STATISTICS), episodes), np.float64)
        self._stamp = np.zeros(episodes, np.int64)
        self._times = np.full((len(TIME_COLUMNS), episodes), np.nan)
        self._untimed = np.zeros(0, np.int64)  # finished episodes whose time is not stamped yet
        self.timed = False
        """Whether the curve has :data:`TIME_COLUMNS` (it was given times)."""
        self._lock = threading.Lock()
        self.version = 0
        """Grows by one at each :meth:`update` that found finished episodes."""

    @property
    def episodes_done(self) -> int:
        """Episodes finished over all experiments, at the last :meth:`update`."""
        return int(self._count.sum())

    def update(
        self, steps: np.ndarray, seconds: np.ndarray | None = None, times: np.ndarray | None = None
    ) -> int:
        """Take in the episodes finished since the last call; returns :attr:`version`.

        ``steps`` may be written by the training threads meanwhile: each recomputed column's
        statistics and count come from one copy of that column, and a column that finished
        again meanwhile is recomputed at the next call.

        Args:
            steps: the run's ``(experiments, episodes)`` steps, -1 where not done.
            seconds: a training run's :attr:`LiveProgress.episode_seconds`, which gives the curve
                :data:`TIME_COLUMNS`.
            times: or a finished run's per-episode times (:func:`episode_seconds`, ``(2,
                episodes)``), as read from its ``curves.csv``.
        """
        counts = np.count_nonzero(steps >= 0, axis=0)
        with self._lock:
            if times is not None:
                self._take_times(np.asarray(times, dtype=np.float64))
            changed = np.flatnonzero(counts != self._count)
            if seconds is not None:
                self.timed = True
                changed = np.union1d(changed, self._untimed)
            if changed.size == 0:
                return self.version
            part = curve_statistics(steps[:, changed])  # a copy of just these columns
            n = len(part["count"])  # it leaves out trailing columns nobody finished: 0 there
            self.version += 1
            for row, key in enumerate(STATISTICS):
                values = np.zeros(changed.size)
                values[:n] = part[key]
                self._stats[row, changed] = values
            count = np.zeros(changed.size, np.int64)
            count[:n] = part["count"]
            self._count[changed] = count
            self._stamp[changed] = self.version
            if seconds is not None:
                done, stamps = steps[:, changed] >= 0, seconds[:, :, changed]
                self._times[:, changed] = episode_seconds(done.astype(np.int64) - 1, stamps)
                self._untimed = changed[(done & np.isnan(stamps[0])).any(axis=0)]
            return self.version

    def _take_times(self, times: np.ndarray) -> None:
        """Replace the episodes' times (under the lock); the episodes whose time changed are
        sent again."""
        self.timed = True
        same = (times == self._times) | (np.isnan(times) & np.isnan(self._times))
        differ = np.flatnonzero(~same.all(axis=0))
        if differ.size:
            self.version += 1
            self._times[:] = times
            self._stamp[differ] = self.version

    def curve(self, start: int = 0, stop: int | None = None) -> dict[str, list]:
        """Episodes ``start`` to ``stop`` (0-based, end excluded; None: the last finished one) in
        :func:`curve_statistics`' layout."""
        with self._lock:
            nonzero = np.flatnonzero(self._count)
            last = int(nonzero[-1]) + 1 if nonzero.size else 0
            stop = last if stop is None else max(0, min(int(stop), last))
            start = max(0, min(int(start), stop))
            out: dict[str, list] = {"episodes": list(range(start + 1, stop + 1))}
            for row, key in enumerate(STATISTICS):
                out[key] = self._stats[row, start:stop].tolist()
            out["count"] = self._count[start:stop].tolist()
            if self.timed:
                out.update(time_lists(self._times[:, start:stop]))
        return out

    def changed_since(self, version: int) -> list[tuple[int, int]]:
        """The spans ``(start, stop)`` (0-based, end excluded) of episodes that changed after
        ``version``, nearby ones joined (:data:`SPAN_GAP`)."""
        with self._lock:
            columns = np.flatnonzero(self._stamp > version)
        if columns.size == 0:
            return []
        breaks = np.flatnonzero(np.diff(columns) > SPAN_GAP)
        starts = np.concatenate([[columns[0]], columns[breaks + 1]])
        stops = np.concatenate([columns[breaks], [columns[-1]]]) + 1
        return [(int(a), int(b)) for a, b in zip(starts, stops, strict=True)]
