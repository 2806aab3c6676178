"""``/api/robots`` and ``/api/robot``: the offered robots and the one the operator teaches."""

from __future__ import annotations

import shutil
from typing import Annotated, Literal

from fastapi import APIRouter, Query
from fastapi.responses import FileResponse
from starlette.background import BackgroundTask

from studio._layout import physics_cache_dir
from studio.kinematics import robot_spec

from .._deps import DemonstrationsDep, PoliciesDep, RecordingsDep, RobotsDep, SettingsDep
from .._schemas import RobotChoice, RobotsPublic, SimulationPublic
from ..services import (
    MEDIA_TYPES,
    ExportFormat,
    export_for_robot,
    export_rollout,
    simulate_for_robot,
)
from . import file_responses

router = APIRouter(tags=["robots"])


@router.get("/api/robots")
def read_robots(robots: RobotsDep) -> RobotsPublic:
    """The offered robots (the Puma560 first, the default) with their joints, and the one taught."""
    return RobotsPublic.model_validate(robots.public())


@router.put("/api/robot")
def set_robot(body: RobotChoice, robots: RobotsDep) -> RobotsPublic:
    """Teach another robot: the scene draws it from its own meshes and the live source drives it
    from the next frame (cartesian retargeting; joint mode is the Puma560's). An unknown name is
    refused (422) and changes nothing."""
    robots.choose(body.name)
    return RobotsPublic.model_validate(robots.public())


@router.get(
    "/api/robot/export/{kind}/{name}",
    responses=file_responses(*sorted(set(MEDIA_TYPES.values()))),
)
def export_for_the_robot(
    kind: Literal["recording", "demonstration"],
    name: str,
    recordings: RecordingsDep,
    demonstrations: DemonstrationsDep,
    robots: RobotsDep,
    format: ExportFormat = "csv",
    unchecked: bool = False,
    robot: str | None = None,
    retime: bool = False,
    limit_margin: Annotated[float | None, Query(ge=0.0)] = None,
) -> FileResponse:
    """A recording or demonstration as the chosen robot's joint trajectory, retargeted, timed
    and checked for safety as ``studio export SOURCE --robot NAME --format FORMAT`` does: CSV,
    MCAP (ROS 2 messages) or a zipped LeRobotDataset v3.0. Failed checks answer 422 with one
    sentence naming the sample, joint and margin; ``unchecked`` writes the file anyway with the
    findings stated in it (``reason`` "safety" in the 422 says the checks refused it). A
    recording keeps its capture times unless ``retime`` times its path within the robot's
    limits, as a demonstration's is (``studio export --retime``). ``limit_margin`` (rad) is kept
    from every joint's hard limit by the retargeting, the timing and the checks (``studio export
    --limit-margin``; default ``LIMIT_MARGIN_RAD``). For the robot taught unless
    ``robot`` names another (an unknown name: 422 with the list). 404 for no such recording or
    demonstration."""
    store = recordings if kind == "recording" else demonstrations.store
    path = store.path(name)
    target = robot_spec(robot).name if robot is not None else robots.taught
    out, filename, folder = export_for_robot(path, target, format, unchecked, retime, limit_margin)
    return FileResponse(
        out,
        media_type=MEDIA_TYPES[format],
        filename=filename,
        background=BackgroundTask(shutil.rmtree, folder, ignore_errors=True),
    )


@router.get("/api/robot/simulate/{kind}/{name}")
def simulate_for_the_robot(
    kind: Literal["recording", "demonstration"],
    name: str,
    recordings: RecordingsDep,
    demonstrations: DemonstrationsDep,
    robots: RobotsDep,
    settings: SettingsDep,
    robot: str | None = None,
    retime: bool = False,
    limit_margin: Annotated[float | None, Query(ge=0.0)] = None,
) -> SimulationPublic:
    """The physics report ``/api/robot/export/{kind}/{name}`` (and ``studio export``) would
    state in the file, before exporting: the same samples replayed in MuJoCo on the robot's own
    URDF (its motors' force limits, gravity, the table), as ``studio simulate --json`` reports
    them, with the report's sentences (``limit_margin`` as the export's). For the robot taught unless ``robot`` names another (an
    unknown name: 422); 404 for no such recording or demonstration."""
    store = recordings if kind == "recording" else demonstrations.store
    path = store.path(name)
    target = robot_spec(robot).name if robot is not None else robots.taught
    cache = physics_cache_dir(settings.data_dir)
    report = simulate_for_robot(path, target, retime, cache, limit_margin)
    return SimulationPublic.model_validate({**report.as_json(), "sentences": report.sentences()})


@router.get("/api/robot/export/rollout.mcap", responses=file_responses("application/octet-stream"))
def export_the_rollout(
    policies: PoliciesDep,
    run: str | None = None,
    policy: str | None = None,
    unchecked: bool = False,
) -> FileResponse:
    """The rollout last watched of a run's policy (``?run=<id>``) or an uploaded one
    (``?policy=<name>``) as an MCAP of ROS 2 ``trajectory_msgs/msg/JointTrajectory`` for the
    robot it was learnt on, at its own times, checked for safety as ``studio export`` checks it
    (``/api/watch/trajectory.csv`` is the same rollout as CSV). Failed checks answer 422 with
    one sentence (``reason`` "safety"); ``unchecked`` writes it anyway with the findings stated
    in it. 409 when that policy has not been watched yet."""
    watched = policies.watched(run, policy)
    out, filename, folder = export_rollout(
        watched.path, watched.robot, watched.name, watched.times, watched.q, unchecked
    )
    return FileResponse(
        out,
        media_type=MEDIA_TYPES["mcap"],
        filename=filename,
        background=BackgroundTask(shutil.rmtree, folder, ignore_errors=True),
    )
