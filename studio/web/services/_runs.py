"""The page's run queue: runs wait in line and train one at a time in a worker thread.

Every run is a :class:`studio.learning.RunFolder` under ``<data_dir>/runs/``; the queue only adds
the waiting line, the live progress of the run training now, and the list the page shows. The
list holds every run folder there, whatever made it (the page, ``studio train --out runs/x``,
``studio reproduce --out runs/paper``, a sweep): folders appear as they are written, also while
the studio runs. A run inside a group folder (``runs/paper/SV-ZPL``) has the id ``paper~SV-ZPL``.

The worker trains through :meth:`RunFolder.train`, which checkpoints the curve and saves the
policy and status; the kernels release the GIL, so the API keeps answering and the event stream
polls the live arrays.
"""

from __future__ import annotations

import contextlib
import json
import logging
import re
import threading
import time
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from datetime import UTC, datetime
from pathlib import Path

from pydantic import TypeAdapter

from studio._files import now_iso
from studio.learning import (
    DEFAULT_GOAL_JOINTS_DEG,
    LearningError,
    LiveCurve,
    LiveProgress,
    RunBusyError,
    RunFolder,
    RunNotes,
    RunRecord,
    delete_run_folder,
    find_runs,
    goal_degrees,
    write_run_notes,
)

from .._errors import ConflictError, InvalidError, NotFoundError
from .._schemas import GridRunCreate, RunCreate, RunPublic

__all__ = ["Run", "RunQueue"]

log = logging.getLogger(__name__)

CURVE_CACHE_SECONDS = 0.05
"""A live curve takes in the episodes finished meanwhile at most this often, however many clients
ask (only those episodes are recomputed: :class:`studio.learning.LiveCurve`)."""
JSON_SLICE = 2_000
"""Values per ``json.dumps`` call when a curve is encoded (between calls other threads run)."""
CURVE_JSON_SECONDS = 1.0
"""A running run's ``/curve`` answer is encoded again at most this often (its 2,000,000-cell
curve is 180,000 numbers of JSON, encoded holding the GIL); the page follows a running run
through the event stream, which sends only what changed."""
GROUP_SEPARATOR = "~"
"""Joins a group folder's name and a run folder's name into a run id (``paper~SV-ZPL``)."""
RUN_ID = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}(~[A-Za-z0-9_][A-Za-z0-9_.-]{0,99})?$")
"""A run id: a folder name, or a group folder's and a run folder's names joined by ``~``."""
TRAINING_NICENESS = 10
"""How much lower the training threads' CPU priority is than the studio's (Linux ``nice``,
0-19): on a busy machine the API, the live pipeline and the scene get the cores first and
training takes what they leave, so a heavy run cannot starve the page."""


