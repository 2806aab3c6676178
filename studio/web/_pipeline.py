"""The live pipeline: frames from the current source through the kinematics into the scene.

One thread reads the current :class:`studio.capture.FrameSource`; every raw frame goes to the
capture writer (when recording), and frames are turned into poses by the kinematics package's
:class:`studio.kinematics.ArmTracker` (warm-started frame to frame), the same chain demonstration
extraction uses.
The newest pose goes to the scene with ``update_live`` (latest wins, never blocks). When the
kinematics fall behind the stream, only the newest frames of a batch are fitted: the recording
still gets every frame, the scene the newest pose.

Switching sources stops the old one before the new one starts. A source that fails (a dropped
bridge connection, an unplugged serial device) shows its error in :meth:`Pipeline.status` and the
studio keeps running.
"""

from __future__ import annotations

import logging
import threading
import time
from pathlib import Path
from typing import Any

import numpy as np

from studio import StudioError
from studio.kinematics import ArmTracker, TapeConfig, TrackerConfig

from ._errors import ConflictError, storage_sentence

log = logging.getLogger(__name__)

READ_TIMEOUT_S = 0.05
"""How long one read waits for frames, so the thread notices a stop or a source switch quickly."""
MAX_FITS_PER_BATCH = 32
"""At most this many frames of one batch are fitted (the newest); the rest only get recorded."""
IDLE_SLEEP_S = 0.05
"""Sleep between polls when there is no source or it failed."""
ROBOT_JOINTS = 6
FIT_WARNING_AFTER_S = 0.5
"""The arm model must miss the tape by more than the fit's ``max_residual`` for this long (in the
tape's own time) before the user is warned: a tape that lies wrong stays wrong, while sensor noise
and an arm passing through a hard pose last a few frames."""
FIT_WARNING_CLEAR_FRACTION = 0.5
"""Once shown, the warning stays until the residual falls below this fraction of ``max_residual``,
so a residual hovering at the threshold shows one steady warning instead of a flickering one."""


def fit_warning(residual_m: float) -> str:
    """What to tell the user when the arm model cannot follow the tape."""
    return (
        f"The arm model misses the tape by {residual_m * 1000.0:.0f} mm (RMS); check that the "
        "tape lies along the arm and that its shoulder and wrist regions fit this operator."
    )


class FitWatch:
    """Decides, frame by frame, whether the arm fit is bad enough to tell the user.

    The warning is about what it says, the residual: it shows once the residual has stayed above
    the fit's ``max_residual`` for :data:`FIT_WARNING_AFTER_S`, and clears once it falls below
    :data:`FIT_WARNING_CLEAR_FRACTION` of it. The threshold is the fitter's own (one definition,
    :class:`studio.kinematics.FitConfig`), set above what sensor noise gives: a tape with the
    simulator's noise (0.002 rad per angle) is fitted to 2 mm RMS typically and under 13 mm at
    worst. A single frame whose fit misses its landmarks by a millimetre is not a warning.

    Args:
        max_residual: the fit's ``max_residual`` (m).
    """

    def __init__(self, max_residual: float) -> None:
        self.on = float(max_residual)
        self.off = float(max_residual) * FIT_WARNING_CLEAR_FRACTION
        self._above_since: float | None = None
        self.warning: str | None = None

    def update(self, t: float, residual: float) -> str | None:
        """Take the residual (m) of the frame at time ``t`` (s); return the warning to show."""
        if residual > self.on:
            if self._above_since is None or t < self._above_since:  # a looped recording restarts
                self._above_since = t
            if t - self._above_since >= FIT_WARNING_AFTER_S or self.warning is not None:
                self.warning = fit_warning(residual)
            return self.warning
        self._above_since = None
        if self.warning is not None and residual < self.off:
            self.warning = None
        elif self.warning is not None:
            self.warning = fit_warning(residual)
        return self.warning


