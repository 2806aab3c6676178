"""Gymnasium environments of the studio's two arm tasks, registered on ``import studio.learning``
(by :mod:`._gym_ids`, which names them).

- ``TeachStudio/ArmGrid-v0`` (:class:`ArmGridEnv`): the paper's tabular task, a Discrete
  observation (the grid state number) and Discrete actions; its dynamics are the table of
  :meth:`ArmGrid.mdp`, the one the tabular learner steps.
- ``TeachStudio/ArmReach-v0`` (:class:`ArmReachEnv`): joints 1..J as a Box observation (radians)
  and Discrete actions (2J moving one joint each, or more with ``actions``); its ``step`` calls :func:`._reach.reach_step`, the same compiled
  function the linear learner's kernel calls.

Both honour ``reset(seed=...)`` (every random draw comes from the environment's ``np_random``),
render nothing (no render modes), and pass ``gymnasium.utils.env_checker.check_env``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, TypedDict, Unpack

import gymnasium
import numpy as np
from gymnasium import spaces
from numpy.typing import NDArray

from .._errors import LearningError
from ._arm import ArmGrid
from ._gym_ids import ARM_GRID_ID as ARM_GRID_ID
from ._gym_ids import ARM_REACH_ID as ARM_REACH_ID
from ._reach import ArmReach, reach_step


class _GridSettings(TypedDict, total=False):
    """The keyword arguments of :class:`ArmGrid` (each checked there)."""

    joints: int
    bins: int
    low_deg: float | tuple[float, ...] | None
    high_deg: float | tuple[float, ...] | None
    goal: tuple[int, ...] | None
    robot: str


class _ReachSettings(TypedDict, total=False):
    """The keyword arguments of :class:`ArmReach` (each checked there)."""

    joints: int
    step_deg: float
    goal: tuple[float, ...] | None
    position_tolerance: float
    angle_tolerance_deg: float
    shaping: float
    actions: str
    robot: str
    paths: tuple[tuple[tuple[float, ...], ...], ...]


class ArmGridEnv(gymnasium.Env):
    """The paper's arm grid as a Gymnasium environment.

    Args:
        joints, bins, low_deg, high_deg, goal, robot: as :class:`ArmGrid`.
    """

    metadata = {"render_modes": []}

    def __init__(self, render_mode: str | None = None, **grid: Unpack[_GridSettings]) -> None:
        if render_mode is not None:
            raise LearningError(
                f"render_mode is {render_mode!r}; this environment renders nothing, give None."
            )
        self.grid = ArmGrid(**grid)
        self._mdp = self.grid.mdp()
        self.observation_space = spaces.Discrete(self.grid.n_states)
        self.action_space = spaces.Discrete(self.grid.n_actions)
        self.render_mode = None
        self.state = int(self._mdp.start_states[0])

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[int, dict[str, object]]:
        """Start uniformly from every state but the goal (``options={"state": s}`` to choose)."""
        super().reset(seed=seed)
        if options and "state" in options:
            self.grid._check_state(options["state"])
            self.state = int(options["state"])
        else:
            starts = self._mdp.start_states
            self.state = int(starts[self.np_random.integers(starts.shape[0])])
        return self.state, {}

    def step(self, action: int) -> tuple[int, float, bool, bool, dict[str, object]]:
        """Move by ``action``; reward and termination from the grid's table."""
        a = int(action)
        reward = float(self._mdp.reward[self.state, a])
        self.state = int(self._mdp.next_state[self.state, a])
        return self.state, reward, bool(self._mdp.terminal[self.state]), False, {}


class ArmReachEnv(gymnasium.Env):
    """The continuous arm task as a Gymnasium environment.

    Args:
        joints: joints learned, from joint 1 (3 to 6, at most the robot's).
        step_deg: joint increment per action, degrees.
        goal: goal joint angles, radians (``joints`` or 6 values).
        position_tolerance: metres.
        angle_tolerance_deg: degrees.
        shaping: weight of the potential-based shaping reward.
        actions: what one action moves: ``"single"`` (one joint), ``"pairs"`` (also two
            together), ``"all"`` (any joints at once), ``"all-follow"`` (any joints, or all of them
            along the demonstrations) or ``"follow"`` (one joint, or all of them
            along the demonstrated ``paths``; :meth:`follow`).
        paths: the demonstrated joint paths ``"follow"`` follows (:class:`ArmReach`).
        robot: the robot's registry name (``studio robots``; default ``"puma560"``): its first
            ``joints`` joints, limits and forward kinematics.
        arm_reach: the task itself, instead of its settings (a run passes its record's task as
            is: ``gymnasium.make(ARM_REACH_ID, arm_reach=task)``).
    """

    metadata = {"render_modes": []}

    def __init__(
        self,
        render_mode: str | None = None,
        arm_reach: ArmReach | None = None,
        **task: Unpack[_ReachSettings],
    ) -> None:
        if render_mode is not None:
            raise LearningError(
                f"render_mode is {render_mode!r}; this environment renders nothing, give None."
            )
        if arm_reach is not None and task:
            raise LearningError(
                f"Both arm_reach and {', '.join(task)} are given; give the task or its settings."
            )
        self.task = arm_reach if arm_reach is not None else ArmReach(**task)
        self._params = self.task.params
        self.observation_space = spaces.Box(*self.task.observation_bounds, dtype=np.float64)
        self.action_space = spaces.Discrete(self.task.n_actions)
        self.render_mode = None
        self.q = np.ascontiguousarray(self.task.lower + self.task.upper) * 0.5

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[NDArray[np.float64], dict[str, object]]:
        """Start uniformly across the limits, not at the goal (``options={"q": q}`` to choose)."""
        super().reset(seed=seed)
        if options and "q" in options:
            q = np.asarray(options["q"], dtype=np.float64).reshape(-1)
            if (
                q.shape != (self.task.joints,)
                or np.any(q < self.task.lower)
                or np.any(q > self.task.upper)
            ):
                raise LearningError(
                    f"options['q'] is {q.tolist()}; give {self.task.joints} joint angles in radians inside the limits."
                )
            self.q = np.ascontiguousarray(q.copy())
        else:
            self.q = np.ascontiguousarray(self.task.random_start(self.np_random))
        return self.task.observe(self.q), {}

    def follow(self, q_paths: Sequence[np.ndarray]) -> None:
        """Follow the demonstrated joint paths ``q_paths`` when the task's actions are
        ``"follow"`` and it has none yet (:meth:`ArmReach.with_paths`): the action space gains
        the follow action, and the observation the follow cost (:meth:`ArmReach.observe`).
        :func:`run_experiments` calls it with its demonstrations."""
        self.task = self.task.with_paths(q_paths)
        self._params = self.task.params
        self.observation_space = spaces.Box(*self.task.observation_bounds, dtype=np.float64)
        self.action_space = spaces.Discrete(self.task.n_actions)

    def step(self, action: int) -> tuple[NDArray[np.float64], float, bool, bool, dict[str, object]]:
        """Move the action's joints by one step each; ``terminated`` at the goal."""
        reward, terminated = reach_step(self._params, self.q, int(action))
        return self.task.observe(self.q), float(reward), bool(terminated), False, {}
