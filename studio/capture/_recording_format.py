"""The recording file formats, shared by the writers, the readers and the editors: the tape's
(``*.tape.csv``), pose landmarks' (``*.pose.csv``) and hand poses' (``*.hand.csv``).

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

Pose landmarks and hand poses follow the tape format: a JSON header on line 1, the column names
on line 2, one row per observation appended and flushed at least every 0.5 s, and a closing
``# end`` line (a file without it was interrupted and reads back as *recovered*)::

    # teach-studio-pose {"format": "teach-studio-pose", "version": 1, "side": "right", ...}
    t,frame,person,width,height,observable_0,...,observable_6,world_x_0,world_y_0,world_z_0,world_v_0,...,image_x_0,image_y_0,image_v_0,...
    # teach-studio-hand {"format": "teach-studio-hand", "version": 1, "side": "right", ...}
    t,frame,x,y,z,qw,qx,qy,qz

A pose row with ``person`` 0 (no one in view) leaves its landmark fields empty (pandas reads NaN).
``observable_j`` (0 or 1) is what the live fit said of arm joint ``j`` in that frame. No image is
ever stored. Hand poses are in the operator's arm frame (``HumanArm``'s base frame: shoulder at
the origin, z up), metres, with a unit quaternion.
"""

from __future__ import annotations

import dataclasses
import json
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, NotRequired, TypedDict, cast

import numpy as np

from ._errors import CaptureError, RecordingError
from ._observations import (
    HUMAN_JOINTS,
    IMAGE_FIELDS,
    MAX_IMAGE_SIDE,
    POSE_LANDMARKS,
    WORLD_FIELDS,
    HandPose,
    LandmarkFrame,
)

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


POSE_SUFFIX = ".pose.csv"
"""File name ending of pose-landmark recordings."""
HAND_SUFFIX = ".hand.csv"
"""File name ending of hand-pose recordings."""
OBSERVATION_VERSION = 1
"""The newest version of the pose and hand formats this code reads and writes."""
POSE_RATE_HZ = 30.0
"""Nominal rate of a camera (the page sends what it achieves; the header keeps this nominal one)."""
HAND_RATE_HZ = 60.0
"""Nominal rate of hand-guide updates (the scene's push rate)."""

_POSE_FIXED = ("t", "frame", "person", "width", "height")
_OBSERVABLE = tuple(f"observable_{j}" for j in range(HUMAN_JOINTS))
_WORLD = tuple(f"world_{a}_{i}" for i in range(POSE_LANDMARKS) for a in ("x", "y", "z", "v"))
_IMAGE = tuple(f"image_{a}_{i}" for i in range(POSE_LANDMARKS) for a in ("x", "y", "v"))
POSE_COLUMNS = (*_POSE_FIXED, *_OBSERVABLE, *_WORLD, *_IMAGE)
"""Line 2 of a pose recording."""
HAND_COLUMNS = ("t", "frame", "x", "y", "z", "qw", "qx", "qy", "qz")
"""Line 2 of a hand recording."""
_OBS0 = len(_POSE_FIXED)
_WORLD0 = _OBS0 + HUMAN_JOINTS
_IMAGE0 = _WORLD0 + POSE_LANDMARKS * WORLD_FIELDS


@dataclass(frozen=True)
class RecordingKind:
    """One recording format: what it records, its header's tag and its file name ending.

    Attributes:
        name: ``"tape"``, ``"pose"`` or ``"hand"`` (the observation it records).
        format: the header's ``format`` and line 1's tag.
        suffix: the file name ending.
        columns: line 2 (empty for the tape, whose columns depend on its regions).
        rate_hz: the nominal rate a new recording states.
    """

    name: str
    format: str
    suffix: str
    columns: tuple[str, ...]
    rate_hz: float

    @property
    def prefix(self) -> str:
        """How line 1 starts."""
        return f"# {self.format} "


TAPE_KIND = RecordingKind("tape", FORMAT_NAME, RECORDING_SUFFIX, (), 110.0)
POSE_KIND = RecordingKind("pose", "teach-studio-pose", POSE_SUFFIX, POSE_COLUMNS, POSE_RATE_HZ)
HAND_KIND = RecordingKind("hand", "teach-studio-hand", HAND_SUFFIX, HAND_COLUMNS, HAND_RATE_HZ)
RECORDING_KINDS = {kind.name: kind for kind in (TAPE_KIND, POSE_KIND, HAND_KIND)}
"""Every recording format by the observation it records."""
RECORDING_SUFFIXES = tuple(kind.suffix for kind in RECORDING_KINDS.values())
"""Every recording file's ending (the tape's first)."""


def recording_suffix(kind: str) -> str:
    """The file name ending of recordings of ``kind`` (``"tape"``, ``"pose"`` or ``"hand"``)."""
    return RECORDING_KINDS[kind].suffix


def recording_path(out: str | os.PathLike[str], kind: str) -> Path:
    """``out`` named as a recording of ``kind`` that every verb takes (``studio info``,
    ``export``, the page's lists go by the ending): ``x`` and ``x.csv`` become ``x.tape.csv``.

    Raises:
        CaptureError: ``out`` ends as a recording of another kind.
    """
    out = Path(out)
    suffix = recording_suffix(kind)
    if out.name.endswith(suffix):
        return out
    other = kind_of_name(out.name)
    if other is not None:
        raise CaptureError(
            f"{out} is named as a {other.name} recording, but this source records a {kind}; "
            f"give a name ending in {suffix}."
        )
    return out.with_name(out.name.removesuffix(".csv") + suffix)


