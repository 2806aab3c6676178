"""``/api/watch``: the robot in the scene performs a learned policy, step by step."""

from __future__ import annotations

from fastapi import APIRouter, Response

from .._deps import WatchingDep
from .._schemas import WatchCreate, WatchPublic
from . import file_responses

router = APIRouter(prefix="/api/watch", tags=["watch"])


@router.post("")
def watch(body: WatchCreate, watching: WatchingDep) -> WatchPublic:
    """Roll the greedy policy of a run or an uploaded policy (exactly one; 422 otherwise) out from
    a random or the current pose and play it in the scene (409 if the run has no policy yet)."""
    return watching.watch(body)


@router.post("/stop", status_code=204)
def stop_watch(watching: WatchingDep) -> Response:
    """Stop the playback; the robot follows the live source again."""
    watching.stop()
    return Response(status_code=204)


@router.get("/trajectory.csv", response_class=Response, responses=file_responses("text/csv"))
def download_trajectory(
    watching: WatchingDep, run: str | None = None, policy: str | None = None
) -> Response:
    """The rollout last watched of a run's policy (``?run=<id>``) or an uploaded one
    (``?policy=<name>``), or with neither the last rollout watched, as CSV: ``time,q1..q6``
    (seconds, radians), named ``<run id or policy name>.rollout.csv`` as ``studio export``
    names it. 409 when that policy has not been watched yet."""
    filename, text = watching.trajectory_csv(run, policy)
    return Response(
        text,
        media_type="text/csv",
        headers={"Content-Disposition": f'attachment; filename="{filename}"'},
    )
