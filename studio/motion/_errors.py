"""The motion package's one exception family."""

from __future__ import annotations

from studio import StudioError


class MotionError(StudioError):
    """A recorded motion that cannot be put on a robot as asked (too short a stretch, a
    demonstration whose recording is gone): ``str(err)`` is one sentence with the fix."""
