"""The network bridge's wire format: one tape frame per UDP datagram (version 1).

All fields are big-endian (network order)::

    offset  size  type      field
    0       4     bytes     magic b"STAP"
    4       1     uint8     version (1)
    5       1     uint8     flags (bit 0: signed; the others reserved, 0)
    6       2     uint16    regions R
    8       4     uint32    frame counter (wraps at 2**32)
    12      8     float64   timestamp t, seconds since the sender started
    20      2     uint16    status bits (bit 4 switch0, bit 5 trigger, bit 6 switch1)
    22      4*R   float32   bend per region, radians
    22+4R   4*R   float32   twist per region, radians

A signed datagram (flags bit 0) ends with 16 more bytes: the first 16 bytes of the HMAC-SHA256
of everything before them, keyed by :func:`bridge_key` of the studio's token. A receiver given a
key (a network source listening beyond loopback) takes only datagrams signed with it, so nobody
without the token can drive the live tape. The signature authenticates frames; it does not hide
them.

A 16-region frame is 150 bytes (166 signed). A receiver rejects (and counts) datagrams with
another magic, a newer version, a length that does not match R, non-finite angles, or (given a
key) no signature or a wrong one.
"""

from __future__ import annotations

import hashlib
import hmac
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
SIGNED = 0x01
"""Flags bit: the datagram ends with a signature (:data:`SIGNATURE_BYTES`)."""
SIGNATURE_BYTES = 16
"""Length of a datagram's signature: truncated HMAC-SHA256."""
KEY_CONTEXT = b"teach-studio network bridge v1"
"""What :func:`bridge_key` mixes into the token, so the key signs only bridge frames."""


class WireError(ValueError):
    """A datagram that does not decode; the message says why."""


def bridge_key(token: str) -> bytes:
    """The key that signs bridge datagrams, derived from the studio's token (the token itself
    never goes on the wire)."""
    return hmac.new(token.encode(), KEY_CONTEXT, hashlib.sha256).digest()


def _signature(key: bytes, signed_part: bytes) -> bytes:
    return hmac.new(key, signed_part, hashlib.sha256).digest()[:SIGNATURE_BYTES]


def encode_frame(frame: TapeFrame, key: bytes | None = None) -> bytes:
    """One datagram for ``frame`` (angles rounded to float32), signed when given a ``key``
    (:func:`bridge_key`)."""
    regions = frame.bend.shape[0]
    flags = SIGNED if key is not None else 0
    head = HEADER.pack(
        MAGIC,
        WIRE_VERSION,
        flags,
        regions,
        frame.frame & 0xFFFFFFFF,
        frame.t,
        frame.status & 0xFFFF,
    )
    data = head + np.concatenate([frame.bend, frame.twist]).astype(">f4").tobytes()
    return data + _signature(key, data) if key is not None else data


def decode_frame(data: bytes, key: bytes | None = None) -> TapeFrame:
    """The frame in a datagram; given a ``key`` (:func:`bridge_key`), only a datagram signed with
    it.

    Raises:
        WireError: the datagram is malformed or, given a key, unsigned or signed with another
            (the message says which).
    """
    if len(data) < HEADER.size:
        raise WireError(f"{len(data)} bytes is shorter than the {HEADER.size}-byte header")
    magic, version, flags, regions, counter, t, status = HEADER.unpack_from(data)
    if magic != MAGIC:
        raise WireError(f"magic {magic!r} is not {MAGIC!r}")
    if version < 1 or version > WIRE_VERSION:
        raise WireError(
            f"wire version {version} is not supported (this studio reads 1..{WIRE_VERSION})"
        )
    if not 1 <= regions <= MAX_REGIONS:
        raise WireError(f"{regions} regions is outside 1..{MAX_REGIONS}")
    signed = bool(flags & SIGNED)
    expected = HEADER.size + 8 * regions + (SIGNATURE_BYTES if signed else 0)
    if len(data) != expected:
        raise WireError(f"{len(data)} bytes where {regions} regions need {expected}")
    if key is not None:
        if not signed:
            raise WireError(
                "an unsigned frame, where this studio takes only frames signed with its token "
                "(give the sender the token: studio bridge --token)"
            )
        body = data[:-SIGNATURE_BYTES]
        if not hmac.compare_digest(_signature(key, body), data[-SIGNATURE_BYTES:]):
            raise WireError(
                "a frame signed with another token (give the sender this studio's token)"
            )
    count = 2 * regions
    angles = np.frombuffer(data, dtype=">f4", count=count, offset=HEADER.size).astype(np.float64)
    if not np.isfinite(angles).all() or not np.isfinite(t):
        raise WireError("a NaN or infinite value")
    return TapeFrame(float(t), int(counter), angles[:regions], angles[regions:], int(status))
