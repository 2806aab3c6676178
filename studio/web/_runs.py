"""Training runs: validated, queued, executed one at a time in a worker thread, kept on disk.

Each run lives in ``<data_dir>/runs/<id>/``:

- ``config.json``: the ``RunCreate`` body, the grid and Dyna-Q settings it resolved to, and the
  demonstrations' grid paths (so a run can be repeated without the demonstration files);
- ``status.json``: status, times, CPU seconds, error;
- ``steps.csv``: steps per episode, one row per experiment, -1 where not done (written every few
  seconds while training, so a crash keeps the partial curve);
- ``curves.csv``: mean, std, min and max steps per episode over the experiments that finished it;
- ``policy.policy.npz``: the best experiment's Q table (also for a stopped run that finished
  episodes).

The worker calls :func:`studio.learning.run_experiments` with a
:class:`~studio.learning.LiveProgress`; the numba kernels release the GIL, so the API keeps
answering and the SSE stream polls the live arrays for curves. A run that was queued or running
when the process died is listed as ``stopped`` after a restart, with its partial curve.
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
import threading
import time
from collections import deque
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from .._errors import StudioError
from ._errors import ConflictError, InvalidError, NotFoundError
from ._schemas import RunCreate
from ._store import NAME_PATTERN, atomic_write_text, now_iso

log = logging.getLogger(__name__)

CHECKPOINT_SECONDS = 2.0
"""How often a running run's partial curve is written to disk."""
CURVE_CACHE_SECONDS = 0.05
"""A live curve is recomputed at most this often, however many clients ask."""
ROBOT_GOAL_JOINTS = 3
"""The arm grid covers joints 1-3 of the Puma560 (the paper's task)."""
POLICY_FILE = "policy.policy.npz"
STEPS_FILE = "steps.csv"
CURVES_FILE = "curves.csv"
CONFIG_FILE = "config.json"
STATUS_FILE = "status.json"


def curve_of(steps: np.ndarray, start: int = 0) -> dict[str, list]:
    """Learning-curve statistics from an ``(experiments, episodes)`` array with -1 for not done.

    Episodes are listed from index ``start`` up to the last episode that at least one experiment
    finished; each statistic is over the experiments that finished that episode.
    """
    count = (steps >= 0).sum(axis=0)
    nonzero = np.flatnonzero(count)
    last = int(nonzero[-1]) + 1 if nonzero.size else 0
    start = max(0, min(start, last))
    sl = slice(start, last)
    done = steps[:, sl] >= 0
    d, s, c = done, steps[:, sl].astype(np.float64), count[sl]
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(d, s, 0.0).sum(axis=0) / np.maximum(c, 1)
        var = np.where(d, (s - mean) ** 2, 0.0).sum(axis=0) / np.maximum(c, 1)
    low = np.where(d, s, np.inf).min(axis=0) if d.size else np.zeros(0)
    high = np.where(d, s, -np.inf).max(axis=0) if d.size else np.zeros(0)
    return {
        "episodes": list(range(start + 1, last + 1)),
        "mean": np.round(mean, 3).tolist(),
        "std": np.round(np.sqrt(var), 3).tolist(),
        "min": low.astype(np.float64).tolist(),
        "max": high.astype(np.float64).tolist(),
        "count": c.astype(np.int64).tolist(),
    }


def _utc_now() -> str:
    return now_iso()


