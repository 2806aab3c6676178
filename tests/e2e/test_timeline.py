"""Cutting on a recording's timeline: open it, scrub, drag, set the ends with [ and ], cut."""

from __future__ import annotations

import json
from typing import Any

from .conftest import Studio, shot

T = 20_000  # ms: the longest a single UI step may take


def _ends(page: Any) -> tuple[float, float]:
    return float(page.input_value("[data-testid='demo-t0']")), float(
        page.input_value("[data-testid='demo-t1']")
    )


def test_cut_on_the_timeline(page: Any, studio_server: Studio) -> None:
    page.get_by_role("button", name="Timeline of sample-reach-1").click()
    timeline = page.get_by_role("slider", name="Timeline")
    timeline.wait_for(state="visible", timeout=T)
    page.wait_for_selector("[data-testid='timeline-plot'] canvas", timeout=60_000)
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
    page.wait_for_function("() => window.studio.timeline.playhead > 0.3", timeout=T)
    timeline.press(" ")
    assert timeline.get_attribute("data-playing") == "0"
    shot(page, "timeline-ends", "sec-demos")
    for width, height in ((1280, 720), (1920, 1080)):  # the small and the large screen
        page.set_viewport_size({"width": width, "height": height})
        page.wait_for_function(
            "() => document.querySelector('[data-testid=timeline-plot] canvas').clientWidth"
            " >= document.querySelector('[data-testid=timeline-plot]').clientWidth - 2"
        )
        shot(page, f"timeline-{width}x{height}", "timeline")
    page.set_viewport_size({"width": 1440, "height": 900})

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
