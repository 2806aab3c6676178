"""Errors the API turns into 4xx answers with a one-sentence JSON ``detail``.

Each is a :class:`studio.StudioError`, so its message names the problem and the fix; the class
only chooses the HTTP status. Errors from the algorithm packages (bad training settings, a
malformed recording, a refused demonstration) are also ``StudioError`` and answer 422.
"""

from __future__ import annotations

from .._errors import StudioError


class WebError(StudioError):
    """A request the studio refuses; ``status_code`` is the HTTP status to answer."""

    status_code = 400


class NotFoundError(WebError):
    """The named recording, demonstration, run or policy does not exist."""

    status_code = 404


class ConflictError(WebError):
    """The request clashes with the studio's state (in use, already running, name taken)."""

    status_code = 409


class InvalidError(WebError):
    """A bad name, file or parameter."""

    status_code = 422


class TooLargeError(WebError):
    """An upload over the size limit."""

    status_code = 413
