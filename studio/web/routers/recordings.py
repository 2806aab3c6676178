"""``/api/recordings``: list, upload, download, rename, annotate and delete recordings."""

from __future__ import annotations

from typing import Annotated

from fastapi import APIRouter, File, Response, UploadFile
from fastapi.responses import StreamingResponse

from studio.capture import recording_bytes

from .._deps import SettingsDep, StudioDep
from .._errors import ConflictError
from .._schemas import RecordingPublic, RecordingUpdate
from .._store import RECORDING_SUFFIX, receive_upload

router = APIRouter(prefix="/api/recordings", tags=["recordings"])


@router.get("", response_model=list[RecordingPublic])
def list_recordings(studio: StudioDep) -> list[dict]:
    """Every recording, shipped samples first (an unreadable one is listed with its error).

    The file a capture is writing appears once the capture stops.
    """
    capturing = studio.pipeline.capture_name
    return [r for r in studio.recordings.list() if r["name"] != capturing]


@router.post("", response_model=RecordingPublic, status_code=201)
async def upload_recording(
    studio: StudioDep, settings: SettingsDep, file: Annotated[UploadFile, File()]
) -> dict:
    """Upload a ``.tape.csv`` (413 over the limit, 422 if it is not a recording).

    The name comes from the file name; a taken name gets ``-2``, ``-3``, ... appended.
    """
    tmp = await receive_upload(file, studio.recordings.folder, settings.upload_limit_bytes)
    name = studio.recordings.adopt(tmp, file.filename)
    studio.changes.bump("recordings")
    return studio.recordings.info(name)


@router.get("/{name}", response_model=RecordingPublic)
def read_recording(name: str, studio: StudioDep) -> dict:
    """One recording's summary."""
    return studio.recordings.info(name)


@router.get("/{name}/file")
def download_recording(name: str, studio: StudioDep) -> StreamingResponse:
    """The ``.tape.csv`` file, up to its last complete line (a capture in progress may be
    downloaded: its length is fixed when the download starts, so it is a valid recovered file)."""
    snapshot = recording_bytes(studio.recordings.path(name))
    return StreamingResponse(
        snapshot,
        media_type="text/csv",
        headers={
            "Content-Length": str(snapshot.size),
            "Content-Disposition": f'attachment; filename="{name}{RECORDING_SUFFIX}"',
        },
    )


@router.patch("/{name}", response_model=RecordingPublic)
def update_recording(name: str, body: RecordingUpdate, studio: StudioDep) -> dict:
    """Rename (409 if in use or the name is taken) and/or set the operator and notes."""
    studio.recordings.path(name)
    if studio.pipeline.capture_name == name:
        raise ConflictError(f"Recording {name!r} is being captured; stop the recording first.")
    if body.name is not None and body.name != name:
        reason = studio.recording_in_use(name)
        if reason:
            raise ConflictError(reason)
    new = studio.recordings.update(name, body.name, body.notes, body.operator)
    studio.changes.bump("recordings")
    if new != name:
        studio.changes.bump("demonstrations")  # their "recording" follows the rename
    return studio.recordings.info(new)


@router.delete("/{name}", status_code=204)
def delete_recording(name: str, studio: StudioDep) -> Response:
    """Delete a recording (409 while it is the live source or being captured)."""
    studio.recordings.path(name)
    reason = studio.recording_in_use(name)
    if reason:
        raise ConflictError(reason)
    studio.recordings.delete(name)
    studio.changes.bump("recordings")
    return Response(status_code=204)
