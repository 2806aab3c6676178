"""The recording file format (``*.tape.csv``), shared by the writer, the reader and the editors.

A recording is plain text that numpy/pandas read without the studio
(``pandas.read_csv(path, comment="#")``)::

    # teach-studio-recording {"format": "teach-studio-recording", "version": 1, "regions": 16, ...}
    t,frame,status,bend_0,...,bend_15,twist_0,...,twist_15
    0.0,0,0,0.0123,...
    ...
    # end {"frames": 1100, "duration": 9.99, "closed": "2026-11-22T21:40:00+00:00"}

Header keys: ``format``, ``version``, ``regions``, ``tape`` (the :class:`TapeConfig` fields),
``operator``, ``notes``, ``name``, ``rate_hz``, ``source``, ``created`` (ISO 8601, UTC). Angles
are radians, written with Python's shortest exact float repr so a read gives back the very same
numbers. Rows are appended and flushed at least every 0.5 s; a missing ``# end`` line marks a
recording whose capture was interrupted (it is read back as *recovered*).
"""

from __future__ import annotations

import dataclasses
import json
from typing import Any

import numpy as np

FORMAT_NAME = "teach-studio-recording"
"""The ``format`` value and the first line's tag."""
FORMAT_VERSION = 1
"""The newest file version this code reads and writes."""
HEADER_PREFIX = f"# {FORMAT_NAME} "
"""How line 1 starts."""
END_PREFIX = "# end "
"""How the closing line starts."""
RECORDING_SUFFIX = ".tape.csv"
"""File name ending of recordings."""
DEFAULT_RATE_HZ = 110.0
"""The paper's ShapeTape sample rate."""
DEFAULT_REGIONS = 16
"""Regions of the paper's tape (and of ``TapeConfig()``), used when no config says otherwise."""
FIXED_COLUMNS = ("t", "frame", "status")
"""Columns before the angles."""


def columns(regions: int) -> list[str]:
    """The CSV header row's column names for a tape of ``regions`` regions."""
    return [
        *FIXED_COLUMNS,
        *(f"bend_{i}" for i in range(regions)),
        *(f"twist_{i}" for i in range(regions)),
    ]


def header_line(meta: dict[str, Any]) -> str:
    """Line 1 of a recording (with its newline)."""
    return HEADER_PREFIX + json.dumps(meta, separators=(", ", ": ")) + "\n"


def end_line(frames: int, duration: float, closed: str) -> str:
    """The closing line (with its newline)."""
    return (
        END_PREFIX + json.dumps({"frames": frames, "duration": duration, "closed": closed}) + "\n"
    )


def format_row(t: float, frame: int, status: int, bend: np.ndarray, twist: np.ndarray) -> str:
    """One CSV row with exact float reprs (with its newline)."""
    values = [repr(float(t)), str(int(frame)), str(int(status))]
    values.extend(map(repr, bend.tolist()))
    values.extend(map(repr, twist.tolist()))
    return ",".join(values) + "\n"


def tape_config_to_dict(config: Any) -> dict[str, Any] | None:
    """A JSON-ready dict of a :class:`studio.kinematics.TapeConfig` (or a dict, passed through)."""
    if config is None:
        return None
    if isinstance(config, dict):
        return dict(config)
    if dataclasses.is_dataclass(config):
        out: dict[str, Any] = {}
        for field in dataclasses.fields(config):
            value = getattr(config, field.name)
            if isinstance(value, np.ndarray):
                value = value.tolist()
            elif isinstance(value, np.generic):
                value = value.item()
            out[field.name] = value
        return out
    raise TypeError(f"tape config {config!r} is neither a TapeConfig nor a dict")


def tape_config_from_dict(data: dict[str, Any] | None) -> Any:
    """The :class:`studio.kinematics.TapeConfig` a header describes (defaults when absent)."""
    from studio.kinematics import TapeConfig

    if not data:
        return TapeConfig()
    known = {f.name for f in dataclasses.fields(TapeConfig)}
    kwargs = {k: (np.asarray(v) if k == "base" else v) for k, v in data.items() if k in known}
    return TapeConfig(**kwargs)
