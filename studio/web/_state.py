"""The studio's services, built together when the app starts and closed when it stops.

One :class:`Studio` per app holds one service per resource (the live source, the robot taught,
the capture, recordings, demonstrations, training runs, policies, watched rollouts, the review
of a recording and its takes); routes ask for the one they act on through the ``Annotated``
aliases of :mod:`._deps`. Every list's owner announces its own changes through one callback,
:meth:`ListChanges.announce` (the stores, the pipeline's capture, the run queue).
"""

from __future__ import annotations

import numpy as np

from ._settings import Settings
from .live import Pipeline
from .scene import RobotPlayer, Scene
from .services import (
    Capture,
    Demonstrations,
    ListChanges,
    Policies,
    Reviewer,
    Robots,
    Rollouts,
    RunQueue,
    Sources,
    TakeFlow,
    Training,
    Watching,
    recording_store,
)


class Studio:
    """Everything the API acts on, one service per resource.

    Args:
        settings: data directory, ports, limits.
        scene: the viser scene to drive, or None (tests, headless).
    """

    def __init__(self, settings: Settings, scene: Scene | None = None) -> None:
        self.settings = settings
        for folder in (settings.recordings_dir, settings.runs_dir, settings.policies_dir):
            folder.mkdir(parents=True, exist_ok=True)
        self.changes = ListChanges()
        announce = self.changes.announce
        self.scene = scene
        self.pipeline = Pipeline(scene, on_change=announce)
        self.player = None if scene is None else RobotPlayer(scene)
        self.runs = RunQueue(settings.runs_dir, announce, settings.run_workers)
        self.recordings = recording_store(settings.recordings_dir, self.pipeline, announce)
        self.rollouts = Rollouts(scene)
        self.policies = Policies(settings.policies_dir, announce, self.runs, self.rollouts)
        self.demonstrations = Demonstrations(
            self.recordings,
            announce,
            self.pipeline,
            scene,
            self.player,
            self.runs,
            self.policies,
        )
        self.robots = Robots(self.pipeline, scene, self.player)
        self.sources = Sources(settings, self.pipeline, scene, self.recordings, self.robots)
        self.capture = Capture(settings, self.pipeline, self.recordings, self.demonstrations)
        self.training = Training(self.runs, self.demonstrations, self.pipeline, self.rollouts)
        self.watching = Watching(
            self.policies, self.rollouts, self.runs, self.demonstrations, self.pipeline, scene
        )
        self.reviewer = Reviewer(self.recordings, self.pipeline, scene, self.player)
        self.takes = TakeFlow(
            settings.recordings_dir,
            self.recordings,
            self.capture,
            self.demonstrations,
            self.reviewer,
        )

    def start(self) -> None:
        """Start the run worker and the pipeline (with the configured source, if any)."""
        self.runs.start()
        self.pipeline.start()
        if self.scene is not None:
            from studio.learning import ArmGrid

            grid = ArmGrid()  # the default task's goal, until a watch shows another
            goal = np.zeros(6)
            goal[: grid.joints] = grid.angles_of(grid.goal_state)
            self.scene.set_goal(goal)
        self.sources.start_configured()

    def close(self) -> None:
        """Stop training (keeping partial curves), close a capture cleanly, stop the source."""
        self.runs.close()
        self.pipeline.close()
