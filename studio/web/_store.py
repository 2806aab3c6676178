"""The on-disk stores under the data directory: names, uploads, recordings and policies.

Everything a user makes lives in plain files so it survives a restart and can be used without the
studio: ``recordings/*.tape.csv`` (edits of the operator and notes replace the header line
atomically, the frames are never rewritten), ``recordings/*.demo.json``,
``policies/*.policy.npz``. Training runs have their own store in :mod:`studio.web._runs`.

Names are plain file stems (letters, digits, ``-``, ``_``, ``.``; no separators, no ``..``), so a
name from a request can never point outside its folder. New files never replace old ones: an
upload or a new capture whose name is taken gets ``-2``, ``-3``, ... appended.
"""

from __future__ import annotations

import os
import re
import threading
import uuid
from collections.abc import Callable
from datetime import UTC, datetime
from pathlib import Path
from typing import Any, TypeVar

from fastapi import UploadFile

from .._errors import StudioError
from ._errors import ConflictError, InvalidError, NotFoundError, TooLargeError

NAME_PATTERN = re.compile(r"^[A-Za-z0-9_][A-Za-z0-9_.-]{0,99}$")
"""A valid name: 1-100 characters, letters, digits, ``-``, ``_``, ``.``, not starting with ``.``."""
RECORDING_SUFFIX = ".tape.csv"
DEMONSTRATION_SUFFIX = ".demo.json"
POLICY_SUFFIX = ".policy.npz"
SAMPLE_PREFIX = "sample-"
"""Recordings shipped with the repository start with this prefix."""
UPLOAD_CHUNK_BYTES = 1024 * 1024

T = TypeVar("T")


def human_bytes(n: float) -> str:
    """A size as people read it: ``50 MB``, ``1.5 MB``, ``900 kB``, ``120 bytes``."""
    if n >= 1e6:
        return f"{n / 1e6:.3g} MB"
    if n >= 1e3:
        return f"{n / 1e3:.3g} kB"
    return f"{int(n)} bytes"


def check_name(name: str, what: str = "name") -> str:
    """Return ``name`` if it is a plain file stem, else raise a 422 naming the rule."""
    if not isinstance(name, str) or ".." in name or "/" in name or "\\" in name:
        raise InvalidError(
            f"The {what} {name!r} contains a path separator or '..'; use only letters, digits, '-', '_' and '.'."
        )
    if not NAME_PATTERN.match(name):
        raise InvalidError(
            f"The {what} {name!r} is not allowed; use 1 to 100 letters, digits, '-', '_' or '.', not starting with '.'."
        )
    return name


def clean_upload_name(filename: str | None, suffix: str, fallback: str) -> str:
    """The store name for an uploaded file: its stem with odd characters replaced by ``-``.

    A file name holding a path separator or ``..`` is refused (422): browsers send bare names,
    so such a name is a crafted request.
    """
    filename = filename or ""
    if "/" in filename or "\\" in filename or ".." in filename:
        raise InvalidError(
            f"The file name {filename!r} contains a path separator or '..'; upload a file with a plain name."
        )
    stem = filename[: -len(suffix)] if filename.endswith(suffix) else Path(filename).stem
    for extra in (".tape", ".policy", ".demo"):
        stem = stem.removesuffix(extra)
    stem = re.sub(r"[^A-Za-z0-9_.-]+", "-", stem).strip("-.")[:80]
    return stem or fallback


def unique_name(base: str, taken: Callable[[str], bool]) -> str:
    """``base``, or ``base-2``, ``base-3``, ... : the first that is not ``taken``."""
    if not taken(base):
        return base
    k = 2
    while taken(f"{base}-{k}"):
        k += 1
    return f"{base}-{k}"


def atomic_write_text(path: Path, text: str) -> None:
    """Write a small file so that readers see either the old or the new content, never half."""
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:8]}.tmp")
    tmp.write_text(text)
    os.replace(tmp, path)


def now_iso() -> str:
    """The current UTC time, ISO 8601 to the second."""
    return datetime.now(UTC).isoformat(timespec="seconds")


