"""``/api/scene``: scrub the rollout being watched, point the cameras, pose the robot by hand,
place the boxes of the next run.

The scene keeps the scrub position, speed and pause as part of its playback
(:func:`studio.web.scene._model.rescheduled`); this router only checks the values and passes them
on. Angles are in degrees here, at the user's edge, and radians inside.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from fastapi import APIRouter
from pydantic import BaseModel, Field

from studio.kinematics import KinematicsError, RobotArm, check_obstacles, load_robot

from .._deps import RobotsDep, RolloutsDep, SceneDep
from .._errors import ConflictError, InvalidError
from .._schemas import ObstacleBody, ObstaclesPublic, _Body
from ..scene import PLAYBACK_SPEEDS, VIEW_NAMES, Playback, Scene
from ..services import Robots

router = APIRouter(prefix="/api/scene", tags=["scene"])

MAX_STEP = 10_000
"""Most samples one step request may move (a rollout has at most a few thousand)."""


class PlaybackChange(_Body):
    """Scrub, pause, resume, change speed or step the playback (each field optional)."""

    t: float | None = Field(None, description="scrub to this time (s) of the rollout")
    speed: float | None = Field(None, ge=PLAYBACK_SPEEDS[0], le=PLAYBACK_SPEEDS[-1])
    paused: bool | None = None
    step: int = Field(0, ge=-MAX_STEP, le=MAX_STEP, description="samples forward (+) or back (-)")


class PlaybackPublic(BaseModel):
    """The playback the scene shows: where it stands and how it moves."""

    active: bool
    """A rollout (or a jogged pose) was played and can be scrubbed."""
    t: float
    """Time reached in the rollout (s), within ``[0, duration]``."""
    duration: float
    samples: int
    sample: int
    """Index of the last sample at or before ``t``."""
    speed: float
    paused: bool
    finished: bool
    """Played to its end (and not paused)."""
    speeds: list[float]
    """The speeds the page offers."""
    q_robot_deg: list[float]
    """The robot joints the scene shows now (deg). The scene draws a new time up to a tick after
    the playback reaches it: ``shown_sample`` says which sample these joints are."""
    shown_sample: int = -1
    """The sample ``q_robot_deg`` stands at (or after, between two samples); -1 for a live pose."""
    robot: str = "puma560"
    """The robot whose joints the playback holds (it moves only while that robot is drawn)."""
    drawn: str = "puma560"
    """The robot the scene draws now."""


class ViewChange(_Body):
    """Put the browsers' cameras on a preset."""

    view: Literal["front", "top", "side"]


class FollowChange(_Body):
    """Make the browsers' cameras follow the robot's tool, or stop."""

    on: bool


class CameraPublic(BaseModel):
    """A browser's camera (world, m, Z up)."""

    position: list[float]
    look_at: list[float]


class ViewsPublic(BaseModel):
    """The camera presets, whether the cameras follow the tool, and each browser's camera."""

    views: list[str]
    following: bool
    cameras: list[CameraPublic]


class JogChange(_Body):
    """Pose the robot by hand: every joint, in degrees."""

    q_deg: list[float] = Field(..., max_length=32)


class JointPublic(BaseModel):
    """One joint of the robot and its limits."""

    name: str = Field(description='"joint 1", "joint 2", ...: the slider\'s name on the page')
    joint: str = Field("", description="the robot's own name for it (its URDF's, `panda_joint1`)")
    lower_deg: float
    upper_deg: float


class JogPublic(BaseModel):
    """The robot's joints with their limits, and the pose the scene shows."""

    joints: list[JointPublic]
    q_deg: list[float]
    robot: str = Field("puma560", description="the robot posed: the one taught (`/api/robot`)")
    title: str = Field("", description="its name as people read it")


def _shown(scene: Scene | None) -> Scene:
    """The scene (409 when the studio runs without one)."""
    if scene is None:
        raise ConflictError("This studio runs without a 3D scene; start it with its scene.")
    return scene


