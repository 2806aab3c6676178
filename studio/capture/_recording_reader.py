"""Read a recording back, recover an interrupted one, and explain a malformed one.

Every problem names the file, the line and what is wrong. ``strict=True`` raises the first one as
a :class:`RecordingError`; ``strict=False`` keeps every good frame and lists the problems. A file
without its ``# end`` line is a capture that was interrupted: its flushed frames are kept, an
incomplete last line (a write cut short) is dropped, and the recording is marked ``recovered``.
"""

from __future__ import annotations

import os
import re
import warnings
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, BinaryIO, TypeGuard, cast

import numpy as np

from studio import FileLimitError, JSONFileError, loads_json, open_regular

from ._errors import RecordingError
from ._observations import TapeFrame
from ._recording_format import (
    END_PREFIX,
    FIXED_COLUMNS,
    FORMAT_NAME,
    FORMAT_VERSION,
    HEADER_PREFIX,
    MAX_HEADER_BYTES,
    MAX_RATE_HZ,
    MAX_REGIONS,
    RecordingEnd,
    RecordingHeader,
    RecordingSummary,
    columns,
    max_line_bytes,
)

if TYPE_CHECKING:
    from studio.kinematics import TapeConfig

FIX_HINT = "fix or re-export the file, or read it with strict=False to keep the good frames"
"""Second half of every strict-mode error sentence."""
READ_BLOCK_BYTES = 1024 * 1024
"""Bytes read at a time: memory beyond the frames themselves stays about this size."""


class RecordingTimeline:
    """What every recording kind shares: a path, a header, times and the rows of a segment.

    Subclasses are dataclasses with ``path``, ``meta``, ``t``, ``recovered``, ``problems``,
    ``warnings`` and :meth:`frame_at`.
    """

    path: Path
    meta: RecordingHeader
    t: np.ndarray
    recovered: bool
    problems: list[str]
    warnings: list[str]
    kind_name = "tape"
    """What the recording holds: ``"tape"``, ``"pose"`` or ``"hand"`` (the summary's ``kind``)."""

    def __len__(self) -> int:
        return int(self.t.shape[0])

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

    def segment(self, t0: float, t1: float) -> slice:
        """The rows from ``t0`` to ``t1`` seconds after the first frame (inclusive), as a slice."""
        start = float(self.t[0]) if len(self) else 0.0
        lo = int(np.searchsorted(self.t, start + t0, side="left"))
        hi = int(np.searchsorted(self.t, start + t1, side="right"))
        return slice(lo, hi)

    def summary(self) -> RecordingSummary:
        """JSON-ready facts for listings (``studio info``, the web page)."""
        return _summary(
            self.path,
            self.meta,
            len(self),
            self.duration,
            self.recovered,
            self.problems,
            self.warnings,
            self.kind_name,
        )