async def receive_upload(upload: UploadFile, folder: Path, limit: int) -> Path:
    """Stream an upload into a hidden temporary file in ``folder``, refusing more than ``limit`` bytes.

    Returns:
        The temporary file; the caller validates it and moves it to its final name (or deletes it).

    Raises:
        TooLargeError: the upload is over ``limit`` (nothing is kept).
    """
    folder.mkdir(parents=True, exist_ok=True)
    tmp = folder / f".upload-{uuid.uuid4().hex}.tmp"
    size = 0
    try:
        with tmp.open("wb") as out:
            while chunk := await upload.read(UPLOAD_CHUNK_BYTES):
                size += len(chunk)
                if size > limit:
                    raise TooLargeError(
                        f"The upload is larger than the limit of {human_bytes(limit)}; upload a smaller file or start the studio with a larger limit."
                    )
                out.write(chunk)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    if size == 0:
        tmp.unlink(missing_ok=True)
        raise InvalidError("The uploaded file is empty; choose a non-empty file.")
    return tmp


class _FileCache:
    """Parsed file summaries, re-read only when a file's size or modification time changes."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        self._entries: dict[Path, tuple[tuple[int, int], Any]] = {}

    def get(self, path: Path, load: Callable[[Path], T]) -> T:
        stat = path.stat()
        key = (stat.st_mtime_ns, stat.st_size)
        with self._lock:
            hit = self._entries.get(path)
        if hit is not None and hit[0] == key:
            return hit[1]
        value = load(path)
        with self._lock:
            self._entries[path] = (key, value)
        return value


class RecordingStore:
    """Recordings ``<data_dir>/recordings/<name>.tape.csv`` with their editable operator and notes."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self._cache = _FileCache()

    def path(self, name: str) -> Path:
        """The file of recording ``name`` (404 if it does not exist)."""
        path = self.folder / f"{check_name(name, 'recording name')}{RECORDING_SUFFIX}"
        if not path.is_file():
            raise NotFoundError(
                f"There is no recording named {name!r}; pick one from the recordings list."
            )
        return path

    def exists(self, name: str) -> bool:
        """Whether a recording of that name exists."""
        return (self.folder / f"{name}{RECORDING_SUFFIX}").exists()

    def names(self) -> list[str]:
        """Every recording's name, samples first, then alphabetical."""
        if not self.folder.is_dir():
            return []
        names = [
            p.name[: -len(RECORDING_SUFFIX)]
            for p in self.folder.glob(f"*{RECORDING_SUFFIX}")
            if NAME_PATTERN.match(p.name[: -len(RECORDING_SUFFIX)])
        ]
        return sorted(names, key=lambda n: (not n.startswith(SAMPLE_PREFIX), n))

    def read(self, name: str) -> Any:
        """The recording as :func:`studio.capture.read_recording` returns it."""
        from studio.capture import read_recording

        return read_recording(self.path(name))

    def info(self, name: str) -> dict[str, Any]:
        """The ``RecordingPublic`` fields of one recording."""
        path = self.path(name)
        return {
            "name": name,
            **self._cache.get(path, _recording_summary),
            "size_bytes": path.stat().st_size,
            "sample": name.startswith(SAMPLE_PREFIX),
        }

    def list(self) -> list[dict[str, Any]]:
        """Every recording's summary (an unreadable file is listed with its error)."""
        out = []
        for name in self.names():
            try:
                out.append(self.info(name))
            except StudioError as err:
                path = self.folder / f"{name}{RECORDING_SUFFIX}"
                out.append(_broken_recording(name, path, str(err)))
            except FileNotFoundError:  # deleted meanwhile
                continue
        return out

    def update(
        self,
        name: str,
        new_name: str | None = None,
        notes: str | None = None,
        operator: str | None = None,
    ) -> str:
        """Rename and/or annotate a recording; returns its (new) name.

        The header is changed by an atomic replace, the frames are never touched
        (:func:`studio.capture.update_recording_meta`); a rename also updates the demonstrations
        that reference the file (:func:`studio.capture.rename_recording`).
        """
        from studio.capture import rename_recording, update_recording_meta

        path = self.path(name)
        if new_name is not None and new_name != name:
            check_name(new_name, "new recording name")
            if self.exists(new_name):
                raise ConflictError(
                    f"A recording named {new_name!r} already exists; choose another name."
                )
        changes = {k: v for k, v in (("notes", notes), ("operator", operator)) if v is not None}
        if changes:
            update_recording_meta(path, **changes)
        if new_name is not None and new_name != name:
            rename_recording(path, new_name)
            return new_name
        return name

    def delete(self, name: str) -> None:
        """Delete a recording."""
        self.path(name).unlink()

    def adopt(self, tmp: Path, filename: str | None) -> str:
        """Validate an uploaded temporary file as a recording and give it a free name.

        Raises:
            InvalidError: a bad file name, or the file is not a readable recording (the
                temporary file is removed either way).
        """
        from studio.capture import read_recording

        try:
            base = clean_upload_name(filename, RECORDING_SUFFIX, "upload")
            try:
                read_recording(tmp)
            except StudioError as err:
                message = str(err).replace(str(tmp), filename or "the upload")
                message = message.replace(tmp.name, filename or "the upload")
                raise InvalidError(
                    f"{filename or 'The upload'} is not a valid Teach Studio recording: {message}"
                ) from None
            except Exception as err:  # a file the reader did not anticipate
                raise InvalidError(
                    f"{filename or 'The upload'} is not a readable Teach Studio recording ({type(err).__name__}); upload a .tape.csv file."
                ) from None
            name = unique_name(base, self.exists)
            os.replace(tmp, self.folder / f"{name}{RECORDING_SUFFIX}")
            return name
        finally:
            tmp.unlink(missing_ok=True)

    def new_name(self, base: str) -> str:
        """A free recording name starting with ``base``."""
        return unique_name(check_name(base, "recording name"), self.exists)


