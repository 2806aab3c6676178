"""Play a recording back as a live source: real time, faster, as fast as possible; loop; seek."""

from __future__ import annotations

import dataclasses
import math
import os
import queue
import threading
import time
from typing import TYPE_CHECKING

import numpy as np

from ._errors import CaptureError
from ._observation_recording import ObservationRecording, read_any_recording
from ._observations import HandPose, LandmarkFrame, TapeFrame
from ._recording_reader import Recording
from ._source import DEFAULT_QUEUE_FRAMES, ThreadedSource

if TYPE_CHECKING:
    from studio.kinematics import TapeConfig

MAX_SLEEP_SECONDS = 0.05
"""Longest single sleep, so pause/seek/stop take effect quickly."""
ROW_TIME_TOLERANCE_S = 1e-6
"""A played frame's time names a recording row within this (s; a loop adds whole passes)."""
PUT_RETRY_SECONDS = 0.1
"""A file is not a live device: when the consumer lags, playback waits (never drops)."""


class PlaybackSource(ThreadedSource[TapeFrame | LandmarkFrame | HandPose]):
    """Replay a recording's observations (tape frames, landmark frames or hand poses, whichever
    the file holds) with their original timing.

    Args:
        recording: a :class:`Recording`, an :class:`ObservationRecording`, or the path of a
            ``*.tape.csv``, ``*.pose.csv`` or ``*.hand.csv`` file.
        speed: playback speed (1.0 real time, 2.0 twice as fast), or ``None`` for as fast as the
            consumer reads.
        loop: start over at the end (times and frame counters keep increasing).
        queue_frames: frames buffered ahead of the consumer (playback waits, never drops).

    Raises:
        CaptureError: a non-positive speed or an empty recording.
        RecordingError: the file cannot be read.
    """

    kind = "playback"

    def __init__(
        self,
        recording: Recording | ObservationRecording | str | os.PathLike[str],
        speed: float | None = 1.0,
        loop: bool = False,
        queue_frames: int = DEFAULT_QUEUE_FRAMES,
    ) -> None:
        super().__init__(queue_frames)
        self.recording = (
            recording
            if isinstance(recording, Recording | ObservationRecording)
            else read_any_recording(recording)
        )
        if len(self.recording) == 0:
            raise CaptureError(
                f"{self.recording.path} holds no frames; play a recording with frames."
            )
        if speed is not None and not speed > 0:
            raise CaptureError(
                f"speed is {speed}; give a positive speed, or None for as fast as possible."
            )
        self.speed = speed
        self.loop = loop
        self._index = 0
        self._cycles = 0
        self._anchor: tuple[float, float] | None = None  # (wall time, recording time)
        self._resume = threading.Event()
        self._resume.set()
        self._control = threading.Lock()
        self._rising: bool | None = None  # whether the recording's times rise (row_at)

    @property
    def config(self) -> TapeConfig | None:
        """The recording's tape config (None for a pose or hand recording)."""
        return self.recording.config

    @property
    def side(self) -> str:
        """The teaching arm (a pose or hand recording's; the tape's for a tape)."""
        return self.recording.side

    @property
    def observation_kind(self) -> str:
        """``"tape"``, ``"pose"`` or ``"hand"``: what the recording holds."""
        rec = self.recording
        return rec.kind.name if isinstance(rec, ObservationRecording) else "tape"

    @property
    def rate_hz(self) -> float:
        """The recording's nominal frame rate."""
        return self.recording.rate_hz

    @property
    def duration(self) -> float:
        """The recording's duration in seconds."""
        return self.recording.duration

    @property
    def position(self) -> float:
        """Recording time (s from its start) of the next frame to play."""
        with self._control:
            i = min(self._index, len(self.recording) - 1)
        return float(self.recording.t[i] - self.recording.t[0])

    @property
    def paused(self) -> bool:
        """Whether playback is paused."""
        return not self._resume.is_set()

    def row_at(self, t: float) -> int | None:
        """The recording's row (0-based) that a frame this source played was read from, by the
        frame's time ``t``: a loop's later passes are shifted by whole passes. None when no row
        has that time (or the recording's times do not rise, so a time names no single row)."""
        rec = self.recording
        if self._rising is None:
            self._rising = bool(np.all(np.diff(rec.t) > 0))
        if not self._rising:
            return None
        start = float(rec.t[0])
        offset = float(t) - start
        lap = rec.duration + (1.0 / rec.rate_hz if rec.rate_hz > 0 else 0.0)
        if self.loop and lap > 0 and offset > rec.duration + ROW_TIME_TOLERANCE_S:
            offset -= lap * math.floor((offset + ROW_TIME_TOLERANCE_S) / lap)
        row = int(rec.t.searchsorted(start + offset - ROW_TIME_TOLERANCE_S))
        if row < len(rec) and abs(float(rec.t[row]) - start - offset) <= ROW_TIME_TOLERANCE_S:
            return row
        return None

    def pause(self) -> None:
        """Hold playback at the current frame."""
        self._resume.clear()

    def resume(self) -> None:
        """Continue after :meth:`pause`."""
        with self._control:
            self._anchor = None
        self._resume.set()

    def seek(self, t: float) -> None:
        """Continue from recording time ``t`` (seconds from the recording's start, clamped)."""
        rec = self.recording
        target = rec.t[0] + min(max(float(t), 0.0), rec.duration)
        with self._control:
            self._index = int(min(rec.t.searchsorted(target, side="left"), len(rec) - 1))
            self._anchor = None

    def _produce(self) -> None:
        rec = self.recording
        n = len(rec)
        period = 1.0 / rec.rate_hz if rec.rate_hz > 0 else 0.0
        while not self._stop_event.is_set():
            if not self._resume.wait(MAX_SLEEP_SECONDS):
                continue
            with self._control:
                i = self._index
                if i >= n:
                    if not self.loop:
                        return
                    self._cycles += 1
                    self._index = i = 0
                    self._anchor = None
                if self.speed is not None and self._anchor is None:
                    self._anchor = (time.monotonic(), float(rec.t[i]))
                anchor = self._anchor
            if self.speed is not None and anchor is not None:
                due = anchor[0] + (rec.t[i] - anchor[1]) / self.speed
                delay = due - time.monotonic()
                if delay > 0:
                    self._stop_event.wait(min(delay, MAX_SLEEP_SECONDS))
                    continue
            frame = rec.frame_at(i)
            if self._cycles:
                shift = self._cycles * (rec.duration + period)
                frame = dataclasses.replace(
                    frame, t=frame.t + shift, frame=frame.frame + self._cycles * n
                )
            if not self._put(frame):
                return
            with self._control:
                if self._index == i:
                    self._index = i + 1

    def _put(self, frame: TapeFrame | LandmarkFrame | HandPose) -> bool:
        while not self._stop_event.is_set():
            try:
                self._queue.put(frame, timeout=PUT_RETRY_SECONDS)
            except queue.Full:
                continue
            self._record_arrival()
            return True
        return False
