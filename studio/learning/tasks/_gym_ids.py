"""The Gymnasium ids of the two arm tasks, their episode caps, and their registration.

Kept apart from the environments (:mod:`._gym`) so that ``import studio.learning`` registers them
at the cost of Gymnasium alone: the environments, and with them numba and the robot models, load
when one is made (``gymnasium.make(ARM_REACH_ID)``).
"""

from __future__ import annotations

import gymnasium

ARM_GRID_ID = "TeachStudio/ArmGrid-v0"
ARM_REACH_ID = "TeachStudio/ArmReach-v0"
ARM_GRID_MAX_EPISODE_STEPS = 10_000
"""Episode cap of the registered grid environment (the paper's first episodes take ~2500)."""
DEFAULT_MAX_EPISODE_STEPS = 3_000
"""Episode cap of the registered reach environment (about three times the longest greedy path)."""
ENVIRONMENTS = "studio.learning.tasks._gym"
"""The module that defines the environments' classes."""


def register() -> None:
    """Register both environments with Gymnasium (idempotent)."""
    registry = gymnasium.envs.registration.registry
    if ARM_GRID_ID not in registry:
        gymnasium.register(
            ARM_GRID_ID,
            entry_point=f"{ENVIRONMENTS}:ArmGridEnv",
            max_episode_steps=ARM_GRID_MAX_EPISODE_STEPS,
        )
    if ARM_REACH_ID not in registry:
        gymnasium.register(
            ARM_REACH_ID,
            entry_point=f"{ENVIRONMENTS}:ArmReachEnv",
            max_episode_steps=DEFAULT_MAX_EPISODE_STEPS,
        )
