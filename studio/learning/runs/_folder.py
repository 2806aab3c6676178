"""Training runs on disk: one folder layout, its status, its curve and its policy files.

Whatever starts a run (``studio train``, ``studio reproduce``, a sweep, the page's run queue), it
goes through :class:`RunFolder`, so every run folder reads back with :meth:`RunFolder.load` and
the page lists, plots, watches and exports it. What a run trains is its :class:`RunRecord`
(``_run_record.py``, built by ``resolve_run`` in ``_run_request.py``); its statistics and
``curves.csv`` layout are ``_curves.py``'s; the learner's thread is ``_run_train.py``'s; who owns
a live run is ``_owner.py``'s.

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
  :data:`CURVE_COLUMNS`, with each episode's wall and CPU time (:data:`TIME_COLUMNS`, measured
  while it trained), rewritten with every checkpoint of ``steps.csv`` and when the run ends: a
  run recovered after a crash (:meth:`RunFolder.recover`) keeps the times of its last
  checkpoint;
- ``policy.policy.npz``: the best experiment's Q table (see ``_policy.py``), saved with every
  ``steps.csv`` checkpoint from the tables the kernels are filling (:attr:`LiveProgress.snapshot`)
  and again when the run ends, also when it was stopped (Stop, Ctrl-C). A process killed with
  ``kill -9`` leaves the policy of its last checkpoint.

No file of a run folder, nor the folder itself, is read through a symbolic link.

A folder is created atomically: it is built as a hidden temporary folder next to its final place
and renamed there, so a full disk leaves no half-made run behind (:class:`LearningError` says so).

Use::

    record = resolve_run(RunRequest(experiments=20, episodes=100, seed=0))
    run = RunFolder.create(Path("runs"), record)   # runs/<time>-full-<hex>/
    result = run.train(workers=None)               # checkpoints, then policy + status
    again = RunFolder.load(run.path)
    curve_statistics(again.steps())                # the statistics the page and the CLI show
"""

from __future__ import annotations

import contextlib
import io
import json
import logging
import os
import secrets
import shutil
import sys
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import cast

import numpy as np

from studio import StudioError, read_bytes_bounded, read_json

from ..._files import atomic_write_text, now_iso
from ..._numbers import is_int
from .._config import MAX_STEPS_PER_EPISODE, check_budget
from .._errors import ConfigError, LearningError
from .._learner import ExperimentResult, LiveProgress
from ..likeness._run import save_run_likeness
from ._curves import (
    MAX_CURVES_BYTES_PER_EPISODE,
    curve_statistics,
    curves_csv,
    episode_seconds,
    read_curve_times,
)
from ._owner import OWNER_FILE, OwnerLock, owner_alive, pid_alive, this_host
from ._record import RunRecord
from ._train import TrainingThread, watch_training

log = logging.getLogger(__name__)

CONFIG_FILE = "config.json"
STATUS_FILE = "status.json"
STEPS_FILE = "steps.csv"
CURVES_FILE = "curves.csv"
POLICY_FILE = "policy.policy.npz"
STATUSES = ("queued", "running", "done", "stopped", "failed")
MAX_STATUS_BYTES = 64 * 1024
"""Largest ``status.json`` read (the studio writes a few hundred bytes)."""
STEPS_HEADER_BYTES = 1024
"""Room for ``steps.csv``'s comment line when bounding its size."""


