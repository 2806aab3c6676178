"""The export package's one exception family."""

from __future__ import annotations

from typing import TYPE_CHECKING

from studio import StudioError

if TYPE_CHECKING:
    from studio.motion import Finding


class ExportError(StudioError):
    """An export that cannot be made as asked: ``str(err)`` is one sentence with the fix."""


class SafetyError(ExportError):
    """A trajectory refused by the safety checks; ``findings`` lists every problem found.

    One refusal, two renderings: the message (``str(err)``) names the first finding (sample,
    joint or link pair, margin), how many more there are and the command line's fix
    (``--unchecked`` writes the file anyway with all of them stated in it); ``in_words`` says
    the same with the fix in plain words, for a page (no command-line flag in it).

    Attributes:
        findings: every finding's sentence, first by time first.
        found: the findings themselves (sample, time, kind, joint or link pair, sentence).
        in_words: the refusal with its fix in plain words.
    """

    reason = "safety"
    """What refused it, for a program (the page offers to export anyway, findings stated)."""

    def __init__(
        self,
        message: str,
        findings: list[str],
        *,
        found: tuple[Finding, ...] = (),
        in_words: str = "",
    ) -> None:
        super().__init__(message)
        self.findings = findings
        self.found = found
        self.in_words = in_words or message
