"""Import Measurand's raw text files (``frame time raw0 ... rawN`` per line) as a recording."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from studio import FileLimitError, human_size, open_regular

from ._calibration import Calibration, load_calibration
from ._errors import RecordingError
from ._recording_edit import write_recording
from ._recording_format import DEFAULT_RATE_HZ
from ._recording_writer import recording_meta

if TYPE_CHECKING:
    from studio.kinematics import TapeConfig

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
