"""Sweeps read back: the sweep folders of a data folder, as the page lists them and
``studio sweep --resume`` finds them."""

from __future__ import annotations

import contextlib
import csv
import io
from dataclasses import dataclass
from pathlib import Path

from studio import MAX_JSON_BYTES, StudioError, read_bytes_bounded

from ._folder import (
    FIGURE_STEM,
    RUNS_DIR,
    SUMMARY_FILE,
    SWEEP_FORMAT,
    SWEEPS_DIR,
    driver_alive,
    finished_trials,
    read_sweep_file,
    sweep_folder,
)
from ._spec import DEFAULT_METRIC, SWEEP_ID, SpecDict, SweepError, SweepSpec, parse_sweep_spec
from ._summary import check_figure_format, sweep_csv, sweep_figure, sweep_rows


@dataclass(frozen=True)
class SweepInfo:
    """A sweep folder read back (what the page lists).

    Attributes:
        id: the sweep id (also the runs' ``group``).
        spec: the spec as stored.
        status: ``running``, ``done`` or ``interrupted``.
        created: ISO 8601 UTC.
        trials: how many trials the sweep has.
        finished: how many of them finished.
        runs: the trials' run folder names that exist.
        folder: the sweep folder.
    """

    id: str
    spec: SpecDict
    status: str
    created: str
    trials: int
    finished: int
    runs: list[str]
    folder: Path

    @property
    def metric(self) -> str:
        """The metric the summary reports."""
        return str(self.spec.get("metric", {}).get("name", DEFAULT_METRIC))

    @property
    def swept(self) -> list[str]:
        """The swept settings, in the spec's order (the figure's x axis is the first)."""
        return list(self.spec.get("space", {}))

    def summary_csv(self) -> str:
        """``sweep.csv``'s text: as written when the sweep ended, or computed from the run folders
        while it runs (the file is written at its end)."""
        if self.status != "running":
            with contextlib.suppress(StudioError, OSError, UnicodeDecodeError):  # bounded read
                return read_bytes_bounded(self.folder / SUMMARY_FILE, MAX_JSON_BYTES).decode()
        return sweep_csv(sweep_rows(self.folder.parent.parent, self._spec()))

    def rows(self) -> list[dict[str, str]]:
        """``sweep.csv``'s rows (strings, as in the file)."""
        return list(csv.DictReader(io.StringIO(self.summary_csv())))

    def figure(self, fmt: str = "png") -> bytes:
        """The summary figure (:func:`sweep_figure`): as written, or drawn from the run folders."""
        check_figure_format(fmt)
        if self.status != "running":
            with contextlib.suppress(OSError):
                return (self.folder / f"{FIGURE_STEM}.{fmt}").read_bytes()
        spec = self._spec()
        return sweep_figure(sweep_rows(self.folder.parent.parent, spec), spec, fmt)

    def _spec(self) -> SweepSpec:
        return parse_sweep_spec(self.spec, f"sweep {self.id}")


def load_sweep(data_dir: Path, sweep_id: str) -> SweepInfo:
    """Read a sweep folder.

    Raises:
        SweepError: no such sweep, or an unreadable ``sweep.json``.
    """
    if not isinstance(sweep_id, str) or not SWEEP_ID.match(sweep_id):
        raise SweepError(f"{sweep_id!r} is not a sweep id; give a sweep's folder name.")
    folder = sweep_folder(data_dir, sweep_id)
    data = read_sweep_file(folder)
    if data is None or data.get("format") != SWEEP_FORMAT:
        raise SweepError(f"There is no sweep {sweep_id!r} in {folder.parent}; check its name.")
    stored = data.get("spec", {})
    try:
        spec = parse_sweep_spec(stored, f"sweep {sweep_id}")
    except SweepError as err:
        raise SweepError(
            f"Sweep {sweep_id!r} has an unreadable sweep.json ({err}); delete it."
        ) from None
    runs_parent = Path(data_dir) / RUNS_DIR / sweep_id
    runs = (
        sorted(p.name for p in runs_parent.iterdir() if p.is_dir()) if runs_parent.is_dir() else []
    )
    status = str(data.get("status", "interrupted"))
    if status == "running" and not driver_alive(data):  # its driver died
        status = "interrupted"
    return SweepInfo(
        id=sweep_id,
        spec=stored,
        status=status,
        created=str(data.get("created", "")),
        trials=len(data.get("trials", [])),
        finished=len(finished_trials(data_dir, spec)),
        runs=[r for r in runs if not r.startswith(".")],
        folder=folder,
    )


def list_sweeps(data_dir: Path) -> list[SweepInfo]:
    """Every readable sweep in the data folder, newest first."""
    parent = Path(data_dir) / SWEEPS_DIR
    if not parent.is_dir():
        return []
    out = []
    for child in parent.iterdir():
        if child.is_dir() and SWEEP_ID.match(child.name):
            with contextlib.suppress(SweepError):
                out.append(load_sweep(data_dir, child.name))
    return sorted(out, key=lambda s: s.created, reverse=True)


def resume_target(data_dir: Path, what: str | None) -> SweepSpec:
    """The spec of the sweep to resume: by id, or the most recent unfinished one."""
    if what is None:
        unfinished = [s for s in list_sweeps(data_dir) if s.status not in ("done", "running")]
        if not unfinished:
            raise SweepError(
                f"There is no unfinished sweep in {Path(data_dir) / SWEEPS_DIR} that is not running; start one with studio sweep SPEC."
            )
        info = unfinished[0]
    else:
        info = load_sweep(data_dir, what)
    return parse_sweep_spec(info.spec, f"sweep {info.id}")
