"""What every learner shares: how an experiment draws its random numbers, the priority queue of
prioritized sweeping, the planners' budgets, and the run around the kernels (its progress, its
result, its arguments, its threads).

Both learners, tabular (:mod:`._dynaq`) and linear (:mod:`._linear`), import these; neither
imports the other, and :mod:`._experiments` picks one for a task.

Random numbers: a tiny deterministic generator (splitmix64) inside the kernels, so every
experiment is reproducible bit for bit whichever thread runs it. Experiment ``e`` of a run seeded
``seed`` starts from :func:`experiment_seed` ``(seed, e)``; each draw adds :data:`GOLDEN` to the
state and takes :func:`mix` of it, then :func:`below` or :func:`unit` turns the word into an
integer or a float.

The numba helpers are ``inline="always"``: they are compiled into each kernel that calls them,
never called across a boundary (a call that passes arrays updates their reference counts, which
costs more than a heap step). numba's disk cache of a kernel is keyed on the kernel's own file, so
after editing this file touch the kernels' files (or delete their ``__pycache__/*.nb*``) so they
recompile with the change.
"""

from __future__ import annotations

import os
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from dataclasses import dataclass
from typing import TypeVar

import numpy as np
from numba import njit

from ._config import PLANNERS, DynaQConfig, check_budget
from ._errors import LearningError

R = TypeVar("R", bound="ExperimentResult")

PLANNER_CODE = {name: code for code, name in enumerate(PLANNERS)}
"""The kernels' number for each of :data:`PLANNERS`."""
ZERO, FULL, SOFT, PRIORITIZED = (PLANNER_CODE[name] for name in PLANNERS)
MAX_NICENESS = 19
"""The lowest CPU priority Linux gives a thread."""

GOLDEN = np.uint64(0x9E3779B97F4A7C15)
"""splitmix64's increment: each draw adds it to the generator's state."""
_MIX1 = np.uint64(0xBF58476D1CE4E5B9)
_MIX2 = np.uint64(0x94D049BB133111EB)
_U11 = np.uint64(11)
_U27 = np.uint64(27)
_U30 = np.uint64(30)
_U31 = np.uint64(31)
_U32 = np.uint64(32)
_INV_2_53 = 1.0 / 9007199254740992.0

# --------------------------------------------------------------------------- random numbers


@njit(nogil=True, cache=True, inline="always")
def mix(z: np.uint64) -> np.uint64:
    """splitmix64's output function: a well-mixed 64-bit word from the generator's counter."""
    z = (z ^ (z >> _U30)) * _MIX1
    z = (z ^ (z >> _U27)) * _MIX2
    return z ^ (z >> _U31)


@njit(nogil=True, cache=True, inline="always")
def below(z: np.uint64, n: int) -> int:
    """An integer in [0, n) from a random word (Lemire's multiply-shift on the top 32 bits)."""
    return np.int64(((z >> _U32) * np.uint64(n)) >> _U32)


@njit(nogil=True, cache=True, inline="always")
def unit(z: np.uint64) -> float:
    """A float in [0, 1) from a random word."""
    return np.float64(z >> _U11) * _INV_2_53


def experiment_seed(seed: int, experiment: int) -> np.uint64:
    """The generator seed of one experiment, derived from the run seed and its index."""
    return np.uint64(np.random.SeedSequence([seed, experiment]).generate_state(1, np.uint64)[0])


# --------------------------------------------------------------------------- planning


@njit(nogil=True, cache=True, inline="always")
def plan_budget(planner, planning_steps, episode):
    """Planning updates per real step in episode ``episode`` (from 0) for the planner's code."""
    if planner == ZERO:
        return 0
    if planner == SOFT:
        return max(planning_steps - episode, 0)
    return planning_steps


@njit(nogil=True, cache=True, inline="always")
def heap_push(heap_idx, heap_pri, pos, size, idx, priority):
    """Queue ``idx`` with ``priority`` (or raise its priority if queued lower); returns the size."""
    i = pos[idx]
    if i < 0:
        i = size
        size += 1
    elif heap_pri[i] >= priority:
        return size
    while i > 0:  # sift up
        parent = (i - 1) >> 1
        if heap_pri[parent] >= priority:
            break
        heap_idx[i] = heap_idx[parent]
        heap_pri[i] = heap_pri[parent]
        pos[heap_idx[i]] = i
        i = parent
    heap_idx[i] = idx
    heap_pri[i] = priority
    pos[idx] = i
    return size


@njit(nogil=True, cache=True, inline="always")
def heap_pop(heap_idx, heap_pri, pos, size):
    """Remove the highest-priority entry; returns (idx, new size)."""
    top = heap_idx[0]
    pos[top] = -1
    size -= 1
    if size == 0:
        return top, size
    idx = heap_idx[size]
    priority = heap_pri[size]
    i = 0
    while True:  # sift down
        child = 2 * i + 1
        if child >= size:
            break
        if child + 1 < size and heap_pri[child + 1] > heap_pri[child]:
            child += 1
        if heap_pri[child] <= priority:
            break
        heap_idx[i] = heap_idx[child]
        heap_pri[i] = heap_pri[child]
        pos[heap_idx[i]] = i
        i = child
    heap_idx[i] = idx
    heap_pri[i] = priority
    pos[idx] = i
    return top, size


