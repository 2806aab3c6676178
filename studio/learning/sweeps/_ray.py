"""Parameter sweeps on Ray Tune: a checked spec in, one ordinary run per trial out, a summary beside.

:func:`run_sweep` runs a spec's trials (``_sweep_spec.py``) on Ray Tune, on a local Ray using the
machine's cores or on an existing cluster (``address``). Tune brings the scheduling, the retries
of a trial whose worker died, and the optional ASHA early stopping; this module brings:

- **Trials as ordinary runs.** Each trial trains through :class:`RunFolder` into its run folder
  (``_sweep_folder.py``), so the page lists, plots, watches and exports it like any run.
- **The sweep folder**: ``sweep.json``, a record per ended trial, and the summary
  (``_sweep_summary.py``) written when the sweep ends.
- **Resumption by our own check**: ``resume=True`` runs only the trials that did not finish
  (:func:`finished_trials`), so a sweep survives Ctrl-C, a killed driver or a lost cluster alike.

Ray is an optional dependency (``pip install -e '.[cluster]'``), imported only when a sweep runs.
On a multi-machine cluster the data folder must be on storage every node sees at the same path
(as Ray Tune itself requires of its ``storage_path``).
"""

from __future__ import annotations

import contextlib
import importlib.util
import logging
import math
import os
import shutil
import socket
import sys
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Protocol

from studio import StudioError, is_loopback

from ..._files import now_iso
from ..._numbers import is_int
from .._learner import LiveProgress
from ..runs._folder import RunFolder
from ..runs._owner import this_host
from ..runs._record import RunRecord
from ._folder import (
    RAY_DIR,
    TrialEnd,
    check_folder,
    finished_trials,
    prepare_folder,
    record_trial_end,
    set_status,
    trial_records,
    trial_run_path,
)
from ._spec import SweepError, SweepSpec, Trial, trial_record
from ._summary import Metrics, SummaryRow, sweep_rows, trial_metrics, write_summary

MAX_RETRIES = 3
"""A trial whose worker dies (a crash, a lost node, ``kill -9``) is run again up to this often."""
ADDRESS_TIMEOUT_SECONDS = 5.0
"""How long to try to reach a cluster's ``HOST:PORT`` before calling it unreachable."""
RAY_HINT = "install it with pip install -e '.[cluster]'"
_NO_RAY = f"Sweeps run on Ray Tune, which is not installed; {RAY_HINT}."
STOP_WAIT_SECONDS = 300
"""How long a worker whose trial the scheduler stopped waits for the trial to save its run (the
learners end at their next episode boundary) before Tune gives up re-using the worker for the next
trial, which would then fail. Tune's own default, 2 s, is shorter than one episode of a big trial."""
STOP_POLL_SECONDS = 0.1
"""How often the driver looks whether a stopped trial has saved its run (:data:`STOP_WAIT_SECONDS`
at most)."""
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
LOCAL_RAY_ENVIRONMENT = {
    "RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0",
    "RAY_prestart_worker_first_driver": "0",
}
"""Set (always) before Ray is imported when the sweep starts its own Ray.

- ``RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER=0`` is Ray's switch for a single-machine Ray: the node's
  address is then loopback, so the GCS, the raylet, the workers and the agents all listen on
  127.0.0.1 only. Without it every one of them listens on all interfaces, and anyone who reaches
  the machine could join the Ray and run code as the user. (Ray turns
  ``ray.init(_node_ip_address="127.0.0.1")`` back into the machine's network address, so that is
  no way to do it.)
- ``RAY_prestart_worker_first_driver=0``: the raylet starts no idle worker per core when the
  sweep's driver connects. Tune's trials never run in those (each trial's actor gets a worker of
  its own), so they only cost a Python start with Ray imported each, about half a second of CPU
  per core, and were stopped unused.

Set while Ray is imported and while it starts its processes, which inherit it; then put back, so
that nothing else the process starts inherits it."""

Report = dict[str, float | str | None]
"""What a trial reports to Tune: its :data:`Metrics`, ``episodes``, ``final``, where it runs
(``node``, ``hostname``, ``pid``) and, at the end, ``cpu_seconds`` and ``wall_seconds``."""


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
    rows: list[SummaryRow]
    ran: list[str] = field(default_factory=list)
    interrupted: bool = False
    failed: list[str] = field(default_factory=list)


# ----------------------------------------------------------------------------- one trial


@dataclass(frozen=True)
class _Job:
    """What every trial of a sweep shares (sent once to the cluster). The spec goes as the checked
    :class:`SweepSpec`: checking it again costs every trial time that grows with the sweep's
    size (each trial's combination is checked: 0.15 s per trial for a 1,000-trial sweep)."""

    spec: SweepSpec
    trials: dict[str, Trial]
    data_dir: str
    milestones: tuple[int, ...]


