"""The likeness card of any policy kind, rolled out from a demonstration's own start.

Each learner knows how its kind rolls out from given joint angles (a grid policy from the bin
they fall in, a tile-coded policy from the learned joints, a movement primitive from all six:
:meth:`Learner.likeness`); this checks the demonstration once for all, so the page, ``studio
export`` and run files score every policy the same way.
"""

from __future__ import annotations

import numpy as np

from .._errors import LearningError
from .._registry import AnyPolicy, learner_of
from ..tabular._policy import ROLLOUT_RATE_HZ
from ..tasks._robot import PUMA560, robot_title, task_arm
from ._likeness import LikenessCard


def policy_likeness_card(
    policy: AnyPolicy,
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
    return learner_of(policy).likeness(policy, demo_times, q_demo, rate_hz)
