"""``/api/runs``: queue training runs, follow their curves, stop them, download their results.

Every run folder under ``<data_dir>/runs`` is listed, whatever made it; statistics, the CSV
layout and the figure come from :mod:`studio.learning` (``curve_statistics``, ``curves_csv``,
``curve_figure``).
"""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, Query, Response
from fastapi.responses import FileResponse

from studio.learning import curve_figure, curves_csv

from .._deps import RunsDep, TrainingDep
from .._errors import ConflictError, NotFoundError
from .._schemas import CurvePublic, RunCreate, RunPublic
from . import file_responses

router = APIRouter(prefix="/api/runs", tags=["runs"])

PLOT_MEDIA = {"png": "image/png", "svg": "image/svg+xml"}


@router.get("", response_model=list[RunPublic])
def list_runs(runs: RunsDep) -> list[RunPublic]:
    """Every run, newest first, with its status and progress (page, CLI, reproduce, sweeps);
    then the folders that cannot be read, as ``damaged`` with the reason (delete them)."""
    return [run.model() for run in runs.list()] + [d.model() for d in runs.damaged()]


@router.post("", response_model=RunPublic, status_code=201)
def create_run(body: RunCreate, training: TrainingDep) -> RunPublic:
    """Validate and queue a run; it trains when the runs before it are done (422 naming every
    bad field: ``detail`` joins them, ``problems`` lists them, ``by_field`` keys them by field)."""
    return training.submit(body).model()


@router.post("/pair", response_model=list[RunPublic], status_code=201)
def create_run_pair(body: RunCreate, training: TrainingDep) -> list[RunPublic]:
    """Queue a run with its demonstrations and, after it, the same run without them (same
    settings, seed and goal), to compare the two; both are checked before either is queued (422
    as ``POST /api/runs``, and when no demonstration is picked)."""
    return [run.model() for run in training.submit_pair(body)]


@router.get("/{run_id}", response_model=RunPublic)
def read_run(run_id: str, runs: RunsDep) -> RunPublic:
    """One run."""
    return runs.get(run_id).model()


@router.get("/{run_id}/curve", response_model=CurvePublic)
def read_curve(run_id: str, runs: RunsDep) -> Response:
    """Steps per episode: mean, std, median, p10, p90, min, max over the ``count`` experiments
    that finished each episode (a running run's at most a second old: its event stream is live)."""
    return Response(runs.get(run_id).curve_json(), media_type="application/json")


@router.post("/{run_id}/stop", response_model=RunPublic)
def stop_run(run_id: str, runs: RunsDep) -> RunPublic:
    """Stop a queued run, or a running one at its next episode boundary (its curve is kept)."""
    return runs.stop(run_id).model()


@router.post("/{run_id}/mark-stopped", response_model=RunPublic)
def mark_run_stopped(run_id: str, runs: RunsDep) -> RunPublic:
    """Mark a run ``stopped`` that says queued or running but that no live process trains (a
    folder from before owner locks whose pid was reused, or whose host cannot be asked); 409
    while a live process owns it or this studio trains it."""
    return runs.mark_stopped(run_id).model()


@router.delete("/{run_id}", status_code=204)
def delete_run(run_id: str, training: TrainingDep) -> Response:
    """Delete a run and its files, or a damaged run folder (409 while it is training, or naming
    the files that could not be deleted)."""
    training.delete(run_id)
    return Response(status_code=204)


@router.get("/{run_id}/curve.csv", response_class=Response, responses=file_responses("text/csv"))
def download_curve(run_id: str, runs: RunsDep) -> Response:
    """The curve as CSV, in the one layout of ``curves.csv`` (see ``studio/learning/README.md``)."""
    run = runs.get(run_id)
    return Response(
        curves_csv(run.curve()),
        media_type="text/csv",
        headers={"Content-Disposition": f'attachment; filename="{run.id}-curve.csv"'},
    )


@router.get(
    "/{run_id}/plot.{fmt}", response_class=Response, responses=file_responses(*PLOT_MEDIA.values())
)
def download_plot(
    run_id: str,
    fmt: str,
    runs: RunsDep,
    log: Annotated[bool, Query(description="log-scale steps axis")] = False,
) -> Response:
    """The learning curve as a PNG or SVG figure (mean and 10-90 % band, long runs averaged to
    about 600 points)."""
    run = runs.get(run_id)
    if fmt not in PLOT_MEDIA:
        raise NotFoundError(f"There is no plot format {fmt!r}; ask for plot.png or plot.svg.")
    data = curve_figure([(run.name, run.curve())], fmt, log_steps=log, title=run.name)
    return Response(
        data,
        media_type=PLOT_MEDIA[fmt],
        headers={"Content-Disposition": f'attachment; filename="{run.id}-curve.{fmt}"'},
    )


@router.get(
    "/{run_id}/policy",
    response_class=FileResponse,
    responses=file_responses("application/octet-stream"),
)
def download_policy(run_id: str, runs: RunsDep) -> FileResponse:
    """The run's policy file (409 before the run has finished an episode)."""
    run = runs.get(run_id)
    if not run.has_policy:
        raise ConflictError(
            f"Run {run.id} has no policy yet; it is saved when the run finishes or is stopped."
        )
    return FileResponse(
        run.policy_path,
        media_type="application/octet-stream",
        filename=f"{run.id}.policy.npz",
    )