@dataclass(eq=False)
class Recording(RecordingTimeline):
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
        warnings: what loads but looks wrong: negative times, or times that go backwards (a
            sender's clock that jumped); the frames are kept as they are.
    """

    path: Path
    meta: RecordingHeader
    t: np.ndarray
    frame: np.ndarray
    status: np.ndarray
    bend: np.ndarray
    twist: np.ndarray
    recovered: bool = False
    problems: list[str] = field(default_factory=list)
    end: RecordingEnd | None = None
    warnings: list[str] = field(default_factory=list)

    @property
    def regions(self) -> int:
        """Bend/twist regions per frame."""
        return int(self.meta["regions"])

    @property
    def config(self) -> TapeConfig:
        """The :class:`studio.kinematics.TapeConfig` the header describes."""
        from ._recording_format import tape_config_from_dict

        return tape_config_from_dict(self.meta.get("tape"))

    @property
    def side(self) -> str:
        """The teaching arm: the one the tape is strapped to."""
        return self.config.side

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


class _Problems:
    def __init__(self, path: Path, strict: bool) -> None:
        self.path, self.strict = path, strict
        self.items: list[str] = []

    def add(self, line: int, what: str) -> None:
        if self.strict:
            raise RecordingError(f"{self.path}, line {line}: {what}; {FIX_HINT}.")
        self.items.append(f"line {line}: {what}")


def read_header(path: str | os.PathLike[str]) -> RecordingHeader:
    """Only the header of a recording (cheap: for listings; reads at most one bounded line).

    Raises:
        RecordingError: the file is not a readable recording.
    """
    path = Path(path)
    with _open(path) as stream:
        return _parse_header(path, _first_line(path, stream))


def _open(path: Path) -> BinaryIO:
    try:
        return open_regular(path)
    except FileLimitError as err:
        raise RecordingError(str(err)) from None


def _first_line(path: Path, stream: BinaryIO) -> str:
    """Line 1 (without its newline), read without ever buffering more than the header limit."""
    first = stream.readline(MAX_HEADER_BYTES + 1)
    if not first:
        raise RecordingError(
            f"{path}, line 1: the file is empty, so not a recording; open a *.tape.csv file."
        )
    if len(first) > MAX_HEADER_BYTES:
        raise RecordingError(
            f"{path}, line 1: the header is longer than {MAX_HEADER_BYTES:,} bytes, so the file is "
            "damaged or not a recording; open a *.tape.csv file."
        )
    try:
        return first.decode("utf-8").rstrip("\n")
    except UnicodeDecodeError:
        raise RecordingError(
            f"{path}, line 1: binary data, so not a recording; open a *.tape.csv file."
        ) from None


def _parse_header(path: Path, line: str) -> RecordingHeader:
    """The header of line 1, every field checked against its bound before anything uses it."""
    if not line.startswith(HEADER_PREFIX):
        raise RecordingError(
            f"{path}, line 1: not a Teach Studio recording (it should start with '{HEADER_PREFIX.strip()}'); open a *.tape.csv file."
        )
    try:
        meta = loads_json(line[len(HEADER_PREFIX) :], "the header", max_bytes=MAX_HEADER_BYTES)
    except JSONFileError as err:
        raise RecordingError(f"{path}, line 1: {err}") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT_NAME:
        raise RecordingError(
            f"{path}, line 1: the header does not say format '{FORMAT_NAME}'; open a *.tape.csv file."
        )
    version = meta.get("version")
    if not _whole(version) or version < 1 or version > FORMAT_VERSION:
        raise RecordingError(
            f"{path}, line 1: unknown recording version {version!r} (this studio reads 1 to {FORMAT_VERSION}); update Teach Studio."
        )
    regions = meta.get("regions")
    if not _whole(regions) or not 1 <= regions <= MAX_REGIONS:
        raise RecordingError(
            f"{path}, line 1: the header's regions is {_short(regions)}; it must be a whole number from 1 to {MAX_REGIONS}."
        )
    rate = meta.get("rate_hz", 0.0)
    if (
        isinstance(rate, bool)
        or not isinstance(rate, int | float)
        or not 0.0 <= rate <= MAX_RATE_HZ
    ):
        raise RecordingError(
            f"{path}, line 1: the header's rate_hz is {_short(rate)}; it must be a number from 0 to {MAX_RATE_HZ:g}."
        )
    for key in TEXT_KEYS:
        if meta.get(key) is not None and not isinstance(meta[key], str):
            raise RecordingError(
                f"{path}, line 1: the header's {key} is {_short(meta[key])}; it must be text."
            )
    tape = meta.get("tape")
    if tape is not None and (not isinstance(tape, dict) or tape.get("regions", regions) != regions):
        raise RecordingError(
            f"{path}, line 1: the header's tape is {_short(tape)}; it must describe a tape of {regions} regions."
        )
    return cast(RecordingHeader, meta)  # every key it names was checked above


def parse_end(text: str) -> RecordingEnd | None:
    """The data of an ``# end`` line (``text`` without its prefix), or ``None`` when it is not a
    JSON object (every recording kind's one reading)."""
    try:
        end = loads_json(text, "the '# end' line", max_bytes=MAX_HEADER_BYTES)
    except JSONFileError:
        return None
    return cast(RecordingEnd, end) if isinstance(end, dict) else None


def time_warnings(
    negative: int,
    first_negative: str | None,
    backwards: int,
    first_backward: tuple[str, float, float] | None,
) -> list[str]:
    """The sentences for times below zero or going backwards (every recording kind's one wording).

    Args:
        negative: how many frames have a negative time; ``first_negative`` where the first is
            (``"line 12"``).
        backwards: how many times the time goes back; ``first_backward`` where the first is, its
            time and the time before it.
    """
    out = []
    if negative:
        out.append(
            f"{negative} frame{'s' if negative > 1 else ''} with a negative time (first at {first_negative}); the frames are kept as recorded"
        )
    if first_backward is not None:
        where, t, before = first_backward
        out.append(
            f"time goes backwards {backwards} time{'s' if backwards > 1 else ''} (first at {where}: {t:.3f} s after {before:.3f} s), so durations and cuts may be wrong; check the sender's clock"
        )
    return out


def array_time_warnings(t: np.ndarray) -> list[str]:
    """:func:`time_warnings` of a whole column of times (frames counted from 0)."""
    below = np.flatnonzero(t < 0)
    back = np.flatnonzero(np.diff(t) < 0) + 1
    first_back = (
        None if not back.size else (f"frame {back[0]}", float(t[back[0]]), float(t[back[0] - 1]))
    )
    return time_warnings(
        int(below.size), f"frame {below[0]}" if below.size else None, int(back.size), first_back
    )


TEXT_KEYS = ("name", "operator", "notes", "source", "created")
"""Header keys that hold text (a listing shows them as they are)."""


def _whole(value: object) -> TypeGuard[int]:
    return isinstance(value, int) and not isinstance(value, bool)


def _short(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


@dataclass
class _Scan:
    """What one pass over a recording's lines found (rows kept only when asked)."""

    meta: RecordingHeader
    keep_rows: bool = True
    blocks: list[np.ndarray] = field(default_factory=list)
    count: int = 0
    first_t: float | None = None
    last_t: float | None = None
    end: RecordingEnd | None = None
    problems: list[str] = field(default_factory=list)
    negative: int = 0
    first_negative: int | None = None
    backwards: int = 0
    first_backward: tuple[int, float, float] | None = None

    @property
    def warnings(self) -> list[str]:
        """The time checks' findings as sentences (see :attr:`Recording.warnings`)."""
        backward = None
        if self.first_backward is not None:
            line, t, before = self.first_backward
            backward = (f"line {line}", t, before)
        negative = None if self.first_negative is None else f"line {self.first_negative}"
        return time_warnings(self.negative, negative, self.backwards, backward)

    @property
    def duration(self) -> float:
        if self.count < 2 or self.first_t is None or self.last_t is None:
            return 0.0
        return self.last_t - self.first_t


def _scan(path: Path, strict: bool, keep_rows: bool) -> _Scan:
    """Read a recording line by line in blocks, checking each line as :func:`read_recording` says.

    Memory stays bounded by one block plus (when ``keep_rows``) the parsed frames: nothing is
    allocated from what the header claims, and a line longer than any row can be (a hole of zero
    bytes in a sparse file, a binary blob) is skipped without being buffered.
    """
    with _open(path) as stream:
        meta = _parse_header(path, _first_line(path, stream))
        regions = int(meta["regions"])
        expected = columns(regions)
        column_row = ",".join(expected).encode("ascii")
        scan = _Scan(meta, keep_rows)
        second = stream.readline(len(column_row) + 2)
        if not second.endswith(b"\n") and not stream.read(1):
            return scan  # the capture died before the column row was complete
        if second.rstrip(b"\n") != column_row:
            raise RecordingError(
                f"{path}, line 2: the column row does not match {regions} regions (expected '{','.join(expected[:5])},...'); {FIX_HINT}."
            )
        problems = _Problems(path, strict)
        lines = _Lines(stream, max_line_bytes(regions), problems)
        for block, first_number, last_complete in lines:
            _scan_block(block, first_number, last_complete, len(expected), scan, problems)
    frames = scan.end.get("frames") if isinstance(scan.end, dict) else None
    if _whole(frames) and frames != scan.count and not problems.items:
        problems.add(
            lines.number, f"the '# end' line counts {frames} frames but {scan.count} were read"
        )
    scan.problems = problems.items
    return scan


class _Lines:
    """The data lines of an open recording, in blocks of whole lines, never buffering a line
    longer than ``max_line`` bytes (such a line is a problem, skipped as it streams past)."""

    def __init__(self, stream: BinaryIO, max_line: int, problems: _Problems) -> None:
        self.stream, self.max_line, self.problems = stream, max_line, problems
        self.number = 2  # lines before the first data line

    def _overlong(self, size: int) -> None:
        self.number += 1
        self.problems.add(
            self.number,
            f"a line of {size:,} bytes, longer than any row can be (damaged, e.g. a hole of zero bytes)",
        )

    def __iter__(self) -> Iterator[tuple[list[bytes], int, bool]]:
        """Yields ``(lines, number of the first, whether the last one ended with a newline)``."""
        pending = b""
        skipping = 0  # bytes of an overlong line dropped so far
        while True:
            chunk = self.stream.read(READ_BLOCK_BYTES)
            if not chunk:
                break
            if skipping:
                cut = chunk.find(b"\n")
                if cut < 0:
                    skipping += len(chunk)
                    continue
                self._overlong(skipping + cut)
                skipping, chunk = 0, chunk[cut + 1 :]
            data = pending + chunk
            cut = data.rfind(b"\n")
            pending = data[cut + 1 :]
            if cut >= 0:
                lines = data[:cut].split(b"\n")
                yield lines, self.number + 1, True
                self.number += len(lines)
            if len(pending) > self.max_line:
                skipping, pending = len(pending), b""
        if skipping:
            self._overlong(skipping)
        elif pending:
            yield [pending], self.number + 1, False
            self.number += 1


def _scan_block(
    block: list[bytes],
    first_number: int,
    last_complete: bool,
    width: int,
    scan: _Scan,
    problems: _Problems,
) -> None:
    """Check and parse one block of lines into ``scan`` (the rules of :func:`read_recording`)."""
    joined = b"\n".join(block)
    try:
        lines = joined.decode("utf-8").split("\n")
        damaged = False
    except UnicodeDecodeError:
        # bytes that are not text: a damaged disk block or a binary file; each line holding
        # them is a problem of its own (U+FFFD cannot occur in a written recording, all ASCII)
        lines = joined.decode("utf-8", errors="replace").split("\n")
        damaged = True
    rows: list[str] = []
    row_lines: list[int] = []
    last_index = len(lines) - 1
    for index, line in enumerate(lines):
        number = first_number + index
        if line.startswith("#"):
            if line.startswith(END_PREFIX):
                scan.end = parse_end(line[len(END_PREFIX) :])
                if scan.end is None:
                    problems.add(number, "the '# end' line is not valid JSON")
                    scan.end = {}
            continue
        if scan.end is not None:
            problems.add(number, "data after the '# end' line")
            continue
        if index == last_index and not last_complete:
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
    if data.shape[0]:
        _check_times(data[:, 0], np.asarray(row_lines)[good], scan)
        if scan.first_t is None:
            scan.first_t = float(data[0, 0])
        scan.last_t = float(data[-1, 0])
        scan.count += int(data.shape[0])
        if scan.keep_rows:
            scan.blocks.append(data)


def _check_times(t: np.ndarray, lines: np.ndarray, scan: _Scan) -> None:
    """Count negative times and steps back in time (from the previous block's last time on)."""
    negative = np.flatnonzero(t < 0)
    if negative.size:
        scan.negative += int(negative.size)
        if scan.first_negative is None:
            scan.first_negative = int(lines[negative[0]])
    before = np.concatenate([[scan.last_t], t[:-1]]) if scan.last_t is not None else t[:-1]
    after = t if scan.last_t is not None else t[1:]
    back = np.flatnonzero(after < before)
    if back.size:
        scan.backwards += int(back.size)
        if scan.first_backward is None:
            i = int(back[0]) + (0 if scan.last_t is not None else 1)
            scan.first_backward = (int(lines[i]), float(t[i]), float(before[back[0]]))


def read_recording(path: str | os.PathLike[str], strict: bool = True) -> Recording:
    """Read a ``*.tape.csv`` recording.

    The file is read in blocks: memory holds the frames and one block, whatever the file holds
    (a header's claims are checked against their bounds before anything is allocated).

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
    scan = _scan(path, strict, keep_rows=True)
    regions = int(scan.meta["regions"])
    width = len(FIXED_COLUMNS) + 2 * regions
    data = np.concatenate(scan.blocks) if scan.blocks else np.zeros((0, width))
    scan.blocks.clear()
    r = regions
    return Recording(
        path=path,
        meta=scan.meta,
        t=data[:, 0].copy(),
        frame=data[:, 1].astype(np.int64),
        status=data[:, 2].astype(np.int64),
        bend=data[:, 3 : 3 + r].copy(),
        twist=data[:, 3 + r : 3 + 2 * r].copy(),
        recovered=scan.end is None,
        problems=scan.problems,
        end=scan.end,
        warnings=scan.warnings,
    )


def summarize_recording(path: str | os.PathLike[str], strict: bool = True) -> RecordingSummary:
    """:meth:`Recording.summary` of a file, streamed: memory stays one block, however long the file.

    For ``studio info`` and listings, which need the counts but not the frames.

    Raises:
        RecordingError: as :func:`read_recording`.
    """
    path = Path(path)
    scan = _scan(path, strict, keep_rows=False)
    return _summary(
        path, scan.meta, scan.count, scan.duration, scan.end is None, scan.problems, scan.warnings
    )


class RecordingBytes:
    """A consistent prefix of a recording file, for downloads: every complete line, no partial one.

    A file under capture grows while it is sent, and its last row may be half written; a
    download that trusts ``stat`` then sends more bytes than it announced, or a torn row. This
    fixes the length when it is opened (up to and including the last newline) and reads from the
    same open file, so a concurrent append or an atomic header edit (a new inode) cannot change
    what is sent. Iterate it once for the bytes; it closes itself at the end.

    Attributes:
        path: the recording.
        size: bytes that will be yielded (the announced ``Content-Length``).
    """

    def __init__(self, path: Path, stream: BinaryIO, size: int) -> None:
        self.path, self._stream, self.size = path, stream, size

    def __iter__(self) -> Iterator[bytes]:
        try:
            self._stream.seek(0)
            left = self.size
            while left > 0:
                chunk = self._stream.read(min(READ_BLOCK_BYTES, left))
                if not chunk:  # truncated under us (cannot happen to a recording): stop short
                    return
                left -= len(chunk)
                yield chunk
        finally:
            self.close()

    def close(self) -> None:
        """Release the file (also done when iteration ends)."""
        self._stream.close()


def recording_bytes(path: str | os.PathLike[str]) -> RecordingBytes:
    """The bytes of a recording up to its last complete line, fixed at this moment (see
    :class:`RecordingBytes`); works on finished and live recordings alike.

    Raises:
        RecordingError: the file is missing or not a regular file.
    """
    path = Path(path)
    stream = _open(path)
    try:
        end = os.fstat(stream.fileno()).st_size
        while end > 0:  # back off to the last newline, a block at a time
            start = max(0, end - READ_BLOCK_BYTES)
            stream.seek(start)
            cut = stream.read(end - start).rfind(b"\n")
            if cut >= 0:
                end = start + cut + 1
                break
            end = start
    except BaseException:
        stream.close()
        raise
    return RecordingBytes(path, stream, end)


def _summary(
    path: Path,
    meta: RecordingHeader,
    frames: int,
    duration: float,
    recovered: bool,
    problems: list[str],
    warnings: list[str],
    kind: str = "tape",
) -> RecordingSummary:
    """The JSON-ready facts of a recording (one definition for every reader and kind)."""
    return {
        "path": str(path),
        "kind": kind,
        "name": str(meta.get("name") or path.name),
        "frames": frames,
        "duration": duration,
        "regions": int(meta.get("regions", 0)),
        "rate_hz": float(meta.get("rate_hz", 0.0)),
        "source": meta.get("source", ""),
        "operator": meta.get("operator", ""),
        "notes": meta.get("notes", ""),
        "created": meta.get("created", ""),
        "recovered": recovered,
        "problems": list(problems),
        "warnings": list(warnings),
    }


_EMPTY_FIELD = re.compile(r"(?<=,)(?=,|\n|$)")
"""An empty field (never the first one, the time): NaN where a format allows it."""


def _to_array(
    rows: list[str],
    row_lines: list[int],
    width: int,
    problems: _Problems,
    empty_as_nan: bool = False,
) -> tuple[np.ndarray, list[int]]:
    """Rows as a float array; a row with a field that is not a number is left out and named.

    ``empty_as_nan``: an empty field reads as NaN (the landmark formats leave unseen points
    empty); otherwise it is a problem like any other non-number.
    """
    if not rows:
        return np.zeros((0, width)), []
    # fast path: numpy's C parser (correctly rounded, so exact reprs come back exactly) over all
    # rows at once, when they hold only number characters and it reads exactly the expected count;
    # anything else takes the slow path, which names the line and the field
    joined = "\n".join(rows)
    if _plain(joined.replace("\n", ",")):
        text = (_EMPTY_FIELD.sub("nan", joined) if empty_as_nan else joined).replace("\n", ",")
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", DeprecationWarning)
            try:
                flat = np.fromstring(text, dtype=np.float64, sep=",")
            except ValueError:
                flat = np.zeros(0)
        if flat.size == len(rows) * width:
            return flat.reshape(len(rows), width), row_lines
    good: list[list[float]] = []
    kept: list[int] = []
    for line, number in zip(rows, row_lines, strict=True):
        fields = line.split(",")
        bad = next(
            (x for x in fields if not (empty_as_nan and x == "") and not _is_number(x)), None
        )
        if bad is not None:
            problems.add(number, f"'{bad[:20]}' is not a number")
            continue
        good.append([float(x) if x else float("nan") for x in fields])
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
