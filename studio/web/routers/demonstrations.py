"""``/api/demonstrations``: cut demonstrations out of recordings (or mark them live), list,
preview on the robot and delete them.

The shipped samples' demonstrations are listed too: they can be previewed and trained on, never
deleted.
"""

from __future__ import annotations

import uuid

import numpy as np
from fastapi import APIRouter, Response

from studio.capture import RECORDING_SUFFIX, RECORDING_SUFFIXES, Demonstration
from studio.kinematics import robot_spec
from studio.learning import (
    POLICY_SUFFIX,
    LearningError,
    fit_dmp_policy,
    goal_degrees,
    has_default_goal,
    save_dmp_policy,
)
from studio.motion import demonstration_grid

from .._deps import StudioDep
from .._errors import InvalidError
from .._schemas import (
    DemonstrationCreate,
    DemonstrationDetail,
    DemonstrationMark,
    DemonstrationPublic,
    MarkPublic,
    PolicyPublic,
    RunCreate,
)
from .._state import Studio
from ..services import StoredFile, prepare_run
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


def read_public(studio: Studio, name: str) -> DemonstrationPublic:
    """One demonstration's list entry by name (404 if none)."""
    return demonstration_public(studio.demonstrations.entry(name))


@router.get("")
def list_demonstrations(studio: StudioDep) -> list[DemonstrationPublic]:
    """Every demonstration: the shipped samples, then yours newest first; a damaged file is
    listed with the reason."""
    listed = [demonstration_public(e) for e in studio.demonstrations.entries()]
    samples = [d for d in listed if d.sample]
    mine = sorted((d for d in listed if not d.sample), key=lambda d: (d.created, d.name))
    return samples + mine[::-1]


@router.post("", status_code=201)
def create_demonstration(body: DemonstrationCreate, studio: StudioDep) -> DemonstrationPublic:
    """Cut ``[t0, t1]`` out of a recording (422 with the reason when it is refused)."""
    name = studio.cut_demonstration(body.recording, body.t0, body.t1, body.goal_from_end, body.name)
    return read_public(studio, name)


@router.get("/mark")
def read_mark(studio: StudioDep) -> MarkPublic:
    """Whether a live demonstration is being marked, and since when (recording time, s)."""
    return MarkPublic(marking=studio.mark_t0 is not None, t0=studio.mark_t0)


@router.post("/mark")
def mark_demonstration(body: DemonstrationMark, studio: StudioDep) -> MarkPublic:
    """Mark the start, then the end, of a demonstration while a capture runs.

    On ``stop`` the segment is cut from the recording being captured and returned as
    ``demonstration`` (422 with the reason when it is refused; 409 without a running capture).
    """
    if body.action == "start":
        return MarkPublic(marking=True, t0=studio.mark_start())
    name = studio.mark_stop(body.goal_from_end, body.name)
    return MarkPublic(marking=False, t0=None, demonstration=read_public(studio, name))


@router.post("/check", status_code=204, response_class=Response)
def check_run_demonstrations(body: RunCreate, studio: StudioDep) -> Response:
    """Check a run form as it is filled in (the demonstrations picked against its goal and task)
    with the one resolver a run is started with; nothing is queued. 204 when it would start, else
    the 422 starting it would answer (``detail``, ``problems``, ``by_field``)."""
    prepare_run(studio.with_robot(body), studio.demonstration_path)
    return Response(status_code=204)


@router.get("/{name}")
def read_demonstration(name: str, studio: StudioDep) -> DemonstrationDetail:
    """One demonstration with its robot path (radians) and grid path."""
    demo = studio.demonstrations.load(name)  # a damaged file answers with the reader's sentence
    entry = studio.demonstrations.entry(name)
    return DemonstrationDetail(
        **demonstration_public(entry).model_dump(),
        times=demo.times.tolist(),
        q_robot=demo.q_robot.tolist(),
        grid_path=[int(s) for s in demo.grid_path],
    )


@router.post("/{name}/dmp", status_code=201)
def fit_demonstration_primitive(name: str, studio: StudioDep) -> PolicyPublic:
    """Fit the movement-primitive baseline (a DMP) to the demonstration on the robot taught, in
    that robot's joint space (the demonstration retargeted onto it, as a training run replays
    it), and keep it among the policies as ``<name>-dmp-<robot>`` (a sample's name without its
    ``sample-`` prefix; ``-2``, ... when taken): it
    is watched, scored and exported like the others. 404 for no such demonstration; 422 when it
    cannot be retargeted (its recording gone) or fitted."""
    studio.demonstrations.load(name)  # 404 with the store's sentence
    robot = studio.pipeline.robot_name
    demo = studio.demonstration_path(name, robot)
    try:
        policy = fit_dmp_policy(
            demo.times if demo.times is not None else np.zeros(0),
            demo.q_robot,
            robot=robot,
            notes=f"fitted to the demonstration {name} on the {robot_spec(robot).title}",
        )
    except LearningError as err:
        raise InvalidError(str(err)) from None
    tmp = studio.policies.folder / f".dmp-{uuid.uuid4().hex}.tmp"
    try:
        save_dmp_policy(tmp, policy)
        taken = studio.policy_names()
        base = studio.policies.new_name(f"{name}-dmp-{robot}")  # a user's, not a sample's, name
        new = studio.policies.claim(tmp, base, lambda n: n in taken, suffix=POLICY_SUFFIX)
    finally:
        tmp.unlink(missing_ok=True)
    return policy_public(studio.policies.entry(new))


@router.post("/{name}/preview", status_code=202, response_class=Response)
def preview_demonstration(name: str, studio: StudioDep) -> Response:
    """Draw the demonstration's tool path and play it on the robot in the scene."""
    studio.preview_demonstration(name)
    return Response(status_code=202)


@router.delete("/{name}", status_code=204)
def delete_demonstration(name: str, studio: StudioDep) -> Response:
    """Delete a demonstration (409 for a sample, or while a queued or running run replays it)."""
    studio.delete_demonstration(name)
    return Response(status_code=204)
