"""Recording in takes: the file ``recordings/takes.json`` that keeps each session's takes.

A session is a run of takes recorded one after another (LeRobot's recording loop: record, review,
keep or redo, next). Each take is a recording of its own; the file says which were kept and, once
the session is made into demonstrations, which demonstration each became. Its format is in
``recordings/README.md`` ("Takes").
"""

from __future__ import annotations

import json
import os
from dataclasses import asdict, dataclass, field
from pathlib import Path

from studio._files import atomic_write_text
from studio._json import read_json

from ._errors import RecordingError

TAKES_FILE = "takes.json"
"""The takes file's name in a data folder's ``recordings/``."""
TAKES_FORMAT = "teach-studio-takes"
TAKES_VERSION = 1
TAKE_STATES = ("recording", "review", "kept")
"""A take is being recorded, waits to be kept or redone, or is kept."""


@dataclass
class Take:
    """One take of a session.

    Attributes:
        recording: the recording's name (``recordings/<name>.tape.csv`` or ``.pose.csv``/``.hand.csv``).
        state: one of :data:`TAKE_STATES`.
        demonstration: the demonstration cut from it, once the session is made into demonstrations.
        error: why it could not be cut (one sentence), if it could not.
    """

    recording: str
    state: str = "recording"
    demonstration: str | None = None
    error: str | None = None


@dataclass
class TakeSession:
    """Takes recorded one after another; ``finished`` is set once they became demonstrations."""

    started: str
    takes: list[Take] = field(default_factory=list)
    finished: str | None = None


def read_takes(path: str | os.PathLike[str]) -> list[TakeSession]:
    """Every session in a takes file, oldest first (none when the file does not exist yet).

    Raises:
        RecordingError: the file is damaged (one sentence naming it and the fix).
    """
    path = Path(path)
    if not path.exists():
        return []
    data = read_json(path, f"the takes file {path}")
    fix = f"fix it or move it aside (the recordings themselves are untouched): {path}"
    if not (isinstance(data, dict) and data.get("format") == TAKES_FORMAT):
        raise RecordingError(f"The takes file is not a {TAKES_FORMAT} file; {fix}.")
    if data.get("version") != TAKES_VERSION:
        raise RecordingError(
            f"The takes file has version {data.get('version')!r}; this studio reads version {TAKES_VERSION}. Update the studio, or {fix}."
        )
    try:
        return [
            TakeSession(
                started=str(s["started"]),
                finished=None if s.get("finished") is None else str(s["finished"]),
                takes=[_take(t) for t in s["takes"]],
            )
            for s in data["sessions"]
        ]
    except (KeyError, TypeError, ValueError) as err:
        raise RecordingError(f"The takes file has a malformed session ({err}); {fix}.") from None


def _take(raw: dict[str, object]) -> Take:
    take = Take(
        recording=str(raw["recording"]),
        state=str(raw["state"]),
        demonstration=None if raw.get("demonstration") is None else str(raw["demonstration"]),
        error=None if raw.get("error") is None else str(raw["error"]),
    )
    if take.state not in TAKE_STATES:
        raise ValueError(f"take state {take.state!r}")
    return take


def write_takes(path: str | os.PathLike[str], sessions: list[TakeSession]) -> Path:
    """Write every session to the takes file (an atomic replace)."""
    data = {
        "format": TAKES_FORMAT,
        "version": TAKES_VERSION,
        "sessions": [asdict(s) for s in sessions],
    }
    return atomic_write_text(path, json.dumps(data, indent=1) + "\n")