def _recording_summary(path: Path) -> dict[str, Any]:
    from studio.capture import read_recording

    summary = read_recording(path).summary()
    return {
        "frames": int(summary["frames"]),
        "duration": float(summary["duration"]),
        "rate_hz": float(summary["rate_hz"]) if summary.get("rate_hz") else None,
        "created": str(summary.get("created") or ""),
        "operator": str(summary.get("operator") or ""),
        "notes": str(summary.get("notes") or ""),
        "source": str(summary.get("source") or ""),
        "recovered": bool(summary["recovered"]),
        "error": None,
    }


def _broken_recording(name: str, path: Path, error: str) -> dict[str, Any]:
    return {
        "name": name,
        "frames": 0,
        "duration": 0.0,
        "rate_hz": None,
        "created": "",
        "operator": "",
        "notes": "",
        "source": "",
        "recovered": False,
        "error": error,
        "size_bytes": path.stat().st_size if path.exists() else 0,
        "sample": name.startswith(SAMPLE_PREFIX),
    }


class PolicyStore:
    """Uploaded policy files ``<data_dir>/policies/<name>.policy.npz``."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self._cache = _FileCache()

    def path(self, name: str) -> Path:
        """The file of uploaded policy ``name`` (404 if it does not exist)."""
        path = self.folder / f"{check_name(name, 'policy name')}{POLICY_SUFFIX}"
        if not path.is_file():
            raise NotFoundError(f"There is no policy named {name!r}; pick one from the list.")
        return path

    def exists(self, name: str) -> bool:
        """Whether an uploaded policy of that name exists."""
        return (self.folder / f"{name}{POLICY_SUFFIX}").exists()

    def names(self) -> list[str]:
        """Every uploaded policy's name, alphabetical."""
        if not self.folder.is_dir():
            return []
        return sorted(
            p.name[: -len(POLICY_SUFFIX)]
            for p in self.folder.glob(f"*{POLICY_SUFFIX}")
            if NAME_PATTERN.match(p.name[: -len(POLICY_SUFFIX)])
        )

    def load(self, name: str) -> Any:
        """The policy as :func:`studio.learning.load_policy` returns it (cached)."""
        return self.load_file(self.path(name))

    def load_file(self, path: Path) -> Any:
        """Any policy file (a run's too), cached until the file changes."""
        from studio.learning import load_policy

        return self._cache.get(path, load_policy)

    def delete(self, name: str) -> None:
        """Delete an uploaded policy."""
        self.path(name).unlink()

    def adopt(self, tmp: Path, filename: str | None, taken: Callable[[str], bool]) -> str:
        """Validate an uploaded temporary file as a policy and give it a free name.

        Args:
            tmp: the received file.
            filename: the name the browser sent.
            taken: whether a name is used (by an uploaded policy or a run).

        Raises:
            InvalidError: the file is not a readable policy (the temporary file is removed).
        """
        from studio.learning import load_policy

        try:
            base = clean_upload_name(filename, POLICY_SUFFIX, "policy")
            try:
                load_policy(tmp)
            except StudioError as err:
                raise InvalidError(str(err).replace(tmp.name, filename or "The upload")) from None
            name = unique_name(base, taken)
            os.replace(tmp, self.folder / f"{name}{POLICY_SUFFIX}")
            return name
        finally:
            tmp.unlink(missing_ok=True)


