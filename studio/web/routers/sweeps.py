"""``/api/sweeps``: parameter sweeps made by ``studio sweep``, their summary table and figure.

A sweep's trials are ordinary runs (listed, plotted, watched and exported through ``/api/runs``
under the ids given in ``runs``); this router only reads the sweep folders. The summary, its CSV
and its figure come from :mod:`studio.learning` (``load_sweep``, ``SweepInfo``).
"""

from __future__ import annotations

from typing import Literal

from fastapi import APIRouter, Response
from starlette.concurrency import run_in_threadpool

from studio.learning import SweepError, SweepInfo, list_sweeps, load_sweep

from .._deps import SettingsDep
from .._errors import NotFoundError
from .._schemas import SweepPublic
from ..services import GROUP_SEPARATOR

router = APIRouter(prefix="/api/sweeps", tags=["sweeps"])

FIGURE_MEDIA = {"png": "image/png", "svg": "image/svg+xml"}


def sweep_public(info: SweepInfo) -> SweepPublic:
    """The API view of a sweep folder."""
    rows = info.rows()
    return SweepPublic(
        id=info.id,
        status=info.status,  # type: ignore[arg-type]
        created=info.created,
        task=str(info.spec.get("task", "")),
        metric=info.metric,
        swept=info.swept,
        trials=info.trials,
        finished=info.finished,
        runs=[f"{info.id}{GROUP_SEPARATOR}{name}" for name in info.runs],
        columns=list(rows[0]) if rows else [],
        rows=rows,
    )


def _sweep(settings: SettingsDep, sweep_id: str) -> SweepInfo:
    try:
        return load_sweep(settings.data_dir, sweep_id)
    except SweepError as err:
        raise NotFoundError(str(err)) from None


@router.get("", response_model=list[SweepPublic])
def list_all(settings: SettingsDep) -> list[SweepPublic]:
    """Every sweep in the data folder, newest first, with its summary rows."""
    return [sweep_public(info) for info in list_sweeps(settings.data_dir)]


@router.get("/{sweep_id}", response_model=SweepPublic)
def read_sweep(sweep_id: str, settings: SettingsDep) -> SweepPublic:
    """One sweep (404 if there is no such sweep)."""
    return sweep_public(_sweep(settings, sweep_id))


@router.get("/{sweep_id}/sweep.csv")
def download_summary(sweep_id: str, settings: SettingsDep) -> Response:
    """``sweep.csv``: one row per trial (settings, status, metrics, CPU and wall time)."""
    info = _sweep(settings, sweep_id)
    return Response(
        info.summary_csv(),
        media_type="text/csv",
        headers={"Content-Disposition": f'attachment; filename="{info.id}-sweep.csv"'},
    )


@router.get("/{sweep_id}/figure.{fmt}")
async def download_figure(
    sweep_id: str, fmt: Literal["png", "svg"], settings: SettingsDep
) -> Response:
    """The metric against the first swept setting, mean and standard error over the seeds."""
    info = _sweep(settings, sweep_id)
    data = await run_in_threadpool(info.figure, fmt)  # drawing can take a moment: not on the loop
    return Response(
        data,
        media_type=FIGURE_MEDIA[fmt],
        headers={"Content-Disposition": f'inline; filename="{info.id}-sweep.{fmt}"'},
    )
