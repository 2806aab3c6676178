"""Write and read pose-landmark and hand-pose recordings (formats: :mod:`._recording_format`).

The writer is the tape recorder's crash-safe appender (:class:`~._recording_writer.AppendWriter`):
rows are flushed and fsynced at least every 0.5 s, a full disk stops it with the rows on disk
kept, and a file without its ``# end`` line reads back as *recovered*. The reader streams the file
in bounded blocks like the tape reader, names the file, the line and the problem, and with
``strict=False`` keeps every good row. :func:`read_any_recording` picks the reader from line 1.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path
from typing import TYPE_CHECKING, cast

import numpy as np

from studio import JSONFileError, loads_json

from ._errors import RecordingError
from ._observations import HandPose, LandmarkFrame, Observation
from ._recording_format import (
    END_PREFIX,
    MAX_HEADER_BYTES,
    MAX_RATE_HZ,
    OBSERVATION_VERSION,
    POSE_KIND,
    RECORDING_KINDS,
    RecordingEnd,
    RecordingHeader,
    RecordingKind,
    RecordingSummary,
    check_hand_rows,
    check_pose_rows,
    hand_at,
    hand_row,
    observation_meta,
    pose_at,
    pose_row,
)
from ._recording_reader import (
    FIX_HINT,
    TEXT_KEYS,
    Recording,
    RecordingTimeline,
    _first_line,
    _Lines,
    _open,
    _Problems,
    _short,
    _to_array,
    _whole,
    array_time_warnings,
    parse_end,
    read_recording,
    summarize_recording,
)
from ._recording_reader import _parse_header as _parse_tape_header
from ._recording_writer import DEFAULT_FLUSH_SECONDS, AppendWriter, RecordingWriter

if TYPE_CHECKING:
    from studio.kinematics import TapeConfig

MAX_FIELD_BYTES = 32
"""Longest field of a row (a float64 repr is at most 24 characters)."""
SIDES = ("right", "left")


class ObservationWriter(AppendWriter):
    """Append pose-landmark frames (``kind="pose"``) or hand poses (``"hand"``) to a new file.

    Args:
        path: the new file (``*.pose.csv`` or ``*.hand.csv``; never overwritten).
        kind: ``"pose"`` or ``"hand"``.
        side: the teaching arm, ``"right"`` or ``"left"``.
        operator, notes, name, source: as :class:`RecordingWriter`'s.
        flush_seconds: longest time a row stays in memory.
        extra: more header keys (JSON-ready).

    Raises:
        RecordingError: a bad kind or side, or the file exists or cannot be created.
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        kind: str,
        *,
        side: str = "right",
        operator: str = "",
        notes: str = "",
        name: str | None = None,
        source: str = "",
        flush_seconds: float = DEFAULT_FLUSH_SECONDS,
        extra: dict[str, object] | None = None,
    ) -> None:
        if kind not in ("pose", "hand"):
            raise RecordingError(f"kind is {kind!r}; record 'pose' or 'hand' observations.")
        if side not in SIDES:
            raise RecordingError(f"side is {side!r}; give 'right' or 'left'.")
        self.kind = RECORDING_KINDS[kind]
        path = Path(path)
        meta = observation_meta(
            self.kind,
            side=side,
            operator=operator,
            notes=notes,
            name=path.name.removesuffix(self.kind.suffix) if name is None else name,
            source=source,
            created=datetime.now(UTC).isoformat(timespec="seconds"),
            **(extra or {}),
        )
        self._open(path, meta, list(self.kind.columns), flush_seconds, self.kind.prefix)

    def _rows(self, observations: Sequence[Observation]) -> list[str]:
        pose = self.kind is POSE_KIND
        out = []
        for obs in observations:
            if pose and isinstance(obs, LandmarkFrame):
                out.append(pose_row(obs))
            elif not pose and isinstance(obs, HandPose):
                out.append(hand_row(obs))
            else:
                raise RecordingError(
                    f"{self.path} records {self.kind.name} observations, not {type(obs).__name__}; record each source into its own file."
                )
        return out


def recording_writer(
    kind: str,
    path: str | os.PathLike[str],
    *,
    config: TapeConfig | None = None,
    side: str = "right",
    operator: str = "",
    notes: str = "",
    source: str = "",
) -> AppendWriter:
    """A new writer for observations of ``kind`` (``"tape"``, ``"pose"`` or ``"hand"``).

    Raises:
        RecordingError: as the writers.
    """
    if kind == "tape":
        return RecordingWriter(path, config=config, operator=operator, notes=notes, source=source)
    return ObservationWriter(path, kind, side=side, operator=operator, notes=notes, source=source)


