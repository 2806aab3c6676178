"""``/api/runs``: queue training runs, follow their curves, stop them, download their results."""

from __future__ import annotations

import io
from typing import Annotated

from fastapi import APIRouter, Query, Response
from fastapi.responses import FileResponse

from .._deps import StudioDep
from .._errors import ConflictError, NotFoundError
from .._runs import curve_csv
from .._schemas import CurvePublic, RunCreate, RunPublic

router = APIRouter(prefix="/api/runs", tags=["runs"])

PLOT_MEDIA = {"png": "image/png", "svg": "image/svg+xml"}


@router.get("", response_model=list[RunPublic])
def list_runs(studio: StudioDep) -> list[dict]:
    """Every run, newest first, with its status and progress."""
    return [run.public() for run in studio.runs.list()]


@router.post("", response_model=RunPublic, status_code=201)
def create_run(body: RunCreate, studio: StudioDep) -> dict:
    """Validate and queue a run; it trains when the runs before it are done (422 with a reason)."""
    run = studio.runs.submit(body, studio.demonstration_path)
    return run.public()


@router.get("/{run_id}", response_model=RunPublic)
def read_run(run_id: str, studio: StudioDep) -> dict:
    """One run."""
    return studio.runs.get(run_id).public()


@router.get("/{run_id}/curve", response_model=CurvePublic)
def read_curve(run_id: str, studio: StudioDep) -> dict:
    """Steps per episode (mean, std, min, max over the experiments that finished each episode)."""
    return studio.runs.get(run_id).curve()


@router.post("/{run_id}/stop", response_model=RunPublic)
def stop_run(run_id: str, studio: StudioDep) -> dict:
    """Stop a queued run, or a running one at its next episode boundary (its curve is kept)."""
    return studio.runs.stop(run_id).public()


@router.delete("/{run_id}", status_code=204)
def delete_run(run_id: str, studio: StudioDep) -> Response:
    """Delete a run and its files (409 while it is training)."""
    run = studio.runs.get(run_id)
    if studio.policy_in_use(f"run:{run.id}"):
        raise ConflictError(
            f"Run {run.id}'s policy is playing in the scene; stop watching it first."
        )
    studio.runs.delete(run_id)
    return Response(status_code=204)


@router.get("/{run_id}/curve.csv")
def download_curve(run_id: str, studio: StudioDep) -> Response:
    """The curve as CSV: episode, mean, std, min, max, experiments."""
    run = studio.runs.get(run_id)
    return Response(
        curve_csv(run.curve()),
        media_type="text/csv",
        headers={"Content-Disposition": f'attachment; filename="{run.id}-curve.csv"'},
    )


@router.get("/{run_id}/plot.{fmt}")
def download_plot(
    run_id: str,
    fmt: str,
    studio: StudioDep,
    log: Annotated[bool, Query(description="log-scale steps axis")] = False,
) -> Response:
    """The learning curve as a PNG or SVG figure (mean, +-1 std band, min-max band)."""
    run = studio.runs.get(run_id)
    if fmt not in PLOT_MEDIA:
        raise NotFoundError(f"There is no plot format {fmt!r}; ask for plot.png or plot.svg.")
    data = render_plot(run.name, run.curve(), fmt, log)
    return Response(
        data,
        media_type=PLOT_MEDIA[fmt],
        headers={"Content-Disposition": f'attachment; filename="{run.id}-curve.{fmt}"'},
    )


@router.get("/{run_id}/policy")
def download_policy(run_id: str, studio: StudioDep) -> FileResponse:
    """The run's policy file (409 before the run has finished an episode)."""
    run = studio.runs.get(run_id)
    if not run.has_policy:
        raise ConflictError(
            f"Run {run.id} has no policy yet; it is saved when the run finishes or is stopped."
        )
    return FileResponse(
        run.policy_path,
        media_type="application/octet-stream",
        filename=f"{run.id}.policy.npz",
    )


def render_plot(title: str, curve: dict, fmt: str, log: bool) -> bytes:
    """A learning-curve figure drawn with matplotlib's Agg/SVG canvases (no GUI, thread-safe)."""
    import numpy as np
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 4), dpi=120, layout="constrained")
    ax = fig.add_subplot()
    episodes = np.asarray(curve["episodes"])
    if episodes.size:
        mean, std = np.asarray(curve["mean"]), np.asarray(curve["std"])
        ax.fill_between(episodes, curve["min"], curve["max"], alpha=0.15, label="min-max")
        ax.fill_between(episodes, np.maximum(mean - std, 1), mean + std, alpha=0.3, label="±1 std")
        ax.plot(episodes, mean, lw=1.8, label="mean")
        ax.legend(loc="upper right")
    else:
        ax.text(
            0.5, 0.5, "no finished episodes yet", ha="center", va="center", transform=ax.transAxes
        )
    if log:
        ax.set_yscale("log")
    ax.set_xlabel("episode")
    ax.set_ylabel("steps to the goal")
    ax.set_title(title)
    ax.grid(alpha=0.3)
    buffer = io.BytesIO()
    fig.savefig(buffer, format=fmt)
    return buffer.getvalue()
