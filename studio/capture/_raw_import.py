"""Import Measurand's raw text files (``frame time raw0 ... rawN`` per line) as a recording."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np

from ._calibration import Calibration, load_calibration
from ._errors import RecordingError
from ._recording_edit import write_recording
from ._recording_format import DEFAULT_RATE_HZ
from ._recording_writer import recording_meta

MIN_FIELDS = 2
"""``frame`` and ``time`` come before the channels."""


def read_raw_text(
    path: str | os.PathLike[str], channels: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Parse a raw file into ``(frame (N,), time (N,), raw (N, channels))``.

    Blank lines and lines starting with ``#`` are skipped. Lines may carry more channels than
    the calibration uses (the extra are ignored).

    Raises:
        RecordingError: naming the file and line of the first bad line.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8", errors="strict")
    except OSError as err:
        raise RecordingError(f"cannot open {path} ({err.strerror}); check the path.") from None
    except UnicodeDecodeError:
        raise RecordingError(
            f"{path} is not a text file; give Measurand's raw text export."
        ) from None
    frames, times, raws = [], [], []
    for number, line in enumerate(text.splitlines(), start=1):
        line = line.strip()
        if not line or line.startswith("#"):
            continue
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
        frames.append(values[0])
        times.append(values[1])
        raws.append(values[MIN_FIELDS:])
    if not frames:
        raise RecordingError(f"{path} holds no frames; give Measurand's raw text export.")
    return np.array(frames, dtype=np.int64), np.array(times), np.array(raws)


def import_raw(
    raw_path: str | os.PathLike[str],
    calibration: Calibration | str | os.PathLike[str],
    out: str | os.PathLike[str],
    *,
    config: Any = None,
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
