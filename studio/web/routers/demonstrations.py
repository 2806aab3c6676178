"""``/api/demonstrations``: cut demonstrations out of recordings (or mark them live), list,
preview on the robot and delete them."""

from __future__ import annotations

from fastapi import APIRouter, Response

from .._deps import StudioDep
from .._errors import ConflictError
from .._schemas import (
    DemonstrationCreate,
    DemonstrationDetail,
    DemonstrationMark,
    DemonstrationPublic,
    MarkPublic,
)

router = APIRouter(prefix="/api/demonstrations", tags=["demonstrations"])


@router.get("", response_model=list[DemonstrationPublic])
def list_demonstrations(studio: StudioDep) -> list[dict]:
    """Every demonstration, newest first."""
    return studio.demonstrations.list()


@router.post("", response_model=DemonstrationPublic, status_code=201)
def create_demonstration(body: DemonstrationCreate, studio: StudioDep) -> dict:
    """Cut ``[t0, t1]`` out of a recording (422 with the reason when it is refused)."""
    name = studio.cut_demonstration(body.recording, body.t0, body.t1, body.goal_from_end, body.name)
    return studio.demonstrations.info(name)


@router.get("/mark", response_model=MarkPublic)
def read_mark(studio: StudioDep) -> dict:
    """Whether a live demonstration is being marked, and since when (recording time, s)."""
    return {"marking": studio.mark_t0 is not None, "t0": studio.mark_t0}


@router.post("/mark", response_model=MarkPublic)
def mark_demonstration(body: DemonstrationMark, studio: StudioDep) -> dict:
    """Mark the start, then the end, of a demonstration while a capture runs.

    On ``stop`` the segment is cut from the recording being captured and returned as
    ``demonstration`` (422 with the reason when it is refused; 409 without a running capture).
    """
    if body.action == "start":
        t0 = studio.mark_start()
        return {"marking": True, "t0": t0}
    name = studio.mark_stop(body.goal_from_end, body.name)
    return {"marking": False, "t0": None, "demonstration": studio.demonstrations.info(name)}


@router.get("/{name}", response_model=DemonstrationDetail)
def read_demonstration(name: str, studio: StudioDep) -> dict:
    """One demonstration with its robot path (radians) and grid path."""
    return studio.demonstrations.detail(name)


@router.post("/{name}/preview", status_code=202)
def preview_demonstration(name: str, studio: StudioDep) -> Response:
    """Draw the demonstration's tool path and play it on the robot in the scene."""
    studio.preview_demonstration(name)
    return Response(status_code=202)


@router.delete("/{name}", status_code=204)
def delete_demonstration(name: str, studio: StudioDep) -> Response:
    """Delete a demonstration (409 while a queued or running training run replays it)."""
    studio.demonstrations.path(name)
    run = studio.runs.uses_demonstration(name)
    if run is not None:
        raise ConflictError(
            f"Demonstration {name!r} is used by run {run.id}, which is {run.status}; stop that run first."
        )
    studio.demonstrations.delete(name)
    if studio.scene is not None:
        studio.scene.clear_path(f"demo-{name}")
    studio.changes.bump("demonstrations")
    return Response(status_code=204)
