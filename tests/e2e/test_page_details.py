"""In a real browser: the page's details a user trips over (issue 18, item 13).

A failed switch to the serial source leaves one state; the "live" chip is readable; viser's own
notice and panel leave the scene uncovered; the scene and the chart explain their marks; run
names are never cut without a tooltip and say which task they learn.
"""

from __future__ import annotations

import socket
from collections.abc import Iterator
from typing import Any

import pytest

from tests.e2e.conftest import Studio, own_page, shot
from tests.web.conftest import wait_for

pytestmark = pytest.mark.e2e

READY_TIMEOUT_MS = 30_000
T = 20.0  # s: the longest one step of the page may take (the machine may be busy)
WCAG_AA = 4.5
"""WCAG 2's least contrast ratio for normal text (level AA)."""
ENDED = ("done", "stopped", "failed")
LONG_NAME = "a-run-name-long-enough-to-be-cut-in-the-list"


@pytest.fixture
def fresh_page(browser: Any, studio_server: Studio) -> Iterator[Any]:
    """A page of its own on the studio (its 3D scene left out); the source is the simulator
    again afterwards."""
    try:
        with own_page(browser, studio_server) as page:
            yield page
    finally:
        studio_server.send("PUT", "/api/source", {"kind": "simulator"})  # as the stories expect


def _visible_errors(page: Any) -> list[str]:
    return [
        page.inner_text(f"[data-testid='{testid}']")
        for testid in ("source-status-error", "source-error")
        if page.is_visible(f"[data-testid='{testid}']")
    ]


def _free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_failed_switch_to_serial_leaves_one_state(fresh_page: Any, studio_server: Studio):
    page = fresh_page
    # A network source nobody sends to: after a moment it has its own error.
    page.select_option("[data-testid='source-kind']", "network")
    page.fill("[data-testid='source-port']", str(_free_udp_port()))
    page.click("[data-testid='source-apply']")
    assert wait_for(lambda: page.inner_text("#top-source-kind") == "network")
    assert wait_for(lambda: "no frames" in " ".join(_visible_errors(page)))

    # Serial with a calibration file that is not there: the switch happens, with one message.
    page.select_option("[data-testid='source-kind']", "serial")
    page.fill("[data-testid='source-device']", "/dev/ttyUSB0")
    page.fill("[data-testid='source-calibration']", "/nowhere/cal.json")
    page.click("[data-testid='source-apply']")
    assert wait_for(lambda: page.inner_text("#top-source-kind") == "serial")
    assert page.input_value("[data-testid='source-kind']") == "serial"
    assert wait_for(lambda: len(_visible_errors(page)) == 1), _visible_errors(page)
    assert "/nowhere/cal.json" in _visible_errors(page)[0]
    source = studio_server.get("/api/source")
    assert source["kind"] == "serial" and not source["running"]  # the network source stopped
    shot(page, "13-serial-failed", "sec-source")

    # A refused switch (no device) changes nothing: the selector goes back to what runs.
    page.select_option("[data-testid='source-kind']", "simulator")
    page.click("[data-testid='source-apply']")
    assert wait_for(lambda: page.inner_text("#top-source-kind") == "simulator")
    page.select_option("[data-testid='source-kind']", "serial")
    page.fill("[data-testid='source-device']", "")
    page.click("[data-testid='source-apply']")
    assert wait_for(lambda: page.is_visible("[data-testid='source-error']"))
    assert "device is missing" in page.inner_text("[data-testid='source-error']")
    assert page.input_value("[data-testid='source-kind']") == "simulator"
    assert page.inner_text("#top-source-kind") == "simulator"
    assert studio_server.get("/api/source")["kind"] == "simulator"
    assert not page.errors


def _contrast(page: Any, selector: str) -> float:
    """WCAG 2 contrast ratio of an element's computed text colour on its background."""
    return page.evaluate(
        """(selector) => {
            const e = document.querySelector(selector);
            const style = getComputedStyle(e);
            const rgb = (c) => c.match(/[\\d.]+/g).slice(0, 3).map(Number);
            const lum = ([r, g, b]) => {
                const f = (v) => { v /= 255; return v <= 0.03928 ? v / 12.92 : ((v + 0.055) / 1.055) ** 2.4; };
                return 0.2126 * f(r) + 0.7152 * f(g) + 0.0722 * f(b);
            };
            const a = lum(rgb(style.color)), b = lum(rgb(style.backgroundColor));
            return (Math.max(a, b) + 0.05) / (Math.min(a, b) + 0.05);
        }""",
        selector,
    )


