"""Errors the API turns into 4xx answers with a one-sentence JSON ``detail``.

Each is a :class:`studio.StudioError`, so its message names the problem and the fix; the class
only chooses the HTTP status. Errors from the algorithm packages (bad training settings, a
malformed recording, a refused demonstration) are also ``StudioError`` and answer 422. A write
the disk refuses (full, read-only, not permitted) is one sentence too, made here for every write
path (:func:`storage_sentence`), answered as 507.
"""

from __future__ import annotations

import dataclasses
import errno
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from pydantic import BaseModel, Field

from studio import StudioError
from studio.motion import Finding


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


class TooManyRequestsError(WebError):
    """A flood of updates from one client (the studio keeps running; the update is dropped)."""

    status_code = 429


class StorageError(WebError):
    """The disk refused a write: full, over quota, read-only, or not the studio's to write."""

    status_code = 507


STORAGE_PROBLEMS = {
    errno.ENOSPC: ("is full", "free some space"),
    errno.EDQUOT: ("is over your disk quota", "free some space"),
    errno.EROFS: ("is read-only", "start the studio with --data-dir on a writable disk"),
    errno.EACCES: (
        "may not be written by the studio",
        "fix the folder's permissions or start the studio with another --data-dir",
    ),
    errno.EPERM: (
        "may not be written by the studio",
        "fix the folder's permissions or start the studio with another --data-dir",
    ),
}
"""The write failures a user can fix, by errno: what the disk is, and the fix."""


def storage_errno(err: BaseException) -> int | None:
    """The errno of a write failure a user can fix, or None for any other error.

    ``err`` is an ``OSError``, or an error whose message quotes one (the capture writer reports
    its disk failures as a :class:`studio.capture.RecordingError` naming the ``strerror``).
    """
    if isinstance(err, OSError):
        return err.errno if err.errno in STORAGE_PROBLEMS else None
    text = str(err)
    for code in STORAGE_PROBLEMS:
        if os.strerror(code) in text:
            return code
    return None


def storage_sentence(
    err: BaseException, folder: Path, kept: str = "nothing was changed", then: str = "try again"
) -> str | None:
    """One sentence for a write the disk refused, or None when ``err`` is no such failure.

    Args:
        err: the failure (see :func:`storage_errno`).
        folder: where the studio was writing (the data folder or one of its subfolders).
        kept: what is left, e.g. ``"1234 frames kept"`` for a capture.
        then: what to do after the fix, e.g. ``"record again"``.
    """
    code = storage_errno(err)
    if code is None:
        return None
    what, fix = STORAGE_PROBLEMS[code]
    return f"The disk holding {folder} {what}: {kept}; {fix} and {then}."


def os_error_answer(err: OSError, data_dir: Path) -> tuple[int, str]:
    """The HTTP status and the one sentence for an ``OSError`` a request ran into.

    A write the disk refused is a 507 naming the disk and the fix; a file deleted by another
    request meanwhile (a rename racing a delete) is a 404; anything else is a 500 that still
    says what happened.
    """
    sentence = storage_sentence(err, data_dir)
    if sentence is not None:
        return StorageError.status_code, sentence
    if isinstance(err, FileNotFoundError):
        return (
            NotFoundError.status_code,
            "A file this request needs was deleted meanwhile; refresh the list and try again.",
        )
    reason = err.strerror or type(err).__name__
    return 500, f"The studio could not read or write a file ({reason}); see the server log."


class FindingPublic(BaseModel):
    """One problem at one sample of a robot's motion, as the safety checks found it."""

    sample: int = Field(description="the sample's index (0-based row of the file)")
    time: float = Field(description="its time (s)")
    what: str = Field(description="position, velocity, acceleration, collision or reach")
    where: str = Field(description="the joint's name, or the link pair a/b")
    sentence: str = Field(description="the problem in words, with the margin")


def findings_public(findings: Sequence[Finding]) -> list[dict[str, object]]:
    """The findings as the API answers them (:class:`FindingPublic`)."""
    return [FindingPublic.model_validate(dataclasses.asdict(f)).model_dump() for f in findings]


class ErrorPublic(BaseModel):
    """What every refused request answers: one sentence, and for a refused form every bad field."""

    detail: str = Field(description="one sentence naming the problem and the fix")
    reason: str | None = Field(
        None, description="a machine-readable reason, e.g. a refused demonstration's"
    )
    problems: list[str] | None = Field(None, description="every bad field of a refused form")
    by_field: dict[str, str] | None = Field(None, description="the problems keyed by field")
    findings: list[FindingPublic] | None = Field(
        None, description="an export the safety checks refused (reason safety): every finding"
    )


ERROR_RESPONSE = "An error: one sentence saying what is wrong and how to fix it."


def document_errors(schema: dict[str, Any]) -> dict[str, Any]:
    """Make an OpenAPI schema say what the studio's errors really look like.

    FastAPI declares its own validation-error shape (``detail`` a list) for 422, but the studio
    answers every error, 422 included, as :class:`ErrorPublic`; and any operation may answer
    404, 409, 413, 507 and the like. Each operation gets that one error shape for 422 and as
    its ``default`` response.
    """
    components = schema.setdefault("components", {}).setdefault("schemas", {})
    for name in ("HTTPValidationError", "ValidationError"):
        components.pop(name, None)
    components["ErrorPublic"] = ErrorPublic.model_json_schema(
        ref_template="#/components/schemas/{model}"
    )
    error = {
        "description": ERROR_RESPONSE,
        "content": {"application/json": {"schema": {"$ref": "#/components/schemas/ErrorPublic"}}},
    }
    for item in schema.get("paths", {}).values():
        for operation in item.values():
            if not isinstance(operation, dict) or "responses" not in operation:
                continue
            responses = operation["responses"]
            if "422" in responses:
                responses["422"] = error
            responses["default"] = error
    return schema
