"""``/api/capture``: record every raw frame of the live source to a new recording file."""

from __future__ import annotations

from fastapi import APIRouter, Response

from .._deps import StudioDep
from .._schemas import CapturePublic, CaptureStart, RecordingPublic
from .recordings import read_public

router = APIRouter(prefix="/api/capture", tags=["capture"])


@router.get("")
def read_capture(studio: StudioDep) -> CapturePublic:
    """The capture in progress (``active`` false when none)."""
    return CapturePublic.model_validate(studio.pipeline.capture_status())


@router.post("/start")
def start_capture(body: CaptureStart, studio: StudioDep) -> CapturePublic:
    """Start recording (409 if a recording is already running, there is no running source, or
    the name is taken; 422 for a bad name or one starting with ``sample-``)."""
    studio.start_capture(body.name, body.operator, body.notes)
    return CapturePublic.model_validate(studio.pipeline.capture_status())


@router.delete("/error", status_code=204)
def dismiss_capture_error(studio: StudioDep) -> Response:
    """Dismiss the reason the last capture stopped by itself (the page's close button)."""
    studio.pipeline.dismiss_capture_error()
    return Response(status_code=204)


@router.post("/stop")
def stop_capture(studio: StudioDep) -> RecordingPublic:
    """Stop recording; the file is closed cleanly and listed (409 if none is running)."""
    return read_public(studio, studio.stop_capture())
