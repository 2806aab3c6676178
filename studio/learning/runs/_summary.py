"""Listing facts about grids and policy files: the one place they are computed.

The web page, the CLI and scripts list policies and demonstrations; what a listing says about a
goal (its angles in degrees, whether it is the grid's default) or about a policy file (its
planner, how many episodes its curve holds) is computed here, next to the formats it reads.
"""

from __future__ import annotations

from typing import TypedDict

import numpy as np

from ..linear._policy import TilePolicyFile
from ..primitives._policy import DmpPolicyFile
from ..tabular._policy import PolicyFile
from ..tasks._arm import ArmGrid
from ._record import task_spec

POLICY_SUFFIX = ".policy.npz"
"""The file suffix of policy files (the format is in :mod:`._policy`)."""
GOAL_DECIMALS = 6
"""Goal angles are reported to a micro-degree: exact enough to compare, short enough to read."""


def goal_degrees(grid: ArmGrid) -> list[float]:
    """The centre of ``grid``'s goal bin, one angle in degrees per joint."""
    return [round(float(x), GOAL_DECIMALS) for x in np.degrees(grid.angles_of(grid.goal_state))]


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


def policy_summary(policy: PolicyFile | TilePolicyFile | DmpPolicyFile) -> PolicySummary:
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
    task: dict[str, object]
    if isinstance(policy, DmpPolicyFile):
        task = {"kind": "dmp", "basis": policy.primitive.basis, "robot": policy.robot}
        grid, joints = {}, len(policy.goal)
        goal = [round(float(x), GOAL_DECIMALS) for x in np.degrees(policy.goal)]
    elif isinstance(policy, TilePolicyFile):
        reach = policy.task
        if reach is None:
            task, joints, goal = {"kind": policy.env_id or "gymnasium"}, 0, []
        else:
            task, joints = task_spec(reach, policy.coder.coding), reach.joints
            if reach.paths:  # a listing names how many demonstrations it follows, not their points
                task["paths"] = len(reach.paths)
            goal = [round(float(x), GOAL_DECIMALS) for x in np.degrees(reach.goal[:joints])]
        grid: dict[str, object] = {}
    else:
        task, grid, joints = task_spec(policy.grid), policy.grid.to_dict(), policy.grid.joints
        goal = goal_degrees(policy.grid)
    return {
        "task": task,
        "grid": grid,
        "joints": joints,
        "goal_deg": goal,
        "planning": "none" if isinstance(policy, DmpPolicyFile) else policy.config.planning,
        "episodes": int(len(policy.mean_steps)),
        "experiments": int(policy.experiments),
        "created": policy.created,
        "notes": policy.notes,
    }
