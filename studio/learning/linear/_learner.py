"""Linear Dyna-Q over tile coding on the continuous arm task as a
:class:`studio.learning._interface.Learner`.

The algorithm is :mod:`._linear` (the kernel, top to bottom); its environments :mod:`._env`,
its policy files :mod:`._policy`. This module only puts them behind the one learner interface.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from dataclasses import fields
from pathlib import Path
from typing import cast

import gymnasium
import numpy as np

from .._config import REACH_DEFAULTS, TASK_ARM_REACH, DynaQConfig
from .._errors import LearningError
from .._interface import Evaluation, Rollout, Start, TrainingRun, listed_degrees
from .._learner import LiveProgress
from .._tiles import TileCoding
from ..likeness._likeness import LikenessCard, likeness_card, robot_tool_positions
from ..tasks._demo_motion import DemonstrationMotion
from ..tasks._gym import ARM_REACH_ID
from ..tasks._reach import ArmReach, _follow_walk, _walk
from ._greedy import _success_many
from ._linear import (
    LinearResult,
    _greedy_episode,
    _run_compiled,
    greedy_rollout,
    greedy_success,
    run_linear_experiments,
)
from ._policy import (
    DEFAULT_MAX_STEPS,
    DEFAULT_SECONDS_PER_STEP,
    FORMAT_NAME,
    TilePolicyFile,
    demonstrated_pace,
    load_tile_policy,
    rollout_tile_policy,
    save_tile_policy,
    tile_rollout,
)

log = logging.getLogger(__name__)

KIND = TASK_ARM_REACH
"""The tile-coded learner's kind: the continuous-joint arm task (a run record's ``task.kind``)."""
WATCH_MAX_STEPS = 1_500
"""Most joint steps of a watched rollout (a minute of motion at 0.04 s per step)."""


FORM_ACTIONS = "single"
"""The action set the page's train form starts the continuous task with: one joint per action.
With the follow action (:data:`REACH_DEFAULTS`' ``"follow"``, the default of ``studio train`` and
the API) a run taught by a demonstration presses the teacher's button from its first own episode:
its curve starts at the teacher's level and stays there, so a person who ticks a sample and
presses Start sees nothing learn (issue 40). With one joint per action the curve falls within the
first episodes with or without a sample (``tests/web/test_form_curve.py``); the follow
action stays the form's other choice, "one joint, or follow the demonstrations"."""
CODING_SETTINGS = ("tilings", "tiles", "size")
"""The continuous task's tile-coding settings (:meth:`ArmReach.features`); its other settings
are :class:`ArmReach` fields."""


def reach_spec(task: ArmReach, coding: TileCoding | None = None) -> dict[str, object]:
    """The continuous task as run records and policy listings write it: ``{"kind":
    "arm-reach", **task.to_dict(), "tile_coding": coding.to_dict()}`` (no ``tile_coding``
    without a coding)."""
    spec: dict[str, object] = {"kind": KIND, **task.to_dict()}
    if coding is not None:
        spec["tile_coding"] = coding.to_dict()
    return spec


