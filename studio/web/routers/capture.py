"""``/api/capture``: record every raw frame of the live source to a new recording file."""

from __future__ import annotations

from fastapi import APIRouter

from .._deps import StudioDep
from .._schemas import CapturePublic, CaptureStart, RecordingPublic

router = APIRouter(prefix="/api/capture", tags=["capture"])


@router.get("", response_model=CapturePublic)
def read_capture(studio: StudioDep) -> dict:
    """The capture in progress (``active`` false when none)."""
    return studio.pipeline.capture_status()


@router.post("/start", response_model=CapturePublic)
def start_capture(body: CaptureStart, studio: StudioDep) -> dict:
    """Start recording (409 if a recording is already running or there is no running source)."""
    studio.start_capture(body.name, body.operator, body.notes)
    return studio.pipeline.capture_status()


@router.post("/stop", response_model=RecordingPublic)
def stop_capture(studio: StudioDep) -> dict:
    """Stop recording; the file is closed cleanly and listed (409 if none is running)."""
    name = studio.stop_capture()
    return studio.recordings.info(name)
