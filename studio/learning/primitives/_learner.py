"""The movement-primitive baseline as a :class:`studio.learning._interface.Learner`.

The algorithm is :mod:`._dmp` (Ijspeert et al. 2013, fitted by least squares); its policy files
are :mod:`._policy`. This module only puts them behind the one learner interface: it "trains"
by fitting a primitive to a run's first recorded demonstration.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .._errors import LearningError
from .._interface import Evaluation, Rollout, Start, TrainingRun, listed_degrees
from .._learner import LiveProgress
from ..likeness._likeness import LikenessCard, likeness_card, robot_tool_positions
from ..tabular._policy import ROLLOUT_RATE_HZ
from ..tasks._demo_motion import DemonstrationMotion
from ._policy import (
    FORMAT_NAME,
    DmpPolicyFile,
    fit_dmp_policy,
    load_dmp_policy,
    rollout_dmp_policy,
    save_dmp_policy,
)

KIND = "dmp"
"""The movement primitive's kind (as policy listings name what a policy acts on)."""
OWN_DEMONSTRATION = "its demonstration"
"""How a movement primitive's own demonstration is named beside its rollout."""


class DmpLearner:
    """The movement primitive; its policies are :class:`DmpPolicyFile`."""

    kind = KIND
    title = "movement primitive"
    format = FORMAT_NAME
    policy_type = DmpPolicyFile
    grid_states = False
    settings_field = ""  # (no run trains it: it is fitted to one demonstration)
    form_keys: tuple[str, ...] = ()
    sweep_keys: tuple[str, ...] = ()
    shortest_paths = False
    prepare_seconds = 0.0  # (numpy only: nothing to compile)
    trains: type | None = None
    watch_max_steps: int | None = None

    def train(
        self, run: TrainingRun, live: LiveProgress, workers: int | None = None
    ) -> DmpPolicyFile:
        if not run.demonstration_motions:
            raise LearningError(
                "A movement primitive is fitted to a recorded demonstration; give the run one."
            )
        motion = run.demonstration_motions[0]
        robot = getattr(run.task, "robot", None)
        return fit_dmp_policy(motion.times, motion.q_robot, **({"robot": robot} if robot else {}))

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
        save_dmp_policy(path, _policy(result), compress=compress)

    def load(self, path: str | Path) -> DmpPolicyFile:
        return load_dmp_policy(path)

    def learned_joints(self, policy: object) -> int:
        return len(_policy(policy).goal)

    def pose_start(self, policy: object, q: np.ndarray) -> Start:
        q = np.asarray(q, dtype=np.float64)
        # another robot's pose: the primitive's own start
        return Start(q=q) if len(q) == len(_policy(policy).goal) else Start()

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
        if start.state is not None:
            raise LearningError(
                "A grid state is no start of a movement primitive; give start joint angles."
            )
        times, q, reached = rollout_dmp_policy(policy, start.q, rate_hz)
        return Rollout(
            times=times,
            q=q,
            reached=reached,
            steps=len(times) - 1,
            states=(),
            seed=None,  # (a random start is its demonstration's: no seed to report)
            goal=policy.goal,
            robot=policy.robot,
        )

    def summary(self, rollout: Rollout) -> str:
        return f"the movement primitive {'reaches the goal' if rollout.reached else 'does NOT reach the goal'}"

    def evaluate(
        self, policy: object, starts: np.ndarray, *, max_steps: int | None = None
    ) -> Evaluation:
        policy = _policy(policy)
        outcomes = []
        for q in np.atleast_2d(np.asarray(starts, dtype=np.float64)):
            pose = policy.demo_q[0].copy()  # the joints not given: where its demonstration began
            pose[: len(q)] = q
            outcomes.append(rollout_dmp_policy(policy, pose, ROLLOUT_RATE_HZ))
        return Evaluation.of(  # a step: one sample of its rollout
            [reached for *_, reached in outcomes],
            [len(times) - 1 for times, *_ in outcomes],
            1.0 / ROLLOUT_RATE_HZ,
        )

    def likeness(
        self, policy: object, demo_times: np.ndarray, demo_q: np.ndarray, rate_hz: float
    ) -> LikenessCard:
        policy = _policy(policy)
        start = np.asarray(demo_q, dtype=np.float64)[0]
        times, q, _ = rollout_dmp_policy(policy, start, rate_hz)

        def tool(q: np.ndarray) -> np.ndarray:
            return robot_tool_positions(policy.robot, q)

        return likeness_card(times, q, demo_times, demo_q, tool, joints=policy.learned_joints)

    def own_demonstration(self, policy: object) -> DemonstrationMotion | None:
        policy = _policy(policy)
        return DemonstrationMotion(OWN_DEMONSTRATION, policy.demo_times, policy.demo_q)

    def beside(
        self, policy: object, demonstrations: Sequence[Sequence[Sequence[float]]]
    ) -> np.ndarray | None:
        return _policy(policy).demo_q  # the demonstration it was fitted to

    def not_an_arm(self, policy: object, what: str) -> str | None:
        return None

    def describe(self, policy: object) -> dict[str, object]:
        policy = _policy(policy)
        return {
            "task": {"kind": KIND, "basis": policy.primitive.basis, "robot": policy.robot},
            "grid": {},
            "joints": len(policy.goal),
            "goal_deg": listed_degrees(policy.goal),
            "planning": "none",
        }

    def task_spec(self, task: object, coding: object | None = None) -> dict[str, object]:
        raise LearningError(_NO_TASK)

    def task_from_spec(self, spec: dict[str, object]) -> tuple[object, None]:
        raise LearningError(_NO_TASK)

    def task_form(self, task: object, coding: object | None) -> dict[str, object]:
        raise LearningError(_NO_TASK)

    def demonstrations_of(self, paths: list[object]) -> list[object]:
        raise LearningError(_NO_TASK)

    def mean_shortest_steps(self, task: object) -> float | None:
        return None


_NO_TASK = (
    "A movement primitive learns no run's task; fit it to a demonstration with fit_dmp_policy."
)


def _policy(policy: object) -> DmpPolicyFile:
    if not isinstance(policy, DmpPolicyFile):
        raise LearningError(
            f"This is a {type(policy).__name__}, not a movement primitive; give a policy of its own kind."
        )
    return policy
