"""The live pipeline: observations from the current source through their fitter into the scene.

One thread reads the current :class:`studio.capture.FrameSource`; every raw observation goes to
the capture writer (when recording), and observations are turned into poses by their kind's
fitter (:func:`studio.capture.fitter_for`: the tape's :class:`studio.kinematics.ArmTracker`, the
landmarks' stream fitter, the hand guide's IK; warm-started observation to observation), the same
chain demonstration extraction uses. Sources fed by calls (the camera, the hand guide) hand each
observation to :meth:`Pipeline.observe`, which fits and records it at once and says what the fit
made of it.
The newest pose goes to the scene as a :class:`LivePose` (``show_live``: latest wins, never
blocks). When the
kinematics fall behind the stream, only the newest frames of a batch are fitted: the recording
still gets every frame, the scene the newest pose.

Switching sources stops the old one before the new one starts. A source that fails (a dropped
bridge connection, an unplugged serial device) shows its error in :meth:`Pipeline.status` and the
studio keeps running.
"""

from __future__ import annotations

import dataclasses
import logging
import threading
import time
from collections.abc import Callable, Sequence
from pathlib import Path

import numpy as np

from studio import StudioError
from studio.capture import (
    Fitted,
    FrameSource,
    Observation,
    ObservationFitter,
    TapeFrame,
    fitter_for,
)
from studio.kinematics import HumanArm, RetargetedPath, Retargeter, RobotArm, TapeConfig

from .._errors import ConflictError
from ..scene import LivePose, LiveScene
from ._planned_playback import PlannedPlayback
from ._recorder import CaptureWriter, Recorder

log = logging.getLogger(__name__)

READ_TIMEOUT_S = 0.05
"""How long one read waits for frames, so the thread notices a stop or a source switch quickly."""
MAX_FITS_PER_BATCH = 32
"""At most this many frames of one batch are fitted (the newest); the rest only get recorded."""
IDLE_SLEEP_S = 0.05
"""Sleep between polls when there is no source or it failed."""
ROBOT_JOINTS = 6


