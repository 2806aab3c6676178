"""Crash-safe recording: append rows, flush and fsync at least every 0.5 s, never rewrite.

The writer holds an advisory ``flock`` on the file while it records, so the editors in
:mod:`._recording_edit` refuse to replace a file under a running capture (the lock dies with the
process, so a killed capture never leaves the file locked).
"""

from __future__ import annotations

import fcntl
import os
import threading
import time
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from ._errors import RecordingError
from ._frames import TapeFrame
from ._recording_format import (
    DEFAULT_RATE_HZ,
    DEFAULT_REGIONS,
    FORMAT_NAME,
    FORMAT_VERSION,
    RECORDING_SUFFIX,
    columns,
    end_line,
    format_row,
    header_line,
    tape_config_to_dict,
)

DEFAULT_FLUSH_SECONDS = 0.5
"""Longest time a captured frame waits in memory before it is on disk (issue: <= 0.5 s)."""


def recording_meta(
    regions: int,
    *,
    tape: Any = None,
    operator: str = "",
    notes: str = "",
    name: str = "",
    rate_hz: float = DEFAULT_RATE_HZ,
    source: str = "",
    created: str | None = None,
    **extra: Any,
) -> dict[str, Any]:
    """The header dict of a new recording (see :mod:`._recording_format`)."""
    return {
        "format": FORMAT_NAME,
        "version": FORMAT_VERSION,
        "regions": int(regions),
        "tape": tape_config_to_dict(tape),
        "operator": operator,
        "notes": notes,
        "name": name,
        "rate_hz": float(rate_hz),
        "source": source,
        "created": created or datetime.now(UTC).isoformat(timespec="seconds"),
        **extra,
    }


class RecordingWriter:
    """Append frames to a new ``*.tape.csv`` file, crash-safely.

    Frames are buffered in memory and written, flushed and fsynced by :meth:`write` or by a
    background flusher at least every ``flush_seconds``, so a killed process loses at most that
    much. :meth:`close` writes the ``# end`` line.

    Args:
        path: the new file (must not exist: a recording is never overwritten).
        regions: bend/twist regions per frame (``config.regions`` when ``config`` is given).
        config: the :class:`studio.kinematics.TapeConfig` (stored in the header).
        operator: who wore the tape.
        notes: free text.
        name: display name (default: the file name without ``.tape.csv``).
        rate_hz: nominal sample rate.
        source: where the frames came from (``"simulator"``, ``"serial:/dev/ttyUSB0"``, ...).
        flush_seconds: longest time a frame stays in memory.
        extra: more header keys (JSON-ready).

    Raises:
        RecordingError: the file exists or cannot be created.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        regions: int | None = None,
        *,
        config: Any = None,
        operator: str = "",
        notes: str = "",
        name: str | None = None,
        rate_hz: float = DEFAULT_RATE_HZ,
        source: str = "",
        flush_seconds: float = DEFAULT_FLUSH_SECONDS,
        extra: dict[str, Any] | None = None,
    ) -> None:
        self.path = Path(path)
        if regions is None:
            regions = int(config.regions) if config is not None else DEFAULT_REGIONS
        self.regions = int(regions)
        if flush_seconds <= 0:
            raise RecordingError(f"flush_seconds is {flush_seconds}; give a positive number.")
        self.flush_seconds = float(flush_seconds)
        stem = self.path.name.removesuffix(RECORDING_SUFFIX)
        self.meta = recording_meta(
            self.regions,
            tape=config,
            operator=operator,
            notes=notes,
            name=stem if name is None else name,
            rate_hz=rate_hz,
            source=source,
            **(extra or {}),
        )
        try:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._file = open(self.path, "x", encoding="utf-8", newline="\n")  # noqa: SIM115
        except FileExistsError:
            raise RecordingError(
                f"{self.path} already exists; choose another file name (recordings are never overwritten)."
            ) from None
        except OSError as err:
            raise RecordingError(
                f"cannot create {self.path} ({err.strerror}); choose a writable folder."
            ) from None
        fcntl.flock(self._file.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        self._lock = threading.Lock()
        self._buffer: list[str] = [header_line(self.meta), ",".join(columns(self.regions)) + "\n"]
        self._frames = 0
        self._first_t: float | None = None
        self._last_t: float | None = None
        self._closed = False
        self._last_flush = time.monotonic()
        self._flush_locked()
        self._stop = threading.Event()
        self._flusher = threading.Thread(
            target=self._flush_loop, name="studio-recorder", daemon=True
        )
        self._flusher.start()

    @property
    def frames(self) -> int:
        """Frames written so far."""
        return self._frames

    @property
    def duration(self) -> float:
        """Seconds between the first and the last frame written."""
        if self._first_t is None or self._last_t is None:
            return 0.0
        return self._last_t - self._first_t

    @property
    def closed(self) -> bool:
        """Whether :meth:`close` ran."""
        return self._closed

    def write(self, frame: TapeFrame) -> None:
        """Append one frame."""
        self.write_many((frame,))

    def write_many(self, frames: list[TapeFrame] | tuple[TapeFrame, ...]) -> None:
        """Append frames in order (flushing to disk when the last flush is ``flush_seconds`` old).

        Raises:
            RecordingError: the writer is closed, or a frame has the wrong number of regions.
        """
        if not frames:
            return
        rows = []
        for frame in frames:
            if frame.bend.shape != (self.regions,) or frame.twist.shape != (self.regions,):
                raise RecordingError(
                    f"{self.path}: a frame has {frame.bend.shape[0]} regions but the recording has {self.regions}; record each tape into its own file."
                )
            rows.append(format_row(frame.t, frame.frame, frame.status, frame.bend, frame.twist))
        with self._lock:
            if self._closed:
                raise RecordingError(
                    f"{self.path} is closed; open a new RecordingWriter to record more."
                )
            self._buffer.extend(rows)
            self._frames += len(rows)
            if self._first_t is None:
                self._first_t = frames[0].t
            self._last_t = frames[-1].t
            if time.monotonic() - self._last_flush >= self.flush_seconds:
                self._flush_locked()

    def flush(self) -> None:
        """Write, flush and fsync everything buffered now."""
        with self._lock:
            if not self._closed:
                self._flush_locked()

    def close(self) -> Path:
        """Flush, write the ``# end`` line and close. Idempotent.

        Returns:
            The recording's path.
        """
        self._stop.set()
        with self._lock:
            if self._closed:
                return self.path
            closed_at = datetime.now(UTC).isoformat(timespec="seconds")
            self._buffer.append(end_line(self._frames, self.duration, closed_at))
            self._flush_locked()
            self._closed = True
            self._file.close()
        if self._flusher is not threading.current_thread():
            self._flusher.join(self.flush_seconds * 4)
        return self.path

    def __enter__(self) -> RecordingWriter:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _flush_locked(self) -> None:
        if self._buffer:
            try:
                self._file.write("".join(self._buffer))
                self._file.flush()
                os.fsync(self._file.fileno())
            except OSError as err:
                raise RecordingError(
                    f"cannot write {self.path} ({err.strerror}); free disk space or record elsewhere (the frames flushed so far are safe)."
                ) from None
            self._buffer.clear()
        self._last_flush = time.monotonic()

    def _flush_loop(self) -> None:
        while not self._stop.wait(self.flush_seconds / 2):
            with self._lock:
                if self._closed:
                    return
                if self._buffer and time.monotonic() - self._last_flush >= self.flush_seconds / 2:
                    try:
                        self._flush_locked()
                    except RecordingError:
                        return  # the next write() or close() retries and raises it to the caller
