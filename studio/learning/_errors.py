"""The learning package's user-facing errors.

Every bad parameter, bad demonstration or bad policy file raises a :class:`LearningError` whose
message names the thing, the bad value and the fix, so the CLI and the web page can show it as is.
"""

from __future__ import annotations

from .._errors import StudioError


class LearningError(StudioError):
    """Bad input to the learning engine; ``str(err)`` says what is wrong and how to fix it."""


class ConfigError(LearningError):
    """One or more bad training settings.

    Attributes:
        problems: one sentence per bad field, each naming the field, its value and the allowed
            range; ``str(err)`` joins them, so a form can also show them field by field.
    """

    def __init__(self, problems: list[str]) -> None:
        super().__init__(" ".join(problems))
        self.problems = list(problems)


class PolicyFileError(LearningError):
    """A policy file that cannot be read: missing, corrupt, or written by a newer studio."""
