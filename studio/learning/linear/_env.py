"""The linear learner's environments: making and checking them, their compiled twins, the
episodes' starts and the demonstrations they replay.

For our arm task (``TeachStudio/ArmReach-v0``) and Gymnasium's ``MountainCar-v0`` an experiment
runs in one compiled kernel that steps a numba twin of the environment's dynamics
(:func:`task_step`: the arm's are defined once in :mod:`._reach`; Mountain Car's twin,
:func:`mountain_car_step`, is tested equal to Gymnasium's ``step``). :func:`inspect_env` finds a
twin when an environment is one of these, unwrapped but for wrappers that change nothing
(:data:`_PASS_THROUGH_WRAPPERS`); any other environment runs as a Python loop. Start states come
from ``env.reset`` in both paths (:func:`reset_states`, seeded per experiment by
:func:`reset_seed`), so both give the same result bit for bit.

The twins compile in the arm's dynamics (:mod:`..tasks._reach` and what it calls); numba's disk
cache is keyed on this file alone, so after editing those, touch this file too.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from ..._kernels import frozen
from .._config import DynaQConfig
from .._errors import LearningError
from ..tasks._follow import follow_cost
from ..tasks._reach import ArmReach, reach_step

if TYPE_CHECKING:
    import gymnasium

TASK_REACH = 0
"""The compiled twin of ``TeachStudio/ArmReach-v0`` (:func:`._reach.reach_step`)."""
TASK_MOUNTAIN_CAR = 1
"""The compiled twin of Gymnasium's ``MountainCar-v0`` (:func:`mountain_car_step`)."""
# Mountain Car's parameter layout (gymnasium's attribute names)
_MOUNTAIN_CAR_PARAMS = (
    "force",
    "gravity",
    "max_speed",
    "min_position",
    "max_position",
    "goal_position",
    "goal_velocity",
)


@njit(nogil=True, cache=True)
def mountain_car_step(params, state, action):
    """Gymnasium's ``MountainCarEnv.step`` on ``state = [position, velocity]`` (in place).

    Returns ``(reward, terminated)``. The same float64 operations in the same order as Gymnasium
    1.x, so the result is equal bit for bit (a test steps both side by side).
    """
    force, gravity, max_speed = params[0], params[1], params[2]
    min_position, max_position = params[3], params[4]
    position = state[0]
    velocity = state[1]
    velocity += (action - 1) * force + math.cos(3 * position) * (-gravity)
    velocity = min(max(velocity, -max_speed), max_speed)
    position += velocity
    position = min(max(position, min_position), max_position)
    if position == min_position and velocity < 0:
        velocity = 0.0
    state[0] = position
    state[1] = velocity
    return -1.0, position >= params[5] and velocity >= params[6]


@njit(nogil=True, cache=True, inline="always")
def task_step(task, params, state, action):
    """Step the compiled twin of task ``task`` (in place); returns ``(reward, terminated)``."""
    if task == TASK_REACH:
        return reach_step(params, state, action)
    return mountain_car_step(params, state, action)


@njit(nogil=True, cache=True, inline="always")
def observe(task, params, state, obs):
    """The observation the learner sees: the state (Mountain Car rounds it to float32); an arm
    task that follows paths also observes the follow cost (:meth:`._reach.ArmReach.observe`)."""
    if task == TASK_MOUNTAIN_CAR:
        for d in range(state.shape[0]):
            obs[d] = np.float64(np.float32(state[d]))
    else:
        for d in range(state.shape[0]):
            obs[d] = state[d]
        if obs.shape[0] > state.shape[0]:
            obs[state.shape[0]] = follow_cost(params, state)[1]


# --------------------------------------------------------------------------- set-up


@dataclass(frozen=True)
class EnvTask:
    """What a run knows about its environment after inspecting it."""

    code: int | None  # compiled task code, or None for the Python loop
    params: np.ndarray
    low: np.ndarray
    high: np.ndarray
    n_actions: int
    max_steps: int
    reach: ArmReach | None
    env_id: str | None
    follows: bool = False
    """The arm task, under whatever wrappers, following demonstrated paths (its learner adds a
    value common to every action, :mod:`._common_value`)."""

    @property
    def state_dims(self) -> int:
        """The compiled twin's state size: the arm task's joints (its observation may add the
        follow cost), else the observation's."""
        return self.reach.joints if self.reach is not None else int(self.low.shape[0])


_PASS_THROUGH_WRAPPERS = ("TimeLimit", "OrderEnforcing", "PassiveEnvChecker")
"""Gymnasium wrappers that change neither observations, actions nor rewards."""


def make_env(env: str | Callable[[], gymnasium.Env], index: int) -> gymnasium.Env:
    """A fresh environment from an id or a zero-argument callable."""
    import gymnasium

    try:
        made = gymnasium.make(env) if isinstance(env, str) else env()
    except gymnasium.error.Error as err:
        raise LearningError(
            f"Gymnasium cannot make {env!r} ({err}); give a registered environment id."
        ) from None
    if not isinstance(made, gymnasium.Env):
        raise LearningError(
            f"The environment factory returned a {type(made).__name__}; return a gymnasium.Env."
        )
    return made