def kind_of_name(filename: str) -> RecordingKind | None:
    """The recording kind a file name's ending says, or None."""
    return next((k for k in RECORDING_KINDS.values() if filename.endswith(k.suffix)), None)


def kind_of_observation(observation: object) -> RecordingKind:
    """The recording kind that stores ``observation``."""
    if isinstance(observation, LandmarkFrame):
        return POSE_KIND
    if isinstance(observation, HandPose):
        return HAND_KIND
    return TAPE_KIND


def _number(value: float) -> str:
    return repr(float(value))


def pose_row(frame: LandmarkFrame) -> str:
    """One pose row (with its newline): exact float reprs, empty landmark fields without a person."""
    observable = frame.observable if frame.observable is not None else np.zeros(HUMAN_JOINTS)
    values = [_number(frame.t), str(int(frame.frame)), "1" if frame.person else "0"]
    values += [str(int(frame.width)), str(int(frame.height))]
    values += ["1" if bool(b) else "0" for b in observable]
    if frame.world is None:
        values += [""] * (len(_WORLD) + len(_IMAGE))
    else:
        values += map(repr, frame.world.reshape(-1).tolist())
        values += (
            map(repr, frame.image.reshape(-1).tolist())
            if frame.image is not None
            else [""] * len(_IMAGE)
        )
    return ",".join(values) + "\n"


def hand_row(pose: HandPose) -> str:
    """One hand row (with its newline)."""
    values = [_number(pose.t), str(int(pose.frame))]
    values += map(repr, pose.position.tolist())
    values += map(repr, pose.wxyz.tolist())
    return ",".join(values) + "\n"


def observation_meta(
    kind: RecordingKind,
    *,
    side: str = "right",
    operator: str = "",
    notes: str = "",
    name: str = "",
    source: str = "",
    created: str,
    **extra: object,
) -> RecordingHeader:
    """The header dict of a new pose or hand recording."""
    meta: RecordingHeader = {
        "format": kind.format,
        "version": OBSERVATION_VERSION,
        "side": side,
        "operator": operator,
        "notes": notes,
        "name": name,
        "rate_hz": kind.rate_hz,
        "source": source,
        "created": created,
    }
    return cast(RecordingHeader, {**meta, **extra}) if extra else meta


def check_pose_rows(data: np.ndarray) -> np.ndarray:
    """Which parsed pose rows ``(N, columns)`` are good, and for the others why not (or '')."""
    why = np.full(data.shape[0], "", dtype=object)
    fixed = data[:, :_WORLD0]
    person = data[:, 2]
    if data.shape[0] == 0:
        return why
    integral = np.isfinite(fixed).all(axis=1) & (fixed[:, 1:] == np.round(fixed[:, 1:])).all(axis=1)
    why[~integral] = "a missing or non-integer counter, person, size or observable flag"
    flags = np.concatenate([data[:, 2:3], data[:, _OBS0:_WORLD0]], axis=1)
    why[(why == "") & ~np.isin(flags, (0.0, 1.0)).all(axis=1)] = (
        "a person or observable flag not 0 or 1"
    )
    sizes = data[:, 3:5]
    why[(why == "") & ~((sizes >= 1) & (sizes <= MAX_IMAGE_SIDE)).all(axis=1)] = (
        f"an image size outside 1 to {MAX_IMAGE_SIDE} pixels"
    )
    world = data[:, _WORLD0:_IMAGE0]
    image = data[:, _IMAGE0:]
    seen = person == 1.0
    world_ok = np.where(seen, np.isfinite(world).all(axis=1), np.isnan(world).all(axis=1))
    image_ok = np.isfinite(image).all(axis=1) | np.isnan(image).all(axis=1)
    why[(why == "") & ~(world_ok & image_ok)] = (
        "landmarks that are missing, NaN or infinite for a person in view (or given without one)"
    )
    return why


def check_hand_rows(data: np.ndarray) -> np.ndarray:
    """Which parsed hand rows are good, and for the others why not (or '')."""
    why = np.full(data.shape[0], "", dtype=object)
    if data.shape[0] == 0:
        return why
    finite = np.isfinite(data).all(axis=1)
    why[~finite] = "a NaN, infinite or missing value"
    integral = data[:, 1] == np.round(data[:, 1])
    why[(why == "") & ~integral] = "a non-integer frame counter"
    norm = np.linalg.norm(np.where(np.isfinite(data[:, 5:9]), data[:, 5:9], 0.0), axis=1)
    why[(why == "") & ~(np.abs(norm - 1.0) < 1e-6)] = "a quaternion that is not of unit length"
    return why


def pose_at(data: np.ndarray, index: int) -> LandmarkFrame:
    """Row ``index`` of a pose recording's parsed rows as a :class:`LandmarkFrame`."""
    row = data[index]
    person = row[2] == 1.0
    image = row[_IMAGE0:].reshape(POSE_LANDMARKS, IMAGE_FIELDS).copy()
    return LandmarkFrame(
        float(row[0]),
        int(row[1]),
        row[_WORLD0:_IMAGE0].reshape(POSE_LANDMARKS, WORLD_FIELDS).copy() if person else None,
        image if person and np.isfinite(image).all() else None,
        int(row[3]),
        int(row[4]),
        row[_OBS0:_WORLD0] == 1.0,
    )


def hand_at(data: np.ndarray, index: int) -> HandPose:
    """Row ``index`` of a hand recording's parsed rows as a :class:`HandPose`."""
    row = data[index]
    return HandPose(float(row[0]), int(row[1]), row[2:5].copy(), row[5:9].copy())