class Run:
    """A run in the list: its folder, and its live progress while this studio trains it."""

    def __init__(self, run_id: str, folder: RunFolder, live: LiveProgress | None = None) -> None:
        self.id = run_id
        self.folder = folder
        self.live = live  # set from submission on, so a Stop is never lost
        self._curve = LiveCurve(folder.record.episodes)
        self._curve_lock = threading.RLock()
        self._json_lock = threading.Lock()
        self._curve_taken: tuple[float, object] = (-1e9, None)  # when, and which steps array
        self._curve_json: tuple[float, int, bytes] | None = None  # when, version, JSON
        self._mtime = _status_mtime(folder.path)

    @property
    def status(self) -> str:
        """``queued``, ``running``, ``done``, ``stopped`` or ``failed``."""
        return self.folder.status

    def refresh(self) -> bool:
        """Read a run another process owns again when it wrote progress or its owner went away
        (a lock let go changes no file); whether anything was read."""
        folder = self.folder
        if self.live is not None or not (
            self.status in ("running", "queued") or folder.interrupted
        ):
            return False
        mtime = _status_mtime(folder.path)
        gone = self.status in ("running", "queued") and folder.owner_alive() is False
        if mtime == self._mtime and not gone:
            return False
        self._mtime = mtime
        with contextlib.suppress(OSError, LearningError):
            folder.reload()
        return True

    @property
    def name(self) -> str:
        """The run's label: its name, else planner and size."""
        return self.folder.record.label()

    @property
    def has_policy(self) -> bool:
        """Whether the run saved a policy file."""
        return self.folder.has_policy

    @property
    def policy_path(self) -> Path:
        """Where the run's policy is (or will be) saved."""
        return self.folder.policy_path

    @property
    def demonstrations(self) -> list[str]:
        """Names of the demonstrations the page asked for (none for other origins)."""
        return list(self.folder.record.demonstration_names)

    def live_curve(self) -> LiveCurve:
        """The run's curve, brought up to date: while it trains at most every
        :data:`CURVE_CACHE_SECONDS`, recomputing only the episodes finished meanwhile."""
        live = self.live
        with self._curve_lock:  # one thread updates; the others wait without holding the GIL
            when, source = self._curve_taken
            now = time.monotonic()
            if live is not None and self.status == "running":
                if now - when > CURVE_CACHE_SECONDS or source is not live.steps:
                    self._curve.update(live.steps, seconds=live.episode_seconds)
                    self._curve_taken = (now, live.steps)
            elif self.status != "queued":  # (a queued run has no steps yet)
                steps = self.folder.steps()
                if source is not steps:
                    self._curve.update(steps, times=self.folder.episode_times())
                    self._curve_taken = (now, steps)
        return self._curve

    @contextlib.contextmanager
    def curve_held(self) -> Iterator[LiveCurve]:
        """:meth:`live_curve`, which no other thread updates until the block ends (an event
        built from it is consistent: the run's ``episodes_done`` and the curve's pieces)."""
        with self._curve_lock:
            yield self.live_curve()

    def curve(self, start: int = 0) -> dict[str, list]:
        """The learning curve (:func:`studio.learning.curve_statistics`)."""
        return self.live_curve().curve(start)

    def curve_json(self) -> bytes:
        """:meth:`curve` as JSON (``CurvePublic``), encoded once per change for every client, and
        at most every :data:`CURVE_JSON_SECONDS` while the run trains."""
        running = self.status == "running"
        with self._json_lock:  # one thread encodes; the others wait for its answer
            curve, cached, now = self.live_curve(), self._curve_json, time.monotonic()
            if (
                cached is None
                or (cached[1] != curve.version and not running)
                or (cached[1] != curve.version and now - cached[0] > CURVE_JSON_SECONDS)
            ):
                with self._curve_lock:
                    version, data = curve.version, curve.curve()
                cached = self._curve_json = (now, version, _json_in_slices(data).encode())
        return cached[2]

    def model(self, curve: LiveCurve | None = None) -> RunPublic:
        """The run as the API shows it (``episodes_done`` from ``curve`` when given)."""
        done = (curve or self.live_curve()).episodes_done
        folder, record = self.folder, self.folder.record
        cpu, note, live = folder.cpu_seconds, None, self.live
        if self.status == "running" and live is not None:
            cpu, note = live.cpu_seconds, live.note
        return RunPublic(
            id=self.id,
            name=self.name,
            status=folder.status,  # type: ignore[arg-type]
            config=run_create_of(record),
            created=folder.created,
            started=folder.started,
            finished=folder.finished,
            episodes_done=done,
            episodes_total=record.experiments * record.episodes,
            cpu_seconds=round(float(cpu), 3),
            error=folder.error,
            note=note,
            has_policy=folder.has_policy,
            origin=record.origin,
            group=record.group,
            elsewhere=self.status in ("queued", "running") and self.live is None,
        )


class DamagedRun:
    """A run folder that cannot be read: listed with the reason, so it can be deleted."""

    def __init__(self, run_id: str, path: Path, reason: str) -> None:
        self.id = run_id
        self.path = path
        self.reason = reason

    def model(self) -> RunPublic:
        """The folder as the API lists it: status ``damaged``, the reason as its error."""
        try:
            stamp = datetime.fromtimestamp(self.path.lstat().st_mtime, UTC)
            created = stamp.isoformat(timespec="seconds")
        except OSError:
            created = ""
        return RunPublic(
            id=self.id,
            name=self.id,
            status="damaged",
            config=GridRunCreate(),
            created=created,
            started=None,
            finished=None,
            episodes_done=0,
            episodes_total=0,
            cpu_seconds=0.0,
            error=self.reason,
            has_policy=False,
            damaged=True,
        )


