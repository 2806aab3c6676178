"""``/api/recordings``: list, upload, download, copy, rename, annotate and delete recordings; a
recording's timeline (its joints over time) and its review on the robot.

The shipped samples are listed first; they can be played, cut and copied, never changed.
"""

from __future__ import annotations

from typing import Annotated

import numpy as np
from fastapi import APIRouter, File, Query, Response, UploadFile
from fastapi.responses import StreamingResponse
from starlette.concurrency import run_in_threadpool

from studio.capture import DEFAULT_SERIES_POINTS, MAX_SERIES_POINTS, RecordingError, recording_bytes

from .._deps import RecordingsDep, ReviewerDep, SettingsDep
from .._errors import ConflictError, NotFoundError
from .._schemas import (
    RecordingCopy,
    RecordingPublic,
    RecordingReview,
    RecordingUpdate,
    TimelinePublic,
    TimelineSignal,
)
from ..services import RecordingStore, RecordingSummary, StoredFile, receive_upload
from . import file_responses

router = APIRouter(prefix="/api/recordings", tags=["recordings"])


def recording_public(entry: StoredFile[RecordingSummary]) -> RecordingPublic:
    """The list entry of one recording, from the capture package's summary of it."""
    summary = entry.value or {}
    return RecordingPublic.model_validate(
        {
            "name": entry.name,
            "frames": summary.get("frames", 0),
            "duration": summary.get("duration", 0.0),
            "rate_hz": summary.get("rate_hz") or None,
            "created": summary.get("created") or "",
            "operator": summary.get("operator") or "",
            "notes": summary.get("notes") or "",
            "source": summary.get("source") or "",
            "recovered": summary.get("recovered", False),
            "size_bytes": entry.size_bytes,
            "sample": entry.sample,
            "error": entry.error,
            "kind": summary.get("kind", "tape"),
            "warnings": summary.get("warnings") or [],
        }
    )


def read_public(recordings: RecordingStore, name: str) -> RecordingPublic:
    """One recording's list entry by name (404 if none).

    A file another process is capturing is shown as such, not read (it grows, and without its
    ``# end`` line a reader would call it recovered).
    """
    if recordings.captured_elsewhere(name):
        path = recordings.path(name)
        return RecordingPublic(
            name=name,
            frames=0,
            duration=0.0,
            rate_hz=None,
            created="",
            operator="",
            notes="",
            source="",
            recovered=False,
            size_bytes=path.stat().st_size,
            sample=False,
            capturing=True,
        )
    return recording_public(recordings.entry(name))


@router.get("")
def list_recordings(recordings: RecordingsDep) -> list[RecordingPublic]:
    """Every recording, the shipped samples first; a damaged file is listed with the reason.

    The file this studio's capture is writing appears once the capture stops; one another
    studio on the same data folder is capturing is listed as ``capturing``.
    """
    listed = []
    for name in recordings.listed():
        try:
            listed.append(read_public(recordings, name))
        except (NotFoundError, FileNotFoundError):  # deleted meanwhile
            continue
    return listed


@router.post("", status_code=201)
async def upload_recording(
    recordings: RecordingsDep, settings: SettingsDep, file: Annotated[UploadFile, File()]
) -> RecordingPublic:
    """Upload a ``.tape.csv`` (413 over the limit, 422 if it is not a recording).

    The name comes from the file name; a taken name gets ``-2``, ``-3``, ... appended.
    """
    tmp = await receive_upload(file, recordings.folder, settings.upload_limit_bytes)

    def adopt() -> RecordingPublic:  # parsing a long recording takes seconds: not on the loop
        return read_public(recordings, recordings.adopt(tmp, file.filename))

    return await run_in_threadpool(adopt)


@router.get("/{name}")
def read_recording(name: str, recordings: RecordingsDep) -> RecordingPublic:
    """One recording's summary."""
    return read_public(recordings, name)


