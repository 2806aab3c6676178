"""Segments an operator marked live: stretches of frames with the tape's trigger held down.

The ShapeTape has a trigger and two switches; holding the trigger during a demonstration marks its
start and stop in the recording itself, with no one at the keyboard. The simulator holds it during
:meth:`SimulatorSource.reach`.
"""

from __future__ import annotations

import numpy as np

from ._frames import TRIGGER_BIT
from ._recording_reader import Recording


def trigger_segments(recording: Recording, bit: int = TRIGGER_BIT) -> list[tuple[float, float]]:
    """``[(t0, t1), ...]`` (seconds from the first frame) of every run of frames with ``bit`` set.

    Args:
        recording: the recording.
        bit: the status bit that marks a segment (default: the trigger).

    Returns:
        The segments in order, ready for :func:`extract_demonstration`.
    """
    if len(recording) == 0:
        return []
    on = (recording.status & bit) != 0
    edges = np.diff(np.concatenate([[False], on, [False]]).astype(np.int8))
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1) - 1
    t = recording.t - recording.t[0]
    return [(float(t[a]), float(t[b])) for a, b in zip(starts, ends, strict=True)]
