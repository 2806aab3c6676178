"""Request and response bodies of the API about the robots (see ``docs/api.md``): the robot
taught, the robots offered, and a motion's physics report. Kept apart from :mod:`._schemas`, whose
families and conventions they follow, so that module stays small."""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, Field

from ._schemas import _Body


class RobotChoice(_Body):
    """Choose the robot the operator teaches."""

    name: str = Field(description="one of the names `GET /api/robots` lists")


class RobotInfo(BaseModel):
    """One offered robot."""

    name: str
    title: str
    joints: list[str]
    goal_deg: list[float] = Field(
        default_factory=list,
        description="its default goal, joints 1-3 in degrees: the train form's goal for it, the goal `studio train --robot NAME` trains towards",
    )
    joint_mode: bool = Field(
        False,
        description="whether its joints can follow the operator's one by one (retargeting's joint mode); every robot follows the hand",
    )


class RobotsPublic(BaseModel):
    """The offered robots (the default first) and the one taught now."""

    robots: list[RobotInfo]
    robot: str
    drawn: str | None = Field(
        None, description="the robot the 3D scene has drawn (null without a scene)"
    )
    drawn_meshes: int = Field(0, description="how many meshes the scene draws it with")
    limit_margin_rad: float = Field(
        description="how far (rad) plans keep every joint from its hard limit by default; an "
        "export may ask for another (its limit_margin, `studio export --limit-margin`)"
    )


class ContactPublic(BaseModel):
    """Two links, a link and the table, or a link and an obstacle box, that touched in the simulated
    replay."""

    kind: Literal["self", "table", "obstacle"]
    link_a: str
    link_b: str = Field(
        description='the other link, "table", or an obstacle box ("obstacle_1", ...)'
    )
    first_sample: int = Field(description="the first sample they touched at (0-based)")
    first_time_s: float
    samples: int = Field(description="how many samples they touched at")
    depth_m: float = Field(description="the deepest they went into each other (m)")


class SimulationPublic(BaseModel):
    """A trajectory replayed in MuJoCo on the robot (``studio simulate --json``'s keys, and the
    report in sentences as the exported file states it)."""

    completed: bool = Field(description="the arm came to rest within 1 cm of the motion's end")
    max_joint_error_rad: float
    max_tool_error_m: float
    saturated_samples: int = Field(description="samples where a motor was at its force limit")
    contacts: list[ContactPublic]
    sentences: list[str] = Field(description="the report as the exported file states it")
    times: list[float] = Field(default_factory=list, description="the samples' times (s, from 0)")
    q_simulated: list[list[float]] = Field(
        default_factory=list,
        description="the joints (rad) the simulated robot reached at each sample: the motion "
        "it makes (empty when the simulation went unstable)",
    )
