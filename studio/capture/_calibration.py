"""ShapeTape raw channel counts: their calibration to bend/twist radians, and Measurand's raw
text files (``frame time raw0 ... rawN`` per line) imported as a recording.

The tape reports two channels per region; channel ``2 i`` carries region ``i``'s bend and channel
``2 i + 1`` its twist. A calibration subtracts the flat-pose reading and applies a linear gain per
channel: ``angle[c] = gains[c] * (raw[c] - offsets[c])``.

File (``*.calibration.json``)::

    {"format": "teach-studio-calibration", "version": 1, "regions": 16,
     "offsets": [32 raw counts], "gains": [32 radians per count], "serial": 5001, "notes": "..."}

How to make one: lay the tape flat and straight on a table, record a few seconds of raw frames
(``Measurand``'s raw text, or a :class:`SerialSource` with :meth:`Calibration.identity`), and
average each channel: that is ``offsets`` (:meth:`Calibration.from_flat` does it). ``gains``
come from the maker's sheet, or from bending the tape round a cylinder of known radius (bend =
region length / radius) and dividing by the change in counts.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from studio import FileLimitError, StudioError, human_size, open_regular, read_json

from ._errors import CaptureError, RecordingError
from ._recording_edit import write_recording
from ._recording_format import DEFAULT_RATE_HZ, DEFAULT_REGIONS, MAX_REGIONS
from ._recording_writer import recording_meta

if TYPE_CHECKING:
    from studio.kinematics import TapeConfig


CALIBRATION_FORMAT = "teach-studio-calibration"
"""The ``format`` value of calibration files."""
CALIBRATION_VERSION = 1
"""The version this code writes and the newest it reads."""
RAW_CENTRE = 32768
"""A uint16 channel's mid-scale count: the flat reading of an uncalibrated channel."""
DEFAULT_GAIN = 1.0e-4
"""Radians per count when no gain is known (the full uint16 range spans about +-3.3 rad)."""
MAX_CALIBRATION_BYTES = 1024 * 1024
"""Largest calibration file read (one of the largest tape's is about 20 kB)."""