def test_the_live_chip_is_readable(fresh_page: Any) -> None:
    page = fresh_page
    assert wait_for(lambda: page.inner_text("[data-testid='connection']") == "live")
    assert page.get_attribute("[data-testid='connection']", "class") == "chip ok"
    assert _contrast(page, "[data-testid='connection']") >= WCAG_AA
    # the chip keeps the chip's shape: no message box's border or margin leaks into it
    border = page.evaluate(
        "() => getComputedStyle(document.querySelector('#conn')).borderLeftWidth"
    )
    assert border == "0px"


SCENE_COVERED = """() => {
    // Points over the scene's canvas whose topmost element is not the canvas: something covers it.
    const area = (c) => c.getBoundingClientRect().width * c.getBoundingClientRect().height;
    const canvas = [...document.querySelectorAll("canvas")].sort((a, b) => area(b) - area(a))[0];
    if (!canvas) return ["no canvas"];
    const r = canvas.getBoundingClientRect();
    const covered = [];
    for (let i = 1; i < 10; i++) {
        for (let j = 1; j < 10; j++) {
            const x = r.left + (r.width * i) / 10, y = r.top + (r.height * j) / 10;
            const top = document.elementFromPoint(x, y);
            if (top && top.nodeName !== "CANVAS") {  // the scene is drawn on stacked canvases
                covered.push(`${i},${j}: ${top.className || top.nodeName} ${(top.textContent || "").slice(0, 40)}`);
            }
        }
    }
    return covered;
}"""


def test_viser_covers_nothing_of_the_scene(browser: Any, studio_server: Studio) -> None:
    with own_page(browser, studio_server, scene=True) as page:
        page.wait_for_function("() => document.querySelector('#scene').src !== ''")
        scene = page.frame_locator("#scene")
        scene.locator("canvas").first.wait_for(state="visible", timeout=60_000)
        frame = page.locator("#scene").element_handle().content_frame()
        # The scene has loaded once its websocket is connected (viser then sends the scene).
        assert wait_for(lambda: frame.evaluate("() => !!document.querySelector('canvas')"), T)
        toast = scene.get_by_text("Software WebGL rendering detected")
        assert wait_for(lambda: toast.count() == 0 or not toast.first.is_visible(), T)
        assert wait_for(lambda: frame.evaluate(SCENE_COVERED) == [], T), frame.evaluate(
            SCENE_COVERED
        )
        assert not scene.get_by_role("button", name="Reset view").is_visible()  # folded in the rail
        shot(page, "13-scene-uncovered")


def test_the_scene_and_the_chart_explain_their_marks(
    fresh_page: Any, studio_server: Studio
) -> None:
    page = fresh_page
    colors = studio_server.get("/api/config")["scene_colors"]
    legend = page.get_by_test_id("scene-legend")
    assert legend.is_visible()
    text = legend.inner_text()
    assert "goal pose" in text and "goal" in text and "rollout" in text
    shown = page.evaluate(
        """() => Object.fromEntries([...document.querySelectorAll('#scene-legend [data-color]')]
            .map((e) => [e.dataset.color, getComputedStyle(e).backgroundColor]))"""
    )
    for name, color in shown.items():  # the scene's own colours, defined once
        assert color == "rgb({}, {}, {})".format(*colors[name]), name

    run = studio_server.send(
        "POST", "/api/runs", {"name": "e2e-key", "episodes": 5, "experiments": 2}
    )
    assert wait_for(lambda: studio_server.get(f"/api/runs/{run['id']}")["status"] == "done", 180)
    row = page.locator(f"[data-testid='run-row'][data-id='{run['id']}']")
    row.wait_for(timeout=T * 1000)
    if not row.get_by_test_id("run-show").is_checked():
        row.get_by_test_id("run-show").check()
    key = page.get_by_test_id("curve-key")
    assert wait_for(key.is_visible)
    assert "mean" in key.inner_text() and "± 1 std" in key.inner_text()
    page.select_option("[data-testid='curve-band']", "minmax")
    assert wait_for(lambda: "min–max" in key.inner_text())
    # the dashed marker's key shows exactly when the chart draws a marker
    drawn = page.evaluate(
        """async () => {
            const { plottedRuns, chartData, fewerFrom } = await import("/static/chart.js");
            const runs = plottedRuns(); const d = chartData(runs, "minmax", true);
            return runs.some((r, i) => fewerFrom(d, i) !== null); }"""
    )
    assert page.get_by_test_id("curve-key-fewer").is_visible() == drawn
    shot(page, "13-legends")


