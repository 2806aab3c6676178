"""Training a run: the learner in a thread of its own, watched by the caller's thread.

The kernels release the GIL, so a run learns in a daemon thread (:class:`TrainingThread`) while
the thread that started it (the page's queue worker, ``studio train``'s main thread) checkpoints
the curve and the policy at most every :data:`CHECKPOINT_SECONDS` and reports progress
(:func:`watch_training`); a Ctrl-C there stops the learner at the next episode boundary.
At every poll it also stamps the episodes finished meanwhile with their experiment's wall and CPU
time (:class:`EpisodeClock`): the kernels read no clock, so time per episode is measured here.
:meth:`studio.learning.RunFolder.train` puts the two together with the run folder's files.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

import numpy as np

from .._errors import LearningError
from .._learner import ExperimentResult, LiveProgress
from .._prepare import prepare_learner
from ._record import RunRecord

log = logging.getLogger(__name__)

CHECKPOINT_SECONDS = 1.0
"""How often a training run's ``steps.csv`` is written to disk (at most this much is lost)."""
CHECKPOINT_COST_FACTOR = 10.0
"""A checkpoint waits at least this many times as long as the last one took to write, so a huge
run (20 x 50,000 episodes) spends under a tenth of a core on checkpoints."""


def train_learner(
    record: RunRecord, live: LiveProgress, workers: int | None = None
) -> ExperimentResult:
    """Run the record's experiments with its learner (:meth:`RunRecord.trained_by`): its task's
    own, Dyna-Q on the arm grid or linear Dyna-Q with tile coding on ``TeachStudio/ArmReach-v0``,
    or the baseline it names; the first run on a machine compiles the kernels first."""
    chosen = record.trained_by()
    prepare_learner(chosen.kind, live)
    return chosen.train(record, live, workers)  # type: ignore[return-value]


class TrainingThread:
    """:func:`train_learner` in a daemon thread; its result, or the error it raised.

    Attributes:
        ended: set when the learner returned or raised (waited on, never ``join``: a Ctrl-C
            inside ``join`` can end it too early).
        result: what it learnt, once ended without an error.
        error: what it raised, once ended with one.
    """

    def __init__(
        self, run_id: str, record: RunRecord, live: LiveProgress, workers: int | None
    ) -> None:
        self.run_id = run_id
        self.ended = threading.Event()
        self.result: ExperimentResult | None = None
        self.error: BaseException | None = None
        self._args = (record, live, workers)
        self._thread = threading.Thread(
            target=self._run, name=f"studio-train-{run_id}", daemon=True
        )

    def start(self) -> TrainingThread:
        """Start learning; returns itself."""
        self._thread.start()
        return self

    def _run(self) -> None:
        try:
            self.result = train_learner(*self._args)
        except BaseException as err:  # handed to the caller's thread
            self.error = err
        finally:
            self.ended.set()


class EpisodeClock:
    """Stamps each finished episode with its experiment's wall and CPU seconds so far
    (:attr:`LiveProgress.episode_seconds`), sampled where the run's thread polls the learner.

    An episode seen finished at a poll gets its experiment's clocks at that poll, or the
    experiment's final clocks when it has ended: exact to within one poll. When several episodes
    of an experiment finished since the last poll, the time between the two polls is shared out
    among them in proportion to their Q updates (real and planning), the learner's work.
    """

    def __init__(self, live: LiveProgress) -> None:
        self._live = live
        experiments = live.steps.shape[0]
        self._done = np.zeros(experiments, np.int64)  # episodes stamped, per experiment
        self._last = np.zeros((2, experiments))  # the last stamp, per experiment

    def sample(self) -> int:
        """Stamp the episodes finished since the last call; returns how many episodes are
        finished in all (:attr:`LiveProgress.completed`, counted once for both)."""
        live = self._live
        clocks = live.experiment_seconds()  # before the steps: a stamp is never too early
        done = np.count_nonzero(live.steps >= 0, axis=1)
        for e in np.flatnonzero(done > self._done):
            if not np.isfinite(clocks[:, e]).all():  # its start is not registered yet
                continue
            first, last = int(self._done[e]), int(done[e])
            work = np.maximum(live.updates[e, first:last], 1).astype(np.float64)
            share = np.cumsum(work) / work.sum()
            start = self._last[:, e]
            clock = np.maximum(clocks[:, e], start)  # clocks never run back
            live.episode_seconds[:, e, first:last] = start[:, None] + np.outer(clock - start, share)
            self._last[:, e] = clock
            self._done[e] = last
        return int(done.sum())


def watch_training(
    thread: TrainingThread,
    live: LiveProgress,
    checkpoint: Callable[[], None],
    on_checkpoint: Callable[[LiveProgress], None] | None = None,
    poll_seconds: float = 0.05,
) -> tuple[bool, LearningError | None]:
    """Wait for ``thread`` to end, calling ``checkpoint`` when the curve moved and at most every
    :data:`CHECKPOINT_SECONDS` (less often when one takes over a tenth of that), and
    ``on_checkpoint`` every ``poll_seconds``, stamping finished episodes with their time
    (:class:`EpisodeClock`) at each poll.

    A Ctrl-C, or a :class:`LearningError` from ``checkpoint`` (a full disk), stops the learner
    at its next episode boundary and waits for it.

    Returns:
        Whether it was interrupted (Ctrl-C), and the checkpoint's error, if any.
    """
    interrupted, disk = False, None
    saved, last, every = 0, time.monotonic(), CHECKPOINT_SECONDS
    clock = EpisodeClock(live)
    while not thread.ended.is_set():
        try:
            thread.ended.wait(poll_seconds)
            done = clock.sample()
            if on_checkpoint is not None:
                on_checkpoint(live)
            now = time.monotonic()
            if now - last >= every and done != saved and not thread.ended.is_set():
                checkpoint()
                saved, last = done, time.monotonic()
                # a huge run's checkpoint costs: keep writing it under a tenth of the time
                every = max(CHECKPOINT_SECONDS, CHECKPOINT_COST_FACTOR * (last - now))
        except KeyboardInterrupt:
            interrupted = True
            live.stop()
        except LearningError as err:  # a full disk mid-run: stop, keep what is on disk
            log.warning("run %s: %s", thread.run_id, err)
            live.stop()
            disk = disk or err
    clock.sample()  # the episodes of the last poll, at their experiments' final clocks
    return interrupted, disk