@dataclass(frozen=True, eq=False)
class Calibration:
    """Flat-pose offsets and per-channel gains of one tape.

    Args:
        offsets: raw counts of the flat tape, ``(2 * regions,)``.
        gains: radians per count, ``(2 * regions,)``.
        serial: the tape's serial number, if known.
        notes: free text.
    """

    offsets: np.ndarray
    gains: np.ndarray
    serial: int | None = None
    notes: str = ""

    def __post_init__(self) -> None:
        offsets = np.asarray(self.offsets, dtype=np.float64)
        gains = np.asarray(self.gains, dtype=np.float64)
        if offsets.ndim != 1 or offsets.shape != gains.shape or offsets.size % 2:
            raise CaptureError(
                f"calibration offsets {offsets.shape} and gains {gains.shape} must be two equal even-length lists (two channels per region)."
            )
        if not 2 <= offsets.size <= 2 * MAX_REGIONS:
            raise CaptureError(
                f"the calibration has {offsets.size} channels; a tape has 2 to {2 * MAX_REGIONS} (two per region)."
            )
        if not (np.isfinite(offsets).all() and np.isfinite(gains).all()):
            raise CaptureError(
                "the calibration holds a NaN or infinite value; remake it from a flat recording."
            )
        object.__setattr__(self, "offsets", offsets)
        object.__setattr__(self, "gains", gains)

    @property
    def channels(self) -> int:
        """Raw channels (two per region)."""
        return int(self.offsets.shape[0])

    @property
    def regions(self) -> int:
        """Bend/twist regions."""
        return self.channels // 2

    @classmethod
    def identity(cls, regions: int = DEFAULT_REGIONS, gain: float = DEFAULT_GAIN) -> Calibration:
        """Mid-scale offsets and one gain for every channel (before a real calibration exists)."""
        return cls(np.full(2 * regions, float(RAW_CENTRE)), np.full(2 * regions, float(gain)))

    @classmethod
    def from_flat(
        cls,
        raw: np.ndarray,
        gains: np.ndarray | float = DEFAULT_GAIN,
        *,
        serial: int | None = None,
        notes: str = "",
    ) -> Calibration:
        """Offsets from raw frames of the flat tape (their per-channel mean), with given gains.

        Args:
            raw: ``(frames, channels)`` raw counts recorded with the tape held flat.
            gains: radians per count, one per channel or one for all.
            serial, notes: as the class's.
        """
        raw = np.asarray(raw, dtype=np.float64)
        if raw.ndim != 2 or raw.shape[0] < 1:
            raise CaptureError(
                f"flat raw frames have shape {raw.shape}; give (frames, channels) with frames >= 1."
            )
        offsets = raw.mean(axis=0)
        return cls(
            offsets,
            np.broadcast_to(np.asarray(gains, dtype=np.float64), offsets.shape).copy(),
            serial,
            notes,
        )

    def angles(self, raw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(bend, twist)`` in radians from raw counts ``(..., channels)``."""
        raw = np.asarray(raw, dtype=np.float64)
        angle = (raw - self.offsets) * self.gains
        return angle[..., 0::2], angle[..., 1::2]

    def raw(self, bend: np.ndarray, twist: np.ndarray) -> np.ndarray:
        """The raw counts (uint16, rounded and clipped) a device would report for these angles."""
        bend, twist = np.asarray(bend, dtype=np.float64), np.asarray(twist, dtype=np.float64)
        angle = np.empty(bend.shape[:-1] + (self.channels,))
        angle[..., 0::2], angle[..., 1::2] = bend, twist
        return np.clip(np.rint(angle / self.gains + self.offsets), 0, 0xFFFF).astype(np.uint16)

    def to_dict(self) -> dict[str, object]:
        """JSON-ready file contents."""
        return {
            "format": CALIBRATION_FORMAT,
            "version": CALIBRATION_VERSION,
            "regions": self.regions,
            "offsets": self.offsets.tolist(),
            "gains": self.gains.tolist(),
            "serial": self.serial,
            "notes": self.notes,
        }

    def save(self, path: str | os.PathLike[str]) -> Path:
        """Write the calibration as JSON."""
        path = Path(path)
        path.write_text(json.dumps(self.to_dict(), indent=1) + "\n", encoding="utf-8")
        return path


def load_calibration(path: str | os.PathLike[str] | Calibration) -> Calibration:
    """Read a calibration JSON file (a :class:`Calibration` passes through).

    Raises:
        CaptureError: the file is missing, not a regular file, over
            :data:`MAX_CALIBRATION_BYTES`, or not a calibration (the message says which).
    """
    if isinstance(path, Calibration):
        return path
    path = Path(path)
    try:  # bounded: a device such as /dev/zero, a FIFO or a huge file is refused unread
        data = read_json(path, f"calibration {path}", max_bytes=MAX_CALIBRATION_BYTES)
    except StudioError as err:
        raise CaptureError(str(err)) from None
    if not isinstance(data, dict) or data.get("format") != CALIBRATION_FORMAT:
        raise CaptureError(
            f"{path} is not a calibration (no format '{CALIBRATION_FORMAT}'); give a calibration file."
        )
    if data.get("version") != CALIBRATION_VERSION:
        raise CaptureError(
            f"{path} has calibration version {data.get('version')!r}; this studio reads version {CALIBRATION_VERSION}."
        )
    try:
        return Calibration(
            data["offsets"], data["gains"], data.get("serial"), str(data.get("notes", ""))
        )
    except KeyError as err:
        raise CaptureError(
            f"{path} has no {err.args[0]!r} list; give offsets and gains per channel."
        ) from None


MIN_FIELDS = 2
"""``frame`` and ``time`` come before the channels."""
MAX_RAW_BYTES = 2 * 1024**3
"""Largest raw export read (about 20 hours of a 16-region tape at 110 Hz)."""
MAX_RAW_LINE_BYTES = 64 * 1024
"""Longest raw line (a 256-region tape's line is under 8 kB)."""
BLOCK_LINES = 10_000
"""Lines parsed into one numpy block."""


def read_raw_text(
    path: str | os.PathLike[str], channels: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Parse a raw file into ``(frame (N,), time (N,), raw (N, channels))``.

    Blank lines and lines starting with ``#`` are skipped. Lines may carry more channels than
    the calibration uses (the extra are ignored). The file is read line by line into arrays of
    :data:`BLOCK_LINES` rows, so memory holds the numbers and one block; a device, a FIFO, a
    file over :data:`MAX_RAW_BYTES` or a line over :data:`MAX_RAW_LINE_BYTES` is refused.

    Raises:
        RecordingError: naming the file (and the line) of the first problem.
    """
    path = Path(path)
    try:
        stream = open_regular(path)
    except FileLimitError as err:
        raise RecordingError(str(err)) from None
    with stream:
        size = os.fstat(stream.fileno()).st_size
        if size > MAX_RAW_BYTES:
            raise RecordingError(
                f"{path} is {human_size(size)}, more than the {human_size(MAX_RAW_BYTES)} a raw "
                "export can hold; split it into shorter files."
            )
        blocks: list[np.ndarray] = []
        block: list[list[float]] = []
        number = 0
        while line_bytes := stream.readline(MAX_RAW_LINE_BYTES + 1):
            number += 1
            if len(line_bytes) > MAX_RAW_LINE_BYTES:
                raise RecordingError(
                    f"{path}, line {number}: longer than {MAX_RAW_LINE_BYTES:,} bytes, so not "
                    "Measurand's raw text; give its raw text export."
                )
            try:
                line = line_bytes.decode("utf-8").strip()
            except UnicodeDecodeError:
                raise RecordingError(
                    f"{path} is not a text file; give Measurand's raw text export."
                ) from None
            if not line or line.startswith("#"):
                continue
            block.append(_raw_values(path, number, line, channels))
            if len(block) == BLOCK_LINES:
                blocks.append(np.array(block))
                block = []
        if block:
            blocks.append(np.array(block))
    if not blocks:
        raise RecordingError(f"{path} holds no frames; give Measurand's raw text export.")
    data = np.concatenate(blocks)
    return data[:, 0].astype(np.int64), data[:, 1].copy(), data[:, MIN_FIELDS:].copy()


def _raw_values(path: Path, number: int, line: str, channels: int) -> list[float]:
    """``frame, time, raw0 .. raw{channels-1}`` of one line, checked."""
    fields = line.replace(",", " ").split()
    if len(fields) < MIN_FIELDS + channels:
        raise RecordingError(
            f"{path}, line {number}: {len(fields) - MIN_FIELDS} raw channels where the calibration needs {channels}; use the calibration of this tape."
        )
    try:
        values = [float(x) for x in fields[: MIN_FIELDS + channels]]
    except ValueError:
        raise RecordingError(
            f"{path}, line {number}: a value is not a number; fix or re-export the file."
        ) from None
    if not np.isfinite(values).all():
        raise RecordingError(
            f"{path}, line {number}: a NaN or infinite value; fix or re-export the file."
        )
    return values


def import_raw(
    raw_path: str | os.PathLike[str],
    calibration: Calibration | str | os.PathLike[str],
    out: str | os.PathLike[str],
    *,
    config: TapeConfig | None = None,
    operator: str = "",
    notes: str = "",
    rate_hz: float | None = None,
) -> Path:
    """Convert a raw text file into a ``*.tape.csv`` recording.

    Args:
        raw_path: Measurand raw text (``frame time raw0 ... rawN``; time in seconds).
        calibration: the tape's calibration (object or JSON path).
        out: the new recording (must not exist).
        config: the tape config to store (default: ``TapeConfig`` with the calibration's regions).
        operator: who wore the tape.
        notes: free text.
        rate_hz: nominal rate (default: estimated from the times).

    Returns:
        The recording's path.
    """
    cal = load_calibration(calibration)
    counter, t, raw = read_raw_text(raw_path, cal.channels)
    bend, twist = cal.angles(raw)
    if rate_hz is None:
        steps = np.diff(t)
        rate_hz = (
            float(1.0 / np.median(steps))
            if steps.size and np.median(steps) > 0
            else DEFAULT_RATE_HZ
        )
    if config is None:
        from studio.kinematics import TapeConfig

        config = TapeConfig(regions=cal.regions)
    meta = recording_meta(
        cal.regions,
        tape=config,
        operator=operator,
        notes=notes,
        name=Path(out).name.removesuffix(".tape.csv"),
        rate_hz=rate_hz,
        source=f"import:{Path(raw_path).name}",
        calibration=cal.to_dict(),
    )
    return write_recording(out, meta, t - t[0], counter, np.zeros_like(counter), bend, twist)
