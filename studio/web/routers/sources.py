"""``/api/source``: the live source (simulator, recording, network bridge, serial, camera, hand
guide), playback, the human-to-robot mapping, and the observations the page hands in."""

from __future__ import annotations

from fastapi import APIRouter

from .._deps import StudioDep
from .._schemas import (
    HandPublic,
    HandTarget,
    LandmarksFrame,
    LandmarksPublic,
    PlaybackAction,
    ReachAction,
    RetargetUpdate,
    SourcePublic,
    SourceUpdate,
)

router = APIRouter(prefix="/api/source", tags=["source"])


@router.get("")
def read_source(studio: StudioDep) -> SourcePublic:
    """The live source: kind, rate, frames, dropped frames, error, fit residual, robot pose."""
    return SourcePublic.model_validate(studio.source_public())


@router.put("")
def set_source(body: SourceUpdate, studio: StudioDep) -> SourcePublic:
    """Switch the live source; the old one is stopped first (409 while recording).

    A source that cannot be built or cannot start (pyserial missing, an unreadable calibration
    file, no such serial device, a port in use) is still selected, the old one stopped, and
    shows its error in ``error``, so the page shows one message next to the source it names.
    A request that names no device or recording is refused (4xx) and changes nothing.
    """
    studio.set_source(**body.model_dump())
    return SourcePublic.model_validate(studio.source_public())


@router.post("/playback")
def control_playback(body: PlaybackAction, studio: StudioDep) -> SourcePublic:
    """Play, pause or seek the recording source (409 if the source is not a recording)."""
    studio.playback(body.action, body.t, body.speed)
    return SourcePublic.model_validate(studio.source_public())


@router.put("/retarget")
def set_retarget(body: RetargetUpdate, studio: StudioDep) -> SourcePublic:
    """Map the arm onto the robot joint by joint or by hand position, mirrored or not."""
    studio.pipeline.set_retarget(body.mode, body.mirror)
    return SourcePublic.model_validate(studio.source_public())


@router.post("/reach")
def simulator_reach(body: ReachAction, studio: StudioDep) -> SourcePublic:
    """Make the simulated operator reach the pose that retargets onto a goal of the robot taught
    (joints 1-3, degrees; its default goal when omitted), or go back to random reaching (409 if the source is
    not the simulator). Handy for recording demonstrations that end at the goal."""
    studio.simulator_reach(body.action, body.goal_deg)
    return SourcePublic.model_validate(studio.source_public())


@router.post("/landmarks")
def post_landmarks(body: LandmarksFrame, studio: StudioDep) -> LandmarksPublic:
    """One frame of pose landmarks from the page's camera: fitted, shown, and recorded while a
    capture runs (409 unless the source is the camera, or while another page sends frames; 422
    for NaN or wrong sizes; 429 for a flood, the frame dropped and the studio running on)."""
    return studio.post_landmarks(body)


@router.post("/hand")
def post_hand(body: HandTarget, studio: StudioDep) -> HandPublic:
    """Move the operator's hand (arm frame, metres): exactly what dragging the scene's handle
    does (409 unless the source is the hand guide; 422 for NaN or wrong sizes; 429 for a flood)."""
    return HandPublic.model_validate(studio.hand_moved(body.position, body.wxyz))
