"""Tabular Dyna-Q on the arm grid as a :class:`studio.learning._interface.Learner`.

The algorithm is :mod:`._dynaq` (the paper's Fig. 1, top to bottom); its policy files are
:mod:`._policy`. This module only puts them behind the one learner interface.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import fields
from pathlib import Path

import numpy as np

from .._config import TASK_ARM_GRID, DynaQConfig
from .._errors import LearningError
from .._interface import Evaluation, Rollout, Start, TrainingRun, listed_degrees
from .._learner import ExperimentResult, LiveProgress
from ..likeness._likeness import LikenessCard, likeness_card, robot_tool_positions
from ..tasks._arm import ArmGrid
from ..tasks._demo_motion import DemonstrationMotion
from ..tasks._mdp import TabularMDP
from ..tasks._robot import default_goal
from ._dynaq import _run_experiment, run_tabular_experiments
from ._policy import (
    FORMAT_NAME,
    ROLLOUT_MAX_STEPS,
    ROLLOUT_SECONDS_PER_STEP,
    PolicyFile,
    greedy_path,
    load_policy,
    rollout,
    save_policy,
)

KIND = TASK_ARM_GRID
"""The tabular learner's kind: the paper's arm grid (a run record's ``task.kind``)."""


def goal_degrees(grid: ArmGrid) -> list[float]:
    """The centre of ``grid``'s goal bin, one angle in degrees per joint."""
    return listed_degrees(grid.angles_of(grid.goal_state))


class TabularLearner:
    """Tabular Dyna-Q on an :class:`ArmGrid`; its policies are :class:`PolicyFile`."""

    kind = KIND
    title = "grid policy"
    format = FORMAT_NAME
    policy_type = PolicyFile
    grid_states = True
    settings_field = "grid"
    form_keys = ("bins",)
    sweep_keys = tuple(f.name for f in fields(ArmGrid))
    shortest_paths = True
    prepare_seconds = 8.0
    trains: type | None = ArmGrid
    watch_max_steps: int | None = ROLLOUT_MAX_STEPS

    def train(
        self, run: TrainingRun, live: LiveProgress, workers: int | None = None
    ) -> ExperimentResult:
        grid = _grid(run.task)
        return run_tabular_experiments(
            grid.mdp(),
            run.config,
            run.experiments,
            run.episodes,
            run.seed,
            run.demonstrations,  # type: ignore[arg-type]
            workers=workers,
            live=live,
        )

    def kernels(self) -> list[object]:
        return [_run_experiment]

    def warm(self) -> None:
        corridor = TabularMDP(
            np.array([[1], [1]]), np.array([[1.0], [0.0]]), np.array([False, True]), np.array([0])
        )
        for planning in ("full", "prioritized"):
            config = DynaQConfig(planning=planning, planning_steps=1)
            run_tabular_experiments(corridor, config, 1, 1, 0)

    def save(
        self,
        path: str | Path,
        run: TrainingRun,
        result: object,
        *,
        notes: str = "",
        compress: bool = True,
    ) -> None:
        assert isinstance(result, ExperimentResult)
        save_policy(
            path,
            _grid(run.task),
            result.q[result.best_experiment()],
            result.config,
            result.mean_steps(),
            experiments=run.experiments,
            notes=notes,
            compress=compress,
        )

    def load(self, path: str | Path) -> PolicyFile:
        return load_policy(path)

    def learned_joints(self, policy: object) -> int:
        return _policy(policy).grid.joints

    def pose_start(self, policy: object, q: np.ndarray) -> Start:
        return Start(q=np.asarray(q, dtype=np.float64))

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
        grid = policy.grid
        hold = default_goal(grid.robot)  # the joints beyond the grid's
        if start.state is not None:
            state = int(start.state)
        elif start.seed is not None:
            starts = grid.mdp().start_states
            state = int(starts[np.random.default_rng(start.seed).integers(len(starts))])
        elif start.q is None:  # its own: the zero pose, or the start nearest it off the table
            state = grid.nearest_start(np.zeros(grid.joints))
        else:
            q = np.asarray(start.q, np.float64)
            state = grid.state_of_angles(q[: grid.joints])
            if len(q) == len(hold):  # a whole pose: its other joints hold where they are
                hold[grid.joints :] = q[grid.joints :]
        steps = ROLLOUT_MAX_STEPS if max_steps is None else max_steps
        times, q_path = rollout(
            policy,
            state,
            rate_hz,
            steps,
            seconds_per_step=(
                ROLLOUT_SECONDS_PER_STEP if seconds_per_step is None else seconds_per_step
            ),
            hold=hold,
        )
        states = greedy_path(policy, state, steps)
        goal = default_goal(grid.robot)
        goal[: grid.joints] = grid.angles_of(grid.goal_state)
        return Rollout(
            times=times,
            q=q_path,
            reached=states[-1] == grid.goal_state,
            steps=len(states) - 1,
            states=tuple(states),
            seed=start.seed,
            goal=goal,
            robot=grid.robot,
        )

    def summary(self, rollout: Rollout) -> str:
        outcome = "reach the goal" if rollout.reached else "do NOT reach the goal"
        return f"{rollout.steps} grid steps from state {rollout.states[0]} {outcome}"

    def evaluate(
        self, policy: object, starts: np.ndarray, *, max_steps: int | None = None
    ) -> Evaluation:
        policy = _policy(policy)
        grid = policy.grid
        steps = ROLLOUT_MAX_STEPS if max_steps is None else max_steps
        paths = [
            greedy_path(policy, grid.state_of_angles(q[: grid.joints]), steps)
            for q in np.atleast_2d(np.asarray(starts, dtype=np.float64))
        ]
        return Evaluation.of(
            [p[-1] == grid.goal_state for p in paths],
            [len(p) - 1 for p in paths],
            ROLLOUT_SECONDS_PER_STEP,
        )

    def likeness(
        self, policy: object, demo_times: np.ndarray, demo_q: np.ndarray, rate_hz: float
    ) -> LikenessCard:
        policy = _policy(policy)
        grid = policy.grid
        start = np.asarray(demo_q, dtype=np.float64)[0]
        state = grid.state_of_angles(start[: grid.joints])
        times, q = rollout(policy, state, rate_hz, hold=start)

        def tool(q: np.ndarray) -> np.ndarray:
            return robot_tool_positions(grid.robot, q)

        return likeness_card(times, q, demo_times, demo_q, tool, joints=grid.joints)

    def own_demonstration(self, policy: object) -> DemonstrationMotion | None:
        return None

    def beside(
        self, policy: object, demonstrations: Sequence[Sequence[Sequence[float]]]
    ) -> np.ndarray | None:
        return None  # (a grid run's demonstrations are state paths: the scene shows its states)

    def not_an_arm(self, policy: object, what: str) -> str | None:
        return None

    def describe(self, policy: object) -> dict[str, object]:
        grid = _policy(policy).grid
        return {
            "task": self.task_spec(grid),
            "grid": grid.to_dict(),
            "joints": grid.joints,
            "goal_deg": goal_degrees(grid),
            "planning": _policy(policy).config.planning,
        }

    def task_spec(self, task: object, coding: object | None = None) -> dict[str, object]:
        return {"kind": KIND, **_grid(task).to_dict()}

    def task_from_spec(self, spec: dict[str, object]) -> tuple[ArmGrid, None]:
        spec = dict(spec)
        if spec.get("goal") is not None:
            spec["goal"] = tuple(spec["goal"])  # type: ignore[arg-type]
        return ArmGrid(**spec), None  # type: ignore[arg-type]

    def task_form(self, task: object, coding: object | None) -> dict[str, object]:
        return {"bins": _grid(task).bins}

    def demonstrations_of(self, paths: list[object]) -> list[object]:
        return [list(map(int, p)) for p in paths]  # type: ignore[call-overload]

    def mean_shortest_steps(self, task: object) -> float | None:
        return _grid(task).mean_shortest_steps()


def _policy(policy: object) -> PolicyFile:
    if not isinstance(policy, PolicyFile):
        raise LearningError(
            f"This is a {type(policy).__name__}, not a grid policy; give a policy of its own kind."
        )
    return policy


def _grid(task: object) -> ArmGrid:
    if not isinstance(task, ArmGrid):
        raise LearningError(
            f"This run's task is a {type(task).__name__}, not the arm grid; train it with its own learner."
        )
    return task
