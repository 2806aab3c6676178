"""The studio's state: the stores, the live pipeline, the run queue, the scene and the watched rollouts.

One :class:`Studio` per app, built when the app starts and closed when it stops. Routes reach it
through the ``StudioDep`` dependency. List changes bump a version per list; the SSE stream
compares versions, so a slow or vanished client never holds anything up.
"""

from __future__ import annotations

import logging
import threading
import uuid
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import numpy as np

from studio import StudioError, is_loopback
from studio.capture import DEFAULT_PORT, being_recorded
from studio.learning import GOAL_JOINTS, check_goal_deg

from ._errors import ConflictError, InvalidError, NotFoundError, TooManyRequestsError
from ._pipeline import Pipeline
from ._runs import RunQueue
from ._settings import Settings
from ._store import (
    demonstration_store,
    policy_store,
    recording_store,
)

log = logging.getLogger(__name__)

LIST_NAMES = ("recordings", "demonstrations", "runs", "policies")
ROLLOUTS_KEPT = 16
"""Policies whose last watched rollout stays downloadable (each at most a megabyte or two)."""


class ListChanges:
    """A version number per list (recordings, demonstrations, runs, policies)."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._versions = dict.fromkeys(LIST_NAMES, 0)

    def bump(self, name: str) -> None:
        """Record that list ``name`` changed."""
        with self._lock:
            self._versions[name] += 1

    def versions(self) -> dict[str, int]:
        """The current versions."""
        with self._lock:
            return dict(self._versions)


class Studio:
    """Everything the API acts on.

    Args:
        settings: data directory, ports, limits.
        scene: the viser scene to drive, or None (tests, headless).
    """

    def __init__(self, settings: Settings, scene: Any = None) -> None:
        self.settings = settings
        for folder in (settings.recordings_dir, settings.runs_dir, settings.policies_dir):
            folder.mkdir(parents=True, exist_ok=True)
        self.changes = ListChanges()
        self.recordings = recording_store(settings.recordings_dir)
        self.policies = policy_store(settings.policies_dir)
        self.demonstrations = demonstration_store(settings.recordings_dir)
        self.runs = RunQueue(settings.runs_dir, self.changes.bump, settings.run_workers)
        self.scene = scene
        self.pipeline = Pipeline(scene)
        self.watch_lock = threading.Lock()
        self.watching: str | None = None  # "policy:<name>" or "run:<id>" being played
        # the last rollout watched of each policy key: (times, q), the oldest watched first
        self.rollouts: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        self.mark_t0: float | None = None  # live demonstration start, recording time (s)

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
        if self.settings.source is not None:
            try:
                self.start_source(self.settings.source)
            except Exception as err:  # the studio still starts: the page shows why
                log.warning("could not start the source %s: %s", self.settings.source, err)
                message = (
                    str(err)
                    if isinstance(err, StudioError)
                    else f"The {self.settings.source} source could not start ({type(err).__name__}: {err}); choose another source."
                )
                self.pipeline.report_error(
                    "simulator" if self.settings.source == "simulator" else "recording", message
                )

    def close(self) -> None:
        """Stop training (keeping partial curves), close a capture cleanly, stop the source."""
        self.runs.close()
        self.pipeline.close()

    # ------------------------------------------------------------------ source

    def start_source(self, source: str) -> None:
        """Start ``"simulator"``, a recording by name, or a recording file by path."""
        if source == "simulator":
            self.set_source(kind="simulator")
            return
        path = Path(source)
        if path.is_file() and path.resolve().parent != self.settings.recordings_dir.resolve():
            from studio.capture import PlaybackSource

            name = self.recordings.stem_of(path.name)
            self.pipeline.set_source(PlaybackSource(path, loop=True), "recording", name)
            return
        name = self.recordings.stem_of(path.name) if path.is_file() else source
        self.set_source(kind="recording", recording=name, loop=True)

    def set_source(
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
        """Build a source of ``kind`` and make it the live one."""
        if kind in ("camera", "hand"):
            from studio.capture import CameraSource, HandSource

            fed = CameraSource if kind == "camera" else HandSource
            self.pipeline.set_source(fed(side or "right"), kind)
            if kind == "hand" and self.scene is not None:
                self.scene.show_hand_handle(self.pipeline.side(), self.hand_moved)
            return
        if self.scene is not None:
            self.scene.show_hand_handle(None, None)
        if kind == "simulator":
            from studio.capture import SimulatorSource

            source = SimulatorSource(seed=seed if seed is not None else 0)
            self.pipeline.set_source(source, kind)
        elif kind == "recording":
            if recording is None:
                raise InvalidError(
                    "recording is missing; give the name of a recording to play back."
                )
            from studio.capture import PlaybackSource

            current = self.pipeline.source
            if (
                self.pipeline.kind == "recording"
                and self.pipeline.recording == recording
                and current is not None
                and current.running
            ):
                # The recording already playing: change its speed and loop in place, so that
                # ticking "loop" never restarts it from 0.
                if speed is not None:
                    current.speed = speed
                if loop is not None:
                    current.loop = loop
                return
            path = self.recordings.path(recording)
            source = PlaybackSource(
                path, speed=speed if speed is not None else 1.0, loop=True if loop is None else loop
            )
            self.pipeline.set_source(source, kind, recording)
        elif kind == "network":
            from studio.capture import NetworkSource

            # Loopback unless the user asked for another address (serve --bridge-host); beyond
            # loopback only frames signed with the studio's token are taken.
            host = self.settings.bridge_host
            token = None if is_loopback(host) else self.settings.token
            source = NetworkSource(host, DEFAULT_PORT if port is None else port, token=token)
            self.pipeline.set_source(source, kind)
        elif kind == "serial":
            if not device:
                raise InvalidError(
                    "device is missing; give the serial device of the tape, for example /dev/ttyUSB0."
                )
            from studio.capture import SerialSource

            path = calibration.strip() if calibration else ""
            try:
                source = SerialSource(device, calibration=path or None)
            except StudioError as err:
                # pyserial missing, a missing or malformed calibration file: the switch happens
                # as for a device that cannot open, with the serial source showing why.
                self.pipeline.report_error(kind, str(err))
                return
            self.pipeline.set_source(source, kind)
        else:  # the schema allows only the kinds above
            raise InvalidError(
                f"kind is {kind!r}; give simulator, recording, network, serial, camera or hand."
            )

    def simulator_reach(self, action: str, goal_deg: list[float]) -> None:
        """Make the simulator reach a robot goal (``goal_deg``, joints 1-3) or wander again.

        Raises:
            ConflictError: the live source is not the simulator.
            ConfigError: the goal is not 3 angles within the Puma560's limits.
        """
        source = self.pipeline.source
        if self.pipeline.kind != "simulator" or source is None:
            raise ConflictError(
                "The live source is not the simulator; switch the source to the simulator first."
            )
        if action == "wander":
            source.wander()
            return
        q = goal_q_robot(goal_deg)
        source.reach(q)
        if self.scene is not None:
            self.scene.set_goal(q)

    def _observe_fed(self, kind: str, *args: Any, **kwargs: Any) -> tuple[Any, Any]:
        """Hand one update to the fed source ``kind`` (camera or hand) and fit it; returns the
        observation and the fit (None when the fit failed: the pipeline's status says why).

        Raises:
            ConflictError: the live source is not ``kind``.
            TooManyRequestsError: a flood (the update is dropped).
        """
        from studio.capture import FloodError

        source = self.pipeline.source
        if self.pipeline.kind != kind or source is None:
            label = "camera" if kind == "camera" else "hand guide"
            raise ConflictError(
                f"The live source is not the {label}; switch the source to {kind} first."
            )
        try:
            observation = source.submit(*args, **kwargs)
        except FloodError as err:
            raise TooManyRequestsError(str(err)) from None
        return observation, self.pipeline.observe(observation)

    def post_landmarks(self, frame: dict[str, Any]) -> dict[str, Any]:
        """Fit and record one frame of landmarks from the page (``LandmarksFrame``).

        Raises:
            ConflictError: the live source is not the camera.
            TooManyRequestsError: a flood (the frame is dropped).
            CaptureError: NaN or wrong sizes (422).
        """
        observation, fitted = self._observe_fed("camera", **frame)
        observable = None if fitted is None else fitted.observable
        warning = fitted.warning if fitted is not None else self.pipeline.status()["error"]
        return {
            "person_detected": observation.person,
            "observable": None if observable is None else [bool(b) for b in observable],
            "warning": warning,
            "q_human": None if fitted is None else [float(x) for x in fitted.q_human],
            "q_robot": None if fitted is None else [float(x) for x in fitted.q_robot],
        }

    def hand_moved(self, position: Any, wxyz: Any = None) -> dict[str, Any]:
        """Move the operator's hand to a pose (``HandTarget``): what dragging the scene's handle
        does. Returns the arm and robot reached (``HandPublic``).

        Raises:
            ConflictError: the live source is not the hand guide.
            TooManyRequestsError: a flood (the update is dropped).
            CaptureError: NaN or wrong sizes (422).
        """
        _, fitted = self._observe_fed("hand", position, wxyz)
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

    def source_public(self) -> dict[str, Any]:
        """``SourcePublic``: the pipeline status plus the playback state."""
        status = self.pipeline.status()
        status["playback"] = None
        source = self.pipeline.source
        if self.pipeline.kind == "recording" and source is not None:
            status["playback"] = _playback_state(source)
        return status

    def playback(self, action: str, t: float | None, speed: float | None) -> None:
        """Play, pause or seek the recording source.

        Raises:
            ConflictError: the live source is not a recording.
        """
        source = self.pipeline.source
        if self.pipeline.kind != "recording" or source is None:
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

    # ------------------------------------------------------------------ capture

    def start_capture(self, name: str | None, operator: str | None, notes: str | None) -> str:
        """Start recording every raw frame of the live source into a new file.

        Raises:
            ConflictError: a capture is already running, or there is no running source.
        """
        from studio.capture import recording_suffix, recording_writer

        if self.pipeline.capture_name is not None:
            raise ConflictError(
                f"Recording {self.pipeline.capture_name!r} is already running; stop it before starting another."
            )
        source = self.pipeline.source
        if source is None:
            raise ConflictError("There is no live source to record; choose a source first.")
        base = name or f"capture-{datetime.now(UTC):%Y%m%d-%H%M%S}"
        if name is not None:
            self.recordings.check_new_name(name)
        final = self.recordings.new_name(base)
        kind = getattr(source, "observation_kind", "tape")
        path = self.settings.recordings_dir / f"{final}{recording_suffix(kind)}"
        writer = recording_writer(
            kind,
            path,
            config=self.pipeline.tape_config(),
            side=self.pipeline.side(),
            operator=operator or "",
            notes=notes or "",
            source=self.pipeline.source_label(),
        )
        self.pipeline.start_capture(writer, final, path)
        self.mark_t0 = None
        self.changes.bump("recordings")
        return final

    def stop_capture(self) -> str:
        """Close the capture cleanly; returns the new recording's name."""
        name, _ = self.pipeline.stop_capture()
        self.mark_t0 = None
        self.changes.bump("recordings")
        return name

    # ------------------------------------------------------------------ demonstrations

    def demonstration_path(self, name: str) -> np.ndarray:
        """The Puma560 joint path ``(N, 6)`` (rad) of a demonstration, for training runs.

        Raises:
            InvalidError: no such demonstration (a bad run parameter, so 422 rather than 404).
        """
        try:
            demo = self.demonstrations.load(name)
        except NotFoundError:
            raise InvalidError(
                f"demonstrations names {name!r}, which does not exist; pick demonstrations from the list."
            ) from None
        return np.asarray(demo.q_robot, dtype=np.float64)

    def cut_demonstration(
        self,
        recording: str,
        t0: float,
        t1: float,
        goal_from_end: bool = False,
        name: str | None = None,
    ) -> str:
        """Cut ``[t0, t1]`` (s) of a recording into a saved demonstration; returns its name.

        Raises:
            InvalidError: the segment is refused (the capture package's reason) or the name is bad.
        """
        from studio.capture import extract_demonstration

        if t1 <= t0:
            raise InvalidError(
                f"The segment ends at {t1:g} s, not after its start at {t0:g} s; give t1 > t0."
            )
        if name is not None:
            self.demonstrations.check_new_name(name)
        path = self.recordings.path(recording)
        final = name or self.demonstrations.new_name(f"{recording}.{t0:.2f}-{t1:.2f}")
        demo = extract_demonstration(
            path,
            t0,
            t1,
            mode=self.pipeline.retarget_mode,
            goal_from_end=goal_from_end,
            name=final,
        )
        tmp = self.settings.recordings_dir / f".cut-{uuid.uuid4().hex}.tmp"
        demo.save(tmp)  # then named without replacing a file that took the name meanwhile
        final = self.demonstrations.claim(tmp, final, exact=name is not None)
        self.changes.bump("demonstrations")
        if self.scene is not None:
            self.scene.show_path(f"demo-{final}", np.asarray(demo.q_robot))
        return final

    def mark_start(self) -> float:
        """Mark the start of a live demonstration (needs a running capture)."""
        t = self.pipeline.capture_time()
        if t is None:
            raise ConflictError(
                "Marking a demonstration needs a running recording; press Record first."
            )
        self.mark_t0 = t
        return t

    def mark_stop(self, goal_from_end: bool, name: str | None) -> str:
        """Cut the marked segment out of the recording being captured."""
        t1 = self.pipeline.capture_time()
        recording = self.pipeline.capture_name
        if t1 is None or recording is None:
            raise ConflictError(
                "Marking a demonstration needs a running recording; press Record first."
            )
        if self.mark_t0 is None:
            raise ConflictError("No demonstration start is marked; mark the start first.")
        t0, self.mark_t0 = self.mark_t0, None
        self.pipeline.flush_capture()
        return self.cut_demonstration(recording, t0, t1, goal_from_end, name)

    def preview_demonstration(self, name: str) -> None:
        """Draw a demonstration's path and play it on the robot."""
        demo = self.demonstrations.load(name)
        if self.scene is not None:
            q = np.asarray(demo.q_robot, dtype=float)
            self.scene.show_path(f"demo-{name}", q)
            self.scene.play_trajectory(np.asarray(demo.times, dtype=float), q)

    # ------------------------------------------------------------------ in-use checks

    def recording_in_use(self, name: str) -> str | None:
        """Why recording ``name`` cannot be deleted or renamed now, or None (a capture by
        another studio on the same data folder counts: its writer's lock says so)."""
        if self.pipeline.kind == "recording" and self.pipeline.recording == name:
            return f"Recording {name!r} is the live source; switch the source to another one first."
        if self.pipeline.capture_name == name:
            return f"Recording {name!r} is being captured; stop the recording first."
        if self.captured_elsewhere(name):
            return f"Recording {name!r} is being captured by another studio or `studio record` on this data folder; stop that capture first."
        return None

    def captured_elsewhere(self, name: str) -> bool:
        """Whether another process (a second studio, ``studio record``) is capturing ``name``."""
        if self.pipeline.capture_name == name:
            return False
        try:
            return being_recorded(self.recordings.path(name))
        except StudioError:  # missing, a link, not a regular file: nobody writes it
            return False

    def policy_in_use(self, key: str) -> bool:
        """Whether the scene is playing this policy (``policy:<name>`` or ``run:<id>``)."""
        return (
            self.watching == key
            and self.scene is not None
            and bool(getattr(self.scene, "playing", False))
        )

    def policy_names(self) -> set[str]:
        """Names taken by uploaded policies and runs (a policy upload must not shadow them)."""
        return set(self.policies.names()) | {run.id for run in self.runs.list()}

    def policy_file(self, run: str | None, policy: str | None) -> tuple[Path, str]:
        """The file of a run's or an uploaded policy and its key (``run:<id>`` or
        ``policy:<name>``); ``policy`` may also name a run, as the policy list does."""
        if (run is None) == (policy is None):
            raise InvalidError("Give either run or policy (exactly one) to choose what to watch.")
        if run is not None:
            r = self.runs.get(run)
            if not r.has_policy:
                raise ConflictError(
                    f"Run {run} has no policy yet; wait until it has finished episodes, then try again."
                )
            return r.policy_path, f"run:{run}"
        assert policy is not None
        if not self.policies.exists(policy):
            try:
                r = self.runs.get(policy)
            except (NotFoundError, InvalidError):
                r = None
            if r is not None and r.has_policy:
                return r.policy_path, f"run:{policy}"
        return self.policies.path(policy), f"policy:{policy}"

    def load_policy(self, run: str | None, policy: str | None) -> tuple[Any, str]:
        """Load the policy of a run or an uploaded policy, of either kind, through the policy
        store's one reader; returns it and its key (see :meth:`policy_file`)."""
        path, key = self.policy_file(run, policy)
        return self.policies.load_file(path), key

    def keep_rollout(self, key: str, times: np.ndarray, q: np.ndarray) -> None:
        """Remember the rollout just watched of policy ``key`` (the last :data:`ROLLOUTS_KEPT`
        policies' are kept) and mark it as playing."""
        with self.watch_lock:
            self.rollouts.pop(key, None)
            self.rollouts[key] = (times, q)
            while len(self.rollouts) > ROLLOUTS_KEPT:
                self.rollouts.pop(next(iter(self.rollouts)))
            self.watching = key

    def forget_rollout(self, key: str) -> None:
        """Drop the rollout of policy ``key`` (its file is gone)."""
        with self.watch_lock:
            self.rollouts.pop(key, None)

    def watched_rollout(self, key: str | None) -> tuple[str, np.ndarray, np.ndarray] | None:
        """The last rollout watched of policy ``key`` (None: of any policy) as ``(key, times,
        q)``, or None."""
        with self.watch_lock:
            if key is None:
                key = next(reversed(self.rollouts), None)
            if key is None or key not in self.rollouts:
                return None
            return (key, *self.rollouts[key])


def _playback_state(source: Any) -> dict[str, Any] | None:
    return {
        "playing": bool(source.running and not source.paused),
        "speed": None if source.speed is None else float(source.speed),
        "t": float(source.position),
        "duration": float(source.duration),
        "loop": bool(source.loop),
    }


def goal_q_robot(goal_deg: list[float]) -> np.ndarray:
    """A Puma560 pose (rad, (6,)) with joints 1-3 at ``goal_deg`` and the wrist at zero.

    Raises:
        ConfigError: not three finite angles within the robot's limits (the learning package's
            one goal check, as for a run).
    """
    q = np.zeros(6)
    q[:GOAL_JOINTS] = np.radians(check_goal_deg(goal_deg))
    return q