class Pipeline:
    """The live source, its kinematics, the capture writer, and live demonstration marking.

    Args:
        scene: the :class:`studio.web._scene.StudioScene` to feed, or None (headless, tests).
    """

    def __init__(self, scene: Any = None) -> None:
        self.scene = scene
        self._lock = threading.RLock()
        self._source: Any = None
        self._kind: str | None = None
        self._recording: str | None = None
        self._start_error: str | None = None
        self._mode = "joint"
        self._mirror = True
        self._tracker: ArmTracker | None = None  # the live chain for the source's tape
        self._fit_watch: FitWatch | None = None  # when the tracker's fit is worth a warning
        self._q_human: np.ndarray | None = None
        self._q_robot = np.zeros(ROBOT_JOINTS)
        self._residual: float | None = None
        self._last_t: float | None = None
        self._writer: Any = None
        self._capture_name: str | None = None
        self._capture_path: Path | None = None
        self._capture_frames = 0
        self._capture_rejected = 0  # frames of another tape width, left out of the recording
        self._capture_t0: float | None = None
        self._capture_last_t: float | None = None
        self._kin_error: str | None = None
        self._fit_warning: str | None = None
        self._capture_error: str | None = None  # kept until dismissed: fits never clear it
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
        with self._lock:
            if self._writer is not None:
                self._close_writer()
            self._stop_source()

    # ------------------------------------------------------------------ source

    def set_source(self, source: Any, kind: str, recording: str | None = None) -> None:
        """Switch to ``source`` (already constructed, not started); stops the old one first.

        Raises:
            ConflictError: a capture is running (stop it before switching).
        """
        with self._lock:
            if self._writer is not None:
                raise ConflictError(
                    "A recording is being captured from the current source; stop the recording before switching the source."
                )
            self._stop_source()
            self._kind, self._recording, self._source = kind, recording, source
            self._start_error = None
            self._tracker = None
            self._fit_watch = None
            self._kin_error = None
            self._fit_warning = None
            self._residual = None
            if source is None:
                return
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
            self.set_source(None, kind)  # type: ignore[arg-type]
            self._start_error = message

    def clear_source(self) -> None:
        """Stop the source and run without one."""
        self.set_source(None, None)  # type: ignore[arg-type]

    def _stop_source(self) -> None:
        source = self._source
        self._source = None
        if source is not None:
            try:
                source.stop()
            except Exception:  # a failing device must not keep the studio from switching
                log.exception("stopping the %s source failed", self._kind)

    @property
    def source(self) -> Any:
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
        """Switch the human-to-robot mapping (applies from the next frame)."""
        with self._lock:
            self._mode = mode
            if mirror is not None:
                self._mirror = bool(mirror)
            if self._tracker is not None:
                self._tracker.mode = mode
                self._tracker.mirror = self._mirror

    @property
    def retarget_mode(self) -> str:
        """``"joint"`` or ``"cartesian"``: how the arm is mapped onto the robot now."""
        return self._mode

    def status(self) -> dict[str, Any]:
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
                or self._rejected_warning(),
                "rejected": int(getattr(st, "rejected", 0) or 0) + self._capture_rejected,
                "recording": self._recording,
                "retarget": {"mode": self._mode, "mirror": self._mirror},
                "fit_residual_mm": None if self._residual is None else self._residual * 1000.0,
                "q_robot": [float(x) for x in self._q_robot],
                "recording_active": self._writer is not None,
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

    def start_capture(self, writer: Any, name: str, path: Path) -> None:
        """Send every raw frame to ``writer`` from now on.

        Raises:
            ConflictError: a capture is already running, or there is no running source.
        """
        with self._lock:
            if self._writer is not None:
                writer.close()
                raise ConflictError(
                    f"Recording {self._capture_name!r} is already running; stop it before starting another."
                )
            self._writer, self._capture_name, self._capture_path = writer, name, path
            self._capture_frames = 0
            self._capture_rejected = 0
            self._capture_error = None
            self._capture_t0 = None
            self._capture_last_t = None

    def stop_capture(self) -> tuple[str, Path]:
        """Close the capture file cleanly; returns its name and path.

        Raises:
            ConflictError: no capture is running.
        """
        with self._lock:
            if self._writer is None:
                raise ConflictError("No recording is running; press Record to start one.")
            name, path = self._capture_name, self._capture_path
            self._close_writer()
        assert name is not None and path is not None
        return name, path

    def flush_capture(self) -> None:
        """Write the capture's buffered frames to disk now (for cutting a demonstration)."""
        with self._lock:
            if self._writer is not None and hasattr(self._writer, "flush"):
                self._writer.flush()

    def _close_writer(self) -> None:
        try:
            self._writer.close()
        except Exception as err:  # the file's flushed frames are still there, marked recovered
            log.warning("closing the capture %s failed: %s", self._capture_name, err)
            self._capture_error = self._capture_failure(err)
        self._writer = None
        self._capture_name = None

    def _capture_failure(self, err: Exception) -> str:
        """One sentence for a capture the disk (or the writer) stopped, with the frames kept."""
        kept = getattr(self._writer, "frames_on_disk", self._capture_frames)
        folder = self._capture_path.parent if self._capture_path is not None else Path(".")
        sentence = storage_sentence(
            err, folder.resolve(), f"the recording stopped, {kept} frames kept", "record again"
        )
        if sentence is not None:
            return sentence
        return f"Writing the recording {self._capture_name!r} failed ({err}); it was stopped, its first {kept} frames are kept."

    def dismiss_capture_error(self) -> None:
        """Forget the last capture failure (the user has read it)."""
        with self._lock:
            self._capture_error = None

    def capture_status(self) -> dict[str, Any]:
        """The ``CapturePublic`` fields."""
        with self._lock:
            active = self._writer is not None
            seconds = 0.0
            if active and self._capture_t0 is not None and self._capture_last_t is not None:
                seconds = self._capture_last_t - self._capture_t0
            return {
                "active": active,
                "name": self._capture_name,
                "seconds": round(float(seconds), 3),
                "frames": self._capture_frames if active else 0,
                "rejected": self._capture_rejected,
                "error": self._capture_error,
            }

    def capture_time(self) -> float | None:
        """Seconds since the capture started (in the recording's own time), or None."""
        with self._lock:
            if self._writer is None:
                return None
            if self._capture_t0 is None or self._capture_last_t is None:
                return 0.0
            return self._capture_last_t - self._capture_t0

    @property
    def capture_name(self) -> str | None:
        """Name of the recording being captured, if any."""
        return self._capture_name

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

    def _rejected_warning(self) -> str | None:
        if not self._capture_rejected:
            return None
        return f"{self._capture_rejected} frames of another tape width were left out of the recording; check that one tape sends."

    def _record(self, frames: list[Any]) -> None:
        """Append frames to the capture; a frame of another width than the recording's is left
        out and counted (one odd frame never ends a capture); a failed write ends it, with the
        reason kept in ``capture_status()["error"]`` until dismissed."""
        with self._lock:
            writer = self._writer
            if writer is None:
                return
            regions = getattr(writer, "regions", None)
            if regions is not None:
                fits = [f for f in frames if np.shape(f.bend) == (regions,) == np.shape(f.twist)]
                self._capture_rejected += len(frames) - len(fits)
                frames = fits
                if not frames:
                    return
            try:
                writer.write_many(frames)
            except Exception as err:
                log.warning("writing the capture %s failed: %s", self._capture_name, err)
                self._capture_error = self._capture_failure(err)
                error = self._capture_error
                self._close_writer()  # says nothing more: the writer reported its failure once
                self._capture_error = error
                return
            if self._capture_t0 is None:
                self._capture_t0 = float(frames[0].t)
            self._capture_last_t = float(frames[-1].t)
            self._capture_frames += len(frames)

    def _live_tracker(self) -> tuple[ArmTracker, FitWatch]:
        """The tracker for the current source's tape and its fit watch, built on its first frame."""
        tracker, watch = self._tracker, self._fit_watch
        if tracker is None or watch is None:
            config = TrackerConfig(tape=self.tape_config(), mode=self._mode, mirror=self._mirror)
            tracker = ArmTracker(config)  # the arm the tape is strapped to
            watch = FitWatch(config.fit.max_residual)
            if self.scene is not None:  # and the scene draws that arm following, the tape on it
                self.scene.set_side(config.tape.side)
            self._tracker, self._fit_watch = tracker, watch
        return tracker, watch

    def _fit(self, source: Any, frames: list[Any]) -> None:
        try:
            tracker, watch = self._live_tracker()
            tracked = None
            for frame in frames:
                tracked = tracker.track(frame.bend, frame.twist)
                with self._lock:
                    self._q_human = tracked.q_human
                    self._q_robot = tracked.q_robot
                    self._residual = tracked.residual
                    self._last_t = float(frame.t)
                    self._kin_error = None
                    self._fit_warning = watch.update(float(frame.t), tracked.residual)
            if self.scene is not None and tracked is not None:
                self.scene.update_live(tracked.q_human, tracked.q_robot, tracked.tape_points)
        except StudioError as err:
            with self._lock:
                self._kin_error = str(err)
        except Exception as err:  # e.g. NaN frames from a device: shown, not fatal
            message = f"The arm fit failed on a frame ({type(err).__name__}: {err})."
            if message != self._kin_error:  # log each new problem once, not 110 times a second
                log.exception("the kinematics failed on a frame")
            with self._lock:
                self._kin_error = message
