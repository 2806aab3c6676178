"""The export package's one exception family."""

from __future__ import annotations

from studio import StudioError


class ExportError(StudioError):
    """An export that cannot be made as asked: ``str(err)`` is one sentence with the fix."""


class SafetyError(ExportError):
    """A trajectory refused by the safety checks; ``findings`` lists every problem found.

    The message names the first finding (sample, joint or link pair, margin) and how many more
    there are; ``--unchecked`` writes the file anyway with all of them stated in it.
    """

    reason = "safety"
    """What refused it, for a program (the page offers to export anyway, findings stated)."""

    def __init__(self, message: str, findings: list[str]) -> None:
        super().__init__(message)
        self.findings = findings
