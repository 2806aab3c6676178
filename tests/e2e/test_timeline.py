"""Cutting on a recording's timeline: open it, scrub, drag, set the ends with [ and ], cut."""

from __future__ import annotations

import json
from typing import Any

import pytest

from tests.page_hooks import hook

from .conftest import Studio, shot

pytestmark = pytest.mark.e2e

T = 20_000  # ms: the longest a single UI step may take


def _ends(page: Any) -> tuple[float, float]:
    return float(page.input_value("[data-testid='demo-t0']")), float(
        page.input_value("[data-testid='demo-t1']")
    )


def _shoot_small_and_large(page: Any, name: str) -> None:
    """Screenshots of the timeline on the small and the large screen, once its plot fits each."""
    for width, height in ((1280, 720), (1920, 1080)):
        page.set_viewport_size({"width": width, "height": height})
        page.wait_for_function(
            "() => document.querySelector('[data-testid=timeline-plot] canvas').clientWidth"
            " >= document.querySelector('[data-testid=timeline-plot]').clientWidth - 2"
        )
        shot(page, f"{name}-{width}x{height}", "timeline")
    page.set_viewport_size({"width": 1440, "height": 900})


def test_cut_on_the_timeline(page: Any, studio_server: Studio) -> None:
    page.get_by_role("button", name="Timeline of sample-reach-1").click()
    timeline = page.get_by_role("slider", name="Timeline")
    timeline.wait_for(state="visible", timeout=T)
    page.wait_for_selector("[data-testid='timeline-plot'] canvas", timeout=60_000)
    # the answer to this click drawn (an earlier story's plot of the same recording may be up)
    page.wait_for_function(
        "p => { const t = p.S.timeline; return t.data && t.drawn === t.asked; }",
        arg=hook(page),
        timeout=60_000,
    )
    duration = float(timeline.get_attribute("aria-valuemax"))
    assert duration > 3
    assert page.input_value("[data-testid='demo-recording']") == "sample-reach-1"

    # Dragging across the plot selects a segment: the section's t0 and t1.
    plot = page.locator("[data-testid='timeline-plot'] .u-over")
    plot.scroll_into_view_if_needed()  # as a person scrolls to it: earlier panels may push it down
    over = plot.bounding_box()
    y = over["y"] + over["height"] / 2
    page.mouse.move(over["x"] + over["width"] * 0.2, y)
    page.mouse.down()
    page.mouse.move(over["x"] + over["width"] * 0.6, y, steps=5)
    # as a person's drag spans frames: the plot has the pointer where it is before the release
    # (on a busy machine the plot takes the moves a frame late, and a release before ends short)
    page.wait_for_function(
        "([p, x]) => Math.abs(p.S.timeline.chart.cursor.left - x) < 2",
        arg=[hook(page), over["width"] * 0.6],
        timeout=T,
    )
    page.mouse.up()
    t0, t1 = _ends(page)
    assert 0.1 * duration < t0 < 0.3 * duration and 0.5 * duration < t1 < 0.7 * duration
    shot(page, "timeline-dragged", "sec-demos")

    # The keys: Home, ten steps of 0.1 s, [ sets the start; End, ] sets the end.
    timeline.focus()
    timeline.press("Home")
    for _ in range(10):
        timeline.press("ArrowRight")
    assert float(timeline.get_attribute("aria-valuenow")) == 1.0
    timeline.press("[")
    timeline.press("End")
    timeline.press("]")
    assert _ends(page) == (1.0, round(duration, 2))

    # Space plays from the segment's start and pauses.
    timeline.press("Home")
    timeline.press(" ")
    page.wait_for_function("p => p.S.timeline.playhead > 0.3", arg=hook(page), timeout=T)
    timeline.press(" ")
    assert timeline.get_attribute("data-playing") == "0"
    shot(page, "timeline-ends", "sec-demos")
    _shoot_small_and_large(page, "timeline")

    page.fill("[data-testid='demo-name']", "timeline-demo")
    page.uncheck("[data-testid='demo-goal-from-end']")
    page.click("[data-testid='demo-cut']")
    page.wait_for_selector(
        "[data-testid='demo-ok']:visible, [data-testid='demo-error']:visible", timeout=T
    )
    assert page.is_visible("[data-testid='demo-ok']"), page.inner_text("[data-testid='demo-error']")
    demo = json.loads(
        (studio_server.data_dir / "recordings" / "timeline-demo.demo.json").read_text()
    )
    t0, t1 = demo["segment"]
    assert t0 == 1.0 and abs(t1 - duration) < 0.01
    assert not page.errors  # type: ignore[attr-defined]


def test_a_tape_timeline_plots_its_bend_and_twist_per_region(
    page: Any, studio_server: Studio
) -> None:
    page.get_by_role("button", name="Timeline of sample-reach-2").click()
    page.wait_for_function(
        "p => (p.S.timeline.data || {}).name === 'sample-reach-2'",
        arg=hook(page),
        timeout=60_000,
    )
    served = studio_server.get("/api/recordings/sample-reach-2/timeline?points=50")
    regions = len(served["signals"][0]["labels"])
    show = page.get_by_role("combobox", name="Timeline shows")
    options = show.locator("option").all_inner_texts()
    assert options == ["joints (robot and human arm)", "tape bend", "tape twist"]
    assert len(page.evaluate("p => p.S.timelineShown", hook(page))) == 13  # 6 robot, 7 human joints
    show.select_option("tape bend")
    shown = page.evaluate("p => p.S.timelineShown", hook(page))
    assert shown == [f"tape bend region {i + 1}" for i in range(regions)]
    # the plotted values are the recording's own, in degrees, as the server serves them
    drawn, own = page.evaluate(
        "p => { const d = p.S.timeline; "
        "return [d.chart.data[1], d.data.signals[0].values.map((v) => v[0])]; }",
        hook(page),
    )
    assert drawn == own and len(set(own)) > 1  # region 1's bend, as it varies over the reach
    assert own[0] == served["signals"][0]["values"][0][0]  # the first frame's, as served
    page.locator("#timeline").scroll_into_view_if_needed()
    shot(page, "timeline-tape-bend", "timeline")
    show.select_option("tape twist")
    assert page.evaluate("p => p.S.timelineShown", hook(page))[0] == "tape twist region 1"
    _shoot_small_and_large(page, "timeline-tape-twist")
    show.select_option("joints")
    assert len(page.evaluate("p => p.S.timelineShown", hook(page))) == 13
    assert not page.errors  # type: ignore[attr-defined]
