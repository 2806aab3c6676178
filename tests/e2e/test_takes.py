"""Recording in takes, as a person does it: countdown, stop, review, redo, keep and next, keep,
then the kept takes become demonstrations in one go."""

from __future__ import annotations

import json
import time
from typing import Any

import numpy as np
import pytest

from tests.page_hooks import hook

from .conftest import Studio, shot

pytestmark = pytest.mark.e2e

T = 20_000  # ms: the longest a single UI step may take
AWAY_DEG = [-40.0, 20.0, -40.0]
"""Robot joints 1-3 (degrees) the simulated operator waits at before each take, far from the goal."""


def _phase(page: Any, phase: str) -> None:
    """Wait for the take flow to reach ``phase``; else fail with what the page says."""
    try:
        page.wait_for_selector(f"[data-testid='take-start'][data-phase='{phase}']", timeout=T)
    except Exception:
        state = page.evaluate("p => [p.S.takePhase, p.S.takes]", hook(page))
        raise AssertionError(f"{state}: {page.inner_text('[data-testid=takes-error]')}") from None


def _recorded_for(page: Any, seconds: float) -> None:
    page.wait_for_function(
        f"p => p.S.capture && p.S.capture.active && p.S.capture.seconds > {seconds}",
        arg=hook(page),
        timeout=T,
    )


def _reach(page: Any, studio: Studio) -> None:
    """Half a second of wandering, then the reach to the goal."""
    _recorded_for(page, 0.5)
    studio.send("POST", "/api/source/reach", {"action": "reach"})  # the simulated operator acts
    _recorded_for(page, 3.0)


def _away_from_the_goal(studio: Studio) -> None:
    """Send the simulated operator to a pose far from the goal, and wait until it is there."""
    studio.send("POST", "/api/source/reach", {"action": "reach", "goal_deg": AWAY_DEG})
    deadline = time.monotonic() + 30
    while True:
        q = np.degrees(studio.get("/api/source")["q_robot"][:3])
        if np.abs(q - AWAY_DEG).max() < 10:
            return
        assert time.monotonic() < deadline, f"the operator stayed at {q}"
        time.sleep(0.1)


def _record_a_take(page: Any, studio: Studio) -> None:
    """Start a take (it counts down first) away from the goal, then let the simulated operator
    reach it."""
    _away_from_the_goal(studio)
    page.click("[data-testid='take-start']")
    left = page.locator("[data-testid='capture-countdown-left']")
    left.wait_for(state="visible", timeout=T)
    assert "Recording in 1 s" in left.inner_text()
    _phase(page, "recording")
    _reach(page, studio)
    page.locator("body").focus()  # the keys act on the page, not on a button


def test_record_in_takes(page: Any, studio_server: Studio) -> None:
    if studio_server.get("/api/source")["kind"] != "simulator":
        page.select_option("[data-testid='source-kind']", "simulator")
        page.click("[data-testid='source-apply']")
        page.wait_for_function("p => p.S.source && p.S.source.kind === 'simulator'", arg=hook(page))
    for name in ("Countdown", "Timeline"):
        assert page.get_by_label(name, exact=True).count() == 1, name
    page.get_by_label("Countdown", exact=True).fill("1")

    # A take, stopped with Escape, plays on the robot for review; ← throws it away.
    _record_a_take(page, studio_server)
    page.keyboard.press("Escape")
    _phase(page, "review")
    first = page.locator("[data-testid='take']").first.get_attribute("data-name")
    assert (studio_server.data_dir / "recordings" / f"{first}.tape.csv").is_file()
    shot(page, "takes-review", "sec-record")
    assert page.get_by_role("button", name="Redo take").is_enabled()  # what ← does, by its name
    page.keyboard.press("ArrowLeft")
    _phase(page, "idle")
    assert not (studio_server.data_dir / "recordings" / f"{first}.tape.csv").exists()

    # Two takes: → keeps the first and starts the next (after its countdown); Keep take keeps it.
    _record_a_take(page, studio_server)
    page.keyboard.press("Escape")
    _phase(page, "review")
    _away_from_the_goal(studio_server)  # the next take starts away from the goal
    page.keyboard.press("ArrowRight")
    page.locator("[data-testid='capture-countdown-left']").wait_for(state="visible", timeout=T)
    _phase(page, "recording")
    _reach(page, studio_server)
    page.click("[data-testid='take-start']")  # now "Stop take"
    _phase(page, "review")
    page.get_by_role("button", name="Review take").click()
    page.get_by_role("button", name="Keep take").click()
    _phase(page, "kept")
    assert page.locator("[data-testid='take'][data-state='kept']").count() == 2
    shot(page, "takes-kept", "sec-record")

    # The session becomes two demonstrations in one go.
    page.check("[data-testid='demo-goal-from-end']")
    page.click("[data-testid='takes-make']")
    page.wait_for_selector("[data-testid='takes-made']:visible", timeout=60_000)
    assert not page.is_visible("[data-testid='takes-error']"), page.inner_text(
        "[data-testid='takes-error']"
    )
    assert "Made 2 demonstrations" in page.inner_text("[data-testid='takes-made']")
    takes = json.loads((studio_server.data_dir / "recordings" / "takes.json").read_text())
    session = takes["sessions"][-1]
    assert session["finished"] and [t["state"] for t in session["takes"]] == ["kept", "kept"]
    for take in session["takes"]:
        demo = studio_server.data_dir / "recordings" / f"{take['demonstration']}.demo.json"
        assert demo.is_file()
        assert json.loads(demo.read_text())["recording"].startswith(take["recording"])
        page.wait_for_selector(
            f"[data-testid='demo-row'][data-name='{take['demonstration']}']", timeout=T
        )
    shot(page, "takes-made", "sec-record")
    page.uncheck("[data-testid='demo-goal-from-end']")
    assert not page.errors  # type: ignore[attr-defined]