def _trainable(config: Mapping[str, str], job: _Job) -> None:
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
    where: Report = {"node": host["node"], "hostname": host["hostname"], "pid": os.getpid()}
    start = time.perf_counter()
    run = RunFolder.create(path.parent, record, name=path.name, status="running")
    live = LiveProgress(spec.experiments, spec.episodes)
    stopped: list[SystemExit] = []
    on_checkpoint = _rung_reporter(spec, record, list(job.milestones), where, stopped)
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


def _rung_reporter(
    spec: SweepSpec,
    record: RunRecord,
    pending: list[int],
    where: Report,
    stopped: list[SystemExit],
) -> Callable[[LiveProgress], None]:
    """The run's checkpoint hook: at each ASHA rung in ``pending`` it reports the metrics so far;
    when Tune answers by stopping the trial, it stops the run and keeps the stop in ``stopped``."""
    from ray import tune

    def on_checkpoint(live: LiveProgress) -> None:
        if not pending or stopped:
            return
        done = int((live.steps >= 0).all(axis=0).cumprod().sum())
        while pending and done >= pending[0]:
            k = pending.pop(0)
            metrics: Metrics = trial_metrics(
                live.steps[:, :k], record, spec.convergence_factor, spec.level_steps
            )
            try:
                tune.report({**metrics, "episodes": k, "final": False, **where})
            except SystemExit as stop:  # Tune stopped the trial (ASHA, or Ctrl-C)
                live.stop()
                stopped.append(stop)
                return

    return on_checkpoint


# ----------------------------------------------------------------------------- Ray


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


def _import_ray(local: bool = False) -> ModuleType:
    """Import Ray (with :data:`RAY_ENVIRONMENT` set); ``local``: the sweep starts its own Ray, on
    loopback only (:data:`LOCAL_RAY_ENVIRONMENT`, read by Ray when it is imported)."""
    _set_ray_environment()
    try:
        with _environment(LOCAL_RAY_ENVIRONMENT if local else {}):
            import ray
            from ray import tune  # noqa: F401
    except ImportError:
        raise SweepError(_NO_RAY) from None
    return ray


def _ray_installed() -> bool:
    """Whether Ray can be imported, found without importing it."""
    try:
        return importlib.util.find_spec("ray") is not None
    except ValueError:  # in sys.modules as None: taken out on purpose
        return False


def _ray_initialized() -> bool:
    """Whether this process has already initialised Ray (read without importing it)."""
    ray = sys.modules.get("ray")
    return ray is not None and ray.is_initialized()


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


def _connect(ray: ModuleType, address: str | None, workers: int | None) -> bool:
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


# ----------------------------------------------------------------------------- the sweep


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
    data_dir = Path(data_dir).resolve()
    # A sweep that runs already, exists, or is not there to resume is refused before Ray is
    # imported (seconds of CPU): the answer comes at once.
    check_folder(data_dir, spec, resume)
    # Before anything is written: a missing Ray or cluster leaves no trace. A cluster out of
    # reach is told before Ray is imported too (seconds of CPU), a missing Ray first.
    if address is not None and not _ray_initialized():
        if not _ray_installed():
            raise SweepError(_NO_RAY)
        _check_address(address)
    ray = _import_ray(local=address is None)
    folder = prepare_folder(data_dir, spec, resume)
    trials = spec.trials()
    finished = finished_trials(data_dir, spec) if resume else set()
    todo = [t for t in trials if t.key not in finished]
    progress = SweepProgress(total=len(trials), done=len(finished))
    notify = on_progress or (lambda _p: None)
    if finished:  # the best so far, on resume
        labels = {t.key: t.label() for t in trials}
        for row in sweep_rows(data_dir, spec):
            if row["trial"] in finished:
                _improve(progress, row[spec.metric], labels[str(row["trial"])])
    notify(progress)
    if not todo:
        rows = write_summary(data_dir, spec)
        set_status(folder, "done")
        return SweepResult(folder, spec, rows)

    started = _connect(ray, address, workers)
    if started:  # the driver's host now has its Ray node id
        set_status(folder, "running", host=this_host())
    ran: list[str] = []
    failed: list[str] = []
    try:
        callback = _progress_callback(folder, spec, progress, notify, ran, failed)
        _fit(spec, data_dir, folder, todo, callback)
        _await_stopped_saves(data_dir, spec, folder, ran)
    finally:
        if started:
            ray.shutdown()
    done = finished_trials(data_dir, spec)
    interrupted = len(done) + len(failed) < len(trials)
    rows = write_summary(data_dir, spec)
    set_status(folder, "done" if len(done) == len(trials) else "interrupted")
    return SweepResult(folder, spec, rows, ran=ran, interrupted=interrupted, failed=failed)


