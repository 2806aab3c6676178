"""``/api/robots`` and ``/api/robot``: the offered robots and the one the operator teaches."""

from __future__ import annotations

import shutil
from typing import Literal

from fastapi import APIRouter
from fastapi.responses import FileResponse
from starlette.background import BackgroundTask

from .._deps import StudioDep
from .._robot_export import MEDIA_TYPES, ExportFormat, export_for_robot
from .._schemas import RobotChoice, RobotsPublic
from . import file_responses

router = APIRouter(tags=["robots"])


@router.get("/api/robots")
def read_robots(studio: StudioDep) -> RobotsPublic:
    """The offered robots (the Puma560 first, the default) with their joints, and the one taught."""
    return RobotsPublic.model_validate(studio.robots_public())


@router.put("/api/robot")
def set_robot(body: RobotChoice, studio: StudioDep) -> RobotsPublic:
    """Teach another robot: the scene draws it from its own meshes and the live source drives it
    from the next frame (cartesian retargeting; joint mode is the Puma560's). An unknown name is
    refused (422) and changes nothing."""
    studio.set_robot(body.name)
    return RobotsPublic.model_validate(studio.robots_public())


@router.get(
    "/api/robot/export/{kind}/{name}",
    responses=file_responses(*sorted(set(MEDIA_TYPES.values()))),
)
def export_for_the_robot(
    kind: Literal["recording", "demonstration"],
    name: str,
    studio: StudioDep,
    format: ExportFormat = "csv",
    unchecked: bool = False,
) -> FileResponse:
    """A recording or demonstration as the chosen robot's joint trajectory, retargeted, timed
    and checked for safety as ``studio export SOURCE --robot NAME --format FORMAT`` does: CSV,
    MCAP (ROS 2 messages) or a zipped LeRobotDataset v3.0. Failed checks answer 422 with one
    sentence naming the sample, joint and margin; ``unchecked`` writes the file anyway with the
    findings stated in it. 404 for no such recording or demonstration."""
    store = studio.recordings if kind == "recording" else studio.demonstrations
    path = store.path(name)
    out, filename, folder = export_for_robot(path, studio.pipeline.robot_name, format, unchecked)
    return FileResponse(
        out,
        media_type=MEDIA_TYPES[format],
        filename=filename,
        background=BackgroundTask(shutil.rmtree, folder, ignore_errors=True),
    )
