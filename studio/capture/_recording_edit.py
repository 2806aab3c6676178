"""Edit recordings without ever rewriting one in place.

Every edit writes a complete new file next to the old one, fsyncs it, and swaps it in with
``os.replace`` (atomic on POSIX), so a crash mid-edit leaves either the old or the new file, never
a half-written one. A file under a running capture (its writer holds an ``flock``) is refused.
"""

from __future__ import annotations

import contextlib
import fcntl
import json
import os
import shutil
from collections.abc import Iterator
from datetime import UTC, datetime
from pathlib import Path
from typing import BinaryIO, cast

import numpy as np

from studio import StudioError, read_json

from .._files import atomic_write, atomic_write_text
from ._errors import RecordingError
from ._recording_format import (
    RECORDING_SUFFIX,
    RecordingHeader,
    columns,
    end_line,
    format_row,
    header_line,
    kind_of_name,
)
from ._recording_reader import READ_BLOCK_BYTES, Recording, _first_line, _open
from ._recording_writer import make_folder_of

EDITABLE_KEYS = ("name", "operator", "notes")
"""Header keys :func:`update_recording_meta` may change (the rest describe the data)."""
DEMO_SUFFIX = ".demo.json"
"""File name ending of demonstrations (they reference their recording by file name)."""


def being_recorded(path: str | os.PathLike[str]) -> bool:
    """Whether a :class:`RecordingWriter` is appending to ``path`` right now (it holds the lock).

    Such a file has no ``# end`` line yet, which a reader alone would take for an interrupted
    capture. The lock is seen from any process, so a second studio on the same data folder sees
    the first one's capture too.

    Raises:
        RecordingError: the file does not exist or is not a regular file (a FIFO would block).
    """
    with _open(Path(path)) as f:
        try:
            fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return True
        fcntl.flock(f.fileno(), fcntl.LOCK_UN)
        return False


def _busy_text(path: Path) -> str:
    return (
        f"{path.name} is being recorded right now (by this or another studio on the same data "
        "folder); stop that capture first."
    )


@contextlib.contextmanager
def _not_recording(path: Path) -> Iterator[BinaryIO]:
    """Hold the writers' lock on ``path`` (open for reading) for a change, so no capture can be
    holding the file meanwhile; a capture holding it now is refused."""
    with _open(path) as f:
        try:
            fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            raise RecordingError(_busy_text(path)) from None
        yield f


def delete_recording(path: str | os.PathLike[str]) -> None:
    """Delete a recording's file, refusing one a capture is writing (in any process).

    The check and the unlink happen under the writers' lock, so a capture of another studio on
    the same data folder is never deleted under it. A symbolic link is removed itself, never
    followed.

    Raises:
        RecordingError: a capture is writing the file, or it is not a regular file.
    """
    path = Path(path)
    if path.is_symlink():
        path.unlink()
        return
    with _not_recording(path) as f:
        if os.fstat(f.fileno()).st_ino != os.lstat(path).st_ino:  # replaced meanwhile
            raise RecordingError(f"{path.name} changed while it was being deleted; try again.")
        path.unlink()


def update_recording_meta(path: str | os.PathLike[str], **changes: object) -> RecordingHeader:
    """Change a recording's ``name``, ``operator`` or ``notes`` (atomic replace, data untouched).

    Only line 1 changes; every other byte (frames, the ``# end`` line, or its absence in a
    recovered file) is copied as is.

    Args:
        path: the recording.
        changes: new values for keys in :data:`EDITABLE_KEYS`.

    Returns:
        The new header.

    Raises:
        RecordingError: an unknown key, a non-string value, a bad file, or a capture in progress.
    """
    path = Path(path)
    for key, value in changes.items():
        if key not in EDITABLE_KEYS:
            raise RecordingError(
                f"'{key}' cannot be edited; edit one of {', '.join(EDITABLE_KEYS)}."
            )
        if not isinstance(value, str):
            raise RecordingError(f"{key} must be text, got {type(value).__name__}; give a string.")
    from ._observation_recording import parse_any_header

    with _not_recording(path) as source:
        meta, prefix = parse_any_header(path, _first_line(path, source))
        meta = cast(RecordingHeader, {**meta, **changes})  # keys checked above
        meta["edited"] = datetime.now(UTC).isoformat(timespec="seconds")
        header = header_line(meta, prefix).encode("utf-8")

        def write(out: BinaryIO) -> None:  # the frames are copied as bytes, block by block
            out.write(header)
            shutil.copyfileobj(source, out, READ_BLOCK_BYTES)

        atomic_write(path, write)
    return meta