def _damage_text(err: BaseException) -> str:
    """Why a run folder cannot be read, as one sentence the page shows beside its delete button."""
    if isinstance(err, LearningError):
        return str(err)
    return f"The run folder's config.json or status.json holds a field the studio cannot read ({type(err).__name__}); delete the run."


def _json_in_slices(data: dict[str, list]) -> str:
    """``json.dumps(data)`` (compact) for a dict of long lists, encoded :data:`JSON_SLICE` values
    at a time: one ``json.dumps`` call holds the GIL until it returns, and a whole 20,000-episode
    curve (180,000 numbers) took the event loop's GIL for a tenth of a second and more."""
    fields = []
    for key, values in data.items():
        pieces = [
            json.dumps(values[i : i + JSON_SLICE], separators=(",", ":"))[1:-1]
            for i in range(0, len(values), JSON_SLICE)
        ]
        fields.append(f"{json.dumps(key)}:[{','.join(pieces)}]")
    return "{" + ",".join(fields) + "}"


def _status_mtime(path: Path) -> float:
    try:
        return max((path / name).stat().st_mtime for name in ("status.json", "steps.csv"))
    except (OSError, ValueError):
        with contextlib.suppress(OSError):
            return (path / "status.json").stat().st_mtime
        return 0.0


RUN_CREATE: TypeAdapter[RunCreate] = TypeAdapter(RunCreate)


def run_create_of(record: RunRecord) -> RunCreate:
    """The page's form values of a run, whatever made it (:meth:`RunRecord.form`; a goal the
    person did not type is shown as the grid's goal bin centre, else the default goal)."""
    form = record.form()
    if "goal_deg" not in form:
        goal: list[float] = []
        with contextlib.suppress(LearningError):
            goal = goal_degrees(record.arm_grid())
        form["goal_deg"] = goal or list(DEFAULT_GOAL_JOINTS_DEG)
    return RUN_CREATE.validate_python(form)