def policy_summary(policy: Any) -> dict[str, Any]:
    """The learning-side fields of ``PolicyPublic`` from a loaded policy file."""
    grid = policy.grid
    goal_deg = [float(x) for x in _degrees(grid.angles_of(grid.goal_state))]
    return {
        "grid": grid.to_dict(),
        "goal_deg": goal_deg,
        "planning": policy.config.planning,
        "episodes": int(len(policy.mean_steps)),
        "experiments": int(policy.experiments),
        "created": policy.created,
        "notes": policy.notes,
    }


def _degrees(rad: Any) -> list[float]:
    import numpy as np

    return [round(float(x), 6) for x in np.degrees(rad)]


class DemonstrationStore:
    """Demonstrations ``<data_dir>/recordings/<name>.demo.json`` (next to their recordings)."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self._cache = _FileCache()

    def path(self, name: str) -> Path:
        """The file of demonstration ``name`` (404 if it does not exist)."""
        path = self.folder / f"{check_name(name, 'demonstration name')}{DEMONSTRATION_SUFFIX}"
        if not path.is_file():
            raise NotFoundError(
                f"There is no demonstration named {name!r}; pick one from the demonstrations list."
            )
        return path

    def exists(self, name: str) -> bool:
        """Whether a demonstration of that name exists."""
        return (self.folder / f"{name}{DEMONSTRATION_SUFFIX}").exists()

    def names(self) -> list[str]:
        """Every demonstration's name, alphabetical."""
        if not self.folder.is_dir():
            return []
        return sorted(
            p.name[: -len(DEMONSTRATION_SUFFIX)]
            for p in self.folder.glob(f"*{DEMONSTRATION_SUFFIX}")
            if NAME_PATTERN.match(p.name[: -len(DEMONSTRATION_SUFFIX)])
        )

    def load(self, name: str) -> Any:
        """The demonstration as :mod:`studio.capture` reads it (cached)."""
        path = self.path(name)
        from studio.capture import load_demonstration

        return self._cache.get(path, load_demonstration)

    def info(self, name: str) -> dict[str, Any]:
        """The ``DemonstrationPublic`` fields.

        ``goal`` is the goal bin's centre in degrees (joints of the demonstration's grid);
        ``reaches_goal`` says whether that goal is the default one (false when the goal was set
        from where the demonstration ends).
        """
        import numpy as np

        from studio.learning import ArmGrid

        demo = self.load(name)
        grid = demo.arm_grid()
        default = ArmGrid(
            joints=grid.joints, bins=grid.bins, low_deg=grid.low_deg, high_deg=grid.high_deg
        )
        return {
            "name": name,
            "recording": demo.recording.name.removesuffix(RECORDING_SUFFIX),
            "t0": float(demo.t0),
            "t1": float(demo.t1),
            "steps": max(0, len(demo.grid_path) - 1),
            "goal": [round(float(x), 6) for x in np.degrees(grid.angles_of(grid.goal_state))],
            "reaches_goal": tuple(grid.goal) == tuple(default.goal),
            "created": str(demo.created or ""),
        }

    def detail(self, name: str) -> dict[str, Any]:
        """``DemonstrationDetail``: the summary plus the robot and grid paths."""
        demo = self.load(name)
        return {
            **self.info(name),
            "times": [round(float(t), 6) for t in demo.times],
            "q_robot": [[round(float(x), 6) for x in row] for row in demo.q_robot],
            "grid_path": [int(s) for s in demo.grid_path],
        }

    def list(self) -> list[dict[str, Any]]:
        """Every readable demonstration's summary, newest first."""
        out = []
        for name in self.names():
            try:
                out.append(self.info(name))
            except StudioError:
                continue
        return sorted(out, key=lambda d: (d["created"], d["name"]), reverse=True)

    def delete(self, name: str) -> None:
        """Delete a demonstration file."""
        self.path(name).unlink()

    def new_name(self, base: str) -> str:
        """A free demonstration name starting with ``base``."""
        return unique_name(check_name(base, "demonstration name"), self.exists)
