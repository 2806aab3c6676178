"""``/api/robots`` and ``/api/robot``: the offered robots and the one the operator teaches."""

from __future__ import annotations

from fastapi import APIRouter

from .._deps import StudioDep
from .._schemas import RobotChoice, RobotsPublic

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
