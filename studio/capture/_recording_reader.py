"""Read a recording back, recover an interrupted one, and explain a malformed one.

Every problem names the file, the line and what is wrong. ``strict=True`` raises the first one as
a :class:`RecordingError`; ``strict=False`` keeps every good frame and lists the problems. A file
without its ``# end`` line is a capture that was interrupted: its flushed frames are kept, an
incomplete last line (a write cut short) is dropped, and the recording is marked ``recovered``.
"""

from __future__ import annotations

import json
import os
import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ._errors import RecordingError
from ._frames import TapeFrame
from ._recording_format import END_PREFIX, FORMAT_NAME, FORMAT_VERSION, HEADER_PREFIX, columns

FIX_HINT = "fix or re-export the file, or read it with strict=False to keep the good frames"
"""Second half of every strict-mode error sentence."""


@dataclass(eq=False)
class Recording:
    """A recording in memory.

    Attributes:
        path: where it was read from.
        meta: the header (see :mod:`._recording_format`).
        t: times (s), ``(N,)``.
        frame: frame counters, ``(N,)``.
        status: switch/trigger bits, ``(N,)``.
        bend: ``(N, regions)`` radians.
        twist: ``(N, regions)`` radians.
        recovered: the capture was interrupted (no ``# end`` line); the flushed frames are here.
        problems: what was skipped when read with ``strict=False`` (``"line 12: ..."``).
        end: the ``# end`` line's data, or ``None``.
    """

    path: Path
    meta: dict[str, Any]
    t: np.ndarray
    frame: np.ndarray
    status: np.ndarray
    bend: np.ndarray
    twist: np.ndarray
    recovered: bool = False
    problems: list[str] = field(default_factory=list)
    end: dict[str, Any] | None = None

    def __len__(self) -> int:
        return int(self.t.shape[0])

    @property
    def regions(self) -> int:
        """Bend/twist regions per frame."""
        return int(self.meta["regions"])

    @property
    def duration(self) -> float:
        """Seconds from the first to the last frame (0 for fewer than two)."""
        return float(self.t[-1] - self.t[0]) if len(self) >= 2 else 0.0

    @property
    def rate_hz(self) -> float:
        """The nominal sample rate from the header."""
        return float(self.meta.get("rate_hz", 0.0))

    @property
    def name(self) -> str:
        """Display name (the header's ``name``, else the file name)."""
        return str(self.meta.get("name") or self.path.name)

    @property
    def config(self) -> Any:
        """The :class:`studio.kinematics.TapeConfig` the header describes."""
        from ._recording_format import tape_config_from_dict

        return tape_config_from_dict(self.meta.get("tape"))

    def frames(self) -> list[TapeFrame]:
        """The frames as :class:`TapeFrame` objects."""
        return [self.frame_at(i) for i in range(len(self))]

    def frame_at(self, index: int) -> TapeFrame:
        """Frame number ``index`` (0-based row) as a :class:`TapeFrame`."""
        return TapeFrame(
            float(self.t[index]),
            int(self.frame[index]),
            self.bend[index].copy(),
            self.twist[index].copy(),
            int(self.status[index]),
        )

    def segment(self, t0: float, t1: float) -> slice:
        """The rows from ``t0`` to ``t1`` seconds after the first frame (inclusive), as a slice."""
        start = float(self.t[0]) if len(self) else 0.0
        lo = int(np.searchsorted(self.t, start + t0, side="left"))
        hi = int(np.searchsorted(self.t, start + t1, side="right"))
        return slice(lo, hi)

    def summary(self) -> dict[str, Any]:
        """JSON-ready facts for listings (``studio info``, the web page)."""
        return {
            "path": str(self.path),
            "name": self.name,
            "frames": len(self),
            "duration": self.duration,
            "regions": self.regions,
            "rate_hz": self.rate_hz,
            "source": self.meta.get("source", ""),
            "operator": self.meta.get("operator", ""),
            "notes": self.meta.get("notes", ""),
            "created": self.meta.get("created", ""),
            "recovered": self.recovered,
            "problems": list(self.problems),
        }


class _Problems:
    def __init__(self, path: Path, strict: bool) -> None:
        self.path, self.strict, self.items = path, strict, []

    def add(self, line: int, what: str) -> None:
        if self.strict:
            raise RecordingError(f"{self.path}, line {line}: {what}; {FIX_HINT}.")
        self.items.append(f"line {line}: {what}")


