"""One tape frame: what every source yields, so everything downstream is source-agnostic."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SWITCH0_BIT = 1 << 4
"""Status bit of switch 0 (ShapeTape status byte, bit 4)."""
TRIGGER_BIT = 1 << 5
"""Status bit of the trigger (bit 5)."""
SWITCH1_BIT = 1 << 6
"""Status bit of switch 1 (bit 6)."""
STATUS_BITS_MASK = SWITCH0_BIT | TRIGGER_BIT | SWITCH1_BIT
"""The status bits a frame keeps (the group count, bits 0-2, is the device's framing only)."""


@dataclass(frozen=True, slots=True, eq=False)
class TapeFrame:
    """One sample of the tape.

    Args:
        t: time in seconds since the source started (the device's clock when it has one).
        frame: the frame counter (consecutive from the source; gaps mean lost frames).
        bend: bend angle per region in radians, shape ``(regions,)``.
        twist: twist angle per region in radians, shape ``(regions,)``.
        status: the device's switch/trigger bits (:data:`SWITCH0_BIT`, ...).
    """

    t: float
    frame: int
    bend: np.ndarray
    twist: np.ndarray
    status: int = 0

    @property
    def regions(self) -> int:
        """Number of bend/twist regions."""
        return int(self.bend.shape[0])

    @property
    def switch0(self) -> bool:
        """Whether switch 0 is pressed."""
        return bool(self.status & SWITCH0_BIT)

    @property
    def trigger(self) -> bool:
        """Whether the trigger is pressed."""
        return bool(self.status & TRIGGER_BIT)

    @property
    def switch1(self) -> bool:
        """Whether switch 1 is pressed."""
        return bool(self.status & SWITCH1_BIT)

    def same_as(self, other: TapeFrame) -> bool:
        """Whether two frames hold exactly the same values (arrays compared element-wise)."""
        return (
            self.t == other.t
            and self.frame == other.frame
            and self.status == other.status
            and np.array_equal(self.bend, other.bend)
            and np.array_equal(self.twist, other.twist)
        )


def make_frame(
    t: float, frame: int, bend: np.ndarray, twist: np.ndarray, status: int = 0
) -> TapeFrame:
    """A :class:`TapeFrame` with its arrays as float64 copies (so no caller can change them later)."""
    return TapeFrame(
        float(t),
        int(frame),
        np.array(bend, dtype=np.float64),
        np.array(twist, dtype=np.float64),
        int(status),
    )


def frames_to_arrays(frames: list[TapeFrame]) -> tuple[np.ndarray, ...]:
    """Stack frames into ``(t (N,), frame (N,), status (N,), bend (N, R), twist (N, R))``."""
    if not frames:
        empty = np.zeros((0, 0))
        return np.zeros(0), np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64), empty, empty
    t = np.fromiter((f.t for f in frames), dtype=np.float64, count=len(frames))
    counter = np.fromiter((f.frame for f in frames), dtype=np.int64, count=len(frames))
    status = np.fromiter((f.status for f in frames), dtype=np.int64, count=len(frames))
    bend = np.stack([f.bend for f in frames])
    twist = np.stack([f.twist for f in frames])
    return t, counter, status, bend, twist
