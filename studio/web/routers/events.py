"""``/api/events``: the live stream (Server-Sent Events) of source status, captures, run curves
and list changes.

Each client gets its own generator that polls the studio state; nothing is queued per client, so
a slow or vanished client never holds up the pipeline or training, and a client that disconnects
just ends its generator.
"""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import AsyncIterator

from fastapi import APIRouter, Request
from fastapi.responses import StreamingResponse

from .._deps import CaptureDep, ChangesDep, RunsDep, SourcesDep
from ..services import Capture, ListChanges, Run, RunQueue, Sources

router = APIRouter(prefix="/api/events", tags=["events"])

TICK_S = 0.1
"""The stream wakes up this often."""
SOURCE_EVERY_S = 0.25
"""Source status: about 4 per second."""
RUN_EVERY_S = 0.1
"""Run progress while training: up to 10 per second (at least 5 when the curve moves slowly)."""
KEEPALIVE_EVERY_S = 15.0
"""A comment line this often keeps proxies from closing an idle stream."""


def sse(event: str, data: object) -> str:
    """One Server-Sent Event."""
    return f"event: {event}\ndata: {json.dumps(data, separators=(',', ':'))}\n\n"


async def stream_events(
    changes: ListChanges,
    sources: Sources,
    capture: Capture,
    runs: RunQueue,
    request: Request | None = None,
    max_seconds: float | None = None,
) -> AsyncIterator[str]:
    """The event stream of one client (see ``docs/api.md``).

    Args:
        changes: the lists' versions.
        sources: the live source (its status).
        capture: the capture in progress.
        runs: the runs (their progress while training).
        request: the client's request, to notice a disconnect.
        max_seconds: end the stream after this long (None: until the client leaves).
    """
    start = time.monotonic()
    versions = changes.versions()
    run_seen: dict[str, int] = {}  # per run: the curve version this client has
    last = {"source": -1e9, "run": -1e9, "keepalive": start, "capture": -1e9}
    capture_was_active = False
    yield "retry: 2000\n\n"
    while True:
        now = time.monotonic()
        if max_seconds is not None and now - start > max_seconds:
            return
        if request is not None and await request.is_disconnected():
            return
        if now - last["source"] >= SOURCE_EVERY_S:
            last["source"] = now
            yield sse("source", sources.public())
            status = capture.status()
            if status["active"] or capture_was_active:
                yield sse("capture", status)
            capture_was_active = bool(status["active"])
        if now - last["run"] >= RUN_EVERY_S:
            last["run"] = now
            for run in runs.running():
                yield sse("run", run_event(run, run_seen))
        current = changes.versions()
        for name, version in current.items():
            if version != versions.get(name):
                if name == "runs":
                    for run_id in list(run_seen):
                        final = _final_run(runs, run_id, run_seen)
                        if final is not None:
                            yield sse("run", final)
                yield sse("lists", {"changed": name})
        versions = current
        if now - last["keepalive"] >= KEEPALIVE_EVERY_S:
            last["keepalive"] = now
            yield ": keep-alive\n\n"
        # sleep to the next tick of a fixed schedule, so slow ticks do not lower the rate
        await asyncio.sleep(max(0.0, TICK_S - (time.monotonic() - now)))


def run_event(run: Run, seen: dict[str, int]) -> dict[str, object]:
    """A ``run`` event: the run, and its curve where it changed since this client's last event.

    A client's first event carries the whole curve (``curve``, ``from`` 0); later ones carry
    ``pieces``, each ``{"from", "to", "curve"}``: episodes ``from`` to ``to`` (0-based, end
    excluded) that finished meanwhile, which replace those episodes of the client's copy. So an
    event costs the same at episode 10 and at episode 50,000, and the same when a run's many
    experiments train at far-apart episodes (each running experiment makes one small piece).
    """
    with run.curve_held() as curve:
        event: dict[str, object] = {"run": run.model(curve).model_dump(mode="json")}
        previous = seen.get(run.id)
        if previous is None:
            event.update({"curve": curve.curve(), "from": 0})
        else:
            event["pieces"] = [
                {"from": start, "to": stop, "curve": curve.curve(start, stop)}
                for start, stop in curve.changed_since(previous)
            ]
        seen[run.id] = curve.version
    return event


def _final_run(runs: RunQueue, run_id: str, seen: dict[str, int]) -> dict[str, object] | None:
    """The last event of a run that stopped training since the previous tick."""
    try:
        run = runs.get(run_id)
    except Exception:
        seen.pop(run_id, None)
        return None
    if run.status == "running":
        return None
    event = run_event(run, seen)
    seen.pop(run_id, None)
    return event


@router.get("", response_class=StreamingResponse)
async def events(
    request: Request,
    changes: ChangesDep,
    sources: SourcesDep,
    capture: CaptureDep,
    runs: RunsDep,
    max_seconds: float | None = None,
) -> StreamingResponse:
    """Server-Sent Events: ``source`` (~4/s), ``capture``, ``run`` (>= 5/s while training), ``lists``.

    ``max_seconds`` ends the stream after that long (scripts, tests); browsers leave it out.
    """
    return StreamingResponse(
        stream_events(changes, sources, capture, runs, request, max_seconds),
        media_type="text/event-stream",
        headers={"Cache-Control": "no-cache", "X-Accel-Buffering": "no"},
    )