def test_run_names_are_never_cut_without_a_tooltip_and_name_their_task(
    fresh_page: Any, studio_server: Studio
) -> None:
    page = fresh_page
    grid = studio_server.send(
        "POST", "/api/runs", {"name": LONG_NAME, "episodes": 3, "experiments": 1}
    )
    reach = studio_server.send(
        "POST",
        "/api/runs",
        {"name": LONG_NAME, "task": "arm-reach", "joints": 4, "episodes": 3, "experiments": 1},
    )
    labels = {}
    for run in (grid, reach):
        cell = page.locator(f"[data-testid='run-row'][data-id='{run['id']}'] td.name")
        cell.wait_for(timeout=T * 1000)
        labels[run["id"]] = cell.inner_text()
    assert "grid" in labels[grid["id"]]
    assert "continuous, 4 joints" in labels[reach["id"]]
    assert labels[grid["id"]] != labels[reach["id"]]
    cut = page.evaluate(
        """() => [...document.querySelectorAll("td.name")]
            .filter((td) => td.offsetParent !== null && td.scrollWidth > td.clientWidth)
            .map((td) => [td.textContent.trim(), td.title])"""
    )
    assert any(LONG_NAME in text for text, _ in cut)  # the long name is cut here...
    for text, title in cut:  # ...and every cut name is whole in its tooltip
        assert title and text.split()[0] in title, text
    for run in (grid, reach):
        cell = page.locator(f"[data-testid='run-row'][data-id='{run['id']}'] td.name")
        assert cell.get_attribute("title") == labels[run["id"]]
    for run in (grid, reach):  # the runs were only for their labels: leave the queue free
        studio_server.send("POST", f"/api/runs/{run['id']}/stop")
        assert wait_for(
            lambda r=run: studio_server.get(f"/api/runs/{r['id']}")["status"] in ENDED, 120
        )


CUT_CONTROLS_JS = """() => {
  const side = document.querySelector('aside.panel').getBoundingClientRect();
  const out = [];
  for (const el of document.querySelectorAll('aside.panel details[open] select, aside.panel details[open] input, aside.panel details[open] button')) {
    if (el.offsetParent === null || el.type === 'checkbox' || el.type === 'radio' || el.type === 'file') continue;
    const r = el.getBoundingClientRect();
    if (r.width < 14 || r.right > side.right + 0.5 || r.left < side.left - 0.5) out.push([el.id || el.textContent.trim(), Math.round(r.left), Math.round(r.width)]);
  }
  return out;
}"""
"""Controls of the side panel's open sections that are squeezed to nothing or stick out of it."""


@pytest.mark.parametrize("size", [(1280, 720), (1920, 1080)])
def test_every_control_of_the_side_panel_fits_it(
    browser: Any, studio_server: Studio, size: tuple[int, int]
) -> None:
    """No control of the side panel is squeezed out of sight or reaches past its edge (the Watch
    row once squeezed the policy list to nothing and pushed "compare with" past the edge)."""
    long_name = "a-demonstration-named-at-length-to-widen-the-lists-it-is-in"
    if not any(d["name"] == long_name for d in studio_server.get("/api/demonstrations")):
        studio_server.send(
            "POST",
            "/api/demonstrations",
            {"recording": "sample-reach-1", "t0": 0.2, "t1": 2.5, "name": long_name},
        )
    try:
        with own_page(browser, studio_server, *size) as page:
            page.wait_for_selector(f"#watch-demo option[value*='{long_name}']", state="attached")
            page.locator("#sec-watch").scroll_into_view_if_needed()
            shot(page, f"side-panel-watch-{size[0]}x{size[1]}", "sec-watch")
            assert page.evaluate(CUT_CONTROLS_JS) == []
    finally:
        studio_server.send("DELETE", f"/api/demonstrations/{long_name}")  # the others' lists