def _await_stopped_saves(
    data_dir: Path,
    spec: SweepSpec,
    folder: Path,
    ran: list[str],
    timeout: float = STOP_WAIT_SECONDS,
) -> None:
    """Wait (up to ``timeout`` s) until every trial of ``ran`` that the scheduler stopped has
    saved its run. Tune counts a trial ended as soon as it stops it, while the trial's worker
    still runs to the next episode boundary to save what it learnt; the sweep's last such trial
    has no next trial waiting on its worker, and shutting Ray down then killed it unsaved (on a
    busy machine): its run held no episode, so the sweep read as interrupted and lost its row."""
    records = trial_records(folder)
    pending = [key for key in ran if records.get(key, {}).get("status") == "early-stopped"]
    deadline = time.monotonic() + timeout
    while pending and time.monotonic() < deadline:
        pending = [key for key in pending if _unsaved(data_dir, spec, key)]
        if pending:
            time.sleep(STOP_POLL_SECONDS)


def _unsaved(data_dir: Path, spec: SweepSpec, key: str) -> bool:
    """Whether trial ``key``'s run folder still says it is running (or cannot be read yet)."""
    path = trial_run_path(data_dir, spec.name, key)
    if not path.exists():
        return False  # never started: nothing to wait for
    try:
        return RunFolder.load(path).status == "running"
    except StudioError:
        return True


def _fit(
    spec: SweepSpec, data_dir: Path, folder: Path, todo: list[Trial], callback: object
) -> None:
    """Run the ``todo`` trials on Tune (ASHA when the spec asks), ``callback`` seeing each end."""
    from ray import tune
    from ray.tune.schedulers import ASHAScheduler

    job = _Job(
        spec=spec,
        trials={t.key: t for t in spec.trials()},
        data_dir=str(data_dir),
        milestones=tuple(spec.scheduler.milestones(spec.episodes) if spec.scheduler else ()),
    )
    scheduler = None
    if spec.scheduler is not None:
        scheduler = ASHAScheduler(
            time_attr="episodes",
            max_t=spec.episodes,
            grace_period=spec.scheduler.grace_episodes,
            reduction_factor=spec.scheduler.reduction_factor,
        )
    session = len(list((folder / RAY_DIR).glob("session-*"))) if (folder / RAY_DIR).is_dir() else 0
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


def _improve(progress: SweepProgress, value: object, label: str) -> None:
    is_number = isinstance(value, int | float) and not isinstance(value, bool)
    if is_number and not math.isnan(value) and (progress.best is None or value < progress.best[0]):
        progress.best = (float(value), label)


class _TuneTrial(Protocol):
    """What the progress callback reads of Tune's trial."""

    config: dict[str, str]
    last_result: Report | None


def _progress_callback(
    folder: Path,
    spec: SweepSpec,
    progress: SweepProgress,
    notify: Callable[[SweepProgress], None],
    ran: list[str],
    failed: list[str],
) -> object:
    """A Tune callback that records each ended trial and keeps the progress counts."""
    from ray import tune

    by_key = {t.key: t for t in spec.trials()}
    running: set[str] = set()

    def count() -> None:
        progress.running = len(running)
        notify(progress)

    class Progress(tune.Callback):  # type: ignore[misc, name-defined]
        def on_trial_start(
            self, iteration: int, trials: list, trial: _TuneTrial, **info: object
        ) -> None:
            running.add(trial.config["key"])
            count()

        def on_trial_complete(
            self, iteration: int, trials: list, trial: _TuneTrial, **info: object
        ) -> None:
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
            _record_end(folder, key, trial, result, status)
            if status != "stopped":
                progress.done += 1
                ran.append(key)
            _improve(progress, result.get(spec.metric), by_key[key].label())
            count()

        def on_trial_error(
            self, iteration: int, trials: list, trial: _TuneTrial, **info: object
        ) -> None:
            key = trial.config["key"]
            running.discard(key)
            progress.failed += 1
            failed.append(key)
            error = getattr(trial, "error_file", None)
            _record_end(folder, key, trial, dict(trial.last_result or {}), "failed", error)
            count()

    return Progress()


def _record_end(
    folder: Path, key: str, trial: _TuneTrial, result: Report, status: str, error: object = None
) -> None:
    """Write the trial's end record (``trials/<key>.json``) from its last report."""
    record: TrialEnd = {
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
    record_trial_end(folder, record)