class Run:
    """One training run: its settings, its state, and its live or saved progress."""

    def __init__(self, folder: Path, create: RunCreate, record: dict[str, Any]) -> None:
        self.folder = folder
        self.id = folder.name
        self.create = create
        self.record = record  # config.json: the resolved grid, Dyna-Q settings, demo paths
        self.status = "queued"
        self.created = record.get("created", _utc_now())
        self.started: str | None = None
        self.finished: str | None = None
        self.error: str | None = None
        self.cpu_seconds = 0.0
        self.live: Any = None  # LiveProgress while running
        self._cpu_start = 0.0
        self._steps: np.ndarray | None = None  # saved or final steps
        self._lock = threading.Lock()
        self._curve_cache: tuple[float, np.ndarray] | None = None

    # ------------------------------------------------------------------ views

    @property
    def name(self) -> str:
        """The run's label: the user's name, else planner and size."""
        if self.create.name:
            return self.create.name
        demos = len(self.create.demonstrations)
        extra = f", {demos} demos" if demos else ""
        return f"{self.create.planning} x{self.create.experiments}{extra}"

    @property
    def has_policy(self) -> bool:
        """Whether the run saved a policy file."""
        return (self.folder / POLICY_FILE).is_file()

    @property
    def policy_path(self) -> Path:
        """Where the run's policy is (or will be) saved."""
        return self.folder / POLICY_FILE

    def steps(self) -> np.ndarray:
        """Steps per episode ``(experiments, episodes)``, -1 where not done (live while running)."""
        live = self.live
        if live is not None:
            now = time.monotonic()
            cache = self._curve_cache
            if cache is None or now - cache[0] > CURVE_CACHE_SECONDS:
                cache = (now, live.steps.copy())
                self._curve_cache = cache
            return cache[1]
        if self._steps is not None:
            return self._steps
        return np.full((self.create.experiments, self.create.episodes), -1, np.int64)

    def episodes_done(self) -> int:
        """Episodes finished over all experiments."""
        return int(np.count_nonzero(self.steps() >= 0))

    def curve(self, start: int = 0) -> dict[str, list]:
        """The learning curve (see :func:`curve_of`)."""
        return curve_of(self.steps(), start)

    def public(self, steps: np.ndarray | None = None) -> dict[str, Any]:
        """The ``RunPublic`` fields (``episodes_done`` from ``steps`` when given)."""
        steps = self.steps() if steps is None else steps
        cpu = self.cpu_seconds
        if self.status == "running":
            cpu = time.process_time() - self._cpu_start
        return {
            "id": self.id,
            "name": self.name,
            "status": self.status,
            "config": self.create.model_dump(),
            "created": self.created,
            "started": self.started,
            "finished": self.finished,
            "episodes_done": int(np.count_nonzero(steps >= 0)),
            "episodes_total": self.create.experiments * self.create.episodes,
            "cpu_seconds": round(float(cpu), 3),
            "error": self.error,
            "has_policy": self.has_policy,
        }

    # ------------------------------------------------------------------ disk

    def save_status(self) -> None:
        """Write ``status.json`` atomically."""
        atomic_write_text(
            self.folder / STATUS_FILE,
            json.dumps(
                {
                    "status": self.status,
                    "created": self.created,
                    "started": self.started,
                    "finished": self.finished,
                    "cpu_seconds": self.cpu_seconds,
                    "error": self.error,
                },
                indent=1,
            ),
        )

    def save_steps(self, steps: np.ndarray) -> None:
        """Write ``steps.csv`` and ``curves.csv`` atomically."""
        buffer = io.StringIO()
        np.savetxt(
            buffer,
            steps,
            fmt="%d",
            delimiter=",",
            header="steps per episode; one row per experiment; -1 = not done",
        )
        atomic_write_text(self.folder / STEPS_FILE, buffer.getvalue())
        atomic_write_text(self.folder / CURVES_FILE, curve_csv(curve_of(steps)))

    @classmethod
    def load(cls, folder: Path) -> Run:
        """Read a run folder back; a run caught queued or running by a crash becomes ``stopped``."""
        record = json.loads((folder / CONFIG_FILE).read_text())
        run = cls(folder, RunCreate.model_validate(record["request"]), record)
        try:
            status = json.loads((folder / STATUS_FILE).read_text())
        except (OSError, ValueError):
            status = {"status": "stopped"}
        run.status = status.get("status", "stopped")
        run.created = status.get("created", run.created)
        run.started = status.get("started")
        run.finished = status.get("finished")
        run.cpu_seconds = float(status.get("cpu_seconds") or 0.0)
        run.error = status.get("error")
        steps_path = folder / STEPS_FILE
        if steps_path.is_file():
            try:
                steps = np.loadtxt(steps_path, delimiter=",", dtype=np.int64, ndmin=2)
                if steps.shape == (run.create.experiments, run.create.episodes):
                    run._steps = steps
            except ValueError:
                log.warning("run %s: unreadable %s, curve dropped", run.id, steps_path)
        if run.status in ("queued", "running"):
            was = run.status
            run.status = "stopped"
            run.finished = run.finished or _utc_now()
            run.error = (
                "The studio stopped while this run was training; its curve so far is kept, start it again to finish."
                if was == "running"
                else "The studio stopped before this run started; start it again."
            )
            run.save_status()
        return run