class TileLearner:
    """Linear Dyna-Q with tile coding on an :class:`ArmReach`; its policies are
    :class:`TilePolicyFile`."""

    kind = KIND
    title = "tile-coded policy"
    format = FORMAT_NAME
    policy_type = TilePolicyFile
    grid_states = False
    settings_field = "reach"
    form_keys = tuple(REACH_DEFAULTS)
    sweep_keys = (*(f.name for f in fields(ArmReach)), *CODING_SETTINGS)
    shortest_paths = False
    prepare_seconds = 25.0
    trains: type | None = ArmReach
    watch_max_steps: int | None = WATCH_MAX_STEPS

    def train(
        self, run: TrainingRun, live: LiveProgress, workers: int | None = None
    ) -> LinearResult:
        task = _reach(run.task)
        return run_linear_experiments(
            lambda: gymnasium.make(ARM_REACH_ID, arm_reach=task),
            run.config,
            run.experiments,
            run.episodes,
            run.seed,
            [np.asarray(p, dtype=np.float64) for p in run.demonstrations],
            run.tile_coding(),
            workers=workers,
            live=live,
        )

    def kernels(self) -> list[object]:
        return [_run_compiled, _greedy_episode, _success_many, _walk, _follow_walk]

    def warm(self) -> None:
        # every kernel a run uses, without and with a demonstration (replayed, and followed by
        # the follow action), then a rollout and an evaluation from given starts
        plain = ArmReach(joints=3)
        goal = np.asarray(plain.goal[:3])
        demonstration = np.linspace(goal + np.radians([30.0, -30.0, 30.0]), goal, 40)
        plain.demonstration_actions(demonstration)  # walked over the action table
        followed = ArmReach(joints=3, paths=(tuple(map(tuple, demonstration)),))
        for task, demonstrations in ((plain, None), (followed, [demonstration])):
            result = run_linear_experiments(
                lambda task=task: gymnasium.make(ARM_REACH_ID, arm_reach=task),
                DynaQConfig(planning_steps=1),
                1,
                1,
                0,
                demonstrations,
                task.features(),
                workers=1,
            )
            greedy_rollout(task, result.coder, result.weights[0], np.zeros(3), 1)
        greedy_success(followed, result.coder, result.weights[0], np.zeros((1, 3)), 1)

    def save(
        self,
        path: str | Path,
        run: TrainingRun,
        result: object,
        *,
        notes: str = "",
        compress: bool = True,
    ) -> None:
        assert isinstance(result, LinearResult)
        save_tile_policy(
            path,
            result,
            result.best_experiment(),
            notes=notes,
            compress=compress,
            seconds_per_step=run_pace(run, result.task),
        )

    def load(self, path: str | Path) -> TilePolicyFile:
        return load_tile_policy(path)

    def learned_joints(self, policy: object) -> int:
        task = _policy(policy).task
        return 0 if task is None else task.joints

    def pose_start(self, policy: object, q: np.ndarray) -> Start:
        task = _policy(policy).task
        if task is None:
            return Start(q=np.zeros(0))
        return Start(q=np.clip(np.asarray(q, np.float64)[: task.joints], task.lower, task.upper))

    def roll_out(
        self,
        policy: object,
        start: Start,
        rate_hz: float,
        *,
        max_steps: int | None = None,
        seconds_per_step: float | None = None,
    ) -> Rollout:
        policy = _policy(policy)
        task = policy.task
        if start.state is not None:
            raise LearningError(
                "A grid state is no start of a tile-coded policy; give start joint angles."
            )
        if task is not None and start.seed is not None:
            q_start = task.random_start(np.random.default_rng(start.seed))
        elif start.q is not None:
            q_start = np.asarray(start.q, dtype=np.float64)
        else:
            q_start = np.zeros(0 if task is None else task.joints)
        times, q, reached, path = tile_rollout(
            policy,
            q_start,
            rate_hz,
            DEFAULT_MAX_STEPS if max_steps is None else max_steps,
            seconds_per_step=seconds_per_step,  # None: the policy's own pace
        )
        assert task is not None  # (tile_rollout refuses another environment's policy)
        return path_rollout(task, times, q, path, bool(reached), start.seed)

    def summary(self, rollout: Rollout) -> str:
        return f"the greedy policy {'reaches the goal' if rollout.reached else 'does NOT reach the goal'}"

    def evaluate(
        self, policy: object, starts: np.ndarray, *, max_steps: int | None = None
    ) -> Evaluation:
        policy = _policy(policy)
        task = policy.task
        if task is None:
            raise LearningError(self.not_an_arm(policy, "can be evaluated"))
        cap = DEFAULT_MAX_STEPS if max_steps is None else max_steps
        outcomes = [
            greedy_rollout(task, policy.coder, policy.weights, q[: task.joints], cap)
            for q in np.atleast_2d(np.asarray(starts, dtype=np.float64))
        ]
        return Evaluation.of(
            [reached for _, reached in outcomes],
            [len(path) - 1 for path, _ in outcomes],
            policy.seconds_per_step,
        )

    def likeness(
        self, policy: object, demo_times: np.ndarray, demo_q: np.ndarray, rate_hz: float
    ) -> LikenessCard:
        policy = _policy(policy)
        task = policy.task
        if task is None:
            raise LearningError(self.not_an_arm(policy, "have a likeness card"))
        start = np.asarray(demo_q, dtype=np.float64)[0]
        times, q, _ = rollout_tile_policy(policy, start[: task.joints], rate_hz)

        def tool(q: np.ndarray) -> np.ndarray:
            return robot_tool_positions(task.robot, q)

        return likeness_card(times, q, demo_times, demo_q, tool, joints=task.joints)

    def own_demonstration(self, policy: object) -> DemonstrationMotion | None:
        return None

    def beside(
        self, policy: object, demonstrations: Sequence[Sequence[Sequence[float]]]
    ) -> np.ndarray | None:
        task = _policy(policy).task
        if task is None or not demonstrations:
            return None
        first = np.asarray(demonstrations[0], dtype=np.float64)
        path = np.tile(np.asarray(task.goal), (len(first), 1))  # the others at the goal's
        path[:, : task.joints] = first[:, : task.joints]
        return path

    def not_an_arm(self, policy: object, what: str) -> str | None:
        policy = _policy(policy)
        if policy.task is not None:
            return None
        return f"This policy was trained on {policy.env_id or 'another environment'}, not the arm; only arm policies {what}."

    def describe(self, policy: object) -> dict[str, object]:
        policy = _policy(policy)
        reach = policy.task
        if reach is None:
            task: dict[str, object] = {"kind": policy.env_id or "gymnasium"}
            joints, goal = 0, []
        else:
            task, joints = reach_spec(reach, policy.coder.coding), reach.joints
            if reach.paths:  # a listing names how many demonstrations it follows, not their points
                task["paths"] = len(reach.paths)
            goal = listed_degrees(reach.goal[:joints])
        return {
            "task": task,
            "grid": {},
            "joints": joints,
            "goal_deg": goal,
            "planning": policy.config.planning,
        }

    def task_spec(self, task: object, coding: TileCoding | None = None) -> dict[str, object]:
        return reach_spec(_reach(task), coding)

    def task_from_spec(self, spec: dict[str, object]) -> tuple[ArmReach, TileCoding]:
        settings = {k: v for k, v in spec.items() if k != "tile_coding"}
        return ArmReach.from_dict(settings), TileCoding.from_dict(spec["tile_coding"])

    def task_form(self, task: object, coding: TileCoding | None) -> dict[str, object]:
        task = _reach(task)
        coding = coding if coding is not None else task.features()
        return {
            "joints": task.joints,
            "step_deg": task.step_deg,
            "actions": task.actions,
            "tilings": coding.tilings,
            "tiles": coding.tiles,
        }

    def demonstrations_of(self, paths: list[object]) -> list[object]:
        return [[[float(x) for x in row] for row in cast(list, p)] for p in paths]

    def mean_shortest_steps(self, task: object) -> float | None:
        return None


