"""``/api/capture``: record every raw frame of the live source to a new recording file."""

from __future__ import annotations

from fastapi import APIRouter, Response

from .._deps import CaptureDep, RecordingsDep
from .._schemas import CapturePublic, CaptureStart, RecordingPublic
from .recordings import read_public

router = APIRouter(prefix="/api/capture", tags=["capture"])


@router.get("")
def read_capture(capture: CaptureDep) -> CapturePublic:
    """The capture in progress (``active`` false when none)."""
    return CapturePublic.model_validate(capture.status())


@router.post("/start")
def start_capture(body: CaptureStart, capture: CaptureDep) -> CapturePublic:
    """Start recording (409 if a recording is already running, there is no running source, or
    the name is taken; 422 for a bad name or one starting with ``sample-``)."""
    capture.start(body.name, body.operator, body.notes)
    return CapturePublic.model_validate(capture.status())


@router.delete("/error", status_code=204)
def dismiss_capture_error(capture: CaptureDep) -> Response:
    """Dismiss the reason the last capture stopped by itself (the page's close button)."""
    capture.dismiss_error()
    return Response(status_code=204)


@router.post("/stop")
def stop_capture(capture: CaptureDep, recordings: RecordingsDep) -> RecordingPublic:
    """Stop recording; the file is closed cleanly and listed (409 if none is running)."""
    return read_public(recordings, capture.stop())