# --------------------------------------------------------------------------- the run around the kernels


class LiveProgress:
    """Shared, lock-free progress of a running :func:`run_experiments` call.

    The kernels write ``steps[e, k]`` (and ``updates[e, k]``) the moment episode ``k`` of
    experiment ``e`` ends; entries still -1 are not done yet. A web page polls these arrays from
    another thread to draw live curves, and calls :meth:`stop` to end the run at the next episode
    boundary.

    The learner also sets :attr:`snapshot` once its tables exist: the result so far, whose Q
    tables (or weights) are the very arrays the kernels update in place, so a checkpoint can save
    the policy learnt so far without stopping them (or copying every table).

    The kernels read no clock. Each experiment's thread enters :meth:`counting_cpu` as the
    experiment starts, and both learners start experiments in index order, so the n-th entry is
    experiment n (two threads starting together may swap two starts microseconds apart):
    :meth:`experiment_seconds` then gives each experiment's own wall and CPU seconds so far, and
    the run's watcher (``_run_train.EpisodeClock``) stamps every finished episode with them in
    :attr:`episode_seconds`.

    Args:
        experiments: number of experiments of the run this object will follow.
        episodes: episodes per experiment.
        niceness: how much lower the CPU priority of the threads running the kernels is
            (Linux ``nice``; 0 leaves it). A studio serving a page trains at a lower priority,
            so that a heavy run takes only the CPU its API, live pipeline and scene leave.
    """

    def __init__(self, experiments: int, episodes: int, niceness: int = 0) -> None:
        self.steps = np.full((experiments, episodes), -1, np.int64)
        self.updates = np.full((experiments, episodes), -1, np.int64)
        self.niceness = niceness
        self.note: str | None = None
        """A sentence on what the run does before its first episode (preparing the learner), or
        None once it learns."""
        self._stop = np.zeros(1, np.int64)
        self.snapshot: Callable[[], ExperimentResult] | None = None
        self._cpu_lock = threading.Lock()
        self._cpu_done = 0.0
        self._cpu_running: dict[int, float] = {}  # thread ident -> its CPU clock at start
        self._starts: list[tuple[int, float, float]] = []  # per experiment: ident, wall, CPU
        self._ends: dict[int, tuple[float, float]] = {}  # experiment -> wall and CPU seconds
        self.episode_seconds = np.full((2, experiments, episodes), np.nan, np.float32)
        """Per finished episode, its experiment's own wall (``[0]``) and CPU (``[1]``) seconds from
        the experiment's start to the episode's end; NaN until the run's watcher stamps it."""

    @contextmanager
    def counting_cpu(self) -> Iterator[list[float]]:
        """Count the calling thread's CPU time as this run's while the block runs (the kernels'
        threads wrap each experiment in it), so :attr:`cpu_seconds` grows live.

        Yields a one-element list that holds the block's CPU seconds once it ends.
        """
        ident = threading.get_ident()
        spent = [0.0]
        start = time.thread_time()
        with self._cpu_lock:
            self._cpu_running[ident] = start
            experiment = len(self._starts)
            self._starts.append((ident, time.monotonic(), start))
        try:
            yield spent
        finally:
            spent[0] = time.thread_time() - start
            with self._cpu_lock:
                del self._cpu_running[ident]
                self._cpu_done += spent[0]
                self._ends[experiment] = (time.monotonic() - self._starts[experiment][1], spent[0])

    def experiment_seconds(self) -> np.ndarray:
        """float ``(2, experiments)``: each experiment's wall (``[0]``) and CPU (``[1]``) seconds
        since it started, final once it ended; NaN before it starts."""
        out = np.full((2, self.steps.shape[0]), np.nan)
        now = time.monotonic()
        with self._cpu_lock:
            for e, (ident, wall, cpu) in enumerate(self._starts[: out.shape[1]]):
                if e in self._ends:
                    out[:, e] = self._ends[e]
                    continue
                out[0, e] = now - wall
                with suppress(OSError, AttributeError, OverflowError):  # no per-thread clocks
                    out[1, e] = time.clock_gettime(time.pthread_getcpuclockid(ident)) - cpu
        return out

    @property
    def cpu_seconds(self) -> float:
        """CPU seconds the run's experiments have used so far, the ones still running included."""
        with self._cpu_lock:  # a thread leaves _cpu_running under this lock before it ends
            total = self._cpu_done
            for ident, start in self._cpu_running.items():
                with suppress(OSError, AttributeError, OverflowError):  # no per-thread clocks
                    total += time.clock_gettime(time.pthread_getcpuclockid(ident)) - start
        return total

    def stop(self) -> None:
        """Ask every experiment to stop at its next episode boundary."""
        self._stop[0] = 1

    @property
    def stopped(self) -> bool:
        """Whether :meth:`stop` was called."""
        return bool(self._stop[0])

    @property
    def completed(self) -> int:
        """Episodes finished so far, over all experiments."""
        return int(np.count_nonzero(self.steps >= 0))

    @property
    def total(self) -> int:
        """Episodes the run will do if not stopped."""
        return int(self.steps.size)


