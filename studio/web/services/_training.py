"""Training runs asked for in the page: a ``RunCreate`` made into the learning package's
request on the robot taught, checked by its one resolver, and queued."""

from __future__ import annotations

from studio.learning import (
    ConfigError,
    RunRecord,
    RunRequest,
    resolve_run,
    without_demonstrations,
)

from .._errors import ConflictError
from .._schemas import RunCreate
from ..live import Pipeline
from ._demonstrations import Demonstrations
from ._rollouts import Rollouts
from ._runs import Run, RunQueue


class Training:
    """The page's way to the run queue.

    Args:
        runs: the queue.
        demonstrations: the demonstrations a run replays (their paths on the run's robot).
        pipeline: the live pipeline (the robot taught: a run naming none trains on it).
        rollouts: what the scene plays (a run whose policy plays cannot be deleted).
    """

    def __init__(
        self,
        runs: RunQueue,
        demonstrations: Demonstrations,
        pipeline: Pipeline,
        rollouts: Rollouts,
    ) -> None:
        self.runs = runs
        self.demonstrations = demonstrations
        self.pipeline = pipeline
        self.rollouts = rollouts

    def request(self, create: RunCreate) -> RunRequest:
        """The learning package's request of ``create``: on its robot (the one taught when it
        names none), its demonstrations by their joint paths on that robot.

        Raises:
            InvalidError: a demonstration that does not exist or cannot be retargeted.
        """
        robot = create.robot or self.pipeline.robot_name
        demonstrations = [self.demonstrations.path_on(n, robot) for n in create.demonstrations]
        return create.request(robot, demonstrations)

    def check(self, create: RunCreate) -> RunRecord:
        """The checked record of the run ``create`` asks for (nothing is queued).

        Raises:
            ConfigError: one sentence per bad field, keyed by field (answered as 422).
        """
        return resolve_run(self.request(create))

    def submit(self, create: RunCreate) -> Run:
        """Check a run and queue it."""
        return self.runs.queue(self.check(create))

    def submit_pair(self, create: RunCreate) -> tuple[Run, Run]:
        """Queue a run with demonstrations and its twin without them (same settings, seed and
        goal: :func:`studio.learning.without_demonstrations`), both checked before either is
        queued.

        Raises:
            ConfigError: a bad field of the run (as :meth:`submit`), or no demonstration picked.
        """
        if not create.demonstrations:
            raise ConfigError(
                ["Pick at least one demonstration to compare a run with them against one without."],
                ["demonstrations"],
            )
        request = self.request(create)
        record = resolve_run(request)
        baseline = resolve_run(without_demonstrations(request, record))
        return self.runs.queue(record), self.runs.queue(baseline)

    def delete(self, run_id: str) -> None:
        """Delete a run and its files (409 while its policy plays in the scene, or as
        :meth:`RunQueue.delete`)."""
        if self.rollouts.playing(f"run:{run_id}"):
            raise ConflictError(
                f"Run {run_id}'s policy is playing in the scene; stop watching it first."
            )
        self.runs.delete(run_id)