@dataclass(eq=False)
class ObservationRecording(RecordingTimeline):
    """A pose or hand recording in memory.

    Attributes:
        path: where it was read from.
        meta: the header.
        kind: its :class:`RecordingKind` (``kind.name`` is ``"pose"`` or ``"hand"``).
        t: times (s), ``(N,)``.
        data: the parsed rows ``(N, columns)`` (empty landmark fields are NaN).
        recovered, problems, end: as :class:`Recording`'s.
    """

    path: Path
    meta: RecordingHeader
    kind: RecordingKind
    t: np.ndarray
    data: np.ndarray
    recovered: bool = False
    problems: list[str] = field(default_factory=list)
    end: RecordingEnd | None = None

    config = None
    """A pose or hand recording has no tape (sources ask; the pipeline uses the default)."""

    @property
    def side(self) -> str:
        """The teaching arm."""
        return str(self.meta.get("side", "right"))

    @property
    def frame(self) -> np.ndarray:
        """Frame counters ``(N,)``."""
        return self.data[:, 1].astype(np.int64)

    def frame_at(self, index: int) -> LandmarkFrame | HandPose:
        """Row ``index`` as its observation."""
        return pose_at(self.data, index) if self.kind is POSE_KIND else hand_at(self.data, index)

    def frames(self) -> list[LandmarkFrame | HandPose]:
        """Every row as its observation."""
        return [self.frame_at(i) for i in range(len(self))]

    @property
    def kind_name(self) -> str:
        """``"pose"`` or ``"hand"``."""
        return self.kind.name

    @property
    def warnings(self) -> list[str]:
        """Times below zero or going backwards, in the tape reader's words."""
        return array_time_warnings(self.t)


def _header_kind(path: Path) -> tuple[RecordingKind, str]:
    with _open(path) as stream:
        line = _first_line(path, stream)
    for kind in RECORDING_KINDS.values():
        if line.startswith(kind.prefix):
            return kind, line
    return RECORDING_KINDS["tape"], line  # the tape reader explains what is wrong


def _parse_header(path: Path, kind: RecordingKind, line: str) -> RecordingHeader:
    try:
        meta = loads_json(line[len(kind.prefix) :], "the header", max_bytes=MAX_HEADER_BYTES)
    except JSONFileError as err:
        raise RecordingError(f"{path}, line 1: {err}") from None
    fix = f"open a *{kind.suffix} file"
    if not isinstance(meta, dict) or meta.get("format") != kind.format:
        raise RecordingError(
            f"{path}, line 1: the header does not say format '{kind.format}'; {fix}."
        )
    version = meta.get("version")
    if not _whole(version) or not 1 <= version <= OBSERVATION_VERSION:
        raise RecordingError(
            f"{path}, line 1: unknown {kind.name} recording version {version!r} (this studio reads 1 to {OBSERVATION_VERSION}); update Teach Studio."
        )
    rate = meta.get("rate_hz", 0.0)
    if isinstance(rate, bool) or not isinstance(rate, int | float) or not 0 <= rate <= MAX_RATE_HZ:
        raise RecordingError(
            f"{path}, line 1: the header's rate_hz is {_short(rate)}; it must be a number from 0 to {MAX_RATE_HZ:g}."
        )
    for key in TEXT_KEYS:
        if meta.get(key) is not None and not isinstance(meta[key], str):
            raise RecordingError(
                f"{path}, line 1: the header's {key} is {_short(meta[key])}; it must be text."
            )
    if meta.get("side", "right") not in SIDES:
        raise RecordingError(
            f"{path}, line 1: the header's side is {_short(meta.get('side'))}; it must be 'right' or 'left'."
        )
    return cast(RecordingHeader, meta)  # every key it names was checked above


def parse_any_header(path: Path, line: str) -> tuple[RecordingHeader, str]:
    """The checked header of a recording of any kind from its line 1, and line 1's prefix.

    Raises:
        RecordingError: a header that is not a recording's, or out of its bounds.
    """
    for kind in RECORDING_KINDS.values():
        if kind.name != "tape" and line.startswith(kind.prefix):
            return _parse_header(path, kind, line), kind.prefix
    return _parse_tape_header(path, line), RECORDING_KINDS["tape"].prefix