def result_so_far(
    kind: type[R],
    live: LiveProgress,
    cpu_seconds: np.ndarray,
    q: np.ndarray,
    config: DynaQConfig,
    seed: int,
    **extra: object,
) -> R:
    """A learner's result as it stands: the progress so far, and ``q``, the tables the kernels
    are updating in place (not copied); ``stopped`` while episodes remain. Every learner builds
    its result, final or partial (:attr:`LiveProgress.snapshot`), through this."""
    return kind(
        steps=live.steps.copy(),
        updates=live.updates.copy(),
        cpu_seconds=cpu_seconds.copy(),
        q=q,
        config=config,
        seed=seed,
        stopped=bool(np.any(live.steps < 0)),
        **extra,
    )


def lower_thread_priority(niceness: int) -> None:
    """Run the calling thread ``niceness`` below the process's CPU priority (Linux, per thread).

    Only the threads that run the kernels call it: they hold no GIL while they compute, so
    the process's Python threads (a web server's) never wait for a low-priority thread holding
    it. Idempotent; a no-op for ``niceness <= 0`` and where threads have no priority of their own.
    """
    if niceness <= 0 or not hasattr(os, "setpriority") or sys.platform != "linux":
        return
    try:
        target = min(os.getpriority(os.PRIO_PROCESS, os.getpid()) + niceness, MAX_NICENESS)
        tid = threading.get_native_id()
        if os.getpriority(os.PRIO_PROCESS, tid) < target:
            os.setpriority(os.PRIO_PROCESS, tid, target)
    except OSError:  # never a reason not to train
        return


@dataclass(frozen=True, eq=False)
class ExperimentResult:
    """What :func:`run_experiments` returns.

    Attributes:
        steps: int ``(experiments, episodes)``: real steps per episode; -1 where the run was
            stopped before the episode ended.
        updates: int ``(experiments, episodes)``: Q updates per episode (real plus planning), -1
            where not done.
        cpu_seconds: float ``(experiments,)``: CPU time of each experiment's thread.
        q: float ``(experiments, S, A)``: the final Q tables.
        config: the settings used.
        seed: the seed used.
        stopped: whether the run was stopped early.
    """

    steps: np.ndarray
    updates: np.ndarray
    cpu_seconds: np.ndarray
    q: np.ndarray
    config: DynaQConfig
    seed: int
    stopped: bool

    @property
    def completed(self) -> np.ndarray:
        """bool ``(experiments, episodes)``: which episodes finished."""
        return self.steps >= 0

    def mean_steps(self) -> np.ndarray:
        """Mean steps per episode over the experiments that finished it (NaN where none did)."""
        done = self.completed
        total = np.where(done, self.steps, 0).sum(axis=0).astype(np.float64)
        count = done.sum(axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.where(count > 0, total / np.maximum(count, 1), np.nan)

    def best_experiment(self, tail: float = 0.25) -> int:
        """Index of the experiment with the fewest mean steps over its last ``tail`` of episodes."""
        scores = []
        for row in self.steps:
            done = row[row >= 0]
            if done.size == 0:
                scores.append(np.inf)
                continue
            k = max(1, int(np.ceil(done.size * tail)))
            scores.append(float(done[-k:].mean()))
        return int(np.argmin(scores))


def check_run_arguments(
    config: object,
    experiments: object,
    episodes: object,
    seed: object,
    workers: object,
    live: object,
    n_states: int = 1,
    n_actions: int = 1,
) -> tuple[int, int, LiveProgress]:
    """Check the arguments every learner's ``run_experiments`` shares, before any work starts.

    Returns:
        ``(seed, workers, live)``: the seed as a plain int, the thread count (``None``: one per
        core), and the progress to fill (a new one when ``live`` is None).

    Raises:
        ConfigError, LearningError: one sentence naming the bad argument and the fix.
    """
    if not isinstance(config, DynaQConfig):
        raise LearningError(f"config is a {type(config).__name__}; give a DynaQConfig.")
    check_budget(experiments, episodes, n_states, n_actions)
    if not isinstance(seed, int | np.integer) or isinstance(seed, bool) or not 0 <= seed < 2**63:
        raise LearningError(f"seed is {seed!r}; give a whole number from 0 to 2**63 - 1.")
    if workers is None:
        workers = os.cpu_count() or 1
    if not isinstance(workers, int) or isinstance(workers, bool) or workers < 1:
        raise LearningError(f"workers is {workers!r}; give a whole number of threads, at least 1.")
    if live is None:
        live = LiveProgress(experiments, episodes)  # type: ignore[arg-type]
    elif not isinstance(live, LiveProgress) or live.steps.shape != (experiments, episodes):
        raise LearningError(
            f"live follows a run of shape {getattr(getattr(live, 'steps', None), 'shape', None)}; create LiveProgress({experiments}, {episodes}) for this run."
        )
    if live.completed:
        raise LearningError(
            "live already holds a finished run; create a new LiveProgress for each run."
        )
    return int(seed), workers, live
