"""Run tags and notes (``<run>/notes.json``), and several runs' curves in one CSV.

The rules and the file are :mod:`studio.learning`'s (``write_run_notes``, ``read_run_notes``,
``write_curves_csv``); this router only translates them to HTTP.
"""

from __future__ import annotations

import io
from pathlib import Path
from typing import Annotated

from fastapi import APIRouter, Query, Response
from pydantic import BaseModel, ConfigDict, Field

from studio.learning import (
    RunNotes,
    RunNotesError,
    read_run_notes,
    write_curves_csv,
)

from .._deps import RunsDep
from .._errors import InvalidError
from . import file_responses

router = APIRouter(tags=["runs"])

MAX_CSV_RUNS = 64
"""Most runs in one curves CSV."""


class RunNotesPublic(BaseModel):
    """A run's tags and notes."""

    tags: list[str]
    notes: str
    updated: str | None = Field(None, description="UTC time of the last change; None if never")
    error: str | None = Field(None, description="why the stored notes.json could not be read")


class RunNotesUpdate(BaseModel):
    """New tags and notes for a run (they replace the old ones)."""

    model_config = ConfigDict(extra="forbid")
    tags: list[str] = []
    notes: str = ""


def _public(notes: RunNotes) -> RunNotesPublic:
    return RunNotesPublic(tags=list(notes.tags), notes=notes.notes, updated=notes.updated)


def _notes_public(path: Path) -> RunNotesPublic:
    try:
        return _public(read_run_notes(path))
    except RunNotesError as err:
        return RunNotesPublic(tags=[], notes="", error=str(err))


@router.get("/api/run-notes", response_model=dict[str, RunNotesPublic])
def list_run_notes(runs: RunsDep) -> dict[str, RunNotesPublic]:
    """Every run's tags and notes, by run id (runs without any are left out)."""
    out: dict[str, RunNotesPublic] = {}
    for run in runs.list():
        notes = _notes_public(run.folder.path)
        if notes.tags or notes.notes or notes.error:
            out[run.id] = notes
    return out


@router.get("/api/runs/{run_id}/notes", response_model=RunNotesPublic)
def read_notes(run_id: str, runs: RunsDep) -> RunNotesPublic:
    """A run's tags and notes (empty when it has none)."""
    return _notes_public(runs.get(run_id).folder.path)


@router.put("/api/runs/{run_id}/notes", response_model=RunNotesPublic)
def write_notes(run_id: str, body: RunNotesUpdate, runs: RunsDep) -> RunNotesPublic:
    """Replace a run's tags and notes, stored in ``<run>/notes.json`` beside its ``config.json``
    (422 naming the limit broken; 409 while the run folder is being created or deleted)."""
    return _public(runs.write_notes(run_id, body.tags, body.notes))


@router.get("/api/run-curves.csv", response_class=Response, responses=file_responses("text/csv"))
def download_curves(
    runs: RunsDep,
    run: Annotated[list[str], Query(description="run ids, in the order wanted")] = [],  # noqa: B006
) -> Response:
    """Several runs' curves in one CSV: the one curve layout with a first ``configuration``
    column naming each row's run (as ``studio reproduce``'s ``curves.csv``)."""
    if not run:
        raise InvalidError("No run given; add ?run=<id> for each run to export.")
    if len(run) > MAX_CSV_RUNS:
        raise InvalidError(
            f"{len(run)} runs given, more than the {MAX_CSV_RUNS} one file takes; export fewer."
        )
    out = io.StringIO()
    write_curves_csv(out, runs.labelled_curves(run))
    return Response(
        out.getvalue(),
        media_type="text/csv",
        headers={"Content-Disposition": 'attachment; filename="curves.csv"'},
    )
