"""Watching a learned policy in the scene: its greedy rollout from a random or the current pose,
played on its robot beside the demonstration it learned from, with its likeness card; and the
rollout last watched as CSV. The learner of the policy's kind does the work
(:func:`studio.learning.learner_of`); this service chooses the start, the demonstrations and what
the scene shows."""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np

from studio.kinematics import DEFAULT_ROBOT
from studio.learning import (
    ROLLOUT_RATE_HZ,
    AnyPolicy,
    DemonstrationMotion,
    LearningError,
    RunRecord,
    Start,
    check_policy_robot,
    learner_of,
    likeness_cards,
    policy_obstacles,
    save_trajectory_csv,
)

from .._errors import ConflictError, InvalidError
from .._schemas import LikenessPublic, WatchCreate, WatchPublic
from ..live import Pipeline
from ..scene import Scene
from ._demonstrations import Demonstrations
from ._policies import Policies
from ._rollouts import Rollouts
from ._runs import RunQueue

ROUND_DECIMALS = 6
"""Seconds and radians are sent to a micro-unit: far below what the scene can show."""
TILE_DEMONSTRATION_PATH = "demonstration"
"""Name of the scene path showing a continuous run's (or a movement primitive's) demonstration
beside the watched robot."""


class Watching:
    """A policy watched in the scene (a run's or an uploaded one).

    Args:
        policies: where policies are found by run or name.
        rollouts: what the scene plays, and the last rollout of each policy.
        runs: the run folders (a run's demonstrations, for the likeness card).
        demonstrations: the demonstrations, on any robot.
        pipeline: the live chain (the robot taught, its pose now).
        scene: the scene it plays in, or None (headless: rolled out, not played).
    """

    def __init__(
        self,
        policies: Policies,
        rollouts: Rollouts,
        runs: RunQueue,
        demonstrations: Demonstrations,
        pipeline: Pipeline,
        scene: Scene | None,
    ) -> None:
        self.policies = policies
        self.rollouts = rollouts
        self.runs = runs
        self.demonstrations = demonstrations
        self.pipeline = pipeline
        self.scene = scene

    def watch(self, body: WatchCreate) -> WatchPublic:
        """Roll the greedy policy of a run or an uploaded policy out and play it in the scene.

        Raises:
            ConflictError: the policy is another robot's, or not an arm's.
            InvalidError: a demonstration to compare with that cannot be used.
        """
        policy, key = self.policies.load(body.run, body.policy)
        learner = learner_of(policy)
        if policy.robot is not None:  # (None: not an arm's policy, refused below)
            try:
                check_policy_robot(
                    policy.robot,
                    self.pipeline.robot_name,
                    "This policy",
                    f"pick the {policy.robot} under Source to watch it",
                )
            except LearningError as err:
                raise ConflictError(str(err)) from None
        problem = learner.not_an_arm(policy, "can be watched")
        if problem is not None:
            raise ConflictError(problem)
        scene = self.scene
        if body.start == "current":
            now = np.asarray(scene.current_q_robot() if scene else self.pipeline.q_robot())
            start = learner.pose_start(policy, now)
        else:
            start = Start(seed=start_seed(body))
        rollout = learner.roll_out(
            policy, start, ROLLOUT_RATE_HZ, max_steps=learner.watch_max_steps
        )
        self.rollouts.keep(key, rollout.times, rollout.q)
        if scene is not None:
            record = self._run_record(key)
            beside = learner.beside(policy, record.demonstrations if record is not None else [])
            scene.set_goal(rollout.goal, robot=rollout.robot)
            scene.obstacles.show_watched(policy_obstacles(policy), rollout.robot)
            if beside is not None:  # the demonstration it learned from, beside it
                scene.show_path(TILE_DEMONSTRATION_PATH, beside, robot=rollout.robot)
            else:
                scene.clear_path(TILE_DEMONSTRATION_PATH)
            states = list(rollout.states) if rollout.states else None
            scene.play_trajectory(rollout.times, rollout.q, states, robot=rollout.robot)
        likeness, note = self._likeness(body, policy, key)
        return WatchPublic(
            steps=rollout.steps,
            seed=rollout.seed,
            states=list(rollout.states),
            times=np.round(rollout.times, ROUND_DECIMALS).tolist(),
            q_robot=np.round(rollout.q, ROUND_DECIMALS).tolist(),
            reached_goal=rollout.reached,
            likeness=likeness,
            likeness_note=note,
        )

    def stop(self) -> None:
        """Stop the playback; the robot follows the live source again."""
        self.rollouts.stop()

    def trajectory_csv(self, run: str | None, policy: str | None) -> tuple[str, str]:
        """``(filename, text)``: the rollout last watched of a run's policy or an uploaded one
        (neither: the last rollout watched) in the learning package's CSV format, named
        ``<run id or policy name>.rollout.csv`` as ``studio export`` names it.

        Raises:
            ConflictError: that policy (or any) has not been watched yet.
        """
        key = None if run is None and policy is None else self.policies.file(run, policy)[1]
        last = self.rollouts.last(key)
        if last is None:
            if key is None:
                raise ConflictError(
                    "Nothing has been watched yet; watch a policy first, then download."
                )
            kind, name = key.split(":", 1)
            raise ConflictError(
                f"{'Run' if kind == 'run' else 'Policy'} {name} has not been watched yet; watch it first, then download its rollout."
            )
        key, times, q = last
        filename = f"{key.split(':', 1)[-1]}.rollout.csv"
        with tempfile.TemporaryDirectory() as folder:  # the learning package's CSV format, as is
            path = Path(folder) / filename
            save_trajectory_csv(path, times, q)
            return filename, path.read_text()

    def _run_record(self, key: str) -> RunRecord | None:
        """The record of the run whose policy ``key`` names (``run:<id>``), None for an upload."""
        if not key.startswith("run:"):
            return None
        return self.runs.get(key.removeprefix("run:")).folder.record

    def _demonstration_motions(
        self, body: WatchCreate, policy: AnyPolicy, key: str
    ) -> list[DemonstrationMotion]:
        """The demonstrations to compare with: the one asked for, else the run's own (kept in
        its record, or by name from the list for a run recorded before motions were kept), else
        the one the policy file holds (a movement primitive's)."""
        names: list[str] = [body.demonstration] if body.demonstration else []
        record = self._run_record(key) if not names else None
        if record is not None:
            if record.demonstration_motions:
                return list(record.demonstration_motions)
            names = list(record.demonstration_names)
        own = learner_of(policy).own_demonstration(policy)
        if not names and own is not None:
            return [own]
        robot = policy.robot or DEFAULT_ROBOT
        motions = []
        for name in names:
            self.demonstrations.store.load(name)  # 404 with the store's sentence
            # on the policy's robot: its stored path, or retargeted (422 if it cannot be)
            demo = self.demonstrations.path_on(name, robot)
            times = demo.times if demo.times is not None else np.zeros(0)
            try:
                motions.append(DemonstrationMotion.checked(name, times, demo.q_robot))
            except LearningError as err:
                raise InvalidError(str(err)) from None
        return motions

    def _likeness(
        self, body: WatchCreate, policy: AnyPolicy, key: str
    ) -> tuple[LikenessPublic | None, str]:
        """The watched policy's likeness card against its first demonstration, rolled out from
        that demonstration's own start; or None and the sentence saying why there is none."""
        motions = self._demonstration_motions(body, policy, key)
        if not motions:
            return None, (
                "No likeness card: this policy was not taught from a recorded demonstration; "
                "choose one to compare with."
            )
        motion, card = likeness_cards(policy, motions[:1])[0]
        if isinstance(card, str):
            return None, card
        return LikenessPublic.model_validate({"name": motion.name, **card.to_dict()}), ""


def start_seed(body: WatchCreate) -> int | None:
    """The seed of a random start: the one asked for, else a fresh one the answer reports (so
    the same start can be watched again); None for a start from the current pose."""
    if body.start != "random":
        return None
    if body.seed is not None:
        return body.seed
    return int(np.random.default_rng().integers(2**31))
