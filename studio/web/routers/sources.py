"""``/api/source``: the live source (simulator, recording, network bridge, serial, camera, hand
guide), playback, the human-to-robot mapping, and the observations the page hands in."""

from __future__ import annotations

from fastapi import APIRouter

from .._deps import SourcesDep
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
def read_source(sources: SourcesDep) -> SourcePublic:
    """The live source: kind, rate, frames, dropped frames, error, fit residual, robot pose."""
    return SourcePublic.model_validate(sources.public())


@router.put("")
def set_source(body: SourceUpdate, sources: SourcesDep) -> SourcePublic:
    """Switch the live source; the old one is stopped first (409 while recording).

    A source that cannot be built or cannot start (pyserial missing, an unreadable calibration
    file, no such serial device, a port in use) is still selected, the old one stopped, and
    shows its error in ``error``, so the page shows one message next to the source it names.
    A request that names no device or recording is refused (4xx) and changes nothing.
    """
    sources.switch(**body.model_dump())
    return SourcePublic.model_validate(sources.public())


@router.post("/playback")
def control_playback(body: PlaybackAction, sources: SourcesDep) -> SourcePublic:
    """Play, pause or seek the recording source (409 if the source is not a recording)."""
    sources.playback(body.action, body.t, body.speed)
    return SourcePublic.model_validate(sources.public())


@router.put("/retarget")
def set_retarget(body: RetargetUpdate, sources: SourcesDep) -> SourcePublic:
    """Map the arm onto the robot joint by joint or by hand position, mirrored or not."""
    sources.set_retarget(body.mode, body.mirror)
    return SourcePublic.model_validate(sources.public())


@router.post("/reach")
def simulator_reach(body: ReachAction, sources: SourcesDep) -> SourcePublic:
    """Make the simulated operator reach the pose that retargets onto a goal of the robot taught
    (joints 1-3, degrees; its default goal when omitted), or go back to random reaching (409 if the source is
    not the simulator). Handy for recording demonstrations that end at the goal."""
    sources.simulator_reach(body.action, body.goal_deg)
    return SourcePublic.model_validate(sources.public())


@router.post("/landmarks")
def post_landmarks(body: LandmarksFrame, sources: SourcesDep) -> LandmarksPublic:
    """One frame of pose landmarks from the page's camera: fitted, shown, and recorded while a
    capture runs (409 unless the source is the camera, or while another page sends frames; 422
    for NaN or wrong sizes; 429 for a flood, the frame dropped and the studio running on)."""
    return sources.post_landmarks(body)


@router.post("/hand")
def post_hand(body: HandTarget, sources: SourcesDep) -> HandPublic:
    """Move the operator's hand (arm frame, metres): exactly what dragging the scene's handle
    does (409 unless the source is the hand guide; 422 for NaN or wrong sizes; 429 for a flood)."""
    return HandPublic.model_validate(sources.hand_moved(body.position, body.wxyz))
