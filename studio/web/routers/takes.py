"""``/api/takes``: record in takes: start, stop (the take plays on the robot for review), keep,
redo, and make the session's kept takes into demonstrations in one go."""

from __future__ import annotations

from fastapi import APIRouter, Response

from studio.capture import TakeSession

from .._deps import TakesDep
from .._schemas import TakePublic, TakesFinish, TakesPublic, TakeStart

router = APIRouter(prefix="/api/takes", tags=["takes"])


def takes_public(session: TakeSession | None) -> TakesPublic:
    """The session as the page shows it (empty when none is open)."""
    if session is None:
        return TakesPublic()
    return TakesPublic(
        started=session.started,
        finished=session.finished,
        takes=[TakePublic.model_validate(take, from_attributes=True) for take in session.takes],
    )


@router.get("")
def read_takes(takes: TakesDep) -> TakesPublic:
    """The open take session (``takes`` empty when none is open)."""
    return takes_public(takes.session())


@router.post("/start")
def start_take(takes: TakesDep, body: TakeStart | None = None) -> TakesPublic:
    """Start recording the next take (409 while a take is recorded or under review, or without
    a running source)."""
    return takes_public(takes.start(body.operator if body else None))


@router.post("/stop")
def stop_take(takes: TakesDep) -> TakesPublic:
    """Stop the take; it plays on the robot, its tool path drawn, for review."""
    return takes_public(takes.stop())


@router.post("/review", status_code=202, response_class=Response)
def review_take(takes: TakesDep) -> Response:
    """Play the last take on the robot again."""
    takes.review()
    return Response(status_code=202)


@router.post("/keep")
def keep_take(takes: TakesDep) -> TakesPublic:
    """Keep the take under review."""
    return takes_public(takes.keep())


@router.post("/redo")
def redo_take(takes: TakesDep) -> TakesPublic:
    """Throw the last take away (its recording is deleted) to record it again."""
    return takes_public(takes.redo())


@router.post("/demonstrations")
def make_demonstrations(takes: TakesDep, body: TakesFinish | None = None) -> TakesPublic:
    """Cut each kept take, whole, into a demonstration and close the session; a take that
    cannot be cut says why in its ``error``."""
    return takes_public(takes.make_demonstrations(body.goal_from_end if body else False))
