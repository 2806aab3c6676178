"""In a real browser, the page writes the DOM only when what it shows changes.

The live stream re-sends the source's status several times a second. With software rendering (a
machine without a GPU) every write that changes nothing still costs a style pass, a layout and a
repaint, and that CPU is taken from a training run. So: a still source causes no DOM writes in
the parts it is drawn into, and re-drawing the run list keeps the rows that are drawn the same.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from tests.e2e.conftest import Studio
from tests.page_hooks import hook

pytestmark = pytest.mark.e2e

SOURCE_EVENTS = 8
"""Source events to wait for while watching the DOM (the stream sends about four a second)."""
READY_TIMEOUT_MS = 30_000
EVENTS_TIMEOUT_MS = 20_000
ROW_RATE_FRAMES = 18
"""Chart frames (3 s at CURVE_FPS) over which a training run's row redraws are counted."""
SAMPLE = "sample-reach-1"
SOURCE_ROOTS = "header.topbar, #sec-source, #sec-record, #sec-demos"
"""The parts of the page the source's status is drawn into."""


@pytest.fixture
def quiet_page(browser: Any, studio_server: Studio) -> Iterator[Any]:
    """A fresh page on the studio with a paused recording as the source (nothing moves)."""
    studio_server.send("PUT", "/api/source", {"kind": "recording", "recording": SAMPLE})
    studio_server.send("POST", "/api/source/playback", {"action": "pause"})
    context = browser.new_context(viewport={"width": 1440, "height": 900})
    page = context.new_page()
    try:
        page.goto(studio_server.base + "/")
        page.wait_for_selector("body[data-ready='1']", timeout=READY_TIMEOUT_MS)
        yield page
    finally:
        context.close()
        studio_server.send("PUT", "/api/source", {"kind": "simulator"})  # as the stories expect


def test_a_still_source_writes_nothing_to_the_page(quiet_page: Any) -> None:
    page = quiet_page
    # Let the status settle after the pause (the frame rate falls to 0 over its window), then
    # watch every change to the parts of the page the status is drawn into.
    page.wait_for_function(
        "p => { const s = p.S.source; return s && !s.playback.playing && !s.rate_hz; }",
        arg=hook(page),
        timeout=EVENTS_TIMEOUT_MS,
    )
    assert page.locator(SOURCE_ROOTS).count() == 4
    page.evaluate(
        """async (SOURCE_ROOTS) => {
            window.__mutations = [];
            window.__sourceEvents = 0;
            const { events } = await import("/static/events.js");
            events.addEventListener("source", () => { window.__sourceEvents++; });
            const observer = new MutationObserver((records) => {
                for (const m of records) {
                    const where = m.target.id || (m.target.parentElement && m.target.parentElement.id) || m.target.nodeName;
                    window.__mutations.push(`${m.type} ${where} ${m.attributeName || ""}`);
                }
            });
            // What the source's status is drawn into (renderSource, the capture and mark
            // buttons); the chart and the run list load on their own schedule.
            for (const root of document.querySelectorAll(SOURCE_ROOTS)) {
                observer.observe(root, { subtree: true, childList: true, attributes: true, characterData: true });
            }
        }""",
        SOURCE_ROOTS,
    )
    page.wait_for_function(
        f"() => window.__sourceEvents >= {SOURCE_EVENTS}", timeout=EVENTS_TIMEOUT_MS
    )
    assert page.evaluate("() => window.__mutations") == []


def test_redrawing_the_run_list_keeps_unchanged_rows(
    quiet_page: Any, studio_server: Studio
) -> None:
    page = quiet_page
    run = studio_server.send(
        "POST", "/api/runs", {"name": "quiet-rows", "episodes": 5, "experiments": 2}
    )
    row = f"tr[data-id='{run['id']}']"
    page.wait_for_selector(f"{row}[data-status='done']", timeout=EVENTS_TIMEOUT_MS)
    same, updated = page.evaluate(
        """async (id) => {
            const { renderRuns } = await import("/static/runs.js");
            const { S } = await import("/static/state.js");
            const find = () => document.querySelector(`tr[data-id='${id}']`);
            const before = find();
            renderRuns();
            const same = find() === before;
            const r = S.runs.find((x) => x.id === id);
            r.status = "stopped"; // a change the row shows: it must be redrawn
            renderRuns();
            const updated = find() !== before && find().dataset.status === "stopped";
            r.status = "done";
            renderRuns();
            return [same, updated];
        }""",
        run["id"],
    )
    assert same, "an unchanged run row was rebuilt"
    assert updated, "a changed run row was not redrawn"


def test_a_training_run_redraws_its_row_less_often_than_the_chart(
    quiet_page: Any, studio_server: Studio
) -> None:
    """The run list follows a training run's progress, but at a third of the chart's frames
    (events.js, RUNS_EVERY_FRAMES): rebuilding the list with every frame of the chart was most of
    the page's own work while a run trained."""
    page = quiet_page
    page.evaluate(
        """async () => {
            window.__rowRedraws = {};
            window.__chartFrames0 = (await import("/static/state.js")).S.curveRenders;
            new MutationObserver((records) => {
                for (const m of records) {
                    for (const n of m.addedNodes) {
                        const id = n.dataset && n.dataset.id;
                        if (id) window.__rowRedraws[id] = (window.__rowRedraws[id] || 0) + 1;
                    }
                }
            }).observe(document.getElementById("runs-body"), { childList: true });
        }"""
    )
    run = studio_server.send(
        "POST",
        "/api/runs",
        {"name": "row-rate", "planning": "full", "episodes": 20000, "experiments": 4, "bins": 31},
    )
    row = f"tr[data-id='{run['id']}']"
    try:
        # while it trains: wait for the chart to have drawn enough frames to tell the rates apart
        page.wait_for_selector(f"{row}[data-status='running']", timeout=EVENTS_TIMEOUT_MS * 6)
        p = hook(page)
        page.wait_for_function(
            f"p => p.S.curveRenders - window.__chartFrames0 >= {ROW_RATE_FRAMES}",
            arg=p,
            timeout=EVENTS_TIMEOUT_MS * 6,
        )
        redraws, frames = page.evaluate(
            "([p, id]) => [window.__rowRedraws[id] || 0, p.S.curveRenders - window.__chartFrames0]",
            [p, run["id"]],
        )
    finally:
        studio_server.send("POST", f"/api/runs/{run['id']}/stop")
        page.wait_for_selector(f"{row}:not([data-status='running'])", timeout=EVENTS_TIMEOUT_MS)
    every = page.evaluate("async () => (await import('/static/events.js')).RUNS_EVERY_FRAMES")
    assert every >= 2
    # each status (queued, running) draws at once (and a list reloaded on a status change may
    # draw it again); the progress on every third frame
    assert 2 <= redraws <= frames / every + 6, (redraws, frames)
