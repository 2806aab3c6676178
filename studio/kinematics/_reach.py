"""Whether a robot's tool has reached a target, and whether any pose of the robot could.

The retargeting's goal is the tool within ``RetargetConfig.reach_tolerance`` (1 cm) and
``RetargetConfig.reach_angle`` (5 deg) of the hand's target wherever the target is reachable.
This module is the one definition of both halves, used by the retargeting's tests and
benchmarks:

- :func:`tool_reaches`: the tool at ``q`` is within those tolerances of the target (the angle is
  not asked of an arm that follows the position only).
- :func:`reachable`: some pose of the arm reaches the target: within its joint limits, its links
  at least ``RetargetConfig.clearance`` apart, and, given ``near``, no joint further than
  ``RetargetConfig.max_joint_step`` from ``near`` (the target can be reached in the one frame the
  step cap allows from there), or given ``within_steps_of``, within the joint motion so many
  frames allow of each of those poses (the target can be reached on the way from one to the
  other). It is a search: the IK, run to convergence from ``near`` (or
  home) and from :data:`REACHABLE_STARTS` (:data:`NEAR_STARTS` given ``near``) starts drawn at
  random (seeded) within those bounds;
  "not reachable" means none of those starts found a pose.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence

import numpy as np

from ._puma import Puma560
from ._retarget import RetargetConfig
from ._robots import RobotArm, tool_errors

REACHABLE_STARTS = 24
"""Random starts of :func:`reachable`'s search over the joint ranges, besides home."""

NEAR_STARTS = 8
"""Random starts of :func:`reachable`'s search within one frame's joint motion of ``near``,
besides ``near`` itself (a small box: fewer starts cover it)."""

REACHABLE_ITERATIONS = 200
"""IK iterations from each start of :func:`reachable`'s search (enough to converge)."""


def reach_errors(
    robot: RobotArm | Puma560, q: np.ndarray, oMdes: np.ndarray
) -> tuple[float, float]:
    """How far (m) and how turned (rad) the tool at ``q`` is from ``oMdes`` (4x4); the angle is
    0 for an arm that follows the position only."""
    orientation = not isinstance(robot, RobotArm) or robot.spec.orientation
    return tool_errors(robot.forward(q), oMdes, orientation)


def tool_reaches(
    robot: RobotArm | Puma560,
    q: np.ndarray,
    oMdes: np.ndarray,
    config: RetargetConfig | None = None,
) -> bool:
    """Whether the tool at ``q`` has reached ``oMdes`` (:meth:`RetargetConfig.within_reach`)."""
    return (config or RetargetConfig()).within_reach(*reach_errors(robot, q, oMdes))


def reachable(
    arm: RobotArm,
    oMdes: np.ndarray,
    config: RetargetConfig | None = None,
    near: np.ndarray | None = None,
    *,
    within_steps_of: Sequence[tuple[np.ndarray, int]] = (),
) -> bool:
    """Whether some pose of ``arm`` reaches ``oMdes`` (see the module docstring).

    Args:
        arm: the robot (the Puma560 too, as ``load_robot("puma560")``).
        oMdes: the tool's target (4x4, the arm's base frame).
        config: the tolerances, the clearance and the step cap.
        near: a pose: only poses within one frame's joint motion of it count.
        within_steps_of: ``(pose, frames)`` pairs: only poses within ``frames`` frames' joint
            motion of every such pose count (a target reachable on the way from one pose to
            another, ``frames`` after the first and before the second).
    """
    config = config or RetargetConfig()
    bounds = [*within_steps_of, *([] if near is None else [(near, 1)])]
    lower, upper = steps_box(arm, config, bounds)
    if np.any(lower > upper):
        return False
    rng = np.random.default_rng(0)
    first = arm.home if near is None else near
    starts = REACHABLE_STARTS if near is None else NEAR_STARTS
    found = pose_within(
        arm, oMdes, config, (lower, upper), (first, *rng.uniform(lower, upper, (starts, arm.nq)))
    )
    return found is not None


def steps_box(
    arm: RobotArm, config: RetargetConfig, poses: Sequence[tuple[np.ndarray, int]]
) -> tuple[np.ndarray, np.ndarray]:
    """The joint box ``(lower, upper)`` within the limits and within ``frames`` frames' joint
    motion (``config.max_joint_step`` each) of every ``(pose, frames)``; empty (some lower above
    its upper) where they do not meet."""
    lower, upper = arm.lower, arm.upper
    for pose, frames in poses:
        reach = config.max_joint_step * frames
        lower, upper = np.maximum(lower, pose - reach), np.minimum(upper, pose + reach)
    return lower, upper


def pose_within(
    arm: RobotArm,
    oMdes: np.ndarray,
    config: RetargetConfig,
    box: tuple[np.ndarray, np.ndarray],
    starts: Iterable[np.ndarray],
    iterations: int = REACHABLE_ITERATIONS,
    accept: Callable[[np.ndarray], bool] | None = None,
) -> np.ndarray | None:
    """The first pose within ``box`` (``(lower, upper)``) that the IK finds from one of
    ``starts`` (each clipped into it), that reaches ``oMdes`` clear of contact (its own links
    and the table: :meth:`RobotArm.contacts`) and that ``accept`` (if given) takes; None if
    none does."""
    lower, upper = box
    for start in starts:
        q = arm.inverse(
            oMdes, np.clip(start, lower, upper), iterations=iterations, lower=lower, upper=upper
        ).q
        if not tool_reaches(arm, q, oMdes, config) or arm.contacts(q, config.clearance):
            continue
        if accept is None or accept(q):
            return q
    return None
