"""The one test of what counts as an integer or a finite number in a user's settings.

A ``bool`` is an ``int`` to Python but never a count or a rate to a user, so both tests refuse it;
numpy scalars count (settings are often computed with numpy).
"""

from __future__ import annotations

import math

import numpy as np


def is_int(value: object) -> bool:
    """Whether ``value`` is an integer (Python or numpy), and not a ``bool``."""
    return isinstance(value, int | np.integer) and not isinstance(value, bool)


def is_number(value: object) -> bool:
    """Whether ``value`` is a finite integer or float (Python or numpy), and not a ``bool``."""
    return (
        isinstance(value, int | float | np.integer | np.floating)
        and not isinstance(value, bool)
        and math.isfinite(value)
    )