def _public(scene: Scene, playback: Playback | None, t: float) -> PlaybackPublic:
    q_rad, shown_sample = scene.shown_robot()
    q = np.degrees(q_rad).round(6).tolist()
    speeds = list(PLAYBACK_SPEEDS)
    if playback is None:
        return PlaybackPublic(
            active=False, t=0, duration=0, samples=0, sample=0, speed=1, paused=False,
            finished=False, speeds=speeds, q_robot_deg=q, shown_sample=shown_sample,
            drawn=scene.robot_name,
        )  # fmt: skip
    at = min(max(t, 0.0), playback.duration)
    sample = int(np.searchsorted(playback.times, at, side="right")) - 1
    return PlaybackPublic(
        active=True,
        t=round(at, 6),
        duration=playback.duration,
        samples=len(playback.times),
        sample=max(sample, 0),
        speed=playback.speed,
        paused=playback.paused,
        finished=not playback.paused and t >= playback.duration,
        speeds=speeds,
        q_robot_deg=q,
        shown_sample=shown_sample,
        robot=playback.robot,
        drawn=scene.robot_name,
    )


@router.get("/playback")
def read_playback(scene: SceneDep) -> PlaybackPublic:
    """Where the playback stands (``active`` false before anything was watched)."""
    scene = _shown(scene)
    now = scene.scrub()
    return _public(scene, None, 0.0) if now is None else _public(scene, *now)


@router.post("/playback")
def change_playback(body: PlaybackChange, scene: SceneDep) -> PlaybackPublic:
    """Scrub (``t``), pause or resume, change the speed or step by samples; 409 before a watch,
    422 for a time outside the rollout."""
    scene = _shown(scene)
    now = scene.scrub()
    if now is None:
        raise ConflictError("Nothing has been watched yet; watch a policy first, then scrub it.")
    duration = now[0].duration
    if body.t is not None and not 0 <= body.t <= duration:
        raise InvalidError(
            f"t is {body.t:g} s, outside the rollout's 0 to {duration:g} s; choose a time within it."
        )
    changed = scene.scrub(t=body.t, speed=body.speed, paused=body.paused, step=body.step)
    if changed is None:  # stopped meanwhile
        raise ConflictError("The playback was stopped; watch a policy again, then scrub it.")
    return _public(scene, *changed)


@router.get("/views")
def read_views(scene: SceneDep) -> ViewsPublic:
    """The presets, whether the cameras follow the tool, and each browser's camera."""
    scene = _shown(scene)
    camera = scene.camera
    return ViewsPublic(
        views=list(VIEW_NAMES),
        following=camera.following,
        cameras=[CameraPublic(position=list(v.position), look_at=list(v.look_at)) for v in camera.views()],
    )  # fmt: skip


@router.post("/view")
def change_view(body: ViewChange, scene: SceneDep) -> ViewsPublic:
    """Put every connected browser's camera on the preset (front, top or side)."""
    scene = _shown(scene)
    scene.camera.show(body.view)
    return read_views(scene)


@router.post("/follow")
def change_follow(body: FollowChange, scene: SceneDep) -> ViewsPublic:
    """Make every browser's camera follow the robot's tool (``on``), or stop following."""
    scene = _shown(scene)
    scene.camera.following = body.on
    if body.on:
        scene.camera.follow(scene.tool_positions(scene.current_q_robot(), scene.robot_name)[0])
    return read_views(scene)


def _joints(arm: RobotArm) -> list[JointPublic]:
    """The arm's joints with their limits in degrees, rounded inwards (a slider's end is a pose
    the arm may take, and joints 1-3 there a goal the learning package accepts)."""
    lower = np.ceil(np.degrees(arm.lower) * 1e6) / 1e6
    upper = np.floor(np.degrees(arm.upper) * 1e6) / 1e6
    return [
        JointPublic(name=f"joint {i + 1}", joint=joint, lower_deg=float(lo), upper_deg=float(hi))
        for i, (joint, lo, hi) in enumerate(zip(arm.joint_names, lower, upper, strict=True))
    ]


