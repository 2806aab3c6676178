"""The sweep folder on disk: where a sweep's files and its trials' runs live, and which finished.

Each trial trains through :class:`RunFolder` (the one writer of run folders) into
``<data>/runs/<sweep>/<sweep>-<trial>/``, with ``origin="sweep"`` and ``group=<sweep>``, so the
page lists, plots, watches and exports it like any run. The sweep folder
``<data>/sweeps/<sweep>/`` holds:

- ``sweep.json`` (:class:`SweepFile`): the spec, its trials, its status and the driver's process;
- ``trials/<trial>.json`` (:class:`TrialEnd`): written by the driver when a trial ends: where it
  ran (Ray node, hostname and worker pid), attempts, times;
- ``sweep.csv`` and ``sweep.png``/``.svg``: the summary (``_sweep_summary.py``);
- ``ray/``: Tune's own bookkeeping.

Resumption is by our own check (:func:`finished_trials`): a trial is finished when its record says
``done`` or ``early-stopped`` and its run folder reads back, so a sweep survives Ctrl-C, a killed
driver or a lost cluster alike (Tune's experiment state does not survive a killed driver
reliably, our records do). On a multi-machine cluster the data folder must be on storage every
node sees at the same path.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from pathlib import Path
from typing import NotRequired, TypedDict, cast

from studio import StudioError, read_json

from ..._files import atomic_write_text, now_iso
from ..._layout import RUNS_DIR
from .._errors import LearningError
from ..runs._folder import RunFolder
from ..runs._owner import pid_alive, this_host
from ._spec import Settings, SpecDict, SweepError, SweepSpec

SWEEP_FORMAT = "teach-studio-sweep"
"""The ``format`` field of ``sweep.json``."""
SWEEP_VERSION = 1
SWEEPS_DIR = "sweeps"
"""Sweep folders live in ``<data>/sweeps/<id>/``."""
SWEEP_FILE = "sweep.json"
TRIALS_DIR = "trials"
SUMMARY_FILE = "sweep.csv"
FIGURE_STEM = "sweep"
RAY_DIR = "ray"


class TrialEntry(TypedDict):
    """One trial as ``sweep.json`` lists it."""

    key: str
    settings: Settings
    seed: int


class SweepFile(TypedDict, total=False):
    """``sweep.json``: what the sweep is and whether its driver runs."""

    format: str
    version: int
    spec: SpecDict
    created: str
    trials: list[TrialEntry]
    status: str
    pid: int
    host: dict[str, str | None]


class TrialEnd(TypedDict):
    """``trials/<trial>.json``: what the driver recorded when a trial ended.

    ``status`` is ``done``, ``early-stopped`` (by the scheduler), ``stopped`` (Ctrl-C: runs again
    on resume) or ``failed`` (after its retries, with the ``error`` file of Tune).
    """

    key: str
    status: str
    attempts: int
    node: str | None
    hostname: str | None
    pid: int | None
    episodes: int | None
    wall_seconds: float | None
    cpu_seconds: float | None
    finished: str
    error: NotRequired[str]


def sweep_folder(data_dir: Path, sweep_id: str) -> Path:
    """``<data>/sweeps/<id>``."""
    return Path(data_dir) / SWEEPS_DIR / sweep_id


def trial_run_path(data_dir: Path, sweep_id: str, key: str) -> Path:
    """Where a trial's run folder lives."""
    return Path(data_dir) / RUNS_DIR / sweep_id / f"{sweep_id}-{key}"


def read_sweep_json(path: Path) -> object:
    """A sweep's JSON file (bounded in size and depth), or None when missing or unreadable."""
    try:
        return read_json(path)
    except StudioError:
        return None


def read_sweep_file(folder: Path) -> SweepFile | None:
    """``sweep.json`` of a sweep folder, or None when missing or not an object."""
    data = read_sweep_json(folder / SWEEP_FILE)
    return cast(SweepFile, data) if isinstance(data, dict) else None


def trial_records(folder: Path) -> dict[str, TrialEnd]:
    """The driver's record of every trial that ended, by key."""
    out = {}
    for path in sorted((folder / TRIALS_DIR).glob("t*.json")):
        data = read_sweep_json(path)
        if isinstance(data, dict) and "key" in data:
            out[data["key"]] = data
    return out


def record_trial_end(folder: Path, record: TrialEnd) -> None:
    """Write ``trials/<key>.json``."""
    path = folder / TRIALS_DIR / f"{record['key']}.json"
    atomic_write_text(path, json.dumps(record, indent=1))


