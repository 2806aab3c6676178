"""A recording's timeline and its review on the robot: the series the page plots, the pose at the
timeline's cursor, and a segment's robot path drawn and played in the scene.

The joints come from :func:`studio.capture.recording_series` (the capture package's fitters);
this module only caches them per file and hands them to the scene. On a robot other than the
Puma560 the human arm's joints are retargeted onto it by :func:`studio.motion.series_motion` (the
path an export takes): the timeline plots that robot's joints and its cursor holds the robot at
them; a played stretch is retargeted in the background by the studio's
:class:`~studio.web.scene.RobotPlayer`.
"""

from __future__ import annotations

import threading
from collections import OrderedDict

import numpy as np

from studio.capture import DEMO_ROBOT, RecordingSeries, recording_series
from studio.kinematics import load_robot
from studio.motion import Motion, recording_motion, series_motion

from ..live import Pipeline
from ..scene import PREVIEW_FRAMES, RobotPlayer, Scene
from ._store import RecordingStore

REVIEW_PATH = "review"
"""The scene path that shows the segment under review (one at a time, replaced by the next)."""
CACHED_SERIES = 8
"""How many series are kept (a timeline's pose lookups read the one it plotted)."""


class Reviewer:
    """Series of a studio's recordings, cached until their file changes, and shown on its robot.

    Args:
        recordings: the recordings reviewed.
        pipeline: the live pipeline (the robot taught, the retargeting mode).
        scene: the scene a review plays in, or None (headless).
        player: what plays a stretch on a robot other than the Puma560 (None without a scene).
    """

    def __init__(
        self,
        recordings: RecordingStore,
        pipeline: Pipeline,
        scene: Scene | None,
        player: RobotPlayer | None,
    ) -> None:
        self.recordings = recordings
        self.pipeline = pipeline
        self.scene = scene
        self.player = player
        self._lock = threading.Lock()
        self._cache: OrderedDict[tuple[object, ...], RecordingSeries] = OrderedDict()
        self._plotted: dict[str, RecordingSeries] = {}
        self._on_robot: dict[tuple[str, str], tuple[RecordingSeries, Motion]] = {}

    def series(
        self, name: str, points: int, t0: float | None = None, t1: float | None = None
    ) -> RecordingSeries:
        """The joints of recording ``name`` (404 if none) over ``[t0, t1]`` at ``points`` frames."""
        path = self.recordings.path(name)
        stat = path.stat()
        mode = self.pipeline.retarget_mode
        key = (str(path), stat.st_mtime_ns, stat.st_size, mode, points, t0, t1)
        with self._lock:
            found = self._cache.get(key)
            if found is not None:
                self._cache.move_to_end(key)
        if found is None:
            found = recording_series(path, points, t0, t1, mode=mode)
            with self._lock:
                self._cache[key] = found
                while len(self._cache) > CACHED_SERIES:
                    self._cache.popitem(last=False)
        return found

    def plotted(self, name: str, points: int) -> RecordingSeries:
        """The whole-recording series a timeline plots; its cursor's poses are read from it."""
        series = self.series(name, points)
        with self._lock:
            self._plotted[name] = series
        return series

    def timeline(self, name: str, points: int) -> tuple[RecordingSeries, Motion]:
        """The series a timeline plots and its joints on the robot taught
        (:func:`studio.motion.series_motion`), kept while the series is."""
        series = self.plotted(name, points)
        return series, self._robot_path(name, series)

    def _robot_path(self, name: str, series: RecordingSeries) -> Motion:
        robot = self.pipeline.robot_name
        with self._lock:
            kept = self._on_robot.get((name, robot))
        if kept is not None and kept[0] is series:
            return kept[1]
        motion = series_motion(series, robot, name)
        with self._lock:
            self._on_robot[(name, robot)] = (series, motion)
            while len(self._on_robot) > CACHED_SERIES:
                self._on_robot.pop(next(iter(self._on_robot)))
        return motion

    def hold(self, name: str, t: float) -> np.ndarray:
        """Hold the robot at the pose of recording ``name`` at ``t`` s (the timeline's cursor):
        the robot's joints the timeline plots, between its samples.

        Returns:
            The robot joints shown (rad, (nq,) of the robot taught).
        """
        with self._lock:
            series = self._plotted.get(name)
        if series is None or not len(series.times):
            series = self.plotted(name, 400)
        motion = self._robot_path(name, series)
        robot = motion.robot.name
        if not len(series.times):
            return np.zeros(load_robot(robot, geometry=False).nq)
        q = np.array([np.interp(t, motion.times, col) for col in motion.q.T])
        scene = self.scene
        if scene is not None:
            scene.play_trajectory(np.zeros(1), q[None, :], robot=robot)
        return q

    def play(self, name: str, t0: float | None = None, t1: float | None = None) -> None:
        """Draw the robot's tool path of ``[t0, t1]`` (the whole recording by default) and play
        it on the robot taught in real time (on another robot than the Puma560, once retargeted
        in the background)."""
        scene, player = self.scene, self.player
        robot = self.pipeline.robot_name
        # the series holds the path of the capture chain's robot; any other is retargeted
        if robot != DEMO_ROBOT and scene is not None and player is not None:
            path = self.recordings.path(name)
            stat = path.stat()
            player.play(
                robot,
                f"the recording {name}",
                ("recording", str(path), stat.st_mtime_ns, stat.st_size, robot, t0, t1),
                lambda: recording_motion(path, robot, t0, t1, most_frames=PREVIEW_FRAMES),
                REVIEW_PATH,
            )
            return
        series = self.series(name, 400, t0, t1)
        if scene is not None and len(series.times):
            scene.show_path(REVIEW_PATH, series.q_robot)
            scene.play_trajectory(series.times, series.q_robot)
            if player is not None:
                player.clear_note()