def _parse_lines(
    lines: list[str],
    first_number: int,
    last_complete: bool,
    width: int,
    problems: _Problems,
    end: RecordingEnd | None,
) -> tuple[np.ndarray, list[int], RecordingEnd | None]:
    """Rows of one block as floats (empty fields NaN), their line numbers, and the end line."""
    rows: list[str] = []
    numbers: list[int] = []
    for index, line in enumerate(lines):
        number = first_number + index
        if line.startswith("#"):
            if line.startswith(END_PREFIX):
                end = parse_end(line[len(END_PREFIX) :])
                if end is None:
                    problems.add(number, "the '# end' line is not valid JSON")
                    end = {}
            continue
        if end is not None:
            problems.add(number, "data after the '# end' line")
            continue
        if index == len(lines) - 1 and not last_complete:
            problems.items.append(
                f"line {number}: incomplete last row (the capture was interrupted); dropped"
            )
            continue
        if not line.strip():
            continue
        count = line.count(",") + 1
        if count != width:
            problems.add(number, f"{count} columns where {width} were expected")
            continue
        rows.append(line)
        numbers.append(number)
    data, numbers = _to_array(rows, numbers, width, problems, empty_as_nan=True)
    return data, numbers, end


def _scan_observations(
    path: Path, strict: bool
) -> tuple[RecordingKind, RecordingHeader, np.ndarray, RecordingEnd | None, list[str]]:
    kind, line = _header_kind(path)
    meta = _parse_header(path, kind, line)
    problems = _Problems(path, strict)
    blocks: list[np.ndarray] = []
    end: RecordingEnd | None = None
    width = len(kind.columns)
    check = check_pose_rows if kind is POSE_KIND else check_hand_rows
    with _open(path) as stream:
        stream.readline(MAX_HEADER_BYTES + 1)
        column_row = ",".join(kind.columns).encode("ascii")
        second = stream.readline(len(column_row) + 2)
        if not second.endswith(b"\n") and not stream.read(1):
            return kind, meta, np.zeros((0, width)), None, []
        if second.rstrip(b"\n") != column_row:
            raise RecordingError(
                f"{path}, line 2: the column row is not the {kind.name} format's ('{','.join(kind.columns[:5])},...'); {FIX_HINT}."
            )
        for block, first, complete in _Lines(stream, width * MAX_FIELD_BYTES, problems):
            text = b"\n".join(block).decode("utf-8", errors="replace").split("\n")
            data, numbers, end = _parse_lines(text, first, complete, width, problems, end)
            why = check(data)
            for i in np.flatnonzero(why != ""):
                problems.add(numbers[i], str(why[i]))
            blocks.append(data[why == ""])
    data = np.concatenate(blocks) if blocks else np.zeros((0, width))
    return kind, meta, data, end, problems.items


def read_observation_recording(
    path: str | os.PathLike[str], strict: bool = True
) -> ObservationRecording:
    """Read a ``*.pose.csv`` or ``*.hand.csv`` recording.

    Raises:
        RecordingError: naming the file, the line and the problem (with ``strict=False`` only a
            bad header raises; bad rows are listed in ``problems`` and left out).
    """
    path = Path(path)
    kind, meta, data, end, problems = _scan_observations(path, strict)
    if kind.name == "tape":
        raise RecordingError(f"{path} is a tape recording; read it with read_recording.")
    return ObservationRecording(
        path, meta, kind, data[:, 0].copy(), data, end is None, problems, end
    )


def recording_kind(path: str | os.PathLike[str]) -> str:
    """``"tape"``, ``"pose"`` or ``"hand"``: what the recording at ``path`` holds, from line 1.

    Raises:
        RecordingError: the file is missing, empty or not a text file.
    """
    return _header_kind(Path(path))[0].name


def read_any_recording(
    path: str | os.PathLike[str], strict: bool = True
) -> Recording | ObservationRecording:
    """Read a recording of any kind (tape, pose or hand), chosen by its first line.

    Raises:
        RecordingError: as :func:`read_recording` and :func:`read_observation_recording`.
    """
    if recording_kind(path) == "tape":
        return read_recording(path, strict)
    return read_observation_recording(path, strict)


def summarize_any_recording(path: str | os.PathLike[str], strict: bool = True) -> RecordingSummary:
    """The summary of a recording of any kind (``kind`` says which); a tape recording is streamed.

    Raises:
        RecordingError: as the readers.
    """
    if recording_kind(path) == "tape":
        return summarize_recording(path, strict)
    return read_observation_recording(path, strict).summary()
