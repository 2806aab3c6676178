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
            range; ``str(err)`` joins them.
        by_field: the same sentences keyed by field name, so a form can show each next to its
            field (a problem that concerns no single field is keyed ``""``).
    """

    def __init__(self, problems: list[str], fields: list[str] | None = None) -> None:
        super().__init__(" ".join(problems))
        self.problems = list(problems)
        names = fields if fields is not None else [""] * len(problems)
        self.by_field: dict[str, str] = {}
        for name, problem in zip(names, problems, strict=True):
            self.by_field[name] = (
                f"{self.by_field[name]} {problem}" if name in self.by_field else problem
            )


class PolicyFileError(LearningError):
    """A policy file that cannot be read: missing, corrupt, or written by a newer studio."""
