"""A run's tags and notes: ``notes.json`` beside its ``config.json``, written by people only.

The learner never reads or writes this file, and nothing here touches the files the learner
writes, so a run can be tagged while it trains. ``notes.json`` holds ``format``
(``teach-studio-run-notes``), ``version`` (1), ``tags`` (a list of short words), ``notes`` (free
text) and ``updated`` (UTC time of the last change). A run without the file has no tags and no
notes.
"""

from __future__ import annotations

import json
import unicodedata
from dataclasses import dataclass
from pathlib import Path

from ..._files import FileLimitError, atomic_write_text, now_iso
from ..._json import JSONFileError, read_json
from .._errors import LearningError
from ._folder import CONFIG_FILE

NOTES_FILE = "notes.json"
NOTES_FORMAT = "teach-studio-run-notes"
NOTES_VERSION = 1
MAX_TAGS = 16
MAX_TAG_CHARS = 32
MAX_NOTES_CHARS = 4000
NOTES_FILE_BYTES = 64 * 1024
"""Largest ``notes.json`` read (the limits above write at most about 20 KB)."""


class RunNotesError(LearningError):
    """Tags or notes that cannot be stored, or a ``notes.json`` that cannot be read."""


class RunBusyError(LearningError):
    """The run folder is being written or deleted (it has no ``config.json``)."""


@dataclass(frozen=True)
class RunNotes:
    """A run's tags (in the order given, without repeats) and notes."""

    tags: tuple[str, ...] = ()
    notes: str = ""
    updated: str | None = None

    def to_json(self) -> dict[str, object]:
        """The API's and the file's fields."""
        return {"tags": list(self.tags), "notes": self.notes, "updated": self.updated}


def _has_control(text: str, allowed: str = "") -> bool:
    return any(unicodedata.category(c) == "Cc" and c not in allowed for c in text)


def check_run_notes(tags: list[str], notes: str) -> RunNotes:
    """Tags and notes as they will be stored: each tag stripped, repeats dropped.

    Raises:
        RunNotesError: too many tags, a tag empty, too long, with a comma or a control
            character, or notes too long; the sentence names the limit.
    """
    kept: list[str] = []
    for raw in tags:
        tag = raw.strip() if isinstance(raw, str) else ""
        if not tag:
            raise RunNotesError("A tag is empty; give each tag at least one letter.")
        if len(tag) > MAX_TAG_CHARS:
            raise RunNotesError(
                f"The tag {tag[:MAX_TAG_CHARS]!r}… has {len(tag)} characters, more than the {MAX_TAG_CHARS} allowed; shorten it."
            )
        if "," in tag or _has_control(tag):
            raise RunNotesError(
                f"The tag {tag!r} holds a comma or a control character; tags are single words or short phrases, so split it."
            )
        if tag not in kept:
            kept.append(tag)
    if len(kept) > MAX_TAGS:
        raise RunNotesError(
            f"{len(kept)} tags given, more than the {MAX_TAGS} a run may have; keep the ones you filter by."
        )
    if not isinstance(notes, str):
        raise RunNotesError("The notes are not text; send them as a string.")
    if len(notes) > MAX_NOTES_CHARS:
        raise RunNotesError(
            f"The notes have {len(notes)} characters, more than the {MAX_NOTES_CHARS} allowed; shorten them."
        )
    if _has_control(notes, "\n\t"):
        raise RunNotesError("The notes hold a control character; remove it and save again.")
    return RunNotes(tuple(kept), notes)


def read_run_notes(run_dir: Path) -> RunNotes:
    """The tags and notes stored in a run folder (none when it has no ``notes.json``).

    Raises:
        RunNotesError: ``notes.json`` is a link, too large, not JSON, or not run notes (saving
            new notes replaces it).
    """
    path = Path(run_dir) / NOTES_FILE
    what = f"{Path(run_dir).name}/{NOTES_FILE}"
    if path.is_symlink():
        raise RunNotesError(f"{what} is a symbolic link and is not read; save the notes again.")
    if not path.exists():
        return RunNotes()
    try:
        data = read_json(path, what, max_bytes=NOTES_FILE_BYTES, max_depth=4)
    except (FileLimitError, JSONFileError) as err:
        raise RunNotesError(f"{err} Saving the run's notes again replaces it.") from None
    if not isinstance(data, dict) or data.get("format") != NOTES_FORMAT:
        raise RunNotesError(f"{what} is not a run notes file; save the notes again to replace it.")
    tags, notes = data.get("tags", []), data.get("notes", "")
    if not isinstance(tags, list) or not isinstance(notes, str):
        raise RunNotesError(f"{what} has damaged tags or notes; save the notes again.")
    try:
        checked = check_run_notes(tags, notes)
    except RunNotesError as err:
        raise RunNotesError(f"{what}: {err}") from None
    updated = data.get("updated")
    return RunNotes(checked.tags, checked.notes, updated if isinstance(updated, str) else None)


def write_run_notes(run_dir: Path, tags: list[str], notes: str) -> RunNotes:
    """Check and store a run's tags and notes (atomically: a reader sees the old or the new).

    Raises:
        RunNotesError: the tags or notes break a limit (:func:`check_run_notes`).
        RunBusyError: the folder has no ``config.json``: it is being created or deleted.
    """
    checked = check_run_notes(tags, notes)
    run_dir = Path(run_dir)
    config = run_dir / CONFIG_FILE
    if run_dir.is_symlink() or not config.is_file() or config.is_symlink():
        raise RunBusyError(
            f"Run {run_dir.name} is being written or deleted (it has no {CONFIG_FILE}); wait until the runs list shows it, then save again."
        )
    stored = RunNotes(checked.tags, checked.notes, now_iso())
    body = {"format": NOTES_FORMAT, "version": NOTES_VERSION, **stored.to_json()}
    atomic_write_text(run_dir / NOTES_FILE, json.dumps(body, ensure_ascii=False, indent=1) + "\n")
    if not config.is_file():  # deleted meanwhile: leave nothing that would keep its folder
        (run_dir / NOTES_FILE).unlink(missing_ok=True)
        raise RunBusyError(
            f"Run {run_dir.name} was deleted while its notes were saved; nothing was kept."
        )
    return stored
