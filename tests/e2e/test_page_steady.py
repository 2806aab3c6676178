"""A page that keeps still and tells things apart: notices that come and go never push the
sections below them, two runs never read the same, and the Compare table fits a 1280 x 720 window.
"""

from __future__ import annotations

from typing import Any

import pytest

from tests.e2e.conftest import Studio, own_page, shot
from tests.page_hooks import hook
from tests.web.conftest import wait_for

pytestmark = pytest.mark.e2e

T = 60_000  # ms: the longest one step of the page may take on a busy machine

NOTICES = [
    ("robot_warning", None),
    (
        "robot_warning",
        "The hand is straight above or below the shoulder, where the UR5 cannot reach: its target "
        "is kept 12 cm out from the robot's first axis; move the hand forward to follow it exactly.",
    ),
    ("robot_warning", None),
    (
        "robot_warning",
        "The hand is beyond the UR5's reach: its target is drawn 9 cm back into it; bring the hand "
        "closer to the shoulder to follow it exactly.",
    ),
    ("warning", "Frames arrive late."),
    ("robot_warning", None),
]
"""What the studio's status says from one frame to the next while a hand moves between two of the
robot's warnings (and the source has a word of its own now and then)."""

RECORD_TOP_JS = """async ([p, notices]) => {
    const { set } = await import("/static/state.js");
    const base = p.S.source;
    const top = () => document.getElementById("sec-record").getBoundingClientRect().top;
    const tops = [];
    for (const [field, text] of notices) {
        set("source", { ...base, warning: null, robot_warning: null, [field]: text });
        tops.push(top());
    }
    return tops;
}"""
"""Announce each status in turn, as the live stream does, and read where the Record section
starts after each (the layout is read as the next frame would paint it)."""


def test_notices_that_come_and_go_keep_the_record_section_still(
    browser: Any, studio_server: Studio
) -> None:
    with own_page(browser, studio_server, 1280, 720) as page:
        page.wait_for_function("p => p.S.source && p.S.source.kind", arg=hook(page), timeout=T)
        tops = page.evaluate(RECORD_TOP_JS, [hook(page), NOTICES])
        # the first warning makes room once; from then on the section stays where it is
        assert tops[1] > tops[0]
        assert max(tops[1:]) - min(tops[1:]) < 1, tops
        assert not page.errors


def _labels(page: Any) -> dict[str, str]:
    """Each run's name in the Compare table, by run id."""
    rows = page.locator("[data-testid='compare-row']")
    return {
        row.get_attribute("data-id"): row.locator("td.name").inner_text().strip()
        for row in rows.all()
    }


def test_runs_read_apart_and_the_compare_table_fits_at_1280x720(
    browser: Any, studio_server: Studio
) -> None:
    """Two unnamed runs of the same settings both read "zero x2 · grid", and the twin without
    demonstrations of an unnamed run was unnamed too; the table ran past the window's right."""
    same = {"planning": "zero", "episodes": 4, "experiments": 2, "seed": 5}
    first = studio_server.send("POST", "/api/runs", same)
    second = studio_server.send("POST", "/api/runs", same)
    taught, twin = studio_server.send(
        "POST", "/api/runs/pair", {**same, "demonstrations": ["sample-reach-1"]}
    )
    assert twin["name"] == "zero x2 · no demos"  # as docs/learning.md names the twin
    ours = [first["id"], second["id"], taught["id"], twin["id"]]
    with own_page(browser, studio_server, 1280, 720) as page:
        page.get_by_role("button", name="Compare runs").first.click()
        for run_id in ours:
            page.wait_for_selector(f"[data-testid='compare-row'][data-id='{run_id}']", timeout=T)
        labels = _labels(page)
        assert len(set(labels.values())) == len(labels), labels  # no two runs read the same
        assert labels[twin["id"]].startswith("zero x2 · no demos")
        # the legend names them apart too, once plotted (a run is plotted from its first episode)
        for run_id in (first["id"], second["id"]):
            assert wait_for(
                lambda r=run_id: studio_server.get(f"/api/runs/{r}")["status"] == "done", 300
            )
        for run_id in (first["id"], second["id"]):
            box = page.locator(f"[data-testid='compare-row'][data-id='{run_id}'] input").first
            if not box.is_checked():
                box.check()
        page.wait_for_function(
            "([p, ids]) => ids.every((id) => p.chart.drawnRuns().includes(id))",
            arg=[hook(page), [first["id"], second["id"]]],
            timeout=T,
        )
        legend = page.locator("#curve-plot .u-legend .u-series:not(.band-edge) .u-label")
        names = [n for n in legend.all_inner_texts() if n.startswith("zero x2 · grid")]
        assert len(names) >= 2 and len(set(names)) == len(names), names
        # the dialog fits the window whatever runs it lists (the studio's other runs, a continuous
        # one's tilings and actions among them, bring columns of their own: those scroll inside it)
        measure = """() => {
            const scroll = document.querySelector("#compare-dialog .compare-scroll");
            const dialog = document.getElementById("compare-dialog").getBoundingClientRect();
            return [scroll.scrollWidth - scroll.clientWidth, dialog.right - innerWidth];
        }"""
        assert page.evaluate(measure)[1] <= 0
        # every column in view: these runs' settings, filtered to them, fit the dialog
        page.get_by_test_id("compare-filter").fill("zero x2")
        page.wait_for_function(
            """() => {
                const rows = [...document.querySelectorAll("[data-testid='compare-row']")];
                return rows.length >= 4 && rows.every((r) => r.innerText.includes("zero x2"));
            }"""
        )
        fit = page.evaluate(measure)
        shot(page, "compare-every-column-1280x720")
        assert fit[0] <= 1 and fit[1] <= 0, fit
        assert not page.errors
