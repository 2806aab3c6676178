"""Capture: record every raw observation of the live source into a new recording, and mark a
demonstration live while it records."""

from __future__ import annotations

from datetime import UTC, datetime

from .._errors import ConflictError
from .._settings import Settings
from ..live import Pipeline
from ._demonstrations import Demonstrations
from ._store import RecordingStore


class Capture:
    """The capture of a studio (one at a time) and the live demonstration marked in it.

    Args:
        settings: where recordings go.
        pipeline: the live pipeline, whose source is recorded.
        recordings: the recordings (names taken, the new one listed).
        demonstrations: where a marked segment is cut to.
    """

    def __init__(
        self,
        settings: Settings,
        pipeline: Pipeline,
        recordings: RecordingStore,
        demonstrations: Demonstrations,
    ) -> None:
        self.settings = settings
        self.pipeline = pipeline
        self.recordings = recordings
        self.demonstrations = demonstrations
        self.mark_t0: float | None = None  # live demonstration start, recording time (s)

    @property
    def recording(self) -> str | None:
        """The name of the recording being captured, or None."""
        return self.pipeline.capture_name

    def status(self) -> dict[str, object]:
        """The ``CapturePublic`` fields."""
        return self.pipeline.capture_status()

    def start(self, name: str | None, operator: str | None, notes: str | None) -> str:
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
        self.pipeline.start_capture(writer, final, path)  # which announces the new recording
        self.mark_t0 = None
        return final

    def stop(self) -> str:
        """Close the capture cleanly; returns the new recording's name."""
        name, _ = self.pipeline.stop_capture()
        self.mark_t0 = None
        return name

    def dismiss_error(self) -> None:
        """Forget the reason the last capture stopped by itself (the user has read it)."""
        self.pipeline.dismiss_capture_error()

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
        """Cut the marked segment out of the recording being captured; returns the
        demonstration's name."""
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
        return self.demonstrations.cut(recording, t0, t1, goal_from_end, name)
