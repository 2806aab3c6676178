"""Crash-safe recording: append rows, flush and fsync at least every 0.5 s, never rewrite.

The writer holds an advisory ``flock`` on the file while it records, so the editors in
:mod:`._recording_edit` refuse to replace a file under a running capture (the lock dies with the
process, so a killed capture never leaves the file locked).

Rows go straight to the file descriptor (``os.write``, no hidden library buffer), so when the disk
fills up or fails the writer knows exactly which bytes reached the file. It then stops for good:
the file keeps every row written so far and reads back as a recovered recording, and the error
(one sentence with the number of frames kept) is raised once to the caller.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import secrets
import threading
import time
from collections.abc import Sequence
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, Self, cast

from ._errors import RecordingError
from ._observations import Observation, TapeFrame
from ._recording_format import (
    DEFAULT_RATE_HZ,
    DEFAULT_REGIONS,
    FORMAT_NAME,
    FORMAT_VERSION,
    HEADER_PREFIX,
    MAX_REGIONS,
    RECORDING_SUFFIX,
    RecordingHeader,
    columns,
    end_line,
    format_row,
    header_line,
    tape_config_to_dict,
)

if TYPE_CHECKING:
    from studio.kinematics import TapeConfig

DEFAULT_FLUSH_SECONDS = 0.5
"""Longest time a captured frame waits in memory before it is on disk (issue: <= 0.5 s)."""
HEADER_LINES = 2
"""The JSON header line and the column row come before the frames."""


def make_folder_of(path: Path) -> None:
    """Create the folder a new recording goes into: the last level only, so a mistyped path
    (``/nonexistent/dir/x.tape.csv``) makes no tree of folders.

    Raises:
        RecordingError: its parent folder does not exist, or it cannot be created.
    """
    try:
        path.parent.mkdir(exist_ok=True)
    except FileNotFoundError:
        raise RecordingError(
            f"cannot create {path}: the folder {path.parent.parent} does not exist; create it first, or choose another place."
        ) from None
    except OSError as err:
        raise RecordingError(
            f"cannot create {path} ({err.strerror or err}); choose a writable folder."
        ) from None


def recording_meta(
    regions: int,
    *,
    tape: TapeConfig | dict[str, object] | None = None,
    operator: str = "",
    notes: str = "",
    name: str = "",
    rate_hz: float = DEFAULT_RATE_HZ,
    source: str = "",
    created: str | None = None,
    **extra: object,
) -> RecordingHeader:
    """The header dict of a new recording (see :mod:`._recording_format`).

    Raises:
        RecordingError: ``regions`` is outside 1 to :data:`MAX_REGIONS` (no reader would open
            the file).
    """
    if isinstance(regions, bool) or not 1 <= int(regions) <= MAX_REGIONS:
        raise RecordingError(
            f"a tape of {regions!r} regions cannot be recorded; give 1 to {MAX_REGIONS} regions."
        )
    meta: RecordingHeader = {
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
    }
    return cast(RecordingHeader, {**meta, **extra}) if extra else meta


def _create_locked(path: Path) -> int:
    """Create ``path`` for appending, already holding the writers' ``flock``.

    The file is made under a hidden name, locked, then given its name by a hard link (which
    never replaces a file), so no other process (a second studio on the same folder) ever sees it
    unlocked and takes it for an interrupted capture it may delete.
    """
    tmp = path.with_name(f".{path.name}.{secrets.token_hex(4)}.tmp")
    make_folder_of(path)
    try:
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_APPEND, 0o644)
    except OSError as err:
        raise RecordingError(
            f"cannot create {path} ({err.strerror}); choose a writable folder."
        ) from None
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        os.link(tmp, path)
    except FileExistsError:
        os.close(fd)
        raise RecordingError(
            f"{path} already exists; choose another file name (recordings are never overwritten)."
        ) from None
    except OSError as err:
        os.close(fd)
        raise RecordingError(
            f"cannot create {path} ({err.strerror}); choose a writable folder."
        ) from None
    finally:
        tmp.unlink(missing_ok=True)
    return fd


class AppendWriter:
    """The crash-safe appender every recording format shares (see the module docstring).

    A subclass builds its header dict and column names, calls :meth:`_open`, and turns
    observations into rows in :meth:`_rows`; buffering, the 0.5 s flush, fsync, the lock, the
    ``# end`` line and the one-time error report are here, once.

    Attributes:
        path: the file.
        meta: its header.
        flush_seconds: longest time a row stays in memory.
    """

    suffix = RECORDING_SUFFIX

    def _open(
        self,
        path: Path,
        meta: RecordingHeader,
        column_names: list[str],
        flush_seconds: float,
        prefix: str = HEADER_PREFIX,
    ) -> None:
        """Create the file (never over an existing one), lock it and write its first two lines.

        Raises:
            RecordingError: the file exists or cannot be created, or the disk refuses the header.
        """
        self.path = path
        self.meta = meta
        if flush_seconds <= 0:
            raise RecordingError(f"flush_seconds is {flush_seconds}; give a positive number.")
        self.flush_seconds = float(flush_seconds)
        self._fd = _create_locked(self.path)
        self._lock = threading.Lock()
        self._buffer: list[str] = [header_line(meta, prefix), ",".join(column_names) + "\n"]
        self._frames = 0
        self._lines_on_disk = 0
        self._first_t: float | None = None
        self._last_t: float | None = None
        self._closed = False
        self._error: str | None = None
        self._error_cause = ""
        self._error_reported = False
        self._last_flush = time.monotonic()
        self._flush_locked()
        if self._error is not None:
            if self._lines_on_disk < HEADER_LINES:  # not even the header fits: leave no file
                self.path.unlink(missing_ok=True)
                self._error = (
                    f"cannot start {self.path} ({self._error_cause}); free disk space or record "
                    "to another disk."
                )
            self._check()
        self._stop = threading.Event()
        self._flusher = threading.Thread(
            target=self._flush_loop, name="studio-recorder", daemon=True
        )
        self._flusher.start()

    def _rows(self, observations: Sequence[Observation]) -> list[str]:
        """The CSV rows of ``observations`` (raise :class:`RecordingError` for one that does not
        belong in this file)."""
        raise NotImplementedError

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

    @property
    def frames_on_disk(self) -> int:
        """Frames whose rows are completely written to the file (the rest are still buffered)."""
        return min(max(0, self._lines_on_disk - HEADER_LINES), self._frames)

    @property
    def error(self) -> str | None:
        """Why writing stopped (a full or failing disk), or ``None``."""
        return self._error

    def write(self, frame: Observation) -> None:
        """Append one observation."""
        self.write_many((frame,))

    def write_many(self, frames: Sequence[Observation]) -> None:
        """Append observations in order (flushing to disk when the last flush is ``flush_seconds``
        old).

        Raises:
            RecordingError: the writer is closed, an observation does not fit the file (a tape
                frame of another width), or the disk is full or failing (the rows written before
                are kept in the file).
        """
        if not frames:
            return
        rows = self._rows(frames)
        with self._lock:
            self._check()
            if self._closed:
                raise RecordingError(f"{self.path} is closed; open a new writer to record more.")
            self._buffer.extend(rows)
            self._frames += len(rows)
            if self._first_t is None:
                self._first_t = frames[0].t
            self._last_t = frames[-1].t
            if time.monotonic() - self._last_flush >= self.flush_seconds:
                self._flush_locked()
                self._check()

    def flush(self) -> None:
        """Write and fsync everything buffered now.

        Raises:
            RecordingError: the disk is full or failing (the frames written before are kept).
        """
        with self._lock:
            if not self._closed:
                self._flush_locked()
            self._check()

    def close(self) -> Path:
        """Flush, write the ``# end`` line and close. Idempotent.

        After a write failure the file is left as it is (it reads back as a recovered recording);
        the failure is raised here only if no earlier call reported it (it happened in the
        background flusher), so the caller hears of it exactly once.

        Returns:
            The recording's path.

        Raises:
            RecordingError: the disk is full or failing, and no earlier call said so.
        """
        self._stop.set()
        with self._lock:
            if self._closed:
                return self.path
            if self._error is None:
                closed_at = datetime.now(UTC).isoformat(timespec="seconds")
                self._buffer.append(end_line(self._frames, self.duration, closed_at))
                self._flush_locked()
            self._closed = True
            self._release()
        if self._flusher is not threading.current_thread():
            self._flusher.join(self.flush_seconds * 4)
        if self._error is not None and not self._error_reported:
            self._error_reported = True
            raise RecordingError(self._error)
        return self.path

    def __enter__(self) -> Self:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _check(self) -> None:
        """Raise the write failure, if any, to the caller (who has now been told)."""
        if self._error is not None:
            self._error_reported = True
            raise RecordingError(self._error)

    def _release(self) -> None:
        if self._fd >= 0:
            with contextlib.suppress(OSError):  # the lock goes with the descriptor
                os.close(self._fd)
            self._fd = -1

    def _flush_locked(self) -> None:
        """Write and fsync the buffer; on failure stop for good and keep the message in ``_error``."""
        if self._buffer and self._error is None:
            data = "".join(self._buffer).encode("utf-8")
            self._buffer.clear()
            view = memoryview(data)
            written = 0
            try:
                while written < len(data):
                    n = os.write(self._fd, view[written:])
                    self._lines_on_disk += data.count(b"\n", written, written + n)
                    written += n
                os.fsync(self._fd)
            except OSError as err:
                self._release()
                self._error_cause = err.strerror or str(err)
                kept = self.frames_on_disk
                self._error = (
                    f"cannot write {self.path} ({self._error_cause}); recording stopped with its "
                    f"first {kept} frames on disk ({self._frames - kept} not written): free disk "
                    "space or record to another disk (the file opens as a recovered recording)."
                )
        self._last_flush = time.monotonic()

    def _flush_loop(self) -> None:
        while not self._stop.wait(self.flush_seconds / 2):
            with self._lock:
                if self._closed:
                    return
                if self._buffer and time.monotonic() - self._last_flush >= self.flush_seconds / 2:
                    self._flush_locked()  # a failure waits for the caller's next call
                if self._error is not None:
                    return


class RecordingWriter(AppendWriter):
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
        config: TapeConfig | None = None,
        operator: str = "",
        notes: str = "",
        name: str | None = None,
        rate_hz: float = DEFAULT_RATE_HZ,
        source: str = "",
        flush_seconds: float = DEFAULT_FLUSH_SECONDS,
        extra: dict[str, object] | None = None,
    ) -> None:
        path = Path(path)
        if regions is None:
            regions = int(config.regions) if config is not None else DEFAULT_REGIONS
        self.regions = int(regions)
        stem = path.name.removesuffix(RECORDING_SUFFIX)
        meta = recording_meta(
            self.regions,
            tape=config,
            operator=operator,
            notes=notes,
            name=stem if name is None else name,
            rate_hz=rate_hz,
            source=source,
        )
        if extra:
            meta = cast(RecordingHeader, {**meta, **extra})
        self._open(path, meta, columns(self.regions), flush_seconds)

    def _rows(self, observations: Sequence[Observation]) -> list[str]:
        rows = []
        for frame in observations:
            if not isinstance(frame, TapeFrame):
                raise RecordingError(
                    f"{self.path} records tape frames, not {type(frame).__name__}; record each source into its own file."
                )
            if frame.bend.shape != (self.regions,) or frame.twist.shape != (self.regions,):
                raise RecordingError(
                    f"{self.path}: a frame has {frame.bend.shape[0]} regions but the recording has {self.regions}; record each tape into its own file."
                )
            rows.append(format_row(frame.t, frame.frame, frame.status, frame.bend, frame.twist))
        return rows
