"""A recording played as the source moves the robot along the path planned over all of it.

Live, the retargeting knows only the past: it finds that an IK branch runs out only when it does,
then walks to another one and misses the hand while it walks. A recording played back as the
source is known whole, so the robot taught (any arm but the Puma560, whose joint mode has no
branches) follows the path ``studio export`` writes for it (:func:`studio.export.recording_motion`,
planned by :func:`studio.kinematics.retarget_path`).

Planning takes a fraction of the recording's length, in a child process (:mod:`._plan_child`)
watched by one worker thread (the latest request wins; a plan no longer wanted is stopped, and
so is one under way when the studio closes). The live retargeting drives the robot meanwhile.
The robot moves onto the plan where that makes no jump the live path would not make: at a frame
where the plan's pose lies within the joint motion the frames since the last one allow of the
pose shown, or where the operator's arm jumps too (the first frame played, a seek back, a loop).
Once on it, it stays on it until the source, the robot or the mirroring changes.
"""

from __future__ import annotations

import logging
import subprocess
import sys
import tempfile
import threading
from collections import OrderedDict
from collections.abc import Callable
from pathlib import Path

import numpy as np

from studio.capture import PlaybackSource
from studio.kinematics import RetargetedPath, RobotArm, robot_cache_folder

from ._plan_child import CANNOT, TEMP_PREFIX, load_path

log = logging.getLogger(__name__)

CACHED_PLANS = 4
"""Plans kept (switching back to a robot already planned for follows its plan at once)."""
POLL_S = 0.1
"""How often the planning is checked on (whether it is still wanted, and its child alive)."""
CLOSE_TIMEOUT_S = 5.0
"""How long closing waits for the planning under way to stop."""
LIVE_INSTEAD = "The robot follows the hand as it would live"
"""How a sentence on a plan that could not be made begins."""

_Key = tuple[str, int, str]  # (the recording's path, its mtime in ns, the robot's name)


class Mishap(str):
    """Why a plan was not made this time (the child was killed, crashed or could not start): said
    while the recording plays, then tried again when it is played again. A recording or robot
    that cannot be planned (a plain ``str``) is not tried again until its file changes."""


class PlannedPlayback:
    """The planned path of the recording being played, for the robot being taught."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._key: _Key | None = None  # the plan for the source being played
        self._source = 0  # its id: a new source starts on the live path again
        self._wanted: _Key | None = None  # what the worker is to plan next
        self._worker: threading.Thread | None = None
        self._plans: OrderedDict[_Key, RetargetedPath | str] = OrderedDict()  # or why none
        self._following = False
        self._last: tuple[int, np.ndarray] | None = None  # the last row fitted, the pose shown
        self._title = ""

    def pose(
        self,
        source: object,
        arm: RobotArm,
        mirror: bool,
        t: float,
        q_live: np.ndarray,
        step: float,
    ) -> tuple[RetargetedPath, int] | None:
        """The plan and its row for the frame at time ``t``, when the robot follows the plan
        there; else None (not a recording, not mirrored, still planning, or the plan's pose not
        yet within ``step`` a frame of the pose last shown). ``q_live`` is this frame's live
        pose, the one shown when the plan's is not."""
        recording = getattr(getattr(source, "recording", None), "path", None)
        if not isinstance(source, PlaybackSource) or not mirror or recording is None:
            self.forget()
            return None
        with self._lock:
            key = self._key
        if key is None or id(source) != self._source or key[2] != arm.name:
            try:  # once per source and robot, not per frame
                key = (str(recording), Path(recording).stat().st_mtime_ns, arm.name)
            except OSError:  # the file went away: the live path, as for any source
                self.forget()
                return None
            with self._lock:
                self._key, self._source = key, id(source)
                self._following, self._last, self._title = False, None, arm.spec.title
                if key not in self._plans or isinstance(self._plans[key], Mishap):
                    self._wanted = key
                    self._start_worker()
        row = source.row_at(t)
        with self._lock:
            plan = self._plans.get(key)
            last, self._last = self._last, None if row is None else (row, q_live)
            if not isinstance(plan, RetargetedPath) or row is None or row >= len(plan.q):
                self._following = False
                return None
            if not self._following and not _may_join(plan.q[row], row, last, step):
                return None
            self._following = True
            self._last = (row, plan.q[row])
        return plan, row

    def note(self) -> str | None:
        """One sentence on the robot's path while a recording plays: being planned, followed,
        or why it could not be planned; None otherwise."""
        with self._lock:
            key, title, following = self._key, self._title, self._following
            if key is None:
                return None
            plan = self._plans.get(key)
        if plan is None:
            return (
                f"Planning the {title}'s path over the whole recording; meanwhile it follows "
                "the hand as it would live."
            )
        if isinstance(plan, str):
            return plan
        if following:
            return (
                f"The {title} follows the path planned over the whole recording, as studio "
                "export writes it."
            )
        return (
            f"The {title}'s path over the whole recording is planned; it moves onto it where "
            "the two meet, or where playback starts over."
        )

    def close(self, timeout: float = CLOSE_TIMEOUT_S) -> None:
        """Stop following and stop the planning under way (its child process is killed), waiting
        up to ``timeout`` s for that."""
        self.forget()
        with self._lock:
            worker = self._worker
        if worker is not None:
            worker.join(timeout)

    def forget(self) -> None:
        """Stop following (the source or the robot changed); plans made are kept."""
        with self._lock:
            self._key, self._wanted, self._following, self._last = None, None, False, None

    def _start_worker(self) -> None:
        """Start the worker unless it runs (it takes the latest wanted plan when done)."""
        if self._worker is None or not self._worker.is_alive():
            self._worker = threading.Thread(
                target=self._plan_wanted, name="studio-playback-plan", daemon=True
            )
            self._worker.start()

    def _plan_wanted(self) -> None:
        while True:
            with self._lock:
                wanted, self._wanted = self._wanted, None
                if wanted is None or wanted != self._key:
                    if wanted is None:
                        self._worker = None
                        return
                    continue  # asked for, then left before it started: skip it
            path, _, robot = wanted
            plan = plan_recording(Path(path), robot, lambda key=wanted: self._key != key)
            if plan is None:  # left while planning
                continue
            with self._lock:
                self._plans[wanted] = plan
                self._plans.move_to_end(wanted)
                while len(self._plans) > CACHED_PLANS:
                    self._plans.popitem(last=False)


