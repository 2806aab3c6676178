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

Bounds (checked by the reader before anything is allocated, so a hostile header cannot make it
allocate more than the file's own size justifies): the header line is at most
:data:`MAX_HEADER_BYTES`, ``regions`` at most :data:`MAX_REGIONS`, ``rate_hz`` at most
:data:`MAX_RATE_HZ`, and no data line is longer than :func:`max_line_bytes`.
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Callable, Mapping
from typing import TYPE_CHECKING, NotRequired, TypedDict

import numpy as np

from ._errors import RecordingError

if TYPE_CHECKING:
    from studio.kinematics import TapeConfig

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
MAX_REGIONS = 256
"""Most regions a tape may have (the paper's has 16): a sanity bound against damaged or hostile
headers and datagrams."""
MAX_RATE_HZ = 100_000.0
"""Highest nominal sample rate a header may state (the paper's tape runs at 110 Hz)."""
MAX_HEADER_BYTES = 1024 * 1024
"""Longest header line (free-text notes included)."""
MAX_FIELD_BYTES = 32
"""Longest field a row can hold: a float64 repr is at most 24 characters, an int64 20."""
MIN_LINE_BYTES = 64 * 1024
"""Comment lines may be longer than a row, up to this."""


class RecordingHeader(TypedDict, total=False):
    """Line 1 of a recording of any kind, as read back after its checks (every key optional but
    ``format`` and ``version``; a tape recording always has ``regions``).

    Writers may add keys of their own; a reader keeps them, and these are the ones it knows.
    """

    format: str
    version: int
    regions: int
    """Bend/twist regions per frame (tape recordings)."""
    tape: dict[str, object] | None
    """The :class:`studio.kinematics.TapeConfig` fields (tape recordings)."""
    side: str
    """The teaching arm, ``"right"`` or ``"left"`` (pose and hand recordings)."""
    rate_hz: float
    operator: str
    notes: str
    name: str
    source: str
    created: str
    edited: str
    """When the header was last edited (ISO 8601)."""
    derived_from: str
    """The file a cut or repair was copied from."""
    calibration: dict[str, object]
    """The calibration a raw import converted the counts with."""


class RecordingEnd(TypedDict, total=False):
    """The ``# end`` line's data (``{}`` when the line is damaged)."""

    frames: int
    duration: float
    closed: str


class RecordingSummary(TypedDict):
    """The JSON-ready facts of a recording, for listings (``studio info``, the web page)."""

    path: str
    kind: str
    """``"tape"``, ``"pose"`` or ``"hand"``."""
    name: str
    frames: int
    duration: float
    regions: int
    rate_hz: float
    source: str
    operator: str
    notes: str
    created: str
    recovered: bool
    problems: list[str]
    warnings: list[str]
    live: NotRequired[bool]
    """Whether a capture is still writing the file (``studio info`` adds it)."""


def max_line_bytes(regions: int) -> int:
    """The longest line a recording of ``regions`` regions can hold after its header.

    A longer line is damage (a hole of zero bytes, a binary blob), so the reader never buffers more.
    """
    return max(MIN_LINE_BYTES, (len(FIXED_COLUMNS) + 2 * regions) * MAX_FIELD_BYTES)


def columns(regions: int) -> list[str]:
    """The CSV header row's column names for a tape of ``regions`` regions."""
    return [
        *FIXED_COLUMNS,
        *(f"bend_{i}" for i in range(regions)),
        *(f"twist_{i}" for i in range(regions)),
    ]


def header_line(meta: Mapping[str, object], prefix: str = HEADER_PREFIX) -> str:
    """Line 1 of a recording (with its newline); ``prefix`` names the format (tape by default).

    Raises:
        RecordingError: the header would be longer than :data:`MAX_HEADER_BYTES` (long notes).
    """
    line = prefix + json.dumps(meta, separators=(", ", ": ")) + "\n"
    if len(line.encode("utf-8")) > MAX_HEADER_BYTES:
        raise RecordingError(
            f"the recording's header would be {len(line.encode('utf-8')):,} bytes, over the limit "
            f"of {MAX_HEADER_BYTES:,}; shorten the notes."
        )
    return line


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


def tape_config_to_dict(
    config: TapeConfig | dict[str, object] | None,
) -> dict[str, object] | None:
    """A JSON-ready dict of a :class:`studio.kinematics.TapeConfig` (or a dict, passed through)."""
    if config is None:
        return None
    if isinstance(config, dict):
        return dict(config)
    if dataclasses.is_dataclass(config):
        out: dict[str, object] = {}
        for field in dataclasses.fields(config):
            value = getattr(config, field.name)
            if isinstance(value, np.ndarray):
                value = value.tolist()
            elif isinstance(value, np.generic):
                value = value.item()
            out[field.name] = value
        return out
    raise TypeError(f"tape config {config!r} is neither a TapeConfig nor a dict")


def tape_config_from_dict(data: Mapping[str, object] | None) -> TapeConfig:
    """The :class:`studio.kinematics.TapeConfig` a header describes (defaults when absent)."""
    from studio.kinematics import TapeConfig

    if not data:
        return TapeConfig()
    known = {f.name for f in dataclasses.fields(TapeConfig)}
    kwargs = {k: (np.asarray(v) if k == "base" else v) for k, v in data.items() if k in known}
    make: Callable[..., TapeConfig] = TapeConfig  # it checks each field read from the file
    return make(**kwargs)