def _posed(robots: Robots) -> RobotArm:
    """The arm posed by hand: the robot taught (the scene draws it, once its meshes are read)."""
    return load_robot(robots.taught, geometry=False)


@router.get("/jog")
def read_jog(scene: SceneDep, robots: RobotsDep) -> JogPublic:
    """The taught robot's joints with their limits (deg), and the joints the scene shows (its
    home pose while the scene still draws another robot)."""
    scene = _shown(scene)
    arm = _posed(robots)
    q = scene.current_q_robot()
    if scene.robot_name != arm.name or len(q) != arm.nq:
        q = np.asarray(arm.home, dtype=float)
    q_deg = np.degrees(np.clip(q, arm.lower, arm.upper)).round(6).tolist()
    return JogPublic(joints=_joints(arm), q_deg=q_deg, robot=arm.name, title=arm.spec.title)


@router.post("/jog")
def jog(body: JogChange, scene: SceneDep, robots: RobotsDep, rollouts: RolloutsDep) -> JogPublic:
    """Show the taught robot at the given joints (deg, one per joint of that robot, each within
    its limits; 422 otherwise) until the next watch or Stop."""
    scene = _shown(scene)
    arm = _posed(robots)
    joints = _joints(arm)
    if len(body.q_deg) != len(joints):
        raise InvalidError(
            f"q_deg has {len(body.q_deg)} angles but the {arm.spec.title} has {len(joints)} joints; give one angle per joint."
        )
    for j, value in zip(joints, body.q_deg, strict=True):
        if not j.lower_deg <= value <= j.upper_deg:
            raise InvalidError(
                f"{j.name} is {value:g}°, outside its limits {j.lower_deg:g}° to {j.upper_deg:g}°; choose an angle within them."
            )
    rollouts.release()  # a pose by hand replaces the policy being watched
    scene.hold_pose(np.radians(body.q_deg), robot=arm.name)
    return JogPublic(joints=joints, q_deg=list(body.q_deg), robot=arm.name, title=arm.spec.title)


@router.get("/obstacles")
def edited_obstacles(scene: SceneDep) -> ObstaclesPublic:
    """The boxes placed for the next run, where their handles stand now (dragged in the scene)."""
    boxes = _shown(scene).obstacles.edited()
    return ObstaclesPublic(obstacles=[ObstacleBody(**box.to_dict()) for box in boxes])


@router.put("/obstacles")
def edit_obstacles(body: ObstaclesPublic, scene: SceneDep) -> ObstaclesPublic:
    """Place these boxes for the next run, each with a handle to drag it (422: a bad box)."""
    try:
        boxes = check_obstacles([box.model_dump() for box in body.obstacles])
    except KinematicsError as err:
        raise InvalidError(str(err)) from None
    shown = _shown(scene)
    placed = shown.obstacles.edit(list(boxes), shown.robot_name)  # the robot a run would train
    return ObstaclesPublic(obstacles=[ObstacleBody(**box.to_dict()) for box in placed])


@router.post("/obstacles", status_code=201)
def add_obstacle(scene: SceneDep) -> ObstaclesPublic:
    """Place one more box for the next run, beside the robot drawn (``Add obstacle``; 422 past
    the most boxes a run takes)."""
    shown = _shown(scene)
    boxes = [*shown.obstacles.edited(), shown.obstacles.new_box(shown.robot_name)]
    try:
        check_obstacles(boxes)
    except KinematicsError as err:
        raise InvalidError(str(err)) from None
    placed = shown.obstacles.edit(boxes, shown.robot_name)
    return ObstaclesPublic(obstacles=[ObstacleBody(**box.to_dict()) for box in placed])
