"""The one test of what counts as an integer or a finite number in a user's settings.

A ``bool`` is an ``int`` to Python but never a count or a rate to a user, so both tests refuse it;
numpy scalars count (settings are often computed with numpy).
"""

from __future__ import annotations

import math
import sys


def _numpy_types(*names: str) -> tuple[type, ...]:
    """numpy's types of these names, or none while numpy is not loaded (no value can be one then):
    settings are checked without importing numpy, so `studio train --help` and a mistyped flag
    answer at once."""
    numpy = sys.modules.get("numpy")
    return () if numpy is None else tuple(getattr(numpy, name) for name in names)


def is_numpy_scalar(value: object) -> bool:
    """Whether ``value`` is a numpy integer or float scalar (``np.int64(3)``, ``np.float32(0.5)``)."""
    return isinstance(value, _numpy_types("integer", "floating"))


def is_real(value: object) -> bool:
    """Whether ``value`` is an integer or float (Python or numpy, NaN and infinities included),
    and not a ``bool``."""
    numbers = (int, float, *_numpy_types("integer", "floating"))
    return isinstance(value, numbers) and not isinstance(value, bool)


def is_int(value: object) -> bool:
    """Whether ``value`` is an integer (Python or numpy), and not a ``bool``."""
    return isinstance(value, (int, *_numpy_types("integer"))) and not isinstance(value, bool)


def is_number(value: object) -> bool:
    """Whether ``value`` is a finite integer or float (Python or numpy), and not a ``bool``."""
    return is_real(value) and math.isfinite(value)  # type: ignore[arg-type]