def path_rollout(
    task: ArmReach,
    times: np.ndarray,
    q: np.ndarray,
    path: np.ndarray,
    reached: bool,
    seed: int | None,
) -> Rollout:
    """The :class:`Rollout` of a joint path ``(K + 1, joints)`` on the continuous ``task``,
    sampled as ``times`` and ``q`` (:func:`path_trajectory`)."""
    return Rollout(
        times=times,
        q=q,
        reached=reached,
        steps=len(path) - 1,
        states=(),
        seed=seed,
        goal=np.asarray(task.goal, dtype=np.float64),
        robot=task.robot,
    )


def run_pace(run: TrainingRun, task: ArmReach | None) -> float:
    """The pace of a policy ``run`` makes on ``task``: its recorded demonstrations'
    (:func:`demonstrated_pace`), else the default; a demonstration the task cannot time costs the
    pace, never the policy."""
    motions = [(m.times, m.q_robot) for m in run.demonstration_motions]
    try:
        return demonstrated_pace(task, motions)  # type: ignore[arg-type]
    except LearningError as err:
        log.warning("a run's policy keeps the default pace: %s", err)
        return DEFAULT_SECONDS_PER_STEP


def _policy(policy: object) -> TilePolicyFile:
    if not isinstance(policy, TilePolicyFile):
        raise LearningError(
            f"This is a {type(policy).__name__}, not a tile-coded policy; give a policy of its own kind."
        )
    return policy


def _reach(task: object) -> ArmReach:
    if not isinstance(task, ArmReach):
        raise LearningError(
            f"This run's task is a {type(task).__name__}, not the continuous arm task; train it with its own learner."
        )
    return task