class Pipeline:
    """The live source, its kinematics, and its capture (a :class:`Recorder`).

    Args:
        scene: the :class:`studio.web.scene._scene.StudioScene` to feed, or None (headless, tests).
        on_change: called with ``"recordings"`` whenever a capture adds or finishes a recording
            (the studio's list versions, as the stores and the run queue announce theirs).
    """

    def __init__(
        self, scene: LiveScene | None = None, on_change: Callable[[str], None] | None = None
    ) -> None:
        self.scene = scene
        self._lock = threading.RLock()
        self._fit_lock = threading.Lock()  # one fit at a time (the thread, or a fed source's call)
        self._source: FrameSource | None = None
        self._kind: str | None = None
        self._recording: str | None = None
        self._start_error: str | None = None
        self._mode = "joint"
        self._mirror = True
        self._fitter: ObservationFitter | None = None  # the live chain for the source's kind
        self._arm: RobotArm | None = None  # the robot the live chain drives, when not the Puma560
        self._chosen: RobotArm | None = None  # a robot chosen, driven once drawn (choose_robot)
        self._choosing = False
        self._arm_retargeter: Retargeter | None = None  # the fitted arm onto it (cartesian)
        self._planned = PlannedPlayback()  # a recording played: its path planned over all of it
        self._robot_note: str | None = None  # why it does not follow the hand now
        self._q_human: np.ndarray | None = None
        self._q_robot = np.zeros(ROBOT_JOINTS)
        self._residual: float | None = None
        self._last_t: float | None = None
        self._observable: np.ndarray | None = None  # what the camera's fit could see
        self._recorder = Recorder(self._lock, on_change)
        self._kin_error: str | None = None
        self._fit_warning: str | None = None
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None

    # ------------------------------------------------------------------ lifecycle

    def start(self) -> None:
        """Start the pipeline thread."""
        if self._thread is None:
            self._stop.clear()
            self._thread = threading.Thread(target=self._loop, name="studio-pipeline", daemon=True)
            self._thread.start()

    def close(self) -> None:
        """Stop the capture (closing its file cleanly), the source and the thread."""
        self._stop.set()
        if self._thread is not None:
            self._thread.join(timeout=5.0)
            self._thread = None
        self._planned.close()  # no planning child outlives the studio
        with self._lock:
            self._recorder.close()
            self._stop_source()

    # ------------------------------------------------------------------ source

    def set_source(
        self, source: FrameSource | None, kind: str | None, recording: str | None = None
    ) -> None:
        """Switch to ``source`` (already constructed, not started); stops the old one first.

        Raises:
            ConflictError: a capture is running (stop it before switching).
        """
        with self._lock:
            if self._recorder.active:
                raise ConflictError(
                    "A recording is being captured from the current source; stop the recording before switching the source."
                )
            self._stop_source()
            self._kind, self._recording, self._source = kind, recording, source
            self._start_error = None
            self._fitter = None
            self._arm_retargeter = None
            self._planned.forget()
            self._robot_note = None
            self._observable = None
            self._kin_error = None
            self._fit_warning = None
            self._residual = None
            if source is None:
                return
            if self.scene is not None and getattr(source, "observation_kind", "tape") != "tape":
                self.scene.set_side(self.side(), taped=False)  # no tape to draw from now on
            try:
                source.start()
            except StudioError as err:
                self._start_error = str(err)
            except OSError as err:
                self._start_error = f"The {kind} source could not start ({err.strerror or err}); check the device or port and try again."

    def report_error(self, kind: str, message: str) -> None:
        """Switch to ``kind`` without a source, showing why it could not even be built.

        A failed switch ends the way a source that cannot start does: the old source is
        stopped and ``kind`` is selected with ``message`` as its error, so the server's state,
        the page's selector and the one message shown all name the same source.

        Raises:
            ConflictError: a capture is running (stop it before switching).
        """
        with self._lock:
            self.set_source(None, kind)
            self._start_error = message

    def clear_source(self) -> None:
        """Stop the source and run without one."""
        self.set_source(None, None)

    def _stop_source(self) -> None:
        source = self._source
        self._source = None
        if source is not None:
            try:
                source.stop()
            except Exception:  # a failing device must not keep the studio from switching
                log.exception("stopping the %s source failed", self._kind)

    @property
    def source(self) -> FrameSource | None:
        """The current source object (None without one)."""
        return self._source

    @property
    def kind(self) -> str | None:
        """The current source kind."""
        return self._kind

    @property
    def recording(self) -> str | None:
        """Name of the recording being played back, if the source is a recording."""
        return self._recording

    def set_retarget(self, mode: str, mirror: bool | None) -> None:
        """Switch the human-to-robot mapping (applies from the next frame).

        Raises:
            ConflictError: joint mode for a robot other than the Puma560 (the mode of the
                Puma560, kept for when it is taught again, does not change).
        """
        with self._lock:
            if self._arm is not None and mode == "joint":
                raise ConflictError(
                    f"Joint mode maps the human arm onto the Puma560's joints; the "
                    f"{self._arm.spec.title} follows the hand in cartesian mode: choose cartesian."
                )
            if self._arm is None:
                self._mode = mode
            if mirror is not None:
                self._mirror = bool(mirror)
            if self._fitter is not None:
                self._fitter.mode = self._mode
                self._fitter.mirror = self._mirror
            if self._arm_retargeter is not None:
                self._arm_retargeter.mirror = self._mirror

    def choose_robot(self, arm: RobotArm | None) -> Callable[[], None]:
        """Teach ``arm`` (as :meth:`set_robot`) once it is drawn: it is the robot taught from
        now on (:attr:`robot_name`), while the live chain drives the robot drawn until the
        returned call, which the scene makes once it has drawn ``arm``. Meanwhile the robot drawn
        keeps following the operator, and ``q_robot`` stays its joints."""
        if arm is not None and arm.spec.joint_mode:  # the tracker's own robot, either mode
            arm = None
        with self._lock:
            self._chosen, self._choosing = arm, True

        def drive() -> None:
            with self._lock:
                if not self._choosing or self._chosen is not arm:
                    return  # another robot was chosen meanwhile
            self.set_robot(arm)

        return drive

    def set_robot(self, arm: RobotArm | None) -> None:
        """Teach ``arm`` (None or the ``puma560``: the Puma560, in the chosen mode) from the next
        frame: the fitted human arm is retargeted onto it in cartesian mode
        (:class:`~studio.kinematics.Retargeter`), starting from its home pose."""
        if arm is not None and arm.spec.joint_mode:  # the tracker's own robot, either mode
            arm = None
        with self._fit_lock, self._lock:
            self._chosen, self._choosing = None, False
            self._arm = arm
            self._arm_retargeter = None
            self._planned.forget()
            self._robot_note = None
            self._q_robot = np.zeros(ROBOT_JOINTS) if arm is None else np.array(arm.home)

    def human_reaching(self, q_robot: np.ndarray) -> np.ndarray:
        """The operator's arm pose whose retargeting puts the robot taught at ``q_robot``
        (:meth:`~studio.kinematics.Retargeter.human_reaching`, on a copy of the robot's model so
        the live retargeting is not disturbed)."""
        with self._lock:
            arm, mirror = self._arm, self._mirror
        robot = None if arm is None else arm.scratch_copy()
        retargeter = Retargeter(robot=robot, arm=HumanArm(side=self.side()), mirror=mirror)
        return retargeter.human_reaching(q_robot)

    def plan_note(self) -> str | None:
        """One sentence on the robot's path over the recording played as the source (being
        planned, followed, or why it could not be planned); None for any other source."""
        return self._planned.note()

    @property
    def robot_name(self) -> str:
        """The robot taught (``puma560`` unless another was chosen)."""
        with self._lock:
            arm = self._chosen if self._choosing else self._arm
        return "puma560" if arm is None else arm.name

    @property
    def retarget_mode(self) -> str:
        """``"joint"`` or ``"cartesian"``: how the arm is mapped onto the robot now."""
        return self._mode

    def status(self) -> dict[str, object]:
        """The ``SourcePublic`` fields (without playback, which the state adds)."""
        with self._lock:
            source = self._source
            st = None
            if source is not None:
                try:
                    st = source.status()
                except Exception as err:  # a broken status call is itself a source error
                    self._start_error = f"The source stopped answering ({type(err).__name__}); switch the source again."
            error = self._start_error or (st.error if st is not None else None) or self._kin_error
            return {
                "kind": self._kind,
                "running": bool(st.running) if st is not None else False,
                "rate_hz": float(st.rate_hz) if st is not None else 0.0,
                "frames": int(st.frames) if st is not None else 0,
                "dropped": int(st.dropped) if st is not None else 0,
                "error": error,
                "warning": getattr(st, "warning", None)
                or self._fit_warning
                or self._recorder.rejected_warning(),
                "rejected": int(getattr(st, "rejected", 0) or 0) + self._recorder.rejected,
                "recording": self._recording,
                "retarget": {
                    "mode": self._mode if self._arm is None else "cartesian",
                    "mirror": self._mirror,
                },
                "robot": self.robot_name,
                "robot_warning": self._robot_note,
                "fit_residual_mm": None if self._residual is None else self._residual * 1000.0,
                "q_robot": [float(x) for x in self._q_robot],
                "recording_active": self._recorder.active,
                "side": self.side() if source is not None else None,
                "person_detected": getattr(source, "person_detected", None),
                "observable": None
                if self._observable is None
                else [bool(b) for b in self._observable],
                "camera_fps": getattr(source, "camera_fps", None),
                "model": getattr(source, "model", None),
            }

    def tape_config(self) -> TapeConfig:
        """The tape config of the current source (the default tape when the source has none)."""
        config = getattr(self._source, "config", None)
        return config if config is not None else TapeConfig()

    def source_label(self) -> str:
        """Where frames come from, for a recording's header (``serial:/dev/ttyUSB0``, ...)."""
        source = self._source
        if self._kind == "serial":
            return f"serial:{getattr(source, 'port', '')}"
        if self._kind == "network":
            host, port = getattr(source, "address", ("", 0))
            return f"network:{host}:{port}"
        if self._kind == "recording":
            return f"recording:{self._recording}"
        return self._kind or ""

    def q_robot(self) -> np.ndarray:
        """The newest retargeted robot pose (rad)."""
        with self._lock:
            return self._q_robot.copy()

    def last_time(self) -> float | None:
        """Time stamp of the newest frame."""
        return self._last_t

    # ------------------------------------------------------------------ capture

    def start_capture(self, writer: CaptureWriter, name: str, path: Path) -> None:
        """Send every raw frame to ``writer`` from now on (:meth:`Recorder.start`)."""
        self._recorder.start(writer, name, path)

    def stop_capture(self) -> tuple[str, Path]:
        """Close the capture file cleanly; returns its name and path (:meth:`Recorder.stop`)."""
        return self._recorder.stop()

    def flush_capture(self) -> None:
        """Write the capture's buffered frames to disk now (for cutting a demonstration)."""
        self._recorder.flush()

    def dismiss_capture_error(self) -> None:
        """Forget the last capture failure (the user has read it)."""
        self._recorder.dismiss_error()

    def capture_status(self) -> dict[str, object]:
        """The ``CapturePublic`` fields."""
        return self._recorder.status()

    def capture_time(self) -> float | None:
        """Seconds since the capture started (in the recording's own time), or None."""
        return self._recorder.time()

    @property
    def capture_name(self) -> str | None:
        """Name of the recording being captured, if any."""
        return self._recorder.name

    # ------------------------------------------------------------------ the thread

    def _loop(self) -> None:
        while not self._stop.is_set():
            source = self._source
            if source is None or self._start_error is not None:
                time.sleep(IDLE_SLEEP_S)
                continue
            try:
                frames = source.read(timeout=READ_TIMEOUT_S)
            except StudioError as err:
                with self._lock:
                    if source is self._source:
                        self._start_error = str(err)
                continue
            except Exception as err:  # a source bug must not kill the studio
                log.exception("reading the %s source failed", self._kind)
                with self._lock:
                    if source is self._source:
                        self._start_error = f"The {self._kind} source failed ({type(err).__name__}: {err}); switch the source again."
                continue
            if not frames:
                continue
            self._record(frames)
            if source is self._source:
                self._fit(source, frames[-MAX_FITS_PER_BATCH:])

    def _record(self, frames: Sequence[Observation]) -> None:
        """Append frames to the capture, if one runs (:meth:`Recorder.write`)."""
        self._recorder.write(frames)

    def _live_fitter(
        self, source: FrameSource | None, observation: Observation
    ) -> ObservationFitter:
        """The fitter for the current source's observations, built on its first one."""
        fitter = self._fitter
        if fitter is None:
            tape = self.tape_config()
            side = self.side()
            fitter = fitter_for(
                observation, tape=tape, side=side, mode=self._mode, mirror=self._mirror
            )
            if self.scene is not None:  # the scene draws that arm following (the tape on it)
                self.scene.set_side(side, taped=isinstance(observation, TapeFrame))
            with self._lock:
                if source is self._source:  # not kept for the next source (switched meanwhile)
                    self._fitter = fitter
        return fitter

    def _fit(
        self, source: FrameSource | None, observations: Sequence[Observation]
    ) -> Fitted | None:
        """Fit observations in order and show the newest pose; a failing fit is shown, not fatal."""
        try:
            with self._fit_lock:
                if source is not self._source:
                    # the source was switched while its frames waited for the fit: they belong
                    # to the source before, whose fitter, pose and residual are forgotten
                    return None
                fitter = self._live_fitter(source, observations[0])
                fitted = None
                for observation in observations:
                    fitted = self._onto_arm(fitter.fit(observation), float(observation.t))
                    with self._lock:
                        if source is not self._source:
                            return None  # switched meanwhile (see above)
                        self._q_human = fitted.q_human
                        self._q_robot = fitted.q_robot
                        # a frame the fit could not use (no person in view) has no residual
                        fitted_none = fitted.observable is not None and not fitted.observable.any()
                        self._residual = None if fitted_none else fitted.residual
                        self._observable = fitted.observable
                        self._last_t = float(observation.t)
                        self._kin_error = None
                        self._fit_warning = fitted.warning
            if self.scene is not None and fitted is not None:
                self.scene.show_live(LivePose(fitted.q_human, fitted.q_robot, fitted.tape_points))
            return fitted
        except StudioError as err:
            with self._lock:
                self._kin_error = str(err)
        except Exception as err:  # e.g. NaN frames from a device: shown, not fatal
            message = f"The arm fit failed on a frame ({type(err).__name__}: {err})."
            if message != self._kin_error:  # log each new problem once, not 110 times a second
                log.exception("the kinematics failed on a frame")
            with self._lock:
                self._kin_error = message
        return None

    def _onto_arm(self, fitted: Fitted, t: float) -> Fitted:
        """``fitted`` (the frame at time ``t``) with its robot pose for the robot taught
        (unchanged for the Puma560): retargeted live, or from a recording played as the source,
        its path planned over the whole recording once that is ready
        (:class:`~studio.web.live._planned_playback.PlannedPlayback`)."""
        arm = self._arm
        if arm is None:
            return fitted
        retargeter = self._arm_retargeter
        if retargeter is None:
            human = HumanArm(side=self.side())
            retargeter = Retargeter(robot=arm, arm=human, mirror=self._mirror)
            self._arm_retargeter = retargeter
        q_robot = retargeter.robot_from_human(fitted.q_human)  # kept warm while on the plan
        note = robot_note(arm, retargeter)
        step = retargeter.config.max_joint_step
        planned = self._planned.pose(self._source, arm, self._mirror, t, q_robot, step)
        if planned is not None:
            plan, row = planned
            q_robot, note = plan.q[row].copy(), planned_note(arm, retargeter, plan, row)
        self._robot_note = note
        return dataclasses.replace(fitted, q_robot=q_robot)

    def observe(self, observation: Observation) -> Fitted | None:
        """Fit and record one observation handed in by a fed source (camera, hand guide).

        The recording keeps what the fit saw (a landmark frame's ``observable``). Returns the fit,
        or None when it failed (the reason is in :meth:`status`).
        """
        source = self._source
        if source is None:
            return None
        fitted = self._fit(source, [observation])
        if fitted is not None and fitted.observable is not None:
            observation = dataclasses.replace(observation, observable=fitted.observable)  # type: ignore[type-var]
        self._record([observation])
        return fitted

    def side(self) -> str:
        """The teaching arm: a fed or recorded source's ``side``, else the tape's."""
        side = getattr(self._source, "side", None)
        return str(side) if side in ("right", "left") else self.tape_config().side


