"""Issue 21's comparison in one click: "also train without demonstrations for comparison" queues
a run with demonstrations and its twin without them (same settings and seed) and opens Compare
runs on the two. Controls are found by role and accessible name."""

from __future__ import annotations

import json
from collections.abc import Iterator
from typing import Any

import pytest

from tests.e2e.conftest import ARTIFACTS, Studio, leave_out_scene, own_page
from tests.page_hooks import hook
from tests.web.conftest import wait_for

pytestmark = pytest.mark.e2e

T = 20.0  # s: the longest one step of the page may take (the machine may be busy)


@pytest.fixture
def small_page(browser: Any, studio_server: Studio) -> Iterator[Any]:
    with own_page(browser, studio_server, 1280, 720) as page:
        yield page
        assert not page.errors, page.errors


def test_one_click_trains_with_and_without_demonstrations_and_compares_them(
    small_page: Any, studio_server: Studio
) -> None:
    page = small_page
    form = page.get_by_test_id("train-form")
    page.locator("#train-form [name='name']").fill("pair")
    page.locator("#train-form [name='episodes']").fill("6")
    page.locator("#train-form [name='experiments']").fill("2")
    page.locator("#train-form [name='seed']").fill("7")
    demos = page.get_by_test_id("train-demos")
    demos.get_by_role("checkbox", name="sample-reach-1").check()
    form.get_by_role("checkbox", name="also train without demonstrations for comparison").check()
    before = {r["id"] for r in studio_server.get("/api/runs")}
    form.get_by_role("button", name="Start", exact=True).click()

    table = page.get_by_role("dialog", name="Compare runs")
    assert wait_for(table.is_visible, T)
    assert wait_for(lambda: len({r["id"] for r in studio_server.get("/api/runs")} - before) == 2, T)
    new = [r for r in studio_server.get("/api/runs") if r["id"] not in before]
    by_name = {r["name"]: r for r in new}
    assert set(by_name) == {"pair", "pair · no demos"}
    ids = sorted(r["id"] for r in new)
    # the pair may wait in the queue behind runs of earlier stories: a run is plotted once it has
    # an episode, so let both finish first
    for r in new:
        assert wait_for(
            lambda r=r: studio_server.get(f"/api/runs/{r['id']}")["status"] == "done", 180
        )
    page.wait_for_function(
        "([p, ids]) => JSON.stringify([...p.chart.drawnRuns()].sort()) === JSON.stringify(ids)",
        arg=[hook(page), ids],
        timeout=T * 1000 * 3,
    )
    # on disk: the same settings and seed, demonstrations in one only
    configs = {
        name: json.loads((studio_server.data_dir / "runs" / r["id"] / "config.json").read_text())
        for name, r in by_name.items()
    }
    taught, bare = configs["pair"], configs["pair · no demos"]
    assert taught["seed"] == bare["seed"] == 7
    assert taught["config"] == bare["config"]
    assert len(taught["demonstrations"]) == 1 and bare["demonstrations"] == []
    # the table highlights what differs: the demonstrations
    row = table.locator(f"[data-testid='compare-row'][data-id='{by_name['pair']['id']}']")
    assert wait_for(lambda: row.count() == 1, T)
    cell = row.locator("td[data-key='demonstrations']")
    assert "differs" in (cell.get_attribute("class") or "")
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    page.screenshot(path=str(ARTIFACTS / "21-pair-compare-1280x720.png"))
    page.set_viewport_size({"width": 1920, "height": 1080})
    page.screenshot(path=str(ARTIFACTS / "21-pair-compare-1920x1080.png"))


def test_a_run_that_finished_unseen_is_plotted_when_the_runs_list_reloads(
    browser: Any, studio_server: Studio
) -> None:
    """A short run can go from queued to done between two ticks of the event stream, so no event
    of its own tells the page; a stream that reconnected misses them too. The runs list reloads on
    the "lists" event its end sends, and must then fetch the curve the page holds empty.

    The page here has no event stream, so nothing else brings the curve."""
    run = studio_server.send(
        "POST", "/api/runs", {"name": "unseen", "episodes": 4, "experiments": 1, "seed": 3}
    )
    assert wait_for(lambda: studio_server.get(f"/api/runs/{run['id']}")["status"] == "done", 180)
    context = browser.new_context(viewport={"width": 1280, "height": 720})
    try:
        leave_out_scene(context, studio_server)
        context.route("**/api/events*", lambda route: route.abort())
        page = context.new_page()
        page.goto(studio_server.base + "/")
        page.wait_for_selector("body[data-ready='1']", timeout=60_000)
        plotted = page.evaluate(
            """async (id) => {
                const { S } = await import("/static/state.js");
                const { loadRuns } = await import("/static/runs.js");
                const { plottedRuns } = await import("/static/chart.js");
                const empty = Object.fromEntries(Object.keys(S.curves.values().next().value || { episodes: 0 }).map((k) => [k, []]));
                S.shownTouched = true;
                S.shown = new Set([id]);
                S.runs.find((r) => r.id === id).status = "queued"; // as the page last saw it
                S.curves.set(id, empty); // as the page holds a run it just queued
                await loadRuns();
                return plottedRuns().map((r) => r.id);
            }""",
            run["id"],
        )
    finally:
        context.close()
    assert plotted == [run["id"]]