def curve_csv(curve: dict[str, list]) -> str:
    """A curve as CSV text: ``episode,mean,std,min,max,experiments``."""
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["episode", "mean", "std", "min", "max", "experiments"])
    for row in zip(
        curve["episodes"], curve["mean"], curve["std"], curve["min"], curve["max"], curve["count"],
        strict=True,
    ):  # fmt: skip
        writer.writerow(row)
    return out.getvalue()


def prepare_run(
    create: RunCreate, demonstration_path: Callable[[str], np.ndarray]
) -> tuple[Any, Any, list[list[int]]]:
    """Check a ``RunCreate`` against the learning package's rules before anything is queued.

    Args:
        create: the request.
        demonstration_path: the Puma560 joint path (N, 6), radians, of a demonstration by name.

    Returns:
        ``(grid, config, demonstration grid paths)``.

    Raises:
        StudioError: one sentence naming the bad field and its allowed values (answered as 422).
    """
    from studio.kinematics import Puma560
    from studio.learning import ArmGrid, DynaQConfig, check_budget

    config = DynaQConfig(
        alpha=create.alpha,
        gamma=create.gamma,
        epsilon=create.epsilon,
        planning=create.planning,
        planning_steps=create.planning_steps,
    )
    grid0 = ArmGrid(bins=create.bins)  # validates bins alone first: its message is the clearest
    goal = np.asarray(create.goal_deg, dtype=np.float64)
    if goal.shape != (ROBOT_GOAL_JOINTS,) or not np.all(np.isfinite(goal)):
        raise InvalidError(
            f"goal_deg is {create.goal_deg!r}; give {ROBOT_GOAL_JOINTS} finite angles in degrees, one per joint 1-3."
        )
    robot = Puma560()
    lower = np.degrees(robot.lower[:ROBOT_GOAL_JOINTS])
    upper = np.degrees(robot.upper[:ROBOT_GOAL_JOINTS])
    for j in range(ROBOT_GOAL_JOINTS):
        if not lower[j] <= goal[j] <= upper[j]:
            raise InvalidError(
                f"goal_deg joint {j + 1} is {goal[j]:g} degrees, which the Puma560 cannot reach; give an angle from {lower[j]:g} to {upper[j]:g}."
            )
    bins = tuple(int(b) for b in grid0.bins_of_angles(np.radians(goal)))
    grid = ArmGrid(bins=create.bins, goal=bins)
    centre = np.degrees(grid.angles_of(grid.goal_state))
    for j in range(ROBOT_GOAL_JOINTS):
        if not lower[j] <= centre[j] <= upper[j]:
            raise InvalidError(
                f"goal_deg joint {j + 1} falls in the bin centred at {centre[j]:.1f} degrees, beyond the Puma560's limit of {upper[j] if centre[j] > 0 else lower[j]:g}; choose a goal nearer the middle of the range or another number of bins."
            )
    check_budget(create.experiments, create.episodes, grid.n_states, grid.n_actions)
    if not isinstance(create.seed, int) or not 0 <= create.seed < 2**63:
        raise InvalidError(f"seed is {create.seed!r}; give a whole number from 0 to 2**63 - 1.")
    if create.name is not None and (not create.name.strip() or len(create.name) > 100):
        raise InvalidError("name must be 1 to 100 characters; give a shorter label or none.")
    paths: list[list[int]] = []
    goal_state = grid.goal_state
    for name in create.demonstrations:
        q_path = np.asarray(demonstration_path(name), dtype=np.float64)
        path = grid.path_from_joints(q_path, stop_at_goal=True)
        if path[-1] != goal_state:
            end = np.degrees(q_path[-1, :ROBOT_GOAL_JOINTS])
            raise InvalidError(
                f"Demonstration {name!r} ends at joints ({end[0]:.0f}, {end[1]:.0f}, {end[2]:.0f}) degrees, not in the goal bin; choose demonstrations that reach this run's goal or set the goal where they end."
            )
        paths.append(path)
    if len(paths) > create.episodes:
        raise InvalidError(
            f"The run replays {len(paths)} demonstrations but has only {create.episodes} episodes; give at least as many episodes as demonstrations."
        )
    return grid, config, paths


