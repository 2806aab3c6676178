"""The kinematics package's user-facing error.

Raised for bad input to any kinematics function (wrong array shapes, NaN or infinite angles,
inconsistent configurations), always with one sentence naming the problem and the fix, so that no
bad value reaches Pinocchio and no silently wrong answer comes back.
"""

from __future__ import annotations

from .._errors import StudioError


class KinematicsError(StudioError):
    """Bad input to a kinematics model; ``str(err)`` says what is wrong and how to fix it."""
