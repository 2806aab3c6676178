"""The baselines as :class:`studio.learning._interface.Learner`: the teacher and behaviour cloning.

Both act on the continuous arm task (:class:`ArmReach`) a run describes, beside linear Dyna-Q
(:mod:`..linear`): a run picks one with ``learner`` (``studio train --learner teacher``), and
listings, Watch, ``studio evaluate``, exports and Compare runs then treat its policy like any
other. "Training" one fits it to the run's demonstrations, then rolls it out from each episode's
random start (no learning: its curve is flat), so its curve stands beside Dyna-Q's on the same
axes; an episode that does not reach the goal counts the episode cap.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .._config import CLONING_KIND as CLONING_KIND
from .._config import TEACHER_KIND as TEACHER_KIND
from .._errors import LearningError
from .._interface import Evaluation, Rollout, Start, TrainingRun, listed_degrees
from .._learner import ExperimentResult, LiveProgress, result_so_far
from .._tiles import TileCoding
from ..likeness._likeness import LikenessCard, likeness_card, robot_tool_positions
from ..linear._learner import (
    WATCH_MAX_STEPS,
    TileLearner,
    path_rollout,
    reach_spec,
    run_pace,
)
from ..linear._policy import DEFAULT_MAX_STEPS, path_trajectory
from ..tasks._demo_motion import DemonstrationMotion
from ..tasks._gym_ids import DEFAULT_MAX_EPISODE_STEPS
from ..tasks._reach import ArmReach
from ._cloning import clone_walk, fit_cloning
from ._policy import (
    CLONING_FORMAT,
    TEACHER_FORMAT,
    BaselinePolicyFile,
    CloningPolicyFile,
    TeacherPolicyFile,
    load_baseline_policy,
    save_baseline_policy,
)


@dataclass(frozen=True, eq=False)
class BaselineResult(ExperimentResult):
    """What a baseline's :meth:`train` returns: the run's curve and the fitted policy."""

    policy: BaselinePolicyFile | None = None


class _BaselineLearner:
    """What the teacher and behaviour cloning share (all but fitting and the file format)."""

    kind = ""
    title = ""
    format = ""
    policy_type: type = BaselinePolicyFile
    trains: type | None = ArmReach
    grid_states = False
    settings_field = TileLearner.settings_field
    form_keys = TileLearner.form_keys
    sweep_keys = TileLearner.sweep_keys
    shortest_paths = False
    prepare_seconds = 0.0
    watch_max_steps: int | None = WATCH_MAX_STEPS

    def fit(self, task: ArmReach, paths: list[np.ndarray], pace: float) -> BaselinePolicyFile:
        """The policy of the run's task and demonstrations, at ``pace`` seconds a step."""
        raise NotImplementedError

    def train(
        self, run: TrainingRun, live: LiveProgress, workers: int | None = None
    ) -> BaselineResult:
        task = _reach(run.task)
        paths = [np.asarray(p, dtype=np.float64) for p in run.demonstrations]
        if not paths:
            raise LearningError(
                f"The {self.title} learns from demonstrations; give the run at least one."
            )
        follow = dataclasses.replace(task, actions="follow", paths=()).with_paths(paths)
        policy = self.fit(task, paths, run_pace(run, follow))
        cap = min(run.config.max_steps_per_episode, DEFAULT_MAX_EPISODE_STEPS)
        cpu = np.zeros(run.experiments)

        def so_far() -> BaselineResult:
            return result_so_far(
                BaselineResult, live, cpu, np.zeros((run.experiments, 0, 0)), run.config,
                run.seed, policy=policy,
            )  # fmt: skip

        live.snapshot = so_far
        for e in range(run.experiments):
            with live.counting_cpu() as spent:
                rng = np.random.default_rng([run.seed, e])
                for k in range(run.episodes):
                    if live.stopped:
                        break
                    path, reached = policy.walk(task.random_start(rng), cap)
                    live.updates[e, k] = 0
                    live.steps[e, k] = len(path) - 1 if reached else cap
            cpu[e] = spent[0]
        return so_far()

    def kernels(self) -> list[object]:
        return []

    def warm(self) -> None:
        return None

    def save(
        self,
        path: str | Path,
        run: TrainingRun,
        result: object,
        *,
        notes: str = "",
        compress: bool = True,
    ) -> None:
        if not isinstance(result, BaselineResult) or result.policy is None:
            raise LearningError(f"This is no result of the {self.title}; train the run again.")
        policy = dataclasses.replace(
            result.policy, mean_steps=result.mean_steps(), experiments=run.experiments
        )
        save_baseline_policy(path, policy, notes=notes, compress=compress)

    def load(self, path: str | Path) -> BaselinePolicyFile:
        return load_baseline_policy(path, self.format)

    def learned_joints(self, policy: object) -> int:
        return self._policy(policy).task.joints

    def pose_start(self, policy: object, q: np.ndarray) -> Start:
        task = self._policy(policy).task
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
        policy = self._policy(policy)
        task = policy.task
        if start.state is not None:
            raise LearningError(
                f"A grid state is no start of the {self.title}; give start joint angles."
            )
        if start.seed is not None:
            q_start = task.random_start(np.random.default_rng(start.seed))
        elif start.q is not None:
            q_start = np.asarray(start.q, dtype=np.float64)[: task.joints]
        else:
            q_start = np.zeros(task.joints)
        path, reached = policy.walk(q_start, DEFAULT_MAX_STEPS if max_steps is None else max_steps)
        pace = policy.seconds_per_step if seconds_per_step is None else seconds_per_step
        times, q = path_trajectory(task, path, rate_hz, pace)
        return path_rollout(task, times, q, path, bool(reached), start.seed)

    def summary(self, rollout: Rollout) -> str:
        return f"the {self.title} {'reaches the goal' if rollout.reached else 'does NOT reach the goal'}"

    def evaluate(
        self, policy: object, starts: np.ndarray, *, max_steps: int | None = None
    ) -> Evaluation:
        policy = self._policy(policy)
        cap = DEFAULT_MAX_STEPS if max_steps is None else max_steps
        outcomes = [
            policy.walk(q[: policy.task.joints], cap)
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
        policy = self._policy(policy)
        task = policy.task
        start = np.asarray(demo_q, dtype=np.float64)[0]
        rollout = self.roll_out(policy, Start(q=start), rate_hz)

        def tool(q: np.ndarray) -> np.ndarray:
            return robot_tool_positions(task.robot, q)

        return likeness_card(rollout.times, rollout.q, demo_times, demo_q, tool, joints=task.joints)

    def own_demonstration(self, policy: object) -> DemonstrationMotion | None:
        return None

    def beside(
        self, policy: object, demonstrations: Sequence[Sequence[Sequence[float]]]
    ) -> np.ndarray | None:
        task = self._policy(policy).task
        if not demonstrations:
            return None
        first = np.asarray(demonstrations[0], dtype=np.float64)
        path = np.tile(np.asarray(task.goal), (len(first), 1))
        path[:, : task.joints] = first[:, : task.joints]
        return path

    def not_an_arm(self, policy: object, what: str) -> str | None:
        return None

    def describe(self, policy: object) -> dict[str, object]:
        task = self._policy(policy).task
        spec = {**reach_spec(task), "learner": self.kind}
        if task.paths:
            spec["paths"] = len(task.paths)
        return {
            "task": spec,
            "grid": {},
            "joints": task.joints,
            "goal_deg": listed_degrees(task.goal[: task.joints]),
            "planning": "none",
        }

    def task_spec(self, task: object, coding: TileCoding | None = None) -> dict[str, object]:
        return reach_spec(_reach(task), coding)

    def task_from_spec(self, spec: dict[str, object]) -> tuple[ArmReach, TileCoding]:
        return TileLearner().task_from_spec(spec)

    def task_form(self, task: object, coding: TileCoding | None) -> dict[str, object]:
        return TileLearner().task_form(task, coding)

    def demonstrations_of(self, paths: list[object]) -> list[object]:
        return TileLearner().demonstrations_of(paths)

    def mean_shortest_steps(self, task: object) -> float | None:
        return None

    def _policy(self, policy: object) -> BaselinePolicyFile:
        if not isinstance(policy, self.policy_type):
            raise LearningError(
                f"This is a {type(policy).__name__}, not a {self.title}; give a policy of its own kind."
            )
        return policy  # type: ignore[return-value]


class TeacherLearner(_BaselineLearner):
    """The teacher: the run's demonstrations followed at every step (the follow action of
    :mod:`..tasks._follow` pressed always), no learning; its policies are
    :class:`TeacherPolicyFile`."""

    kind = TEACHER_KIND
    title = "teacher"
    format = TEACHER_FORMAT
    policy_type = TeacherPolicyFile

    def fit(self, task: ArmReach, paths: list[np.ndarray], pace: float) -> TeacherPolicyFile:
        follow = dataclasses.replace(task, actions="follow", paths=()).with_paths(paths)
        return TeacherPolicyFile(task=follow, seconds_per_step=pace)


class CloningLearner(_BaselineLearner):
    """Behaviour cloning (:mod:`._cloning`): toward the demonstrated next state of the nearest
    demonstrated state; its policies are :class:`CloningPolicyFile`."""

    kind = CLONING_KIND
    title = "behaviour cloning"
    format = CLONING_FORMAT
    policy_type = CloningPolicyFile
    prepare_seconds = 3.0

    def kernels(self) -> list[object]:
        return [clone_walk]

    def warm(self) -> None:
        task = ArmReach(joints=3)
        path = np.zeros((2, 3)) + np.asarray(task.goal[:3])
        path[0, 0] -= 4 * task.step
        policy = self.fit(task, [path], 1.0)
        policy.walk(np.zeros(3), 1)

    def fit(self, task: ArmReach, paths: list[np.ndarray], pace: float) -> CloningPolicyFile:
        plain = dataclasses.replace(task, paths=())  # its own moves, not the follow action
        return CloningPolicyFile(
            task=plain, seconds_per_step=pace, cloning=fit_cloning(plain, paths)
        )


def _reach(task: object) -> ArmReach:
    if not isinstance(task, ArmReach):
        raise LearningError(
            f"This run's task is a {type(task).__name__}; the baselines learn the continuous arm task (--task arm-reach)."
        )
    return task
