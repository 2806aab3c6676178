"""What every frame source shares: a lifecycle, a producer thread, a bounded queue, a status.

A source runs its producer in its own daemon thread and pushes frames into a bounded queue; the
consumer drains it with :meth:`ThreadedSource.read`. A full queue drops the frame and counts it,
so a stalled consumer never blocks the device. A producer error (a lost connection, a closed
port) ends the thread and is reported in :meth:`ThreadedSource.status`, never raised in it.
"""

from __future__ import annotations

import collections
import math
import queue
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Generic, Protocol, Self, TypeVar, runtime_checkable

from ._errors import CaptureError
from ._observations import Observation

DEFAULT_QUEUE_FRAMES = 4096
"""Frames a source buffers before it drops (37 s at 110 Hz: a consumer may stall that long)."""
RATE_WINDOW_FRAMES = 110
"""Frames over which the measured rate is averaged (one second at 110 Hz)."""
RATE_WINDOW_SECONDS = 1.0
"""Only frames that arrived this recently count towards the rate, so a source that goes quiet
(a paused recording, a silent bridge, a stalled device) reads 0 Hz within a second."""
SLOW_RATE_WINDOW_SECONDS = 5.0
"""A source slower than a frame or two a second (the camera's pose model without a GPU: 1-3
frames a second) is measured over its last frames within this long, while they keep coming at a
steady pace: else it would read 0 Hz between two of its frames."""
SLOW_RATE_STEADY = 3.0
"""The last frames' intervals count as a steady pace when the longest is at most this many times
the shortest (a frame after a pause is not a rate)."""
STOP_JOIN_SECONDS = 2.0
"""How long :meth:`ThreadedSource.stop` waits for the producer thread to end."""


def check_seconds(seconds: float | None, what: str = "--seconds") -> float | None:
    """A duration to capture or stream for: ``None`` (no limit) or a positive, finite number.

    Raises:
        CaptureError: zero, negative, NaN or infinite.
    """
    if seconds is not None and not (seconds > 0 and math.isfinite(seconds)):
        raise CaptureError(
            f"{what} is {seconds:g}; give a positive number of seconds, or leave it out to go on until Ctrl-C."
        )
    return seconds


@dataclass(frozen=True)
class SourceStatus:
    """A snapshot of a source's health.

    Args:
        kind: ``"simulator"``, ``"playback"``, ``"network"`` or ``"serial"``.
        running: whether the producer thread is running.
        rate_hz: measured frame rate over the frames of the last second (0 with fewer than two).
        frames: frames produced so far.
        dropped: frames lost (queue full, checksum errors, gaps in the device's counter).
        error: why the source stopped or delivers no frames (one sentence with the fix), or
            ``None``. A network source keeps listening and clears it when frames come back.
        rejected: malformed input ignored (network datagrams that failed to decode).
        warning: the last non-fatal problem (for example why a datagram was rejected), or ``None``.
    """

    kind: str
    running: bool
    rate_hz: float
    frames: int
    dropped: int
    error: str | None = None
    rejected: int = 0
    warning: str | None = None

    def to_dict(self) -> dict[str, object]:
        """JSON-ready fields."""
        return {
            "kind": self.kind,
            "running": self.running,
            "rate_hz": self.rate_hz,
            "frames": self.frames,
            "dropped": self.dropped,
            "error": self.error,
            "rejected": self.rejected,
            "warning": self.warning,
        }


@runtime_checkable
class FrameSource(Protocol):
    """The lifecycle every source follows; it yields observations of the arm: tape frames
    (:class:`TapeFrame`), landmark frames or hand poses (see :mod:`._observations`)."""

    def start(self) -> None:
        """Start producing frames in the source's own thread."""

    def stop(self) -> None:
        """Stop producing and release the device."""

    def read(self, timeout: float | None = 0.0) -> Sequence[Observation]:
        """All observations since the last call, waiting up to ``timeout`` s for the first one."""

    def status(self) -> SourceStatus:
        """The source's health."""


ObservationT = TypeVar("ObservationT", bound=Observation)
"""The kind of observation a source yields (:class:`TapeFrame`, a landmark frame, a hand pose)."""


def measured_rate(arrivals: Sequence[float], now: float) -> float:
    """Frames per second from arrival times (s, oldest first): over the last second's frames
    (0 with fewer than two, so a source that goes quiet reads 0 Hz within a second), else over
    the last three frames of a slow source that still comes at a steady pace."""
    recent = [t for t in arrivals if t >= now - RATE_WINDOW_SECONDS]
    if len(recent) >= 2:
        return (len(recent) - 1) / (recent[-1] - recent[0]) if recent[-1] > recent[0] else 0.0
    slow = [t for t in arrivals if t >= now - SLOW_RATE_WINDOW_SECONDS][-3:]
    gaps = [b - a for a, b in zip(slow, slow[1:], strict=False)]
    if len(gaps) < 2 or min(gaps) <= 0 or max(gaps) > SLOW_RATE_STEADY * min(gaps):
        return 0.0
    interval = sum(gaps) / len(gaps)
    return 1.0 / interval if now - slow[-1] <= 2.0 * interval else 0.0


