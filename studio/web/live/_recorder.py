"""The capture of the live source: every raw observation appended to a recording's writer,
counted, and a failed write turned into one sentence with the frames kept.

The pipeline's thread hands each batch it reads to :meth:`Recorder.write`; the studio starts and
stops a capture. The recorder shares the pipeline's lock, so a source is never switched while a
capture starts or runs.
"""

from __future__ import annotations

import logging
import threading
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Protocol

import numpy as np

from studio.capture import Observation

from .._errors import ConflictError, storage_sentence

log = logging.getLogger(__name__)


class CaptureWriter(Protocol):
    """What the pipeline asks of a recording's writer (:class:`studio.capture.AppendWriter`)."""

    path: Path

    def write_many(self, frames: Sequence[Observation]) -> None:
        """Append observations."""

    def flush(self) -> None:
        """Make the written observations durable now."""

    def close(self) -> None:
        """Finish the file cleanly."""


class Recorder:
    """One capture at a time into a recording's writer.

    Args:
        lock: the pipeline's lock, held around every change.
        on_change: called with ``"recordings"`` whenever a capture adds or finishes a recording.
    """

    def __init__(
        self, lock: threading.RLock, on_change: Callable[[str], None] | None = None
    ) -> None:
        self._lock = lock
        self._on_change = on_change
        self._writer: CaptureWriter | None = None
        self._name: str | None = None
        self._path: Path | None = None
        self._frames = 0
        self.rejected = 0  # frames of another tape width, left out of the recording
        self._t0: float | None = None
        self._last_t: float | None = None
        self._error: str | None = None  # kept until dismissed: fits never clear it

    @property
    def active(self) -> bool:
        """Whether a capture runs."""
        return self._writer is not None

    @property
    def name(self) -> str | None:
        """Name of the recording being captured, if any."""
        return self._name

    def start(self, writer: CaptureWriter, name: str, path: Path) -> None:
        """Send every raw frame to ``writer`` from now on.

        Raises:
            ConflictError: a capture is already running.
        """
        with self._lock:
            if self._writer is not None:
                writer.close()
                raise ConflictError(
                    f"Recording {self._name!r} is already running; stop it before starting another."
                )
            self._writer, self._name, self._path = writer, name, path
            self._frames = 0
            self.rejected = 0
            self._error = None
            self._t0 = None
            self._last_t = None
        self._changed()

    def stop(self) -> tuple[str, Path]:
        """Close the capture file cleanly; returns its name and path.

        Raises:
            ConflictError: no capture is running.
        """
        with self._lock:
            if self._writer is None:
                raise ConflictError("No recording is running; press Record to start one.")
            name, path = self._name, self._path
            self.close()
        assert name is not None and path is not None
        return name, path

    def flush(self) -> None:
        """Write the capture's buffered frames to disk now (for cutting a demonstration)."""
        with self._lock:
            if self._writer is not None:
                self._writer.flush()

    def close(self) -> None:
        """Close the writer, if any (a failure to close is kept as the capture's error)."""
        writer = self._writer
        if writer is None:
            return
        try:
            writer.close()
        except Exception as err:  # the file's flushed frames are still there, marked recovered
            log.warning("closing the capture %s failed: %s", self._name, err)
            self._error = self._failure(err)
        self._writer = None
        self._name = None
        self._changed()  # the recording is complete (or kept as far as it got)

    def _changed(self) -> None:
        if self._on_change is not None:
            self._on_change("recordings")

    def _failure(self, err: Exception) -> str:
        """One sentence for a capture the disk (or the writer) stopped, with the frames kept."""
        kept = getattr(self._writer, "frames_on_disk", self._frames)
        folder = self._path.parent if self._path is not None else Path(".")
        sentence = storage_sentence(
            err, folder.resolve(), f"the recording stopped, {kept} frames kept", "record again"
        )
        if sentence is not None:
            return sentence
        return f"Writing the recording {self._name!r} failed ({err}); it was stopped, its first {kept} frames are kept."

    def dismiss_error(self) -> None:
        """Forget the last capture failure (the user has read it)."""
        with self._lock:
            self._error = None

    def status(self) -> dict[str, object]:
        """The ``CapturePublic`` fields."""
        with self._lock:
            active = self._writer is not None
            seconds = 0.0
            if active and self._t0 is not None and self._last_t is not None:
                seconds = self._last_t - self._t0
            return {
                "active": active,
                "name": self._name,
                "seconds": round(float(seconds), 3),
                "frames": self._frames if active else 0,
                "rejected": self.rejected,
                "error": self._error,
            }

    def time(self) -> float | None:
        """Seconds since the capture started (in the recording's own time), or None."""
        with self._lock:
            if self._writer is None:
                return None
            if self._t0 is None or self._last_t is None:
                return 0.0
            return self._last_t - self._t0

    def rejected_warning(self) -> str | None:
        """What the page should know about frames left out of the recording, or None."""
        if not self.rejected:
            return None
        return f"{self.rejected} frames of another tape width were left out of the recording; check that one tape sends."

    def write(self, frames: Sequence[Observation]) -> None:
        """Append frames to the capture; a frame of another width than the recording's is left
        out and counted (one odd frame never ends a capture); a failed write ends it, with the
        reason kept in ``status()["error"]`` until dismissed."""
        with self._lock:
            writer = self._writer
            if writer is None:
                return
            regions = getattr(writer, "regions", None)
            if regions is not None:
                fits = [
                    f
                    for f in frames
                    if np.shape(getattr(f, "bend", None)) == (regions,) == np.shape(f.twist)
                ]
                self.rejected += len(frames) - len(fits)
                frames = fits
                if not frames:
                    return
            try:
                writer.write_many(frames)
            except Exception as err:
                log.warning("writing the capture %s failed: %s", self._name, err)
                self._error = self._failure(err)
                error = self._error
                self.close()  # says nothing more: the writer reported its failure once
                self._error = error
                return
            if self._t0 is None:
                self._t0 = float(frames[0].t)
            self._last_t = float(frames[-1].t)
            self._frames += len(frames)