def robot_note(arm: RobotArm, retargeter: Retargeter) -> str | None:
    """One sentence when ``arm`` does not follow the hand now: held clear of a self-collision,
    or the hand out of its reach; None while it follows."""
    title = arm.spec.title
    if retargeter.held:
        mm = retargeter.config.clearance * 1000.0
        return (
            f"The {title} holds its last pose: following the hand would bring its links closer "
            f"than {mm:.0f} mm; move the hand back the way it came."
        )
    found = retargeter.last_ik
    error = getattr(found, "position_error", 0.0)
    if found is not None and not found.success and error > retargeter.config.reach_tolerance:
        return _out_of_reach(title, error)
    return _target_note(arm, retargeter)


def planned_note(
    arm: RobotArm, retargeter: Retargeter, plan: RetargetedPath, row: int
) -> str | None:
    """:func:`robot_note` for a frame of a recording's planned path (``plan`` at ``row``): out
    of reach, turning between IK branches, or the hand's target moved (``retargeter`` has just
    worked out the same frame's target)."""
    title = arm.spec.title
    if plan.out_of_reach[row]:
        return _out_of_reach(title, float(plan.position_error[row]))
    if not plan.reached[row]:
        return (
            f"The {title} turns from one of its IK branches to another here, its tool off the "
            "hand's target: planned over the whole recording, it turns where it misses the "
            "fewest frames."
        )
    return _target_note(arm, retargeter)


def _out_of_reach(title: str, error: float) -> str:
    return (
        f"The hand is out of the {title}'s reach: its tool stops {error * 100.0:.0f} cm "
        "short, as near as it gets; bring the hand closer to the shoulder."
    )


def _target_note(arm: RobotArm, retargeter: Retargeter) -> str | None:
    """Why the hand's target is not where the hand is: kept out of the robot's hollow, or drawn
    back into its reach; None when it is."""
    title = arm.spec.title
    if retargeter.pushed_out > retargeter.config.reach_tolerance:
        return (
            f"The hand is straight above or below the shoulder, where the {title} cannot "
            f"reach: its target is kept {retargeter.pushed_out * 100.0:.0f} cm out from the "
            "robot's first axis; move the hand forward to follow it exactly."
        )
    if retargeter.pulled_in > retargeter.config.reach_tolerance:
        return (
            f"The hand is beyond the {title}'s reach: its target is drawn "
            f"{retargeter.pulled_in * 100.0:.0f} cm back into it; bring the hand closer to the "
            "shoulder to follow it exactly."
        )
    return None
