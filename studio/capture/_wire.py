"""The network bridge's wire format: one tape frame per UDP datagram (version 1).

All fields are big-endian (network order)::

    offset  size  type      field
    0       4     bytes     magic b"STAP"
    4       1     uint8     version (1)
    5       1     uint8     flags (0; reserved)
    6       2     uint16    regions R
    8       4     uint32    frame counter (wraps at 2**32)
    12      8     float64   timestamp t, seconds since the sender started
    20      2     uint16    status bits (bit 4 switch0, bit 5 trigger, bit 6 switch1)
    22      4*R   float32   bend per region, radians
    22+4R   4*R   float32   twist per region, radians

A 16-region frame is 150 bytes. A receiver rejects (and counts) datagrams with another magic, a
newer version, a length that does not match R, or non-finite angles.
"""

from __future__ import annotations

import struct

import numpy as np

from ._frames import TapeFrame
from ._recording_format import MAX_REGIONS

MAGIC = b"STAP"
"""First four bytes of every datagram."""
WIRE_VERSION = 1
"""The version this code writes and the newest it reads."""
HEADER = struct.Struct("!4sBBHIdH")
"""Everything before the angles."""
DEFAULT_PORT = 47110
"""UDP port of the network source unless told otherwise."""


class WireError(ValueError):
    """A datagram that does not decode; the message says why."""


def encode_frame(frame: TapeFrame) -> bytes:
    """One datagram for ``frame`` (angles rounded to float32)."""
    regions = frame.bend.shape[0]
    head = HEADER.pack(
        MAGIC, WIRE_VERSION, 0, regions, frame.frame & 0xFFFFFFFF, frame.t, frame.status & 0xFFFF
    )
    angles = np.concatenate([frame.bend, frame.twist]).astype(">f4")
    return head + angles.tobytes()


def decode_frame(data: bytes) -> TapeFrame:
    """The frame in a datagram.

    Raises:
        WireError: the datagram is malformed (the message says how).
    """
    if len(data) < HEADER.size:
        raise WireError(f"{len(data)} bytes is shorter than the {HEADER.size}-byte header")
    magic, version, _flags, regions, counter, t, status = HEADER.unpack_from(data)
    if magic != MAGIC:
        raise WireError(f"magic {magic!r} is not {MAGIC!r}")
    if version < 1 or version > WIRE_VERSION:
        raise WireError(
            f"wire version {version} is not supported (this studio reads 1..{WIRE_VERSION})"
        )
    if not 1 <= regions <= MAX_REGIONS:
        raise WireError(f"{regions} regions is outside 1..{MAX_REGIONS}")
    expected = HEADER.size + 8 * regions
    if len(data) != expected:
        raise WireError(f"{len(data)} bytes where {regions} regions need {expected}")
    angles = np.frombuffer(data, dtype=">f4", offset=HEADER.size).astype(np.float64)
    if not np.isfinite(angles).all() or not np.isfinite(t):
        raise WireError("a NaN or infinite value")
    return TapeFrame(float(t), int(counter), angles[:regions], angles[regions:], int(status))