class RunQueue:
    """The runs on disk and the worker thread that trains them one at a time.

    Args:
        folder: ``<data_dir>/runs``.
        on_change: called with ``"runs"`` or ``"policies"`` whenever a list changes.
        workers: threads per run (``None``: one per CPU core).
    """

    def __init__(
        self,
        folder: Path,
        on_change: Callable[[str], None] = lambda _: None,
        workers: int | None = None,
    ) -> None:
        self.folder = folder
        self.on_change = on_change
        self.workers = workers
        self._runs: dict[str, Run] = {}
        self._queue: deque[str] = deque()
        self._cond = threading.Condition()
        self._closing = False
        self._thread: threading.Thread | None = None
        self._load()

    def _load(self) -> None:
        if not self.folder.is_dir():
            return
        for folder in sorted(self.folder.iterdir()):
            if not folder.is_dir() or not (folder / CONFIG_FILE).is_file():
                continue
            try:
                run = Run.load(folder)
            except (OSError, ValueError, KeyError, StudioError) as err:
                log.warning("skipping unreadable run folder %s: %s", folder, err)
                continue
            self._runs[run.id] = run

    # ------------------------------------------------------------------ lifecycle

    def start(self) -> None:
        """Start the worker thread."""
        if self._thread is None:
            self._thread = threading.Thread(target=self._work, name="studio-runs", daemon=True)
            self._thread.start()

    def close(self, timeout: float = 10.0) -> None:
        """Stop the running run (its partial curve is saved) and the worker thread."""
        with self._cond:
            self._closing = True
            for run in self._runs.values():
                if run.status == "running" and run.live is not None:
                    run.live.stop()
            self._cond.notify_all()
        if self._thread is not None:
            self._thread.join(timeout)
            self._thread = None

    # ------------------------------------------------------------------ API

    def list(self) -> list[Run]:
        """Every run, newest first."""
        with self._cond:
            runs = list(self._runs.values())
        return sorted(runs, key=lambda r: (r.created, r.id), reverse=True)

    def get(self, run_id: str) -> Run:
        """The run with that id (404 otherwise)."""
        if not isinstance(run_id, str) or not NAME_PATTERN.match(run_id) or ".." in run_id:
            raise InvalidError(f"The run id {run_id!r} is not valid; use an id from the runs list.")
        with self._cond:
            run = self._runs.get(run_id)
        if run is None:
            raise NotFoundError(f"There is no run {run_id!r}; pick one from the runs list.")
        return run

    def running(self) -> list[Run]:
        """Runs training now (at most one)."""
        with self._cond:
            return [r for r in self._runs.values() if r.status == "running"]

    def uses_demonstration(self, name: str) -> Run | None:
        """A queued or running run that replays demonstration ``name``, if any."""
        with self._cond:
            for run in self._runs.values():
                if run.status in ("queued", "running") and name in run.create.demonstrations:
                    return run
        return None

    def submit(self, create: RunCreate, demonstration_path: Callable[[str], np.ndarray]) -> Run:
        """Validate a run, write its folder and queue it."""
        grid, config, paths = prepare_run(create, demonstration_path)
        created = _utc_now()
        stamp = datetime.now(UTC).strftime("%Y%m%d-%H%M%S")
        self.folder.mkdir(parents=True, exist_ok=True)
        while True:
            run_id = f"{stamp}-{create.planning}-{secrets.token_hex(2)}"
            folder = self.folder / run_id
            try:
                folder.mkdir()
                break
            except FileExistsError:
                continue
        record = {
            "id": run_id,
            "created": created,
            "request": create.model_dump(),
            "grid": grid.to_dict(),
            "config": config.to_dict(),
            "experiments": create.experiments,
            "episodes": create.episodes,
            "seed": create.seed,
            "demonstrations": paths,
        }
        atomic_write_text(folder / CONFIG_FILE, json.dumps(record, indent=1))
        run = Run(folder, create, record)
        run.created = created
        run.save_status()
        with self._cond:
            self._runs[run_id] = run
            self._queue.append(run_id)
            self._cond.notify_all()
        self.on_change("runs")
        return run

    def stop(self, run_id: str) -> Run:
        """Stop a queued run (it never starts) or a running one (at its next episode boundary)."""
        run = self.get(run_id)
        changed = False
        with self._cond:
            if run.status == "queued":
                with contextlib.suppress(ValueError):
                    self._queue.remove(run_id)
                run.status = "stopped"
                run.finished = _utc_now()
                run.error = "Stopped before it started."
                run.save_status()
                changed = True
            elif run.status == "running" and run.live is not None:
                run.live.stop()
        if changed:
            self.on_change("runs")
        return run

    def delete(self, run_id: str) -> None:
        """Delete a run and its folder (409 while it is running)."""
        run = self.get(run_id)
        with self._cond:
            if run.status == "running":
                raise ConflictError(f"Run {run_id} is training; stop it first, then delete it.")
            with contextlib.suppress(ValueError):
                self._queue.remove(run_id)
            del self._runs[run_id]
        had_policy = run.has_policy
        shutil.rmtree(run.folder, ignore_errors=True)
        self.on_change("runs")
        if had_policy:
            self.on_change("policies")

    def wait_idle(self, timeout: float) -> bool:
        """Block until nothing is queued or running (for scripts and tests)."""
        deadline = time.monotonic() + timeout
        with self._cond:
            while self._queue or any(r.status == "running" for r in self._runs.values()):
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
                run.status = "running"
            try:
                self._train(run)
            except Exception as err:  # a bug must not kill the queue: the run shows it
                log.exception("run %s failed", run.id)
                run.status = "failed"
                run.error = f"The run failed unexpectedly ({type(err).__name__}: {err}); see the server log."
                run.finished = _utc_now()
                run.live = None
                run.save_status()
            with self._cond:
                self._cond.notify_all()
            self.on_change("runs")
            if run.has_policy:
                self.on_change("policies")

    def _train(self, run: Run) -> None:
        from studio.learning import (
            ArmGrid,
            DynaQConfig,
            LiveProgress,
            run_experiments,
            save_policy,
        )

        record = run.record
        grid = ArmGrid(**{**record["grid"], "goal": tuple(record["grid"]["goal"])})
        config = DynaQConfig.from_dict(record["config"])
        experiments, episodes = run.create.experiments, run.create.episodes
        live = LiveProgress(experiments, episodes)
        run._cpu_start = time.process_time()
        run.started = _utc_now()
        run.live = live
        run.save_status()
        self.on_change("runs")
        outcome: dict[str, Any] = {}

        def train() -> None:
            try:
                outcome["result"] = run_experiments(
                    grid.mdp(),
                    config,
                    experiments,
                    episodes,
                    run.create.seed,
                    record["demonstrations"],
                    workers=self.workers,
                    live=live,
                )
            except BaseException as err:  # handed to the worker below
                outcome["error"] = err

        thread = threading.Thread(target=train, name=f"studio-run-{run.id}", daemon=True)
        thread.start()
        saved = 0
        while thread.is_alive():
            thread.join(CHECKPOINT_SECONDS)
            done = live.completed
            if thread.is_alive() and done != saved:  # only when the curve moved
                run.save_steps(live.steps.copy())
                saved = done
        result = outcome.get("result")
        steps = live.steps.copy()
        run._steps = steps
        run.save_steps(steps)
        run.finished = _utc_now()
        if result is None:
            err = outcome.get("error")
            run.status = "failed"
            run.error = (
                str(err)
                if isinstance(err, StudioError)
                else f"The run failed unexpectedly ({type(err).__name__}: {err}); see the server log."
            )
            if not isinstance(err, StudioError):
                log.error("run %s failed", run.id, exc_info=err)
            run.cpu_seconds = time.process_time() - run._cpu_start
        else:
            run.cpu_seconds = float(result.cpu_seconds.sum())
            if result.completed.any():
                best = result.best_experiment()
                tmp = run.folder / f".{POLICY_FILE}.tmp.npz"
                save_policy(
                    tmp,
                    grid,
                    result.q[best],
                    config,
                    result.mean_steps(),
                    experiments=experiments,
                    notes=f"run {run.id}: experiment {best} of {experiments}, seed {run.create.seed}, {len(record['demonstrations'])} demonstrations",
                )
                os.replace(tmp, run.policy_path)
            run.status = "stopped" if result.stopped else "done"
            if result.stopped and self._closing:
                run.error = "The studio was shut down during this run; its curve so far is kept, start it again to finish."
        run.live = None
        run.save_status()
