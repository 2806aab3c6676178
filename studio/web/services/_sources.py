"""The live source: choosing it (simulator, recording, network bridge, serial tape, camera, hand
guide), its playback, the simulator's reach, and the observations the page hands in.

Sources are built by the capture package's one factory (:func:`studio.capture.source_from_spec`)
and made live in the pipeline; this service only chooses and checks.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

from studio import StudioError, is_loopback
from studio.capture import (
    DEFAULT_PORT,
    CameraSource,
    Fitted,
    FloodError,
    HandPose,
    HandSource,
    LandmarkFrame,
    PlaybackSource,
    SecondSenderError,
    SimulatorSource,
    source_from_spec,
)
from studio.kinematics import robot_spec
from studio.learning import default_goal_deg, goal_pose

from .._errors import ConflictError, InvalidError, TooManyRequestsError
from .._schemas import LandmarksFrame, LandmarksPublic
from .._settings import Settings
from ..live import Pipeline
from ..scene import Scene
from ._robots import Robots
from ._store import RecordingStore

log = logging.getLogger(__name__)

Fed = TypeVar("Fed", LandmarkFrame, HandPose)
"""An observation a fed source (the camera, the hand guide) takes in."""


class Sources:
    """The live source of a studio.

    Args:
        settings: the bridge's host and the studio's token (a network source beyond loopback).
        pipeline: the live pipeline the source feeds.
        scene: the scene (the hand guide's handle, the simulator's goal), or None.
        recordings: the recordings a playback source plays.
        robots: the robot taught (its state goes with the source's).
    """

    def __init__(
        self,
        settings: Settings,
        pipeline: Pipeline,
        scene: Scene | None,
        recordings: RecordingStore,
        robots: Robots,
    ) -> None:
        self.settings = settings
        self.pipeline = pipeline
        self.scene = scene
        self.recordings = recordings
        self.robots = robots
        # one fed update at a time, numbered, timed, fitted and written in the order it came
        self._fed_lock = threading.Lock()

    def start_configured(self) -> None:
        """Start the source the studio was started with (``serve --source``), if any; one that
        cannot start leaves the studio running, the page showing why."""
        source = self.settings.source
        if source is None:
            return
        try:
            self.start(source)
        except Exception as err:  # the studio still starts: the page shows why
            log.warning("could not start the source %s: %s", source, err)
            message = (
                str(err)
                if isinstance(err, StudioError)
                else f"The {source} source could not start ({type(err).__name__}: {err}); choose another source."
            )
            self.pipeline.report_error(
                "simulator" if source == "simulator" else "recording", message
            )

    def start(self, source: str) -> None:
        """Start ``"simulator"``, a recording by name, or a recording file by path."""
        if source == "simulator":
            self.switch(kind="simulator")
            return
        path = Path(source)
        if path.is_file() and path.resolve().parent != self.settings.recordings_dir.resolve():
            name = self.recordings.stem_of(path.name)
            playback = source_from_spec(str(path.resolve()), loop=True)
            self.pipeline.set_source(playback, "recording", name)
            return
        name = self.recordings.stem_of(path.name) if path.is_file() else source
        self.switch(kind="recording", recording=name, loop=True)

    def switch(
        self,
        kind: str,
        recording: str | None = None,
        port: int | None = None,
        device: str | None = None,
        calibration: str | None = None,
        speed: float | None = None,
        loop: bool | None = None,
        seed: int | None = None,
        side: str | None = None,
    ) -> None:
        """Build a source of ``kind`` (with the capture package's one factory of sources) and
        make it the live one."""
        if self.scene is not None and kind not in ("camera", "hand"):
            self.scene.show_hand_handle(None, None)
        if kind in ("camera", "hand"):
            self.pipeline.set_source(source_from_spec(f"{kind}:{side or 'right'}", fed=True), kind)
            if kind == "hand" and self.scene is not None:
                self.scene.show_hand_handle(self.pipeline.side(), self.hand_moved)
        elif kind == "simulator":
            self.pipeline.set_source(source_from_spec("simulator", seed=seed or 0), kind)
        elif kind == "recording":
            if recording is None:
                raise InvalidError(
                    "recording is missing; give the name of a recording to play back."
                )
            if not self._replay_in_place(recording, speed, loop):
                path = self.recordings.path(recording).resolve()
                playback = source_from_spec(
                    str(path), speed=1.0 if speed is None else speed, loop=loop is not False
                )
                self.pipeline.set_source(playback, kind, recording)
        elif kind == "network":
            # Loopback unless the user asked for another address (serve --bridge-host); beyond
            # loopback only frames signed with the studio's token are taken.
            host = self.settings.bridge_host
            token = None if is_loopback(host) else self.settings.token
            spec = f"udp:{host}:{DEFAULT_PORT if port is None else port}"
            self.pipeline.set_source(source_from_spec(spec, token=token), kind)
        elif kind == "serial":
            if not device:
                raise InvalidError(
                    "device is missing; give the serial device of the tape, for example /dev/ttyUSB0."
                )
            try:
                serial = source_from_spec(
                    f"serial:{device}", calibration=(calibration or "").strip() or None
                )
            except StudioError as err:
                # pyserial missing, a missing or malformed calibration file: the switch happens
                # as for a device that cannot open, with the serial source showing why.
                self.pipeline.report_error(kind, str(err))
                return
            self.pipeline.set_source(serial, kind)
        else:  # the schema allows only the kinds above
            raise InvalidError(
                f"kind is {kind!r}; give simulator, recording, network, serial, camera or hand."
            )

    def _replay_in_place(self, recording: str, speed: float | None, loop: bool | None) -> bool:
        """Change the speed and loop of ``recording`` if it is the one playing (so that ticking
        "loop" never restarts it from 0); whether it was."""
        current = self.pipeline.source
        if not (
            isinstance(current, PlaybackSource)
            and self.pipeline.recording == recording
            and current.running
        ):
            return False
        if speed is not None:
            current.speed = speed
        if loop is not None:
            current.loop = loop
        return True

    def set_retarget(self, mode: str, mirror: bool | None) -> None:
        """Map the arm onto the robot joint by joint or by hand position, mirrored or not."""
        self.pipeline.set_retarget(mode, mirror)

    def simulator_reach(self, action: str, goal_deg: list[float] | None = None) -> None:
        """Make the simulator reach a goal of the robot taught (``goal_deg``, joints 1-3) or
        wander again; no goal: the robot's default goal. The Puma560's goal is mirrored joint by
        joint; another robot's is the arm that puts the hand where that robot's tool goes at it.

        Raises:
            ConflictError: the live source is not the simulator.
            ConfigError: the goal is not 3 angles within the robot's limits.
        """
        source = self.pipeline.source
        if self.pipeline.kind != "simulator" or not isinstance(source, SimulatorSource):
            raise ConflictError(
                "The live source is not the simulator; switch the source to the simulator first."
            )
        if action == "wander":
            source.wander()
            return
        robot = self.pipeline.robot_name
        q = goal_pose(default_goal_deg(robot) if goal_deg is None else goal_deg, robot)
        if robot_spec(robot).joint_mode:  # the Puma560: its joints mirror the arm's one by one
            source.reach(q)
        else:
            source.reach_human(self.pipeline.human_reaching(q))
        if self.scene is not None:
            self.scene.set_goal(q, robot)

    def _fed_source(self, kind: str) -> CameraSource | HandSource:
        """The live fed source ``kind`` (camera or hand).

        Raises:
            ConflictError: the live source is not ``kind``.
        """
        source = self.pipeline.source
        fed = CameraSource if kind == "camera" else HandSource
        if self.pipeline.kind != kind or not isinstance(source, fed):
            label = "camera" if kind == "camera" else "hand guide"
            raise ConflictError(
                f"The live source is not the {label}; switch the source to {kind} first."
            )
        return source

    def _observe_fed(self, submit: Callable[[], Fed]) -> tuple[Fed, Fitted | None]:
        """Hand one update to a fed source (``submit``) and fit it; returns the observation and
        the fit (None when it failed: the pipeline's status says why).

        Raises:
            TooManyRequestsError: a flood (the update is dropped).
            ConflictError: another page sends frames already (the update is dropped).
        """
        with self._fed_lock:
            try:
                observation = submit()
            except FloodError as err:
                raise TooManyRequestsError(str(err)) from None
            except SecondSenderError as err:
                raise ConflictError(str(err)) from None
            return observation, self.pipeline.observe(observation)

    def post_landmarks(self, frame: LandmarksFrame) -> LandmarksPublic:
        """Fit and record one frame of landmarks from the page, as the API parsed it; the camera
        source checks its values (the one check: NaN, sizes, time) and the answer is built
        typed, not read back from a dict.

        Raises:
            ConflictError: the live source is not the camera.
            TooManyRequestsError: a flood (the frame is dropped).
            CaptureError: NaN or wrong sizes (422).
        """
        camera = self._fed_source("camera")
        observation, fitted = self._observe_fed(
            lambda: camera.submit(
                frame.t,
                frame.world,
                frame.image,
                frame.width,
                frame.height,
                frame.fps,
                frame.model,
                frame.sender,
            )
        )
        observable = None if fitted is None else fitted.observable
        return LandmarksPublic(
            person_detected=observation.person,
            observable=None if observable is None else [bool(b) for b in observable],
            warning=fitted.warning if fitted is not None else self.pipeline.status()["error"],
            q_human=None if fitted is None else [float(x) for x in fitted.q_human],
            q_robot=None if fitted is None else [float(x) for x in fitted.q_robot],
        )

    def hand_moved(self, position: object, wxyz: object = None) -> dict[str, object]:
        """Move the operator's hand to a pose (``HandTarget``): what dragging the scene's handle
        does. Returns the arm and robot reached (``HandPublic``).

        Raises:
            ConflictError: the live source is not the hand guide.
            TooManyRequestsError: a flood (the update is dropped).
            CaptureError: NaN or wrong sizes (422).
        """
        hand = self._fed_source("hand")
        _, fitted = self._observe_fed(lambda: hand.submit(position, wxyz))
        if fitted is None:
            raise InvalidError(
                self.pipeline.status()["error"]
                or "The hand guide could not solve this pose; drag the handle elsewhere."
            )
        return {
            "q_human": [float(x) for x in fitted.q_human],
            "q_robot": [float(x) for x in fitted.q_robot],
            "position_error_m": float(fitted.residual),
            "reached": bool(fitted.success),
            "warning": fitted.warning,
        }

    def public(self) -> dict[str, object]:
        """``SourcePublic``: the pipeline status plus the robot's and the playback's state."""
        status = self.pipeline.status()
        status.update(self.robots.state())
        plan = self.pipeline.plan_note()
        notes = status["robot_notes"]
        if plan and isinstance(notes, list):
            status["robot_notes"] = [*notes, plan]
        status["playback"] = None
        source = self.pipeline.source
        if self.pipeline.kind == "recording" and isinstance(source, PlaybackSource):
            status["playback"] = _playback_state(source)
        return status

    def playback(self, action: str, t: float | None, speed: float | None) -> None:
        """Play, pause or seek the recording source.

        Raises:
            ConflictError: the live source is not a recording.
        """
        source = self.pipeline.source
        if self.pipeline.kind != "recording" or not isinstance(source, PlaybackSource):
            raise ConflictError(
                "The live source is not a recording; switch the source to a recording first."
            )
        if speed is not None:
            source.speed = speed
        if action == "play":
            source.resume()
        elif action == "pause":
            source.pause()
        elif action == "seek":
            if t is None:
                raise InvalidError("t is missing; give the time to seek to, in seconds.")
            source.seek(t)


def _playback_state(source: PlaybackSource) -> dict[str, object]:
    return {
        "playing": bool(source.running and not source.paused),
        "speed": None if source.speed is None else float(source.speed),
        "t": float(source.position),
        "duration": float(source.duration),
        "loop": bool(source.loop),
    }