def rename_recording(path: str | os.PathLike[str], new_name: str) -> Path:
    """Rename a recording's file to ``<new_name>`` and its ending (``.tape.csv``, ``.pose.csv``,
    ``.hand.csv``) and its display name to ``new_name``.

    The header is rewritten (atomic replace) and the file moved without overwriting anything;
    demonstrations in the same folder that reference the old file are updated to the new one.

    Returns:
        The new path.

    Raises:
        RecordingError: a name with a path separator, an existing target, or a capture in progress.
    """
    path = Path(path)
    kind = kind_of_name(path.name)
    suffix = kind.suffix if kind is not None else RECORDING_SUFFIX
    new_name = new_name.removesuffix(suffix).strip()
    if not new_name or "/" in new_name or "\\" in new_name or new_name.startswith("."):
        raise RecordingError(
            f"'{new_name}' is not a usable file name; give a plain name without '/'."
        )
    target = path.with_name(new_name + suffix)
    if target == path:
        update_recording_meta(path, name=new_name)
        return path
    if target.exists():
        raise RecordingError(f"{target} already exists; choose another name.")
    update_recording_meta(path, name=new_name)
    try:
        os.link(path, target)  # fails if the target appeared meanwhile: never overwrite
    except FileExistsError:
        raise RecordingError(f"{target} already exists; choose another name.") from None
    path.unlink()
    for demo in path.parent.glob("*" + DEMO_SUFFIX):
        try:
            data = read_json(demo)
        except StudioError:  # an unreadable demonstration is left as it is
            continue
        if isinstance(data, dict) and data.get("recording") == path.name:
            data["recording"] = target.name
            atomic_write_text(demo, json.dumps(data, indent=1) + "\n")
    return target


def write_recording(
    path: str | os.PathLike[str],
    meta: RecordingHeader,
    t: np.ndarray,
    frame: np.ndarray,
    status: np.ndarray,
    bend: np.ndarray,
    twist: np.ndarray,
    *,
    overwrite: bool = False,
    closed: str | None = None,
) -> Path:
    """Write a whole recording at once (imports, cuts), atomically, with its ``# end`` line.

    ``closed`` (ISO time, default now) goes into the ``# end`` line; a fixed value makes
    regenerated files byte-identical.

    Raises:
        RecordingError: the target exists and ``overwrite`` is false, or the arrays disagree.
    """
    path = Path(path)
    n = len(t)
    regions = int(meta["regions"])
    if (
        bend.shape != (n, regions)
        or twist.shape != (n, regions)
        or len(frame) != n
        or len(status) != n
    ):
        raise RecordingError(
            f"{path}: the frame arrays do not agree on {n} frames of {regions} regions."
        )
    if path.exists() and not overwrite:
        raise RecordingError(f"{path} already exists; choose another file name.")
    make_folder_of(path)
    parts = [header_line(meta), ",".join(columns(regions)) + "\n"]
    parts.extend(format_row(t[i], frame[i], status[i], bend[i], twist[i]) for i in range(n))
    duration = float(t[-1] - t[0]) if n >= 2 else 0.0
    parts.append(end_line(n, duration, closed or datetime.now(UTC).isoformat(timespec="seconds")))
    return atomic_write_text(path, "".join(parts))


def copy_recording(
    recording: Recording, path: str | os.PathLike[str], rows: slice | None = None
) -> Path:
    """Write (a slice of) a recording to a new file, e.g. to repair a recovered one or cut a segment."""
    rows = rows or slice(None)
    meta: RecordingHeader = {**recording.meta, "derived_from": recording.path.name}
    return write_recording(
        path,
        meta,
        recording.t[rows],
        recording.frame[rows],
        recording.status[rows],
        recording.bend[rows],
        recording.twist[rows],
    )