def plan_recording(
    path: Path, robot: str, abandoned: Callable[[], bool]
) -> RetargetedPath | str | None:
    """The path of the recording at ``path`` on ``robot`` over all of it, planned in a child
    process (:mod:`studio.web.live._plan_child`, which says why it runs apart). Returns the path, or
    one sentence on why there is none, or None once ``abandoned()`` (polled) says it is not
    wanted any more (the child is stopped)."""
    with tempfile.TemporaryDirectory(prefix=TEMP_PREFIX) as folder:
        out = Path(folder) / "path.npz"
        command = [sys.executable, "-m", "studio.web.live._plan_child", str(path), robot, str(out)]
        cache = robot_cache_folder()  # the robot's geometry, kept when the studio built it
        if cache is not None:
            command.append(str(cache))
        said_at, errors_at = Path(folder) / "said.txt", Path(folder) / "errors.txt"
        try:
            with said_at.open("w") as said_to, errors_at.open("w") as errors_to:
                # stdin stays open while the studio lives: its end tells the child to quit
                child = subprocess.Popen(
                    command, stdin=subprocess.PIPE, stdout=said_to, stderr=errors_to, text=True
                )
        except OSError as err:
            return Mishap(
                f"{LIVE_INSTEAD}: its path over the recording could not be planned ({err})."
            )
        try:
            while True:
                try:
                    child.wait(timeout=POLL_S)
                    break
                except subprocess.TimeoutExpired:
                    if abandoned():
                        child.kill()
                        child.wait()
                        return None
        finally:
            if child.stdin is not None:
                child.stdin.close()
        said = said_at.read_text(errors="replace")
        errors = errors_at.read_text(errors="replace")
        if child.returncode == 0:
            try:
                return load_path(out)
            except (OSError, ValueError, KeyError) as err:
                return Mishap(f"{LIVE_INSTEAD}: its planned path could not be read back ({err}).")
        if child.returncode == CANNOT:
            return f"{LIVE_INSTEAD}: its path over the recording could not be planned ({said.strip()})."
        last = (errors.strip().splitlines() or ["no message"])[-1]
        log.warning("planning %s on the %s failed: %s", path, robot, errors)
        return Mishap(
            f"{LIVE_INSTEAD}: planning its path over the recording failed (exit code "
            f"{child.returncode}: {last}); play the recording again to plan it again."
        )


def _may_join(
    q_plan: np.ndarray,
    row: int,
    last: tuple[int, np.ndarray] | None,
    step: float,
) -> bool:
    """Whether the robot may move onto the plan at ``row`` without a jump the live path would not
    make: the arm itself jumped (nothing fitted before, or a seek back or a loop), or the plan's
    pose is within the frames' joint motion since the pose last shown (one step a frame; some
    frames are skipped when the fit falls behind, or on a seek forward). Measured from the live
    pose of this frame instead, a join could step twice as far."""
    if last is None or row <= last[0]:
        return True
    return bool(np.abs(q_plan - last[1]).max() <= step * (row - last[0]) + 1e-9)
