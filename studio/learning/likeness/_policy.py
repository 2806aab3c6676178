"""The likeness card of any policy kind, rolled out from a demonstration's own start.

One place that knows how each kind rolls out from given joint angles (a grid policy from the bin
they fall in, a tile-coded policy from the learned joints, a movement primitive from all six), so
the page, ``studio export`` and run files score every policy the same way.
"""

from __future__ import annotations

import numpy as np

from .._errors import LearningError
from ..linear._policy import TilePolicyFile, rollout_tile_policy
from ..primitives._policy import DmpPolicyFile, rollout_dmp_policy
from ..tabular._policy import ROLLOUT_RATE_HZ, PolicyFile, rollout
from ..tasks._robot import PUMA560, robot_title, task_arm
from ._likeness import LikenessCard, likeness_card, robot_tool_positions


def policy_likeness_card(
    policy: PolicyFile | TilePolicyFile | DmpPolicyFile,
    demo_times: np.ndarray,
    demo_q: np.ndarray,
    rate_hz: float = ROLLOUT_RATE_HZ,
) -> LikenessCard:
    """Roll ``policy`` out from the demonstration's first sample and compare the two.

    The card compares the joints the policy learns (a grid's or a task's joints; a movement
    primitive's ``learned_joints``); the other joints are held where the rollout keeps them (a
    grid policy: at the demonstration's start; a tile-coded policy: at the task's goal).

    Args:
        policy: a policy of any kind (:func:`load_any_policy`).
        demo_times: the demonstration's sample times ``(N,)`` (s).
        demo_q: its joints on the policy's robot ``(N, nq)`` (rad), for example a
            demonstration's ``q_robot`` (the Puma560's six).
        rate_hz: the rollout's sample rate.

    Raises:
        LearningError: a demonstration that is not ``(N, nq)`` finite angles, a start outside
            the task's joint limits, or a tile-coded policy of another environment.
    """
    q_demo = np.asarray(demo_q, dtype=np.float64)
    robot = policy.robot or PUMA560
    width = task_arm(robot).nq
    if q_demo.ndim != 2 or q_demo.shape[1] != width or q_demo.shape[0] < 1:
        raise LearningError(
            f"The demonstration's joints have shape {q_demo.shape}; give (N, {width}) {robot_title(robot)} angles in radians."
        )
    if not np.all(np.isfinite(q_demo)):
        raise LearningError("The demonstration holds NaN angles; re-record it.")
    start = q_demo[0]
    if isinstance(policy, DmpPolicyFile):
        times, q, _ = rollout_dmp_policy(policy, start, rate_hz)
        joints = policy.learned_joints
    elif isinstance(policy, TilePolicyFile):
        if policy.task is None:
            raise LearningError(
                f"This policy was trained on {policy.env_id or 'another environment'}, not the arm; only arm policies have a likeness card."
            )
        joints = policy.task.joints
        times, q, _ = rollout_tile_policy(policy, start[:joints], rate_hz)
    else:
        grid = policy.grid
        joints = grid.joints
        times, q = rollout(policy, grid.state_of_angles(start[:joints]), rate_hz, hold=start)

    def tool(q: np.ndarray) -> np.ndarray:
        return robot_tool_positions(robot, q)

    return likeness_card(times, q, demo_times, q_demo, tool, joints=joints)
