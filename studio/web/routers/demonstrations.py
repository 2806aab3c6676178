"""``/api/demonstrations``: cut demonstrations out of recordings (or mark them live), list,
preview on the robot and delete them.

The shipped samples' demonstrations are listed too: they can be previewed and trained on, never
deleted.
"""

from __future__ import annotations

from fastapi import APIRouter, Response

from studio.capture import RECORDING_SUFFIX, RECORDING_SUFFIXES, Demonstration
from studio.learning import goal_degrees, has_default_goal
from studio.motion import demonstration_grid

from .._deps import CaptureDep, DemonstrationsDep, PoliciesDep, TrainingDep
from .._schemas import (
    DemonstrationCreate,
    DemonstrationDetail,
    DemonstrationMark,
    DemonstrationPublic,
    MarkPublic,
    PolicyPublic,
    RunCreate,
)
from ..services import Demonstrations, StoredFile
from .policies import policy_public

router = APIRouter(prefix="/api/demonstrations", tags=["demonstrations"])


def demonstration_public(entry: StoredFile[Demonstration]) -> DemonstrationPublic:
    """The list entry of one demonstration (a damaged file: its name, flags and the reason).

    ``goal`` is the goal bin's centre in degrees; ``reaches_goal`` says whether that goal is the
    grid's default one (false when the goal was set from where the demonstration ends).
    """
    demo = entry.value
    if demo is None:
        return DemonstrationPublic(
            name=entry.name,
            recording="",
            t0=0.0,
            t1=0.0,
            steps=0,
            goal=[],
            reaches_goal=False,
            created="",
            sample=entry.sample,
            error=entry.error,
        )
    grid = demonstration_grid(demo)
    return DemonstrationPublic(
        name=entry.name,
        recording=demo.recording.name.removesuffix(
            next(
                (x for x in RECORDING_SUFFIXES if demo.recording.name.endswith(x)), RECORDING_SUFFIX
            )
        ),
        t0=demo.t0,
        t1=demo.t1,
        steps=max(0, len(demo.grid_path) - 1),
        goal=goal_degrees(grid),
        reaches_goal=has_default_goal(grid),
        created=demo.created or "",
        sample=entry.sample,
    )


def read_public(demonstrations: Demonstrations, name: str) -> DemonstrationPublic:
    """One demonstration's list entry by name (404 if none)."""
    return demonstration_public(demonstrations.store.entry(name))


@router.get("")
def list_demonstrations(demonstrations: DemonstrationsDep) -> list[DemonstrationPublic]:
    """Every demonstration: the shipped samples, then yours newest first; a damaged file is
    listed with the reason."""
    return [demonstration_public(e) for e in demonstrations.listed()]


@router.post("", status_code=201)
def create_demonstration(
    body: DemonstrationCreate, demonstrations: DemonstrationsDep
) -> DemonstrationPublic:
    """Cut ``[t0, t1]`` out of a recording (422 with the reason when it is refused)."""
    name = demonstrations.cut(body.recording, body.t0, body.t1, body.goal_from_end, body.name)
    return read_public(demonstrations, name)


@router.get("/mark")
def read_mark(capture: CaptureDep) -> MarkPublic:
    """Whether a live demonstration is being marked, and since when (recording time, s)."""
    return MarkPublic(marking=capture.mark_t0 is not None, t0=capture.mark_t0)


@router.post("/mark")
def mark_demonstration(
    body: DemonstrationMark, capture: CaptureDep, demonstrations: DemonstrationsDep
) -> MarkPublic:
    """Mark the start, then the end, of a demonstration while a capture runs.

    On ``stop`` the segment is cut from the recording being captured and returned as
    ``demonstration`` (422 with the reason when it is refused; 409 without a running capture).
    """
    if body.action == "start":
        return MarkPublic(marking=True, t0=capture.mark_start())
    name = capture.mark_stop(body.goal_from_end, body.name)
    return MarkPublic(marking=False, t0=None, demonstration=read_public(demonstrations, name))


@router.post("/check", status_code=204, response_class=Response)
def check_run_demonstrations(body: RunCreate, training: TrainingDep) -> Response:
    """Check a run form as it is filled in (the demonstrations picked against its goal and task)
    with the one resolver a run is started with; nothing is queued. 204 when it would start, else
    the 422 starting it would answer (``detail``, ``problems``, ``by_field``)."""
    training.check(body)
    return Response(status_code=204)


@router.get("/{name}")
def read_demonstration(name: str, demonstrations: DemonstrationsDep) -> DemonstrationDetail:
    """One demonstration with its robot path (radians) and grid path."""
    demo = demonstrations.store.load(name)  # a damaged file answers with the reader's sentence
    entry = demonstrations.store.entry(name)
    return DemonstrationDetail(
        **demonstration_public(entry).model_dump(),
        times=demo.times.tolist(),
        q_robot=demo.q_robot.tolist(),
        grid_path=[int(s) for s in demo.grid_path],
    )


@router.post("/{name}/dmp", status_code=201)
def fit_demonstration_primitive(
    name: str, demonstrations: DemonstrationsDep, policies: PoliciesDep
) -> PolicyPublic:
    """Fit the movement-primitive baseline (a DMP) to the demonstration on the robot taught, in
    that robot's joint space (the demonstration retargeted onto it, as a training run replays
    it), and keep it among the policies as ``<name>-dmp-<robot>`` (a sample's name without its
    ``sample-`` prefix; ``-2``, ... when taken): it
    is watched, scored and exported like the others. 404 for no such demonstration; 422 when it
    cannot be retargeted (its recording gone) or fitted."""
    return policy_public(policies.store.entry(demonstrations.fit_primitive(name)))


@router.post("/{name}/preview", status_code=202, response_class=Response)
def preview_demonstration(name: str, demonstrations: DemonstrationsDep) -> Response:
    """Draw the demonstration's tool path and play it on the robot in the scene."""
    demonstrations.show(name, play=True)
    return Response(status_code=202)


@router.delete("/{name}", status_code=204)
def delete_demonstration(name: str, demonstrations: DemonstrationsDep) -> Response:
    """Delete a demonstration (409 for a sample, or while a queued or running run replays it)."""
    demonstrations.delete(name)
    return Response(status_code=204)