class ThreadedSource(Generic[ObservationT]):
    """Base of the sources: subclasses implement :meth:`_produce` (the loop) and ``kind``.

    Args:
        queue_frames: capacity of the frame queue; frames beyond it are dropped and counted.
    """

    kind = "source"
    observation_kind = "tape"
    """What the source yields: ``"tape"``, ``"pose"`` or ``"hand"`` (the recording format)."""

    def __init__(self, queue_frames: int = DEFAULT_QUEUE_FRAMES) -> None:
        if queue_frames < 1:
            raise CaptureError(f"queue_frames is {queue_frames}; give at least 1.")
        self._queue: queue.Queue[ObservationT] = queue.Queue(maxsize=queue_frames)
        self._stop_event = threading.Event()
        self._thread: threading.Thread | None = None
        self._lock = threading.Lock()
        self._frames = 0
        self._dropped = 0
        self._rejected = 0
        self._error: str | None = None
        self._warning: str | None = None
        self._arrivals: collections.deque[float] = collections.deque(maxlen=RATE_WINDOW_FRAMES)

    # lifecycle -------------------------------------------------------------------------------
    def start(self) -> None:
        """Start the producer thread (a no-op if it is running)."""
        if self._thread is not None and self._thread.is_alive():
            return
        self._stop_event.clear()
        self._error = None
        self._open()
        self._thread = threading.Thread(target=self._run, name=f"studio-{self.kind}", daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Ask the producer to stop, wait for it, and release resources."""
        self._stop_event.set()
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(STOP_JOIN_SECONDS)
        self._close()

    def __enter__(self) -> Self:
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    @property
    def running(self) -> bool:
        """Whether the producer thread is alive."""
        return self._thread is not None and self._thread.is_alive()

    def read(self, timeout: float | None = 0.0) -> list[ObservationT]:
        """All frames since the last call.

        Args:
            timeout: seconds to wait for the first frame (0: don't wait; ``None``: wait until a
                frame arrives or the source stops).

        Returns:
            The frames in order, possibly none.
        """
        out: list[ObservationT] = []
        if timeout is None:
            while not out:
                try:
                    out.append(self._queue.get(timeout=0.1))
                except queue.Empty:
                    if not self.running:
                        break
        elif timeout > 0:
            try:
                out.append(self._queue.get(timeout=timeout))
            except queue.Empty:
                return out
        while True:
            try:
                out.append(self._queue.get_nowait())
            except queue.Empty:
                return out

    def status(self) -> SourceStatus:
        """A snapshot of the source's health."""
        with self._lock:
            arrivals = list(self._arrivals)
            frames, dropped, rejected = self._frames, self._dropped, self._rejected
            error, warning = self._error, self._warning
        rate = measured_rate(arrivals, time.monotonic())
        return SourceStatus(
            self.kind, self.running, rate, frames, dropped, error, rejected, warning
        )

    # for subclasses --------------------------------------------------------------------------
    def _open(self) -> None:
        """Acquire the device before the thread starts (raise :class:`CaptureError` if you can't)."""

    def _close(self) -> None:
        """Release the device after the thread ended."""

    def _produce(self) -> None:
        """The producer loop: call :meth:`_push` per frame until :attr:`_stop_event` is set."""
        raise NotImplementedError

    def _run(self) -> None:
        try:
            self._produce()
        except Exception as err:  # a producer must never crash silently: report it in status
            message = str(err) if isinstance(err, CaptureError) else f"{type(err).__name__}: {err}"
            self._fail(message)

    def _record_arrival(self) -> None:
        now = time.monotonic()
        with self._lock:
            self._frames += 1
            self._arrivals.append(now)

    def _push(self, frame: ObservationT) -> None:
        """Queue one frame (or count it dropped when the queue is full)."""
        self._record_arrival()
        try:
            self._queue.put_nowait(frame)
        except queue.Full:
            with self._lock:
                self._dropped += 1

    def _count_dropped(self, n: int = 1) -> None:
        with self._lock:
            self._dropped += n

    def _reject(self, why: str) -> None:
        with self._lock:
            self._rejected += 1
            self._warning = why

    def _fail(self, message: str) -> None:
        with self._lock:
            self._error = message
        self._stop_event.set()
