"""The one exception family a user sees.

Every error a user or a device can cause (a bad file, a bad parameter, a lost connection) is raised
as a :class:`StudioError` (or a subclass) whose message is one sentence naming the problem and the
fix. The CLI prints it without a traceback; the API returns it as a 4xx JSON ``detail``.
"""

from __future__ import annotations


class StudioError(Exception):
    """A problem the user can fix; ``str(err)`` says what and how."""