def _text(value: object) -> str | None:
    """A string field of ``status.json``, or None when missing or of another type (damaged)."""
    return value if isinstance(value, str) else None


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
        self._times: np.ndarray | None = None  # per episode wall and CPU seconds, (2, episodes)
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
        planning = record.config.planning
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
        status: dict[str, object] = {}
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
            self._times = self._read_times()
        default = "done" if steps is not None and bool(np.all(steps >= 0)) else "stopped"
        state = status.get("status", default)
        self.status = state if state in STATUSES else "stopped"
        self.created = _text(status.get("created")) or self.record.created or self.created
        self.started = _text(status.get("started"))
        self.finished = _text(status.get("finished"))
        cpu = status.get("cpu_seconds")
        self.cpu_seconds = float(cpu) if isinstance(cpu, int | float) and np.isfinite(cpu) else 0.0
        self.error = _text(status.get("error"))
        pid = status.get("pid")
        self.pid = int(cast(int, pid)) if is_int(pid) else None
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

    def _read_times(self) -> np.ndarray | None:
        path = self.path / CURVES_FILE
        if not path.exists() or path.is_symlink():
            return None
        limit = STEPS_HEADER_BYTES + self.record.episodes * MAX_CURVES_BYTES_PER_EPISODE
        try:
            text = read_bytes_bounded(path, limit).decode("utf-8")
        except (StudioError, ValueError, OSError) as err:
            log.warning("run %s: unreadable %s, its times dropped: %s", self.id, path, err)
            return None
        return read_curve_times(text, self.record.episodes)

    # ------------------------------------------------------------------ views

    def steps(self) -> np.ndarray:
        """Saved steps per episode ``(experiments, episodes)``, -1 where not done."""
        if self._steps is not None:
            return self._steps
        return np.full((self.record.experiments, self.record.episodes), -1, np.int64)

    def episode_times(self) -> np.ndarray | None:
        """Each episode's wall and CPU time as saved in ``curves.csv`` (:data:`TIME_COLUMNS`,
        ``(2, episodes)``, NaN where unknown), or None for a run saved without them."""
        return self._times

    def curve(self, start: int = 0) -> dict[str, list]:
        """The saved curve (:func:`curve_statistics`, with the episodes' times when saved)."""
        return curve_statistics(self.steps(), start, self._times)

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

    def save_steps(self, steps: np.ndarray, seconds: np.ndarray | None = None) -> None:
        """Write ``steps.csv`` and then ``curves.csv``, each atomically. ``steps.csv`` is the
        truth; ``curves.csv`` is derived from it, with the episodes' times from ``seconds``
        (:attr:`LiveProgress.episode_seconds`) when given, else the ones saved before."""
        steps = np.asarray(steps, dtype=np.int64).copy()
        times = self._times if seconds is None else episode_seconds(steps, seconds)
        try:
            atomic_write_text(self.path / STEPS_FILE, steps_text(steps))
            text = curves_csv(curve_statistics(steps, times=times))
            atomic_write_text(self.path / CURVES_FILE, text)
        except OSError as err:
            raise _disk_error(err, "the run's curve", self.path) from None
        self._steps = steps
        self._times = times

    def recover(self) -> None:
        """Write down what :meth:`load` found for a run whose process died: its ``stopped``
        status and a ``curves.csv`` of its last checkpoint, with the episodes' times that
        checkpoint saved (no-op for other runs, and for a run whose owner turns out to be
        alive). The run's lock is held while it is written."""
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
        try:
            self.record.trained_by().save(tmp, self.record, result, notes=notes, compress=compress)
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

        The experiments run in a thread (:class:`TrainingThread`; the kernels release the GIL);
        this thread writes ``steps.csv`` at most every :data:`CHECKPOINT_SECONDS` when the curve
        moved, and calls ``on_checkpoint`` every ``poll_seconds`` (a progress bar).
        ``live.stop()`` (or Ctrl-C here) ends the run at the next episode boundary; a run stopped
        before it started trains nothing.

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
        thread = TrainingThread(self.id, record, live, workers).start()

        def checkpoint() -> None:  # with the times so far: a crash keeps them (recover)
            self.save_steps(live.steps, seconds=live.episode_seconds)
            self._checkpoint_policy(live)

        interrupted, disk = watch_training(thread, live, checkpoint, on_checkpoint, poll_seconds)
        self._finish(live, thread.result, thread.error or disk)
        if interrupted:
            raise KeyboardInterrupt
        return thread.result

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
            self.save_steps(live.steps, seconds=live.episode_seconds)
            if result is not None and result.completed.any() and error is None:
                self.save_policy(result)
                save_run_likeness(self.path, self.policy_path, self.record.demonstration_motions)
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