def finished_trials(data_dir: Path, spec: SweepSpec) -> set[str]:
    """Keys of the trials that need not run again (a resumed sweep skips exactly these): those
    whose run folder says ``done`` (every episode of every experiment; it may have ended while
    the driver was going down, before the driver recorded it), and those the driver recorded as
    stopped early by the scheduler, with a run folder that reads back."""
    records = trial_records(sweep_folder(data_dir, spec.name))
    finished = set()
    for trial in spec.trials():
        try:
            run = RunFolder.load(trial_run_path(data_dir, spec.name, trial.key))
        except LearningError:
            continue
        early = trial.key in records and records[trial.key].get("status") == "early-stopped"
        if run.status == "done" or (early and run.steps().max() >= 0):
            finished.add(trial.key)
    return finished


def driver_alive(stored: Mapping[str, object]) -> bool:
    """Whether the driver that ``sweep.json`` names as running still runs."""
    return stored.get("status") == "running" and pid_alive(stored.get("pid"), stored.get("host"))


def _hostname(stored: Mapping[str, object]) -> str:
    host = stored.get("host")
    name = host.get("hostname") if isinstance(host, dict) else None
    return name if isinstance(name, str) else "this machine"


def prepare_folder(data_dir: Path, spec: SweepSpec, resume: bool) -> Path:
    """Make (or, to resume, check) the sweep folder and mark the sweep running in this process.

    Raises:
        SweepError: the sweep runs elsewhere, exists (or not, to resume), differs from the spec
            it started with, or the disk refuses the folder.
    """
    folder = sweep_folder(data_dir, spec.name)
    stored = check_folder(data_dir, spec, resume)
    try:
        (folder / TRIALS_DIR).mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise SweepError(
            f"Cannot create {folder} ({err.strerror or err}); check the disk."
        ) from None
    if stored is None:
        stored = {
            "format": SWEEP_FORMAT,
            "version": SWEEP_VERSION,
            "spec": spec.to_dict(),
            "created": now_iso(),
            "trials": [
                {"key": t.key, "settings": t.settings, "seed": t.seed} for t in spec.trials()
            ],
        }
    stored["status"] = "running"
    stored["pid"], stored["host"] = os.getpid(), this_host()
    atomic_write_text(folder / SWEEP_FILE, json.dumps(stored, indent=1))
    return folder


def check_folder(data_dir: Path, spec: SweepSpec, resume: bool) -> SweepFile | None:
    """What :func:`prepare_folder` checks, writing nothing: returns the stored sweep file (None
    for a new sweep).

    Raises:
        SweepError: the sweep runs elsewhere, exists (or not, to resume), or differs from the
            spec it started with.
    """
    folder = sweep_folder(data_dir, spec.name)
    stored = read_sweep_file(folder)
    if stored is not None:
        _check_existing(folder, spec, stored, resume)
    elif resume:
        raise SweepError(
            f"There is no sweep {spec.name!r} in {folder.parent} to resume; start it without --resume."
        )
    return stored


def _check_existing(folder: Path, spec: SweepSpec, stored: SweepFile, resume: bool) -> None:
    """Refuse to start over an existing sweep, or to resume one that runs or differs."""
    if driver_alive(stored):  # two drivers would train the same trials into the same folders
        raise SweepError(
            f"Sweep {spec.name!r} is still running (process {stored.get('pid')} on {_hostname(stored)}); wait for it to end, or stop it with Ctrl-C and then studio sweep --resume {spec.name}."
        )
    if not resume:
        state = "finished" if stored.get("status") == "done" else "unfinished"
        raise SweepError(
            f"Sweep {spec.name!r} already exists in {folder.parent} ({state}); continue it with studio sweep --resume {spec.name}, or give another --name."
        )
    if stored.get("spec") != json.loads(json.dumps(spec.to_dict())):
        raise SweepError(
            f"The spec differs from the one sweep {spec.name!r} started with; resume with studio sweep --resume {spec.name} alone, or give another --name."
        )


def set_status(folder: Path, status: str, host: dict[str, str | None] | None = None) -> None:
    """Write the sweep's ``status`` (and the driver's ``host``, when given) into ``sweep.json``."""
    data = read_sweep_file(folder)
    if data is not None:
        data["status"] = status
        if host is not None:
            data["host"] = host
        atomic_write_text(folder / SWEEP_FILE, json.dumps(data, indent=1))