def read_header(path: str | os.PathLike[str]) -> dict[str, Any]:
    """Only the header of a recording (cheap: for listings).

    Raises:
        RecordingError: the file is not a readable recording.
    """
    path = Path(path)
    try:
        with open(path, "rb") as f:
            first = f.readline()
    except OSError as err:
        raise RecordingError(f"cannot open {path} ({err.strerror}); check the path.") from None
    return _parse_header(path, first.decode("utf-8", errors="replace").rstrip("\n"))


def _parse_header(path: Path, line: str) -> dict[str, Any]:
    if not line.startswith(HEADER_PREFIX):
        raise RecordingError(
            f"{path}, line 1: not a Teach Studio recording (it should start with '{HEADER_PREFIX.strip()}'); open a *.tape.csv file."
        )
    try:
        meta = json.loads(line[len(HEADER_PREFIX) :])
    except json.JSONDecodeError as err:
        raise RecordingError(
            f"{path}, line 1: the header is not valid JSON ({err.msg}); {FIX_HINT}."
        ) from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT_NAME:
        raise RecordingError(
            f"{path}, line 1: the header does not say format '{FORMAT_NAME}'; open a *.tape.csv file."
        )
    version = meta.get("version")
    if not isinstance(version, int) or version < 1 or version > FORMAT_VERSION:
        raise RecordingError(
            f"{path}, line 1: unknown recording version {version!r} (this studio reads 1 to {FORMAT_VERSION}); update Teach Studio."
        )
    regions = meta.get("regions")
    if not isinstance(regions, int) or regions < 1:
        raise RecordingError(
            f"{path}, line 1: the header's regions is {regions!r}; it must be a positive integer."
        )
    return meta


def read_recording(path: str | os.PathLike[str], strict: bool = True) -> Recording:
    """Read a ``*.tape.csv`` recording.

    Args:
        path: the file.
        strict: raise on the first problem (``True``), or keep the good frames and list the
            problems in :attr:`Recording.problems` (``False``).

    Returns:
        The recording; ``recovered`` is true when the capture was interrupted.

    Raises:
        RecordingError: naming the file, the line and the problem (header problems always raise,
            since without a header no frame can be read).
    """
    path = Path(path)
    try:
        raw = path.read_bytes()
    except OSError as err:
        raise RecordingError(f"cannot open {path} ({err.strerror}); check the path.") from None
    try:
        text = raw.decode("utf-8")
        damaged = False
    except UnicodeDecodeError:
        # bytes that are not text: a damaged disk block or a binary file; each line holding
        # them is a problem of its own (U+FFFD cannot occur in a written recording, all ASCII)
        text = raw.decode("utf-8", errors="replace")
        damaged = True
    lines = text.split("\n")
    complete_last = lines[-1] == ""
    if complete_last:
        lines.pop()
    if not lines:
        raise RecordingError(
            f"{path}, line 1: the file is empty, so not a recording; open a *.tape.csv file."
        )
    if damaged and NOT_TEXT in lines[0]:
        raise RecordingError(
            f"{path}, line 1: binary data, so not a recording; open a *.tape.csv file."
        )
    meta = _parse_header(path, lines[0])
    regions = int(meta["regions"])
    expected = columns(regions)
    problems = _Problems(path, strict)
    if len(lines) < 2 or (len(lines) == 2 and not complete_last):
        # the capture died before the column row was complete
        empty = np.zeros((0, regions))
        return Recording(
            path,
            meta,
            np.zeros(0),
            np.zeros(0, np.int64),
            np.zeros(0, np.int64),
            empty,
            empty.copy(),
            True,
            [],
        )
    if lines[1].split(",") != expected:
        raise RecordingError(
            f"{path}, line 2: the column row does not match {regions} regions (expected '{','.join(expected[:5])},...'); {FIX_HINT}."
        )
    end: dict[str, Any] | None = None
    rows: list[str] = []
    row_lines: list[int] = []
    width = len(expected)
    last_index = len(lines) - 1
    for index in range(2, len(lines)):
        line = lines[index]
        number = index + 1
        if line.startswith("#"):
            if line.startswith(END_PREFIX):
                try:
                    end = json.loads(line[len(END_PREFIX) :])
                except json.JSONDecodeError:
                    problems.add(number, "the '# end' line is not valid JSON")
                    end = {}
            continue
        if end is not None:
            problems.add(number, "data after the '# end' line")
            continue
        if index == last_index and not complete_last:
            # a row whose write was cut short by a crash: expected in an interrupted capture
            problems.items.append(
                f"line {number}: incomplete last row (the capture was interrupted); dropped"
            )
            continue
        if not line.strip():
            continue
        if damaged and NOT_TEXT in line:
            problems.add(number, "bytes that are not text (a damaged row)")
            continue
        count = line.count(",") + 1
        if count != width:
            problems.add(
                number,
                f"{count} columns where {width} were expected (a truncated or damaged row)",
            )
            continue
        rows.append(line)
        row_lines.append(number)
    data, row_lines = _to_array(rows, row_lines, width, problems)
    if data.shape[0]:
        finite = np.isfinite(data).all(axis=1)
        integral = (data[:, 1] == np.round(data[:, 1])) & (data[:, 2] == np.round(data[:, 2]))
        good = finite & integral
        for i in np.flatnonzero(~good):
            what = (
                "a NaN or infinite value"
                if not finite[i]
                else "a non-integer frame counter or status"
            )
            problems.add(row_lines[i], what)
        data = data[good]
    if (
        end is not None
        and isinstance(end.get("frames"), int)
        and end["frames"] != data.shape[0]
        and not problems.items
    ):
        problems.add(
            len(lines),
            f"the '# end' line counts {end['frames']} frames but {data.shape[0]} were read",
        )
    r = regions
    return Recording(
        path=path,
        meta=meta,
        t=data[:, 0].copy(),
        frame=data[:, 1].astype(np.int64),
        status=data[:, 2].astype(np.int64),
        bend=data[:, 3 : 3 + r].copy(),
        twist=data[:, 3 + r : 3 + 2 * r].copy(),
        recovered=end is None,
        problems=problems.items,
        end=end,
    )


