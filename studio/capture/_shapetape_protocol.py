"""The ShapeTape serial protocol (Measurand tapeAPI, 2000), encoded and decoded.

The host sends ``0x20``; the tape answers with one frame::

    status      1 byte   bits 0-2: number of 8-channel groups G; bit 4 switch0, 5 trigger, 6 switch1
    serial      2 bytes  big-endian serial number
    [if serial > 4096:  counter 2 bytes BE, timer 3 bytes BE, filler 8 bytes]
    data        16 * G   8 x uint16 big-endian per group
    checksum    1 byte   sum of the data bytes, modulo 256
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

REQUEST = b"\x20"
"""The byte that asks the tape for one frame."""
BAUD_RATE = 115200
"""The tape's serial speed."""
GROUP_MASK = 0x07
"""Status bits holding the group count."""
CHANNELS_PER_GROUP = 8
"""uint16 channels per group."""
GROUP_BYTES = 2 * CHANNELS_PER_GROUP
"""Bytes per group."""
EXTENDED_SERIAL = 4096
"""Tapes with a larger serial number send a counter, a timer and filler."""
EXTENDED_BYTES = 2 + 3 + 8
"""Counter, timer and filler bytes of extended frames."""


class ProtocolError(ValueError):
    """A frame that does not decode (bad checksum, wrong length)."""


@dataclass(frozen=True, eq=False)
class RawFrame:
    """One decoded reply: status byte, serial, optional counter/timer, raw channel counts."""

    status: int
    serial: int
    counter: int | None
    timer: int | None
    raw: np.ndarray

    @property
    def groups(self) -> int:
        """8-channel groups in the frame."""
        return self.status & GROUP_MASK


def groups_for(channels: int) -> int:
    """Groups needed to carry ``channels`` channels."""
    return -(-channels // CHANNELS_PER_GROUP)


def encode_reply(
    raw: np.ndarray,
    serial: int,
    switches: int = 0,
    counter: int = 0,
    timer: int = 0,
    corrupt: bool = False,
) -> bytes:
    """The bytes a tape sends for these raw counts (padded with zeros to whole groups).

    Args:
        raw: uint16 channel counts.
        serial: the tape's serial number (extended layout when above 4096).
        switches: status bits 4-6.
        counter: frame counter (extended layout).
        timer: timer ticks (extended layout).
        corrupt: send a wrong checksum (for testing receivers).
    """
    groups = groups_for(len(raw))
    padded = np.zeros(groups * CHANNELS_PER_GROUP, dtype=">u2")
    padded[: len(raw)] = raw
    data = padded.tobytes()
    head = bytes([(switches & 0x70) | groups]) + int(serial).to_bytes(2, "big")
    if serial > EXTENDED_SERIAL:
        head += (
            (counter & 0xFFFF).to_bytes(2, "big") + (timer & 0xFFFFFF).to_bytes(3, "big") + bytes(8)
        )
    checksum = (sum(data) + (1 if corrupt else 0)) & 0xFF
    return head + data + bytes([checksum])


def reply_length(status: int, serial: int) -> int:
    """Bytes still to read after the 3-byte status+serial prefix."""
    extra = EXTENDED_BYTES if serial > EXTENDED_SERIAL else 0
    return extra + GROUP_BYTES * (status & GROUP_MASK) + 1


def decode_reply(prefix: bytes, rest: bytes) -> RawFrame:
    """Decode a reply from its 3-byte prefix and the remaining bytes.

    Raises:
        ProtocolError: wrong length or checksum.
    """
    status, serial = prefix[0], int.from_bytes(prefix[1:3], "big")
    if len(rest) != reply_length(status, serial):
        raise ProtocolError(
            f"{len(rest)} bytes after the header, expected {reply_length(status, serial)}"
        )
    counter = timer = None
    offset = 0
    if serial > EXTENDED_SERIAL:
        counter = int.from_bytes(rest[0:2], "big")
        timer = int.from_bytes(rest[2:5], "big")
        offset = EXTENDED_BYTES
    data = rest[offset:-1]
    if (sum(data) & 0xFF) != rest[-1]:
        raise ProtocolError(f"checksum {rest[-1]} does not match the data ({sum(data) & 0xFF})")
    raw = np.frombuffer(data, dtype=">u2").astype(np.int64)
    return RawFrame(status, serial, counter, timer, raw)
