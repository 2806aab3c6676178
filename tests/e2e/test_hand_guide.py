"""Browser: pick "hand guide" in the page's source selector, move the hand, and see the robot follow
in the API and in the page."""

from __future__ import annotations

import time
from typing import Any

import numpy as np
import pytest

from tests.e2e.conftest import Studio, shot

pytestmark = pytest.mark.e2e

T = 20_000  # ms: the longest a single UI step may take


def _wait(predicate: Any, timeout: float = 20.0) -> Any:
    """Poll ``predicate`` until it returns something truthy (the event, not a fixed sleep)."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = predicate()
        if value:
            return value
        time.sleep(0.1)
    return predicate()


def test_the_hand_guide_moves_the_robot(page: Any, studio_server: Studio) -> None:
    options = page.eval_on_selector_all(
        "[data-testid='source-kind'] option", "els => els.map(e => [e.value, e.textContent])"
    )
    assert ["hand", "hand guide"] in [[v, t.strip()] for v, t in options]
    page.select_option("[data-testid='source-kind']", "hand")
    page.click("#source-apply")
    assert _wait(lambda: studio_server.get("/api/source")["kind"] == "hand")
    before = np.array(studio_server.get("/api/source")["q_robot"])
    shown_before = page.inner_text("#src-q")

    # what the scene's handle sends when dragged, from the page itself (same origin, same guard)
    answer = page.evaluate(
        """async () => {
            const r = await fetch('/api/source/hand', {method: 'POST',
                headers: {'Content-Type': 'application/json'},
                body: JSON.stringify({position: [0.35, 0.05, -0.25], wxyz: null})});
            return {status: r.status, body: await r.json()};
        }"""
    )
    assert answer["status"] == 200, answer
    assert answer["body"]["reached"] is True
    source = studio_server.get("/api/source")
    after = np.array(source["q_robot"])
    assert source["frames"] >= 1
    assert np.allclose(after, answer["body"]["q_robot"])
    assert np.abs(after - before).max() > np.radians(5)
    # the page's source line shows the robot's joints in degrees (about 4 source events a second)
    page.wait_for_function(
        """want => {
            const text = document.querySelector('#src-q').textContent.replace('°', '');
            const shown = text.trim().split(/\\s+/).map(Number);
            return shown.length === want.length && shown.every((v, i) => Math.abs(v - want[i]) <= 1);
        }""",
        arg=[float(x) for x in np.degrees(after)],
        timeout=T,
    )
    assert page.inner_text("#src-q") != shown_before
    shot(page, "hand-guide", "sec-source")
    assert not page.errors  # type: ignore[attr-defined]
