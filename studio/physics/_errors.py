"""The physics package's one exception family."""

from __future__ import annotations

from studio import StudioError


class PhysicsError(StudioError):
    """A simulation that cannot be run as asked: ``str(err)`` is one sentence with the fix."""
