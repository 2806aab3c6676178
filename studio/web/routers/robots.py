"""``/api/robots`` and ``/api/robot``: the offered robots and the one the operator teaches."""

from __future__ import annotations

import json
import shutil
from typing import Annotated, Literal

import numpy as np
from fastapi import APIRouter, Query
from fastapi.responses import FileResponse, Response
from starlette.background import BackgroundTask

from studio._layout import physics_cache_dir
from studio.kinematics import robot_spec
from studio.physics import SimulationReport

from .._deps import DemonstrationsDep, PoliciesDep, RecordingsDep, RobotsDep, SettingsDep
from .._robot_schemas import RobotChoice, RobotsPublic, SimulationPublic
from ..services import (
    EXPORT_HEADER,
    MEDIA_TYPES,
    Download,
    ExportFormat,
    export_for_robot,
    export_rollout,
    simulate_for_robot,
    simulated_motion,
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
    settings: SettingsDep,
    format: ExportFormat = "csv",
    unchecked: bool = False,
    robot: str | None = None,
    retime: bool = False,
    fit: bool = False,
    limit_margin: Annotated[float | None, Query(ge=0.0)] = None,
) -> FileResponse:
    """A recording or demonstration as the chosen robot's joint trajectory, retargeted, timed,
    checked for safety and replayed in physics as ``studio export SOURCE --robot NAME --format
    FORMAT`` does, the physics report stated in the file: CSV, MCAP (ROS 2 messages) or a
    zipped LeRobotDataset v3.0.

    Failed checks answer 422 with one sentence in plain words naming the sample, joint and
    margin, ``reason`` "safety" and every finding (``findings``); ``unchecked`` writes the file
    anyway with the findings stated in it. A recording keeps its capture times unless
    ``retime`` times its path as a demonstration's is (at the person's pace, slower only where
    the robot's limits need it), or ``fit`` does so only where its capture times break those
    limits (what the page asks). The ``X-Studio-Export`` header says in words what the export
    did (JSON: ``said``, ``timed_by``, ``slowed_because``, ``slowdowns``, ``findings``,
    ``physics``). For the robot taught unless ``robot`` names another (an unknown name: 422 with
    the list). 404 for no such recording or demonstration."""
    store = recordings if kind == "recording" else demonstrations.store
    path = store.path(name)
    target = robot_spec(robot).name if robot is not None else robots.taught
    cache = physics_cache_dir(settings.data_dir)
    done = export_for_robot(
        path, target, format, unchecked, retime, limit_margin, fit=fit, cache=cache
    )
    return _send(done, MEDIA_TYPES[format])


def _send(done: Download, media_type: str) -> FileResponse:
    """The download, with what the export did in its ``X-Studio-Export`` header (ASCII JSON),
    its temporary folder removed once sent."""
    return FileResponse(
        done.file,
        media_type=media_type,
        filename=done.name,
        headers={EXPORT_HEADER: json.dumps(done.about)},
        background=BackgroundTask(shutil.rmtree, done.folder, ignore_errors=True),
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
    fit: bool = False,
    limit_margin: Annotated[float | None, Query(ge=0.0)] = None,
) -> SimulationPublic:
    """The physics report ``/api/robot/export/{kind}/{name}`` (and ``studio export``) would
    state in the file, before exporting: the same samples replayed in MuJoCo on the robot's own
    URDF (its motors' force limits, gravity, the table), as ``studio simulate --json`` reports
    them, with the report's sentences. For the robot taught unless ``robot`` names another (an
    unknown name: 422); ``retime``, ``fit`` and ``limit_margin`` as the export's. 404 for no
    such recording or demonstration."""
    store = recordings if kind == "recording" else demonstrations.store
    path = store.path(name)
    target = robot_spec(robot).name if robot is not None else robots.taught
    cache = physics_cache_dir(settings.data_dir)
    report = simulate_for_robot(path, target, retime, cache, limit_margin, fit=fit)
    return SimulationPublic.model_validate(
        {**report.as_json(), "sentences": report.sentences(), **_trajectory(report)}
    )


def _trajectory(report: SimulationReport) -> dict[str, object]:
    """The simulated joint trajectory, as the API answers it (empty when it went unstable)."""
    q = report.q_simulated
    if q is None or report.times is None or not np.all(np.isfinite(q)):
        return {}
    return {"times": report.times.tolist(), "q_simulated": q.tolist()}


@router.post("/api/robot/simulate/{kind}/{name}/play", status_code=202, response_class=Response)
def play_simulated(
    kind: Literal["recording", "demonstration"],
    name: str,
    recordings: RecordingsDep,
    demonstrations: DemonstrationsDep,
    robots: RobotsDep,
    settings: SettingsDep,
    limit_margin: Annotated[float | None, Query(ge=0.0)] = None,
) -> Response:
    """Play in the scene the motion the robot taught makes in physics for what the page's
    export writes (``fit``): the MuJoCo replay's joints at each sample drive the robot drawn,
    its tool path drawn. It is simulated in the background (202 at once); the robot's notes
    (``GET /api/source``) say meanwhile what is being made, and afterwards why it could not
    play. 404 for no such recording or demonstration."""
    store = recordings if kind == "recording" else demonstrations.store
    path = store.path(name)
    target = robots.taught
    cache = physics_cache_dir(settings.data_dir)
    stat = path.stat()
    robots.play_motion(
        f"the simulated motion of the {kind} {name}",
        ("simulated", str(path), stat.st_mtime_ns, limit_margin, target, name),
        lambda: simulated_motion(path, target, cache, limit_margin),
    )
    return Response(status_code=202)


@router.get("/api/robot/export/rollout.mcap", responses=file_responses("application/octet-stream"))
def export_the_rollout(
    policies: PoliciesDep,
    settings: SettingsDep,
    run: str | None = None,
    policy: str | None = None,
    unchecked: bool = False,
    fit: bool = False,
) -> FileResponse:
    """The rollout last watched of a run's policy (``?run=<id>``) or an uploaded one
    (``?policy=<name>``) as an MCAP of ROS 2 ``trajectory_msgs/msg/JointTrajectory`` for the
    robot it was learnt on, at its own times (``fit``: timed within the robot's limits where
    those times break them), checked for safety and replayed in physics as ``studio export``
    does, the report stated in the file (``/api/watch/trajectory.csv`` is the same rollout as
    CSV). Failed checks answer 422 with one sentence (``reason`` "safety", ``findings``);
    ``unchecked`` writes it anyway with the findings stated in it. The ``X-Studio-Export``
    header says what the export did. 409 when that policy has not been watched yet."""
    watched = policies.watched(run, policy)
    done = export_rollout(
        watched.path,
        watched.robot,
        watched.name,
        watched.times,
        watched.q,
        unchecked,
        fit=fit,
        cache=physics_cache_dir(settings.data_dir),
        obstacles=watched.obstacles,
    )
    return _send(done, MEDIA_TYPES["mcap"])