def inspect_env(env: gymnasium.Env, config: DynaQConfig) -> EnvTask:
    """Check the spaces and find a compiled twin of the dynamics, if there is one."""
    from gymnasium import spaces
    from gymnasium.envs.classic_control.mountain_car import MountainCarEnv

    from ..tasks._gym import ArmReachEnv

    name = getattr(getattr(env, "spec", None), "id", None) or type(env.unwrapped).__name__
    if not isinstance(env.action_space, spaces.Discrete):
        raise LearningError(
            f"{name} has a {type(env.action_space).__name__} action space; this learner needs Discrete actions (discretise the actions, for example with a wrapper)."
        )
    if not isinstance(env.observation_space, spaces.Box) or len(env.observation_space.shape) != 1:
        raise LearningError(
            f"{name} has a {env.observation_space} observation space; tile coding needs a one-dimensional Box."
        )
    if int(env.action_space.start) != 0:
        raise LearningError(
            f"{name}'s actions start at {int(env.action_space.start)}; give a Discrete space starting at 0."
        )
    max_steps = int(config.max_steps_per_episode)
    plain = True
    layer = env
    while hasattr(layer, "env"):
        if type(layer).__name__ not in _PASS_THROUGH_WRAPPERS:
            plain = False
        if type(layer).__name__ == "TimeLimit":
            max_steps = min(max_steps, int(layer._max_episode_steps))
        layer = layer.env
    raw = env.unwrapped
    space = env.observation_space
    code: int | None = None
    params = frozen(np.zeros(0))
    reach = None
    if plain and type(raw) is ArmReachEnv:
        code, reach = TASK_REACH, raw.task
        params = reach.params
    elif plain and type(raw) is MountainCarEnv:
        code = TASK_MOUNTAIN_CAR
        params = frozen([float(getattr(raw, p)) for p in _MOUNTAIN_CAR_PARAMS])
    spec_id = getattr(getattr(env, "spec", None), "id", None)
    return EnvTask(
        code,
        params,
        np.asarray(space.low, np.float64),
        np.asarray(space.high, np.float64),
        int(env.action_space.n),
        max_steps,
        reach,
        spec_id,
        type(raw) is ArmReachEnv and bool(raw.task.paths),
    )


def follow_demonstrations(
    envs: Sequence[gymnasium.Env], demonstrations: Sequence[Sequence[int] | np.ndarray]
) -> None:
    """Give every arm task whose actions follow the demonstrations (``actions="follow"``, no
    paths yet) the joint-path demonstrations to follow (:meth:`._gym.ArmReachEnv.follow`)."""
    from ..tasks._gym import ArmReachEnv

    paths = [p for p in map(np.asarray, demonstrations) if p.ndim == 2]  # as env_demonstrations
    for env in envs:
        if paths and type(env.unwrapped) is ArmReachEnv:
            env.unwrapped.follow(paths)
            env.action_space = env.unwrapped.action_space  # the wrappers read them at creation
            env.observation_space = env.unwrapped.observation_space


def followed_task(
    envs: Sequence[gymnasium.Env],
    config: DynaQConfig,
    demonstrations: Sequence[Sequence[int] | np.ndarray],
) -> EnvTask:
    """The run's task: the demonstrations as given are checked first (one sentence naming the
    one at fault), then an arm task that follows demonstrations takes them as its paths
    (:func:`follow_demonstrations`)."""
    env_demonstrations(demonstrations, inspect_env(envs[0], config))
    follow_demonstrations(envs, demonstrations)
    return inspect_env(envs[0], config)


def _internal_state(env: gymnasium.Env, task: EnvTask, obs: np.ndarray) -> np.ndarray:
    """The state a compiled twin steps from, right after ``env.reset``."""
    raw = env.unwrapped
    if task.code == TASK_MOUNTAIN_CAR:
        return np.asarray(raw.state, dtype=np.float64).copy()
    if task.code == TASK_REACH:
        return np.asarray(raw.q, dtype=np.float64).copy()
    return np.asarray(obs, dtype=np.float64)


def reset_seed(seed: int, experiment: int) -> int:
    """The seed of an experiment's first ``env.reset`` (later resets continue its generator)."""
    return int(np.random.SeedSequence([seed, experiment, 1]).generate_state(1, np.uint32)[0])


def reset_states(env: gymnasium.Env, task: EnvTask, seed: int, e: int, episodes: int) -> np.ndarray:
    """Every episode's start state, from the environment's own ``reset`` (seeded once)."""
    states = []
    for k in range(episodes):
        obs, _ = env.reset(seed=reset_seed(seed, e) if k == 0 else None)
        states.append(_internal_state(env, task, obs))
    return np.ascontiguousarray(np.array(states, dtype=np.float64))


def env_demonstrations(
    demonstrations: Sequence[Sequence[int] | np.ndarray], task: EnvTask
) -> tuple[list[np.ndarray | None], list[np.ndarray]]:
    """Per demonstration: its start state (None: from ``env.reset``) and its actions."""
    starts: list[np.ndarray | None] = []
    actions: list[np.ndarray] = []
    for i, demo in enumerate(demonstrations):
        arr = np.asarray(demo)
        if arr.ndim == 2 and task.reach is not None:
            start, acts = task.reach.demonstration_actions(arr, i)
            starts.append(start)
            actions.append(acts)
            continue
        if arr.ndim != 1 or arr.size == 0 or not np.issubdtype(arr.dtype, np.integer):
            what = "a joint path (N, joints) in radians or " if task.reach is not None else ""
            raise LearningError(
                f"Demonstration {i} has shape {arr.shape} and type {arr.dtype}; give {what}a non-empty sequence of action numbers."
            )
        if arr.min() < 0 or arr.max() >= task.n_actions:
            raise LearningError(
                f"Demonstration {i} holds action {int(arr.max() if arr.max() >= task.n_actions else arr.min())}, outside [0, {task.n_actions - 1}]; give actions of this environment."
            )
        starts.append(None)
        actions.append(arr.astype(np.int64))
    return starts, actions
