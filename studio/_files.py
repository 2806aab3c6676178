"""Bounded file reading: every file the studio reads is checked before anything is allocated.

A path a user names (a calibration, a recording, a policy, a demonstration) may point at a device
(``/dev/zero`` never ends), a FIFO (blocks forever), or a file far larger than anything the studio
writes. :func:`open_regular` refuses all of these before a byte is read, and
:func:`read_bytes_bounded` reads a regular file only when its size is within the caller's limit,
never reading past it even if the file grows meanwhile.
"""

from __future__ import annotations

import os
import stat
import tempfile
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import BinaryIO

from ._errors import StudioError


class FileLimitError(StudioError, ValueError):
    """A file that is not a regular file, cannot be opened, or is larger than its kind allows.

    It is also a :class:`ValueError`, so code that already treats unreadable file contents as a
    ``ValueError`` keeps doing so.
    """


def human_size(n: float) -> str:
    """A byte count as people read it (``50 MB``, ``1.5 kB``, ``120 bytes``)."""
    if n >= 1e9:
        return f"{n / 1e9:.3g} GB"
    if n >= 1e6:
        return f"{n / 1e6:.3g} MB"
    if n >= 1e3:
        return f"{n / 1e3:.3g} kB"
    return f"{int(n)} bytes"


def open_regular(path: str | os.PathLike[str], what: str | None = None) -> BinaryIO:
    """Open ``path`` for binary reading, refusing anything but a regular file.

    The file is opened with ``O_NONBLOCK`` so that a FIFO cannot block the open itself, and its
    type is checked on the open descriptor (no race between the check and the read).

    Args:
        path: the file.
        what: the file as the error sentence names it (default: its path).

    Raises:
        FileLimitError: the file is missing, unreadable, or a device, FIFO, socket or folder.
    """
    path = Path(path)
    what = what or str(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as err:
        raise FileLimitError(f"cannot open {what} ({err.strerror}); check the path.") from None
    try:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):
            kind = "a folder" if stat.S_ISDIR(mode) else "a device, pipe or socket"
            raise FileLimitError(f"{what} is {kind}, not a regular file; give a file.")
        os.set_blocking(fd, True)
        return os.fdopen(fd, "rb")
    except BaseException:
        os.close(fd)
        raise


def read_bytes_bounded(
    path: str | os.PathLike[str], max_bytes: int, what: str | None = None
) -> bytes:
    """The whole content of a regular file of at most ``max_bytes`` bytes.

    Args:
        path: the file.
        max_bytes: the largest size this kind of file can sanely have.
        what: the file as the error sentence names it (default: its path).

    Raises:
        FileLimitError: not a regular file, unreadable, or larger than ``max_bytes``.
    """
    what = what or str(Path(path))
    with open_regular(path, what) as stream:
        size = os.fstat(stream.fileno()).st_size
        if size > max_bytes:
            raise FileLimitError(_too_large(what, size, max_bytes))
        try:
            data = stream.read(max_bytes + 1)  # never more, even if the file grew meanwhile
        except OSError as err:
            raise FileLimitError(f"cannot read {what} ({err.strerror}); check the disk.") from None
    if len(data) > max_bytes:
        raise FileLimitError(_too_large(what, len(data), max_bytes))
    return data


def _too_large(what: str, size: int, limit: int) -> str:
    return (
        f"{what} is {human_size(size)}, more than the {human_size(limit)} such a file can "
        "hold; check that it is the right file."
    )


def _read_umask() -> int:
    """This process's umask (read once, at import, before any thread could race the read)."""
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


_UMASK = _read_umask()


def default_mode(directory: bool = False) -> int:
    """The permission bits a plain ``open()`` (or ``mkdir()``) gives under the process's umask.

    ``tempfile.mkstemp`` and ``mkdtemp`` create private (0600 / 0700) entries; what the studio
    moves into place from them gets this mode, so an export reads like a recording or a run.
    """
    return (0o777 if directory else 0o666) & ~_UMASK


def make_temp_dir(prefix: str, parent: Path) -> Path:
    """A new empty folder in ``parent`` to fill and then rename into place, with the mode of a
    folder made by ``mkdir`` (not ``mkdtemp``'s 0700)."""
    folder = Path(tempfile.mkdtemp(prefix=prefix, dir=parent))
    folder.chmod(default_mode(directory=True))
    return folder


def atomic_write(path: str | os.PathLike[str], write: Callable[[BinaryIO], None]) -> Path:
    """Let ``write`` fill a temporary file next to ``path``, fsync it, and ``os.replace`` it in.

    Readers see either the old or the new content, never half; a crash or an error while writing
    leaves the old file and no temporary file behind. This is the one atomic write of the studio.
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        os.fchmod(fd, default_mode())
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def atomic_write_text(path: str | os.PathLike[str], text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` with :func:`atomic_write`."""
    data = text.encode("utf-8")
    return atomic_write(path, lambda f: f.write(data))


def now_iso() -> str:
    """The current UTC time, ISO 8601 to the second: the stamp every studio file records."""
    return datetime.now(UTC).isoformat(timespec="seconds")
