"""Listing facts about grids and policy files: the one place they are computed.

The web page, the CLI and scripts list policies and demonstrations; what a listing says about a
goal (its angles in degrees, whether it is the grid's default) or about a policy file (its
planner, how many episodes its curve holds) is computed here, next to the formats it reads.
"""

from __future__ import annotations

from typing import TypedDict

from .._registry import AnyPolicy, learner_of
from ..tabular._learner import goal_degrees as goal_degrees
from ..tasks._arm import ArmGrid

POLICY_SUFFIX = ".policy.npz"
"""The file suffix of policy files (the format is in :mod:`._policy`)."""


def has_default_goal(grid: ArmGrid) -> bool:
    """Whether ``grid``'s goal is the default goal of a grid with the same robot, joints, bins and
    range.

    A demonstration whose goal was set from where it ends (``goal_from_end``) answers false: it
    trains a different task than the paper's.
    """
    default = ArmGrid(
        joints=grid.joints,
        bins=grid.bins,
        low_deg=grid.low_deg,
        high_deg=grid.high_deg,
        robot=grid.robot,
    )
    return tuple(grid.goal) == tuple(default.goal)


class PolicySummary(TypedDict):
    """A policy file's listing facts (see :func:`policy_summary`)."""

    task: dict[str, object]
    grid: dict[str, object]
    joints: int
    goal_deg: list[float]
    planning: str
    episodes: int
    experiments: int
    created: str
    notes: str


def policy_summary(policy: AnyPolicy) -> PolicySummary:
    """JSON-ready facts about a policy file of either kind for listings (the page, scripts).

    Returns:
        ``task`` (what it acts on, as a run record writes it: ``{"kind": "arm-grid", ...}`` or
        ``{"kind": "arm-reach", ..., "tile_coding": {...}}``; for a tile-coded policy of another
        Gymnasium environment ``{"kind": <its id>}``), ``grid`` (the :meth:`ArmGrid.to_dict` spec
        of a tabular policy, ``{}`` otherwise), ``joints`` (joints it moves, 0 off the arm),
        ``goal_deg`` (the goal of those joints in degrees: the goal bin's centre, see
        :func:`goal_degrees`, or the continuous task's goal angles), ``planning`` (the planner
        it was trained with), ``episodes`` (length of its learning curve), ``experiments`` (how
        many the curve averages), ``created`` and ``notes``. A task following demonstrations
        (``actions="follow"``) gives their number as ``paths``. A movement primitive's task is
        ``{"kind": "dmp", "basis": ..., "robot": ...}`` and its planning ``"none"``.
    """
    facts = learner_of(policy).describe(policy)  # task, grid, joints, goal_deg, planning
    return {
        **facts,  # type: ignore[typeddict-item]
        "episodes": int(len(policy.mean_steps)),
        "experiments": int(policy.experiments),
        "created": policy.created,
        "notes": policy.notes,
    }
