"""Demonstrations and recordings played on the robot the operator teaches.

A demonstration and a recording are a human arm's motion, so on a robot other than the Puma560
(whose joint path a demonstration stores) they are retargeted first, with the export's own
sources (:func:`studio.export.demonstration_motion`, :func:`studio.export.recording_motion`:
the capture fitters, then :func:`studio.kinematics.retarget_path`). That takes seconds, so it
runs in a worker thread, never in a request or the scene thread; the latest request wins, and
the page is told meanwhile what is being retargeted, and afterwards what could not be shown.
"""

from __future__ import annotations

import logging
import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable

import numpy as np

from studio import StudioError
from studio.motion import Motion

from ._protocols import Scene
from ._robot_view import RobotViews

log = logging.getLogger(__name__)

CACHED_MOTIONS = 8
"""Retargeted motions kept (a demonstration previewed again plays at once)."""
PREVIEW_FRAMES = 1100
"""Most frames a recording's stretch is retargeted at for a preview (10 s at 110 Hz); a longer
stretch takes every k-th frame (:func:`studio.export.recording_motion`)."""


class RobotPlayer:
    """Retargets motions onto a robot in a worker thread and plays them in the scene.

    Args:
        scene: the scene to draw and play in.
    """

    def __init__(self, scene: Scene) -> None:
        self.scene = scene
        self._lock = threading.Lock()
        self._request = 0
        self._busy = ""
        self._note = ""
        self._cache: OrderedDict[Hashable, Motion] = OrderedDict()

    def status(self) -> tuple[str, str]:
        """``(busy, note)``: what is being retargeted now, and why the last motion played is
        not all shown on its robot (each one sentence, or empty)."""
        with self._lock:
            return self._busy, self._note

    def clear_note(self) -> None:
        """Forget the last note (a motion that needs no retargeting was played)."""
        with self._lock:
            self._note = ""

    def play(
        self,
        robot: str,
        what: str,
        key: Hashable,
        compute: Callable[[], Motion],
        path: str,
        *,
        goal: bool = False,
        play: bool = True,
    ) -> None:
        """Retarget ``what`` (``the demonstration x``) onto ``robot`` with ``compute`` (cached
        under ``key``), then draw its tool path as ``path``, show its end as ``robot``'s goal
        (``goal``) and play it (``play``). Returns at once."""
        with self._lock:
            self._request += 1
            token = self._request
            found = self._cache.get(key)
            if found is not None:
                self._cache.move_to_end(key)
            else:
                self._busy = f"Retargeting {what} onto the {RobotViews.title(robot)}…"
        if found is not None:
            self._show(token, found, path, goal, play)
            return
        worker = threading.Thread(
            target=self._run,
            args=(token, key, compute, path, goal, play),
            name="studio-retarget",
            daemon=True,
        )
        worker.start()

    def _run(
        self,
        token: int,
        key: Hashable,
        compute: Callable[[], Motion],
        path: str,
        goal: bool,
        play: bool,
    ) -> None:
        try:
            motion = compute()
        except StudioError as err:
            self._finish(token, str(err))
            return
        except Exception as err:  # never a silent worker: the page says what happened
            log.exception("Retargeting failed.")
            self._finish(token, f"Retargeting failed ({type(err).__name__}: {err}); try again.")
            return
        with self._lock:
            self._cache[key] = motion
            while len(self._cache) > CACHED_MOTIONS:
                self._cache.popitem(last=False)
        self._show(token, motion, path, goal, play)

    def _finish(self, token: int, note: str) -> None:
        with self._lock:
            if token == self._request:
                self._busy, self._note = "", note

    def _show(self, token: int, motion: Motion, path: str, goal: bool, play: bool) -> None:
        with self._lock:
            if token != self._request:
                return  # another request came meanwhile: it plays instead
        robot = motion.robot.name
        q = np.asarray(motion.q, dtype=float)
        self.scene.show_path(path, q, robot)
        if goal:
            self.scene.set_goal(q[-1], robot)
        if play:
            self.scene.play_trajectory(np.asarray(motion.times, dtype=float), q, robot=robot)
        note = ""
        if motion.findings:
            note = (
                f"Shown on the {RobotViews.title(robot)}, which holds the closest pose it "
                f"reaches where the hand is out of its reach: {motion.findings[0].sentence}."
            )
        self._finish(token, note)
