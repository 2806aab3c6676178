"""Dependencies the routers ask for, as ``Annotated`` aliases (FastAPI's "bigger applications").

Each route names the service it acts on (``sources: SourcesDep``); the services are the app's
:class:`~._state.Studio`'s, built when the app starts. A test overrides one with
``app.dependency_overrides[get_sources] = ...``.
"""

from __future__ import annotations

import json
import re
from typing import Annotated

from fastapi import Depends, Request

from studio import unpaired_surrogate

from ._errors import InvalidError
from ._settings import Settings, get_settings
from ._state import Studio
from .live import Pipeline
from .scene import Scene
from .services import (
    Capture,
    Demonstrations,
    ListChanges,
    Policies,
    RecordingStore,
    Reviewer,
    Robots,
    Rollouts,
    RunQueue,
    Sources,
    TakeFlow,
    Training,
    Watching,
)


def get_studio(request: Request) -> Studio:
    """The services of the app serving this request."""
    return request.app.state.studio


StudioDep = Annotated[Studio, Depends(get_studio)]
SettingsDep = Annotated[Settings, Depends(get_settings)]


_SURROGATE_ESCAPE = re.compile(rb"\\u[dD][89a-fA-F]")
"""A JSON escape of a UTF-16 surrogate: a body without one holds only real text."""


async def refuse_broken_text(request: Request) -> None:
    """Refuse a JSON body holding a string that is not text (an unpaired ``\\ud800`` escape).

    Such a string cannot be written as UTF-8: stored in a run's or a recording's file, it would
    make every list that shows it fail. Applied to every route, before the route does anything.
    """
    kind = request.headers.get("content-type", "")
    if kind and "json" not in kind:
        return  # an upload: its own reader checks it
    body = await request.body()  # Starlette keeps it: the route reads the same bytes
    if not _SURROGATE_ESCAPE.search(body):
        return
    try:
        value = json.loads(body)
    except ValueError:
        return  # not JSON: the route answers it
    found = unpaired_surrogate(value)
    if found is not None:
        field = found[0] or "The request body"
        raise InvalidError(
            f"{field} holds an unpaired UTF-16 surrogate, which is not text; send it as valid "
            "Unicode text."
        )


def get_sources(studio: StudioDep) -> Sources:
    """The live source."""
    return studio.sources


def get_robots(studio: StudioDep) -> Robots:
    """The robot taught and the ones offered."""
    return studio.robots


def get_capture(studio: StudioDep) -> Capture:
    """The capture and the live demonstration marked in it."""
    return studio.capture


def get_recordings(studio: StudioDep) -> RecordingStore:
    """The recordings."""
    return studio.recordings


def get_demonstrations(studio: StudioDep) -> Demonstrations:
    """The demonstrations."""
    return studio.demonstrations


def get_runs(studio: StudioDep) -> RunQueue:
    """Every run folder and the queue that trains the page's runs."""
    return studio.runs


def get_training(studio: StudioDep) -> Training:
    """The page's way to the run queue."""
    return studio.training


def get_policies(studio: StudioDep) -> Policies:
    """The uploaded policies and the runs'."""
    return studio.policies


def get_rollouts(studio: StudioDep) -> Rollouts:
    """The rollouts watched in the scene."""
    return studio.rollouts


def get_watching(studio: StudioDep) -> Watching:
    """A policy watched in the scene: its rollout, likeness card and CSV."""
    return studio.watching


def get_reviewer(studio: StudioDep) -> Reviewer:
    """A recording's timeline and its review on the robot."""
    return studio.reviewer


def get_takes(studio: StudioDep) -> TakeFlow:
    """The take session."""
    return studio.takes


def get_pipeline(studio: StudioDep) -> Pipeline:
    """The live pipeline."""
    return studio.pipeline


def get_changes(studio: StudioDep) -> ListChanges:
    """The lists' versions."""
    return studio.changes


def get_scene(studio: StudioDep) -> Scene | None:
    """The scene (None: headless)."""
    return studio.scene


SourcesDep = Annotated[Sources, Depends(get_sources)]
RobotsDep = Annotated[Robots, Depends(get_robots)]
CaptureDep = Annotated[Capture, Depends(get_capture)]
RecordingsDep = Annotated[RecordingStore, Depends(get_recordings)]
DemonstrationsDep = Annotated[Demonstrations, Depends(get_demonstrations)]
RunsDep = Annotated[RunQueue, Depends(get_runs)]
TrainingDep = Annotated[Training, Depends(get_training)]
PoliciesDep = Annotated[Policies, Depends(get_policies)]
RolloutsDep = Annotated[Rollouts, Depends(get_rollouts)]
WatchingDep = Annotated[Watching, Depends(get_watching)]
ReviewerDep = Annotated[Reviewer, Depends(get_reviewer)]
TakesDep = Annotated[TakeFlow, Depends(get_takes)]
PipelineDep = Annotated[Pipeline, Depends(get_pipeline)]
ChangesDep = Annotated[ListChanges, Depends(get_changes)]
SceneDep = Annotated[Scene | None, Depends(get_scene)]
