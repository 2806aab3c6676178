"""Smooth joint motions the physics tests replay."""

from __future__ import annotations

import numpy as np


def smooth_move(
    start: np.ndarray, end: np.ndarray, seconds: float, rate_hz: float = 100.0
) -> tuple[np.ndarray, np.ndarray]:
    """Times and joints of a minimum-jerk move from ``start`` to ``end``: at rest at both ends."""
    times = np.arange(0.0, seconds + 0.5 / rate_hz, 1.0 / rate_hz)
    s = times / times[-1]
    blend = 10 * s**3 - 15 * s**4 + 6 * s**5
    return times, start + np.outer(blend, end - start)