def _to_array(
    rows: list[str], row_lines: list[int], width: int, problems: _Problems
) -> tuple[np.ndarray, list[int]]:
    if not rows:
        return np.zeros((0, width)), []
    # fast path: numpy's C parser (correctly rounded, so exact reprs come back exactly) over all
    # rows at once, when they hold only number characters and it reads exactly the expected count;
    # anything else takes the slow path, which names the line and the field
    joined = ",".join(rows)
    if _plain(joined):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            try:
                flat = np.fromstring(joined, dtype=np.float64, sep=",")
            except ValueError:
                flat = np.zeros(0)
        if flat.size == len(rows) * width:
            return flat.reshape(len(rows), width), row_lines
    good: list[list[float]] = []
    kept: list[int] = []
    for line, number in zip(rows, row_lines, strict=True):
        fields = line.split(",")
        bad = next((x for x in fields if not _is_number(x)), None)
        if bad is not None:
            problems.add(number, f"'{bad[:20]}' is not a number")
            continue
        good.append([float(x) for x in fields])
        kept.append(number)
    return np.array(good, dtype=np.float64).reshape(-1, width), kept


NOT_TEXT = "\ufffd"
"""What undecodable bytes become when a damaged file is read."""
_NUMBER_BYTES = b"0123456789.,-+eE"
"""The only bytes of a plain data section."""
_NUMBER = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")
"""A decimal number as Python's repr writes it (no spaces, underscores or hex)."""
_NON_FINITE = frozenset({"nan", "inf", "infinity"})
"""Spellings of NaN and infinity, read as such so the row is reported as NaN or infinite."""


def _plain(rows: str) -> bool:
    """Whether rows hold only number characters (else numpy may read 'nan', 'inf' or stop).

    ``bytes.translate`` deletes the allowed bytes in C, a few milliseconds for a long recording.
    """
    try:
        data = rows.encode("ascii")
    except UnicodeEncodeError:
        return False
    return not data.translate(None, _NUMBER_BYTES)


def _is_number(text: str) -> bool:
    """Whether a field is a number in the file's syntax (NaN and infinity included)."""
    return _NUMBER.fullmatch(text) is not None or text.lstrip("+-").lower() in _NON_FINITE