class RunQueue:
    """The runs under ``<data_dir>/runs`` and the worker thread that trains the page's, in turn.

    Args:
        folder: ``<data_dir>/runs``.
        on_change: called with ``"runs"`` or ``"policies"`` whenever a list changes.
        workers: threads per run (``None``: one per CPU core).

    Attributes:
        before_train: called in the worker with a run just marked running, before it trains
            (tests act in that window, e.g. to stop it; a Stop there is never lost).
        niceness: how much lower the CPU priority of the threads running the kernels is.
    """

    niceness: int = TRAINING_NICENESS

    def __init__(
        self,
        folder: Path,
        on_change: Callable[[str], None] = lambda _: None,
        workers: int | None = None,
    ) -> None:
        self.folder = folder
        self.on_change = on_change
        self.workers = workers
        self.before_train: Callable[[Run], None] | None = None
        self._runs: dict[str, Run] = {}
        self._damaged: dict[str, DamagedRun] = {}
        self._queue: deque[str] = deque()
        self._cond = threading.Condition()
        self._closing = False
        self._thread: threading.Thread | None = None
        self._scan()

    def _id_of(self, path: Path) -> str:
        rel = path.relative_to(self.folder)
        return GROUP_SEPARATOR.join(rel.parts)

    def _scan(self) -> bool:
        """Add run folders written since the last scan (by the CLI, say) and refresh runs that
        another process trains; forget folders deleted by hand. Whether anything changed."""
        changed = False
        found = {self._id_of(p): p for p in find_runs(self.folder)}
        found = {k: p for k, p in found.items() if RUN_ID.match(k)}
        with self._cond:
            known = dict(self._runs)
        damaged: dict[str, DamagedRun] = {}
        for run_id, path in found.items():
            run = known.get(run_id)
            if run is None:
                try:
                    run = Run(run_id, RunFolder.load(path))
                    run.model()  # a damaged field must not break the whole list
                except (OSError, ValueError, TypeError, LearningError) as err:
                    log.warning("unreadable run folder %s: %s", path, err)
                    damaged[run_id] = DamagedRun(run_id, path, _damage_text(err))
                    continue
                # a run whose owner is gone reads as stopped; its status is its owner's to write
                with self._cond:
                    self._runs.setdefault(run_id, run)
                changed = True
            elif run.refresh():
                changed = True
        with self._cond:
            for run_id, run in list(self._runs.items()):
                if run_id not in found and run.live is None and not run.folder.path.exists():
                    del self._runs[run_id]
                    changed = True
            changed = changed or set(damaged) != set(self._damaged)
            self._damaged = damaged
        return changed

    # ------------------------------------------------------------------ lifecycle

    def start(self) -> None:
        """Start the worker thread."""
        if self._thread is None:
            self._thread = threading.Thread(target=self._work, name="studio-runs", daemon=True)
            self._thread.start()

    def close(self, timeout: float = 10.0) -> None:
        """Stop the running run (its partial curve and policy are saved) and the worker thread."""
        with self._cond:
            self._closing = True
            for run in self._runs.values():
                if run.status == "running" and run.live is not None:
                    run.live.stop()
                elif run.status == "queued" and run.live is not None:
                    run.folder.disown()  # never trained here now: others read it as stopped
            self._cond.notify_all()
        if self._thread is not None:
            self._thread.join(timeout)
            self._thread = None

    # ------------------------------------------------------------------ API

    def list(self) -> list[Run]:
        """Every run, newest first (run folders written by other tools included)."""
        if self._scan():
            self.on_change("runs")
        with self._cond:
            runs = list(self._runs.values())
        return sorted(runs, key=lambda r: (r.folder.created, r.id), reverse=True)

    def damaged(self) -> list[DamagedRun]:
        """The run folders that cannot be read (as of the last listing), by id."""
        with self._cond:
            return sorted(self._damaged.values(), key=lambda d: d.id)

    def get(self, run_id: str) -> Run:
        """The run with that id (404 otherwise)."""
        if not isinstance(run_id, str) or not RUN_ID.match(run_id) or ".." in run_id:
            raise InvalidError(f"The run id {run_id!r} is not valid; use an id from the runs list.")
        with self._cond:
            run = self._runs.get(run_id)
        if run is None and self._scan():
            with self._cond:
                run = self._runs.get(run_id)
        if run is None:
            raise NotFoundError(f"There is no run {run_id!r}; pick one from the runs list.")
        if run.refresh():
            self.on_change("runs")
        return run

    def labelled_curves(self, run_ids: Sequence[str]) -> list[tuple[str, dict[str, list]]]:
        """Each run's curve in the order given (a repeated id once), labelled by the run's name,
        with its id after it where two of them share a name (404 for an unknown id)."""
        runs = [self.get(run_id) for run_id in dict.fromkeys(run_ids)]
        names = [r.name for r in runs]
        return [
            (r.name if names.count(r.name) == 1 else f"{r.name} ({r.id})", r.curve()) for r in runs
        ]

    def running(self) -> list[Run]:
        """Runs this studio is training now (at most one)."""
        with self._cond:
            return [r for r in self._runs.values() if r.status == "running" and r.live is not None]

    def uses_demonstration(self, name: str) -> Run | None:
        """A queued or running run that replays demonstration ``name``, if any."""
        with self._cond:
            for run in self._runs.values():
                if run.status in ("queued", "running") and name in run.demonstrations:
                    return run
        return None

    def queue(self, record: RunRecord) -> Run:
        """Write a checked run's folder (atomically) and queue it; it trains when the runs
        before it are done."""
        folder = RunFolder.create(self.folder, record)
        # the kernels' threads run at a lower priority: training must never starve the studio
        live = LiveProgress(record.experiments, record.episodes, niceness=self.niceness)
        run = Run(folder.id, folder, live)
        with self._cond:
            self._runs[run.id] = run
            self._queue.append(run.id)
            self._cond.notify_all()
        self.on_change("runs")
        return run

    def stop(self, run_id: str) -> Run:
        """Stop a queued run (it never starts) or a running one (at its next episode boundary).

        Raises:
            ConflictError: the run is not this studio's to stop (another process trains it).
        """
        run = self.get(run_id)
        changed = False
        with self._cond:
            if run.live is None and run.status in ("queued", "running"):
                raise ConflictError(
                    f"Run {run_id} is trained by another process; stop it there (Ctrl-C)."
                )
            if run.live is not None:
                run.live.stop()  # obeyed even if the worker is about to start it
            if run.status == "queued":
                with contextlib.suppress(ValueError):
                    self._queue.remove(run_id)
                folder = run.folder
                folder.status, folder.finished = "stopped", now_iso()
                folder.error = "Stopped before it started."
                folder.save_status()
                run.live = None
                changed = True
        if changed:
            self.on_change("runs")
        return run

    def mark_stopped(self, run_id: str) -> Run:
        """Mark a run that no live process trains ``stopped`` (its curve is kept).

        Raises:
            ConflictError: this studio trains it (stop it instead), or another live process
                owns it (stop it there).
        """
        run = self.get(run_id)
        if run.live is not None:
            raise ConflictError(f"Run {run_id} is this studio's; stop it instead.")
        try:
            run.folder.mark_stopped()
        except LearningError as err:
            raise ConflictError(str(err)) from None
        run._mtime = _status_mtime(run.folder.path)
        self.on_change("runs")
        return run

    def write_notes(self, run_id: str, tags: list[str], notes: str) -> RunNotes:
        """Replace run ``run_id``'s tags and notes (``<run>/notes.json``) and announce it, so
        other pages show them.

        Raises:
            ConflictError: the run folder is being created or deleted.
            RunNotesError: a limit broken (422).
        """
        run = self.get(run_id)
        try:
            stored = write_run_notes(run.folder.path, tags, notes)
        except RunBusyError as err:
            raise ConflictError(str(err)) from None
        self.on_change("runs")
        return stored

    def delete(self, run_id: str) -> None:
        """Delete a run and its folder (409 while it is training; 507-like 409 naming what could
        not be deleted). A damaged folder from the list may be deleted too."""
        with self._cond:
            broken = self._damaged.get(run_id)
        if broken is not None and run_id not in self._runs:
            self._delete_damaged(broken)
            return
        run = self.get(run_id)
        with self._cond:
            if run.status in ("running", "queued") and run.live is None:
                raise ConflictError(
                    f"Run {run_id} is being trained by another process; stop it there first."
                )
            if run.status == "running":
                raise ConflictError(f"Run {run_id} is training; stop it first, then delete it.")
            with contextlib.suppress(ValueError):
                self._queue.remove(run_id)
            del self._runs[run_id]
        had_policy = run.has_policy
        try:
            run.folder.delete()  # under its owner lock: refused if another process owns it
        except LearningError as err:
            self._scan()  # what is left of it is listed again
            raise ConflictError(str(err)) from None
        finally:
            self.on_change("runs")
            if had_policy:
                self.on_change("policies")

    def _delete_damaged(self, broken: DamagedRun) -> None:
        try:
            delete_run_folder(broken.path)  # a link goes, never what it points to
        except LearningError as err:
            raise ConflictError(str(err)) from None
        finally:
            self._scan()
            self.on_change("runs")

    def wait_idle(self, timeout: float) -> bool:
        """Block until nothing is queued or running here (for scripts and tests): until each
        run's worker let it go (``live`` None), which is after its last file is written. (Its
        status reads "done" before that, while its status file is still being written.)"""
        deadline = time.monotonic() + timeout
        with self._cond:
            while self._queue or any(r.live is not None for r in self._runs.values()):
                left = deadline - time.monotonic()
                if left <= 0:
                    return False
                self._cond.wait(min(left, 0.1))
        return True

    # ------------------------------------------------------------------ the worker

    def _work(self) -> None:
        while True:
            with self._cond:
                while not self._queue and not self._closing:
                    self._cond.wait()
                if self._closing:
                    return
                run = self._runs[self._queue.popleft()]
                run.folder.status = "running"
            try:
                if self.before_train is not None:
                    self.before_train(run)
                self.on_change("runs")
                run.folder.train(run.live, workers=self.workers)
                if self._closing and run.status == "stopped":
                    run.folder.error = "The studio was shut down during this run; its curve so far is kept, start it again to finish."
                    run.folder.save_status()
            except Exception as err:  # a bug must not kill the queue: the run shows it
                log.exception("run %s failed", run.id)
                run.folder.status = "failed"
                run.folder.error = f"The run failed unexpectedly ({type(err).__name__}: {err}); see the server log."
                run.folder.finished = now_iso()
                with contextlib.suppress(LearningError):
                    run.folder.save_status()
            with self._cond:
                run.live = None
                self._cond.notify_all()
            self.on_change("runs")
            if run.has_policy:
                self.on_change("policies")
