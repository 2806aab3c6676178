"""The capture package's error family: every one is a :class:`studio.StudioError`."""

from __future__ import annotations

from studio._errors import StudioError


class CaptureError(StudioError):
    """A capture problem the user can fix (a bad parameter, a missing device, a lost connection)."""


class RecordingError(CaptureError):
    """A recording file that cannot be read or written; the message names the file and line."""


class DemonstrationError(CaptureError):
    """A segment that cannot become a demonstration; ``reason`` is a short machine-readable tag.

    Reasons: ``"never_reaches_goal"``, ``"leaves_joint_range"``, ``"bad_fit"``, ``"too_short"``,
    ``"bad_file"``.
    """

    def __init__(self, message: str, reason: str) -> None:
        super().__init__(message)
        self.reason = reason