@router.get("/{name}/file", response_class=StreamingResponse, responses=file_responses("text/csv"))
def download_recording(name: str, recordings: RecordingsDep) -> StreamingResponse:
    """The ``.tape.csv`` (``.pose.csv``, ``.hand.csv``) file, up to its last complete line (a capture in progress may be
    downloaded: its length is fixed when the download starts, so it is a valid recovered file)."""
    path = recordings.path(name)
    snapshot = recording_bytes(path)
    return StreamingResponse(
        snapshot,
        media_type="text/csv",
        headers={
            "Content-Length": str(snapshot.size),
            "Content-Disposition": f'attachment; filename="{path.name}"',
        },
    )


@router.post("/{name}/copy", status_code=201)
def copy_recording(
    name: str, recordings: RecordingsDep, body: RecordingCopy | None = None
) -> RecordingPublic:
    """Copy a recording (a shipped sample, typically) into your own recordings, to rename and annotate.

    The copy is named ``body.name`` (409 if taken), else the original's name without
    ``sample-``, made free with ``-2``, ``-3``, ...
    """
    return read_public(recordings, recordings.copy(name, body.name if body else None))


@router.patch("/{name}")
def update_recording(
    name: str, body: RecordingUpdate, recordings: RecordingsDep
) -> RecordingPublic:
    """Rename (409 if in use or the name is taken) and/or set the operator and notes.

    The header is changed by an atomic replace, the frames are never touched; a rename also
    updates the demonstrations cut from the recording. Samples are refused (409).
    """
    new = recordings.update(name, body.name, notes=body.notes, operator=body.operator)
    return read_public(recordings, new)


@router.delete("/{name}", status_code=204)
def delete_recording(name: str, recordings: RecordingsDep) -> Response:
    """Delete a recording (409 while it is the live source or being captured, here or by
    another studio on the same data folder, or a sample)."""
    try:  # under the capture's lock: a capture that started meanwhile is refused too
        recordings.delete(name)
    except RecordingError as err:
        raise ConflictError(str(err)) from None
    return Response(status_code=204)


@router.get("/{name}/timeline")
def read_timeline(
    name: str,
    reviewer: ReviewerDep,
    points: Annotated[int, Query(ge=2, le=MAX_SERIES_POINTS)] = DEFAULT_SERIES_POINTS,
) -> TimelinePublic:
    """The human arm's joints and the taught robot's over the whole recording, at about
    ``points`` evenly spaced frames (degrees), fitted as a demonstration cut from it would be and
    retargeted onto that robot as an export would be; and the recording's own values at the same
    frames (``signals``)."""

    series, on_robot = reviewer.timeline(name, points)
    arm = on_robot.robot
    return TimelinePublic(
        name=name,
        kind=series.kind,
        duration=series.duration,
        times=series.times.round(4).tolist(),
        human=np.degrees(series.q_human).round(2).tolist(),
        robot=np.degrees(on_robot.q).round(2).tolist(),
        robot_name=arm.name,
        robot_title=arm.spec.title,
        robot_joints=list(arm.joint_names),
        robot_notes=[*(f.sentence for f in on_robot.findings), *on_robot.notes],
        residual_mm=(series.residual * 1000).round(2).tolist(),
        signals=[
            TimelineSignal(
                name=signal.name,
                unit=signal.unit,
                labels=list(signal.labels),
                values=[
                    [None if np.isnan(v) else v for v in row]
                    for row in signal.values.round(3).tolist()
                ],
            )
            for signal in series.signals
        ],
    )


@router.post("/{name}/review", status_code=202, response_class=Response)
def review_recording(name: str, body: RecordingReview, reviewer: ReviewerDep) -> Response:
    """Show the recording on the robot: with ``t``, hold the pose at ``t`` s (the timeline's
    cursor); else draw the tool path of ``[t0, t1]`` (default: all of it) and play it."""
    if body.t is not None:
        reviewer.hold(name, body.t)
    else:
        reviewer.play(name, body.t0, body.t1)
    return Response(status_code=202)
